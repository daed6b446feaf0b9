"""The plan of an utterance: each segment's target solved once, and the forces, lips, port and voicing of
every segment.

The solving itself is handed in (``solve``: a list of targets -> one :class:`Answer` each), so the plan knows
targets and answers, not the files and processes a solver runs on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import Config
from ..control.equilibrium import canonical
from ..control.solver import TargetSpec, parse_target
from ..control.targets import load_target
from ..errors import ArticError, UnreachableTarget
from ..io.fingerprint import digest
from ..tract.speaker import speaker_tract
from .utterance import Utterance, target_path


@dataclass
class Plan:
    """What each segment does: its label, start and duration (s), forces (N), lips, port, voicing."""

    labels: list[str]
    starts_s: np.ndarray
    durations_s: np.ndarray
    forces_n: list[dict[str, float]]  # jaw and tongue together
    lips: list[tuple[float, float]]  # (area cm^2, length cm)
    ports: list[float]
    voiced: np.ndarray
    glottis_cm2: np.ndarray  # each segment's glottal opening: its own, else adducted (voiced) or abducted
    notes: list[str]  # per segment: how its forces were found
    solutions: list[str]  # the solution files ('' for given forces)
    continues: list[bool] = field(default_factory=list)  # the same phone as the segment before (one interval)


@dataclass
class Answer:
    """A solver's answer to one target: the solution document and its file, or the error that said the
    target is out of reach (its document, the nearest answer, is written too)."""

    doc: dict | None
    path: Path
    unreachable: UnreachableTarget | None = None


Solve = Callable[[list[TargetSpec]], list[Answer]]


def segment_targets(u: Utterance, source: Path | str | None, max_force_n: float) -> list[TargetSpec | None]:
    """Each segment's target (None for a segment with given forces): inline, or a file next to ``source``."""
    out = []
    for k, s in enumerate(u.segments):
        if s.target is None:
            out.append(None)
        elif isinstance(s.target, dict):
            out.append(parse_target(s.target, f"{source}: segments[{k}].target", max_force_n))
        else:
            out.append(load_target(target_path(s.target, source), max_force_n))
    return out


def target_key(t: TargetSpec) -> str:
    """The content key of a target (what its solution is cached by)."""
    return digest(t.model_dump(mode="json"))


def solution_forces(doc: dict) -> tuple[dict[str, float], bool, str]:
    """The forces a solution document settles on (jaw and tongue together), whether they reach the target,
    and which answer they are."""
    jaw = {k: float(v) for k, v in (doc.get("jaw") or {}).get("forces_n", {}).items()}
    for key in ("refined", "chosen", "nearest"):
        if key in doc and "forces_n" in doc[key]:
            reached = key == "chosen" or (key == "refined" and bool(doc[key].get("converged")))
            return {**jaw, **{k: float(v) for k, v in doc[key]["forces_n"].items()}}, reached, key
    raise ArticError(f"solution of '{doc.get('target')}' holds no forces; rerun 'artic solve-target'")


def nearer_target(t: TargetSpec, err: UnreachableTarget) -> TargetSpec | None:
    """The spatial target moved to the nearest reachable point, its tolerance kept (to speak the nearest answer).

    A tolerance widened to reach that point instead is not enough: the point lies on a net's edge, which the
    search for candidates inside the nets' cells can miss."""
    point = getattr(err, "nearest_point_cm", None)
    if t.crucial is None or point is None:
        return None
    crucial = t.crucial.model_copy(update={"at_cm": [float(c) for c in point]})
    return t.model_copy(update={"crucial": crucial, "name": f"{t.name}-nearest"})


def needs_dynamic(targets: list[TargetSpec | None], cfg: Config) -> bool:
    """Whether a spatial target sits at a jaw position the config's maps hold no nets for (the dynamic map then
    carries the typical map there)."""
    netted = [canonical(cfg.epmap.jaw_positions[n]) for n in cfg.epmap.net_jaw_positions
              if n in cfg.epmap.jaw_positions]
    return any(t is not None and not t.needs_tract and
               (t.jaw.forces_n is None or canonical(dict(t.jaw.forces_n)) not in netted) for t in targets)


def settle_answers(items: list[tuple[int, TargetSpec]], solve: Solve, accept_nearest: bool,
                   say: Callable[[str], None] | None = None) -> list[tuple[dict, str, Path]]:
    """(forces, how they were found, solution file) of each (segment, target): solved; an unreachable one
    spoken by its nearest answer when ``accept_nearest`` (a spatial target moved to its nearest reachable
    point and solved again), else an error naming the segment."""
    answers = solve([t for _, t in items])
    again = {}
    for n, ((k, t), a) in enumerate(zip(items, answers)):
        if a.unreachable is not None:
            if not accept_nearest:
                raise UnreachableTarget(f"segment {k}: {a.unreachable}; give --accept-nearest to speak the nearest "
                                        "reachable answer") from None
            wider = nearer_target(t, a.unreachable)
            if wider is not None:
                again[n] = wider
    moved = dict(zip(again, solve(list(again.values())))) if again else {}
    out = []
    for n, ((k, t), a) in enumerate(zip(items, answers)):
        if a.unreachable is not None:
            a = moved.get(n, a)
            if a.unreachable is not None and n in moved:
                raise a.unreachable
            forces, _, which = solution_forces(a.doc)
            if say:
                say(f"segment {k} ({t.name}): unreachable, speaking the nearest answer ({which})")
            out.append((forces, "unreachable: nearest answer", a.path))
            continue
        forces, reached, which = solution_forces(a.doc)
        if not reached:
            if not accept_nearest:
                raise UnreachableTarget(f"segment {k}: target '{t.name}' not reached by the refinement (see "
                                        f"{a.path}); give --accept-nearest to speak the best answer found")
            if say:
                say(f"segment {k} ({t.name}): refinement did not reach the tolerance; speaking its best answer")
            out.append((forces, "refined, not within tolerance", a.path))
            continue
        out.append((forces, "solved" + (", refined" if which == "refined" else ""), a.path))
    return out


def held(forces: list[dict[str, float]], hold: list[bool]) -> None:
    """Each held segment takes the forces of the segment before it (the first ones, of the first that is not
    held), in place."""
    own = [k for k, h in enumerate(hold) if not h]
    if not own:
        raise ArticError("every segment holds the one before; give at least one a target, phoneme or forces")
    for k, h in enumerate(hold):
        if h:
            forces[k] = dict(forces[k - 1] if k > 0 else forces[own[0]])


def plan(u: Utterance, cfg: Config, targets: list[TargetSpec | None], solve: Solve, accept_nearest: bool = False,
         say: Callable[[str], None] | None = None) -> Plan:
    """Solve every distinct target once and collect the forces, lips, port and voicing of each segment."""
    vt = speaker_tract(cfg)
    default_lips = (float(vt.lips.area_cm2), float(vt.lips.length_cm))
    distinct: dict[str, tuple[int, TargetSpec]] = {}
    for k, t in enumerate(targets):
        if t is not None:
            distinct.setdefault(target_key(t), (k, t))
    done = dict(zip(distinct, settle_answers(list(distinct.values()), solve, accept_nearest, say)))
    labels, forces, lips, ports, notes, files = [], [], [], [], [], []
    for s, t in zip(u.segments, targets):
        if t is None:
            labels.append(s.label or ("held" if s.hold else "forces"))
            forces.append({} if s.hold else dict(s.forces_n))
            lips.append(default_lips)
            ports.append(float(vt.velum_port_cm2))
            notes.append("held: the forces of the segment before" if s.hold else "forces given")
            files.append("")
            continue
        f, note, path = done[target_key(t)]
        labels.append(s.label or t.name)
        forces.append(f)
        lips.append(t.lip_tube(default_lips) if t.needs_tract else default_lips)
        ports.append(float(vt.velum_port_cm2 if t.velum_port_cm2 is None else t.velum_port_cm2))
        notes.append(note)
        files.append(str(path))
    held(forces, [s.hold for s in u.segments])
    starts = np.array(u.starts_ms()) / 1e3
    open_ = cfg.speech.glottal_area_voiceless_cm2
    glottis = np.array([s.glottis_cm2 if s.glottis_cm2 is not None else (vt.glottis_cm2 if s.voiced else open_)
                        for s in u.segments], dtype=float)
    return Plan(labels=labels, starts_s=starts, durations_s=np.array([s.duration_ms for s in u.segments]) / 1e3,
                forces_n=forces, lips=lips, ports=ports, voiced=np.array([s.voiced for s in u.segments]),
                glottis_cm2=glottis, notes=notes, solutions=files, continues=[s.continues for s in u.segments])
