"""Stage ``utterances``: a sequence of targets in time -> muscle forces in time -> movement -> tract -> sound.

Each segment's target is solved once (``solve-target --refine``; cached by content under the solutions folder);
its forces switch on at the segment's start with a raised-cosine ramp and hold until the next target
(:mod:`artic_cli.control.course`).  The whole sequence is simulated from the rest posture with contact; each
recorded frame gives an area function (lips and velum from the targets, then the utterance's own course) and
formants; the frames drive the time-domain synthesizer with the LF voice (off in voiceless segments) and a
turbulence noise source at the narrowest place (:mod:`artic_cli.acoustics.aerodynamics`).

Outputs: the WAV, a Praat TextGrid (one interval per segment) and ``NAME.h5`` (forces, control points,
area functions, formant tracks, the noise source), each written atomically; the HDF5 file is the stage's
freshness record and is written last.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from .. import units
from ..acoustics.aerodynamics import turbulence
from ..acoustics.tube import Tube
from ..config import Config, load_config
from ..control.course import activated, course, pulse_step
from ..control.equilibrium import canonical
from ..control.solver import TargetSpec, parse_target
from ..control.targets import load_target
from ..errors import ArticError, NotPhysical, UnreachableTarget
from ..geometry.anatomy import TONGUE_MUSCLES
from ..io.fingerprint import digest
from ..io.store import atomic_h5, atomic_path, open_artifact, stored_content_hash
from ..mechanics.loads import muscle_force_vector, muscle_shares
from ..mechanics.model import ARTICULATOR_SECTIONS, Control
from ..mechanics.simulate import Trajectory, run, settle
from ..schedule import TractEntry
from ..utterance import Utterance, check_forces, load_utterance, target_path
from . import acoustics as ac_stage
from . import mesh as mesh_stage
from . import simulate as sim_stage
from . import solve as solve_stage
from . import synthesize as syn_stage
from . import vocal_tract as vt_stage
from .base import Stage, up_to_date

STAGE = Stage(name="utterances", module=__name__,
              sections=(*ARTICULATOR_SECTIONS, "epmap", "vocal_tract", "acoustics", "speech"),
              reads=("mesh", "epmaps", "acousticmaps"), kind="utterance", hint="rerun 'artic speak UTTERANCE.yaml'")


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
    notes: list[str]  # per segment: how its forces were found
    solutions: list[str]  # the solution files ('' for given forces)


@dataclass
class Spoken:
    utterance: Utterance
    plan: Plan
    trajectory: Trajectory
    tracts: object  # vocal_tract.Tracts
    formants_hz: np.ndarray  # (F, n)
    noise: object  # aerodynamics.Turbulence
    glottis_cm2: np.ndarray
    audio: syn_stage.Audio
    control_points: dict[str, np.ndarray]  # (F, 3) cm
    muscle_names: list[str]
    muscle_force_n: np.ndarray  # (F, M) commanded: the course, after activation dynamics when they are on
    timings_s: dict[str, float]  # wall time of each part: rest, simulation, tract, formants, sound
    segment_eps_cm: np.ndarray  # (K, 3, 3) tip, dorsum, jaw where each segment's forces lead (held from rest)
    beyond_wall_cm: float  # the farthest any tongue node got beyond the wall
    force_course: str  # static or pulse_step
    ramp_ms: float  # each segment's ramp
    activation_ms: tuple[float, float]  # the muscles' activation rise and fall time constants (0, 0: none)
    lead_ms: float = 0.0  # each segment's forces switch on this long before its sound
    prepare_ms: float = 0.0  # the first segment's forces switch on this long before the sound (>= lead_ms)
    segment_lead_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's own lead
    press: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's tongue-force factor


# --- the plan: targets -> forces ---------------------------------------------------------------------

def _targets(u: Utterance, source: Path | str | None, max_force_n: float) -> list[TargetSpec | None]:
    out = []
    for k, s in enumerate(u.segments):
        if s.target is None:
            out.append(None)
        elif isinstance(s.target, dict):
            out.append(parse_target(s.target, f"{source}: segments[{k}].target", max_force_n))
        else:
            out.append(load_target(target_path(s.target, source), max_force_n))
    return out


def solution_forces(doc: dict) -> tuple[dict[str, float], bool, str]:
    """The forces a solution document settles on (jaw and tongue together), whether they reach the target,
    and which answer they are."""
    jaw = {k: float(v) for k, v in (doc.get("jaw") or {}).get("forces_n", {}).items()}
    for key in ("refined", "chosen", "nearest"):
        if key in doc and "forces_n" in doc[key]:
            reached = key == "chosen" or (key == "refined" and bool(doc[key].get("converged")))
            return {**jaw, **{k: float(v) for k, v in doc[key]["forces_n"].items()}}, reached, key
    raise ArticError(f"solution of '{doc.get('target')}' holds no forces; rerun 'artic solve-target'")


def _nearer(t: TargetSpec, err: UnreachableTarget) -> TargetSpec | None:
    """The spatial target moved to the nearest reachable point, its tolerance kept (to speak the nearest answer).

    A tolerance widened to reach that point instead is not enough: the point lies on a net's edge, which the
    search for candidates inside the nets' cells can miss."""
    point = getattr(err, "nearest_point_cm", None)
    if t.crucial is None or point is None:
        return None
    crucial = t.crucial.model_copy(update={"at_cm": [float(c) for c in point]})
    return t.model_copy(update={"crucial": crucial, "name": f"{t.name}-nearest"})


def plan(u: Utterance, cfg: Config, source: Path | str | None = None, maps: Path | str = "data/epmaps.h5",
         mesh: Path | str = "data/mesh.h5", acoustic_maps: Path | str | None = "data/acoustic_maps.h5",
         config: Path | str | None = None, solutions: Path | str = "data/utterances/solutions",
         accept_nearest: bool = False, budget: int = 8,
         say: Callable[[str], None] | None = None, targets: list[TargetSpec | None] | None = None,
         jobs: int = 1, dynamic: Path | str | None = "data/dynamic.h5") -> Plan:
    """Solve every segment's target (cached; distinct targets in ``jobs`` processes) and collect the forces,
    lips and voicing of each segment.  ``dynamic`` carries the typical map to a target's jaw position that was
    not mapped with nets (read only for such a target)."""
    targets = _targets(u, source, cfg.muscles.max_force_n) if targets is None else targets
    vt = vt_stage.speaker_tract(cfg)
    default_lips = (float(vt.lips.area_cm2), float(vt.lips.length_cm))
    distinct: dict[str, tuple[int, TargetSpec]] = {}
    for k, t in enumerate(targets):
        if t is not None:
            distinct.setdefault(digest(t.model_dump(mode="json")), (k, t))
    args = (maps, mesh, acoustic_maps, config, str(solutions), accept_nearest, budget,
            str(dynamic) if dynamic is not None and needs_dynamic(targets, cfg) else None)
    if jobs > 1 and len(distinct) > 1:
        from joblib import Parallel, delayed

        answers = Parallel(n_jobs=min(jobs, len(distinct)))(delayed(_solve_alone)(k, t, *args)
                                                              for k, t in distinct.values())
        failed = [a for a in answers if isinstance(a, ArticError)]
        if failed:  # the earliest segment's problem, whichever process finished first
            raise failed[0]
    else:
        answers = _solve_together(list(distinct.values()), *args)
    done: dict[str, tuple] = {}
    for key, (forces_k, note, path, messages) in zip(distinct, answers):
        done[key] = (forces_k, note, path)
        for m in messages:
            if say:
                say(m)
    labels, forces, lips, ports, notes, files = [], [], [], [], [], []
    for k, (s, t) in enumerate(zip(u.segments, targets)):
        if t is None:
            labels.append(s.label or "forces")
            forces.append(dict(s.forces_n))
            lips.append(default_lips)
            ports.append(float(vt.velum_port_cm2))
            notes.append("forces given")
            files.append("")
            continue
        f, note, path = done[digest(t.model_dump(mode="json"))]
        labels.append(s.label or t.name)
        forces.append(f)
        lips.append(t.lip_tube(default_lips) if t.acoustic is not None else default_lips)
        ports.append(float(vt.velum_port_cm2 if t.velum_port_cm2 is None else t.velum_port_cm2))
        notes.append(note)
        files.append(str(path))
    starts = np.array(u.starts_ms()) / 1e3
    return Plan(labels=labels, starts_s=starts, durations_s=np.array([s.duration_ms for s in u.segments]) / 1e3,
                forces_n=forces, lips=lips, ports=ports, voiced=np.array([s.voiced for s in u.segments]),
                notes=notes, solutions=files)


def needs_dynamic(targets: list[TargetSpec | None], cfg: Config) -> bool:
    """Whether a spatial target sits at a jaw position the config's maps hold no nets for (the dynamic map then
    carries the typical map there)."""
    netted = [canonical(cfg.epmap.jaw_positions[n]) for n in cfg.epmap.net_jaw_positions
              if n in cfg.epmap.jaw_positions]
    return any(t is not None and t.acoustic is None and
               (t.jaw.forces_n is None or canonical(dict(t.jaw.forces_n)) not in netted) for t in targets)


def _solve_together(items: list[tuple[int, TargetSpec]], maps, mesh, acoustic_maps, config, folder: str,
                    accept_nearest: bool, budget: int, dynamic: str | None = None) -> list[tuple]:
    """Solve targets in this process, the maps and simulators loaded once: (forces, how, path, messages) each."""
    if not items:
        return []
    ctx = solve_stage.load_context(maps, dynamic, mesh)
    sim = voicer = None
    if any(t.acoustic is not None for _, t in items):
        solve_stage.add_formants(ctx, maps, mesh, config, acoustic_maps)
        voicer = solve_stage.simulator(mesh, config, voiced=True)
    if any(t.acoustic is None for _, t in items):
        sim = voicer.sim if voicer is not None else solve_stage.simulator(mesh, config)
    mesh_sha = (voicer.sim if voicer is not None else sim).mesh_sha256
    out = []
    for k, t in items:
        messages: list[str] = []
        out.append((*_solve(t, k, ctx, sim, voicer, config, Path(folder), mesh_sha, accept_nearest, budget,
                            messages.append), messages))
    return out


def _solve_alone(k: int, t: TargetSpec, *args) -> tuple | ArticError:
    """One target in a worker process; its error is returned (the parent raises the first segment's)."""
    try:
        return _solve_together([(k, t)], *args)[0]
    except ArticError as err:
        return err


def _solve(t: TargetSpec, k: int, ctx, sim, voicer, config, folder: Path, mesh_sha: str, accept_nearest: bool,
           budget: int, say) -> tuple[dict, str, Path]:
    runner = voicer if t.acoustic is not None else sim
    out = folder / f"{t.name}-{digest(t.model_dump(mode='json'))[:8]}.yaml"
    try:
        doc, path, fresh = solve_stage.solve_target(t, ctx, out, runner, False, True, budget, config, mesh_sha)
    except UnreachableTarget as err:
        if not accept_nearest:
            raise UnreachableTarget(f"segment {k}: {err}; give --accept-nearest to speak the nearest reachable "
                                    "answer") from None
        wider = _nearer(t, err)
        if wider is None:  # an acoustic target: the written answer holds the nearest force set
            from .solve import read as read_solution

            doc, path = read_solution(out), out
        else:
            doc, path, fresh = solve_stage.solve_target(wider, ctx, folder / f"{wider.name}-"
                                                        f"{digest(wider.model_dump(mode='json'))[:8]}.yaml",
                                                        runner, False, True, budget, config, mesh_sha)
        forces, _, which = solution_forces(doc)
        if say:
            say(f"segment {k} ({t.name}): unreachable, speaking the nearest answer ({which})")
        return forces, "unreachable: nearest answer", path
    forces, reached, which = solution_forces(doc)
    if not reached:
        if not accept_nearest:
            raise UnreachableTarget(f"segment {k}: target '{t.name}' not reached by the refinement (see {path}); "
                                    "give --accept-nearest to speak the best answer found")
        if say:
            say(f"segment {k} ({t.name}): refinement did not reach the tolerance; speaking its best answer")
        return forces, "refined, not within tolerance", path
    return forces, "solved" + (", refined" if which == "refined" else ""), path


# --- the run: forces -> movement -> tract -> sound -------------------------------------------------------

def equilibria(model, rest, vectors: np.ndarray, hold_s: float, dt_s: float) -> np.ndarray:
    """(K, 3, 3) tip, dorsum and jaw (cm) after holding each segment's forces ``hold_s`` from the rest posture
    with the jaw free: where its static forces take the articulators (NaN when ``hold_s`` is 0)."""
    out = np.full((len(vectors), 3, 3), np.nan)
    if hold_s <= 0:
        return out
    pts = model.control_points()
    zero = np.zeros((model.n_nodes, 3))
    seen: dict[bytes, np.ndarray] = {}
    for k, v in enumerate(vectors):
        key = np.round(v, 6).tobytes()
        if key not in seen:
            _, end = run(model, rest, lambda t, v=v: Control(node_force=zero, muscle_force=v), hold_s, dt_s)
            seen[key] = np.array([end.x[pts[n]] for n in ("tip", "dorsum", "jaw")])
        out[k] = seen[key]
    return out


def ramp_weights(starts_s: np.ndarray, values: np.ndarray, ramp_s: float, t: np.ndarray) -> np.ndarray:
    """A per-segment value (K,) at times ``t``, moving to each segment's value over ``ramp_s`` from its start."""
    f = course(starts_s, np.asarray(values, float)[:, None], ramp_s, initial=np.asarray(values[:1], float))
    return np.array([f(float(x))[0] for x in t])


def compute(u: Utterance, p: Plan, cfg: Config, mesh, wall, progress=None, model=None) -> Spoken:
    """Simulate the plan's force course from the rest posture and voice it (``model``: the articulator of
    ``mesh``, ``wall`` and ``cfg``, if already built)."""
    view = STAGE.view(cfg)
    sp = view.speech
    model = sim_stage.build(cfg, mesh, wall) if model is None else model
    names = list(model.drivable())
    for k, f in enumerate(p.forces_n):
        bad = [m for m in f if m not in names]
        if bad:
            raise ArticError(f"segment {k}: muscle '{bad[0]}' is unknown; valid: {', '.join(names)}")
    tongue, most = set(TONGUE_MUSCLES), view.muscles.max_force_n
    vectors = np.array([muscle_force_vector(model, {m: min(v * seg.press, max(v, most)) if m in tongue else v
                                                    for m, v in f.items()})
                        for f, seg in zip(p.forces_n, u.segments)])  # a press stops at the muscles' largest force
    ramp_s = units.ms_to_s(sp.ramp_ms if u.ramp_ms is None else u.ramp_ms)
    how = sp.force_course if u.force_course is None else u.force_course
    # every segment's forces switch on its lead before its sound (the utterance's or the config's, or its own);
    # the first one's ``prep`` (>= its lead) before it, during a silent lead-in that the record leaves out (a
    # speaker sets the articulators before voicing): the course's clock starts ``prep`` before the sound
    lead = units.ms_to_s(sp.lead_ms if u.lead_ms is None else u.lead_ms)
    leads = units.ms_to_s(np.array(u.leads_ms(sp.lead_ms)))
    prep = max(leads[0], units.ms_to_s(sp.prepare_ms if u.prepare_ms is None else u.prepare_ms))
    duration = float(p.starts_s[-1] + p.durations_s[-1])
    starts = np.asarray(p.starts_s, float) - leads + prep
    starts[0] = 0.0
    for k in range(1, len(starts)):
        if starts[k] <= starts[k - 1]:
            raise ArticError(f"segments[{k}]: its forces would switch on {units.s_to_ms(leads[k]):g} ms before its "
                             f"sound, not after segment {k - 1}'s; shorten its lead_ms or lengthen segment {k - 1}")
    durations = np.diff(np.r_[starts, duration + prep])  # how long each segment's forces act
    sets = vectors
    if how == "pulse_step":
        for k, pair in enumerate(sp.pulse_antagonists):
            bad = [m for m in pair if m not in names]
            if bad:
                raise ArticError(f"speech.pulse_antagonists[{k}]: '{bad[0]}' is not a muscle or group; valid: "
                                 f"{', '.join(names)}")
        pairs = [(muscle_shares(model, a), muscle_shares(model, b)) for a, b in sp.pulse_antagonists]
        starts, sets = pulse_step(starts, durations, vectors, units.ms_to_s(sp.pulse_ms), sp.pulse_gain,
                                  units.newton_to_dyn(view.muscles.max_force_n), pairs)
    force_at = course(starts, sets, ramp_s)
    if sp.activation_rise_ms > 0 or sp.activation_fall_ms > 0:
        force_at = activated(force_at, duration + prep, units.ms_to_s(sp.activation_rise_ms),
                             units.ms_to_s(sp.activation_fall_ms))
    zero = np.zeros((model.n_nodes, 3))
    clock = [time.perf_counter()]
    timings: dict[str, float] = {}

    def lap(name: str) -> None:
        now = time.perf_counter()
        timings[name] = now - clock[0]
        clock[0] = now

    rest = settle(model)
    lap("rest posture")
    dt = units.ms_to_s(view.simulation.dt_ms)
    eps = equilibria(model, rest, vectors, units.ms_to_s(sp.reach_hold_ms), dt)
    lap("segment EPs")
    start = rest
    if prep > 0:  # the lead-in: the first segment's forces act before the sound starts
        _, start = run(model, rest, lambda t: Control(node_force=zero, muscle_force=force_at(t)), prep, dt)
        start = replace(start, t=0.0)
        lap("lead-in")
    every = max(1, int(round(units.ms_to_s(sp.frame_ms) / dt)))
    traj, _ = run(model, start, lambda t: Control(node_force=zero, muscle_force=force_at(t + prep)), duration, dt,
                  record_every=every, progress=progress, keep_partial=True)
    lap("simulation")
    beyond = 0.0
    if model.contact is not None:  # how far any contact node got beyond the wall (cm)
        from ..mechanics.contact import farthest_beyond_wall

        beyond = max(0.0, farthest_beyond_wall(model.contact, traj.x))
    bad = sim_stage.problems(traj, model.volume_constraint)
    if bad:
        raise NotPhysical(f"utterance '{u.name}': the simulation is not physical ({'; '.join(bad)}); nothing written")
    # the tract, frame by frame
    vtc = vt_stage.speaker_tract(cfg)
    shapes = vt_stage.shapes_of(traj.x, traj.time, mesh, model.rest, np.asarray(model.node_sets["mandible"]))
    lip_ramp = sp.lip_ramp_ms
    entries = [TractEntry(at_ms=float(s * 1e3), ramp_ms=lip_ramp if k else 0.0, lip_area_cm2=a, lip_length_cm=l,
                          velum_port_cm2=port)
               for k, (s, (a, l), port) in enumerate(zip(p.starts_s, p.lips, p.ports))]
    controls = vt_stage.controls_for(vtc, traj.time, entries + list(u.tract))
    tracts = vt_stage.compute(vtc, cfg.speaker.wall, shapes, controls)
    lap("tract")
    # formant tracks on a coarser grid of frames (the last one always), linear between
    stride = max(1, int(round(sp.formant_frame_ms / sp.frame_ms)))
    picked = np.unique(np.r_[np.arange(0, tracts.n_frames, stride), tracts.n_frames - 1])
    tubes = [Tube(tracts.af.length_cm[k], tracts.af.area_cm2[k]) for k in picked]
    ac = ac_stage.compute(tubes, cfg, velum_area_cm2=controls["velum_port_cm2"][picked],
                          port_from_glottis_cm=ac_stage.port_positions(tracts)[picked])
    formants_hz = np.stack([np.interp(traj.time, traj.time[picked], ac.formants_hz[:, j])
                            for j in range(ac.formants_hz.shape[1])], axis=1)
    formants_hz[tracts.af.area_cm2.min(axis=1) <= 0] = np.nan  # a closed tract has none
    lap("formant tracks")
    # the glottis and the air: voiced segments adduct it, voiceless ones open it
    voiced = p.voiced.astype(float)
    v_ramp = units.ms_to_s(sp.voicing_ramp_ms)
    voicing = ramp_weights(p.starts_s, voiced, v_ramp, traj.time)
    glottis = sp.glottal_area_voiceless_cm2 + (sp.glottal_area_voiced_cm2 - sp.glottal_area_voiceless_cm2) * voicing
    aco = view.acoustics
    tb = turbulence(tracts.af.length_cm, tracts.af.area_cm2, glottis, units.kpa_to_cgs(sp.lung_pressure_kpa),
                    aco.air_density_g_cm3, aco.air_viscosity_dyn_s_cm2, sp.noise.critical_reynolds, sp.noise.gain)
    noise = None
    if sp.noise.enabled:
        noise = (tb.noise_rms_dyn_cm2, tb.at_cm / tracts.af.length_cm.sum(axis=1), sp.noise.seed)
    amplitude = list(zip(traj.time.tolist(), voicing.tolist()))
    audio = syn_stage.compute_frames(tracts.af.length_cm, tracts.af.area_cm2, traj.time, cfg, duration,
                                     contour=[(float(a), float(b)) for a, b in u.f0_hz] if len(u.f0_hz) > 1 else None,
                                     f0_hz=float(u.f0_hz[0][1]), amplitude=amplitude,
                                     flow_peak_cm3_s=sp.glottal_flow_peak_cm3_s, noise=noise)
    lap("sound")
    cps = {name: traj.x[:, idx] for name, idx in model.control_points().items()}
    commanded = np.array([force_at(float(t) + prep) for t in traj.time])
    return Spoken(utterance=u, plan=p, trajectory=traj, tracts=tracts, formants_hz=formants_hz, noise=tb,
                  glottis_cm2=glottis, audio=audio, control_points=cps, muscle_names=list(model.muscle_names),
                  muscle_force_n=units.dyn_to_newton(commanded), timings_s=timings, segment_eps_cm=eps,
                  beyond_wall_cm=beyond,
                  force_course=how, ramp_ms=units.s_to_ms(ramp_s),
                  activation_ms=(sp.activation_rise_ms, sp.activation_fall_ms), lead_ms=units.s_to_ms(lead),
                  prepare_ms=units.s_to_ms(prep), segment_lead_ms=units.s_to_ms(leads),
                  press=np.array([seg.press for seg in u.segments]))


# --- files ---------------------------------------------------------------------------------------------

def textgrid_path(wav: Path | str) -> Path:
    return Path(wav).with_suffix(".TextGrid")


def h5_path(wav: Path | str) -> Path:
    return Path(wav).with_suffix(".h5")


def write_textgrid(path: Path | str, p: Plan) -> Path:
    """One interval tier 'segments' (Praat reads it directly)."""
    from praatio import textgrid

    edges = [round(float(v), 9) for v in (*p.starts_s, p.starts_s[-1] + p.durations_s[-1])]
    tier = textgrid.IntervalTier("segments", [(a, b, lab) for a, b, lab in zip(edges[:-1], edges[1:], p.labels)],
                                 0.0, edges[-1])
    tg = textgrid.Textgrid()
    tg.addTier(tier)
    with atomic_path(path, ".TextGrid") as tmp:
        tg.save(str(tmp), format="long_textgrid", includeBlankSpaces=True)
    return Path(path)


def write(wav: Path | str, s: Spoken, prov=None) -> dict[str, Path]:
    """The WAV, the TextGrid, then the HDF5 record (last: it is what says the three are up to date)."""
    syn_stage.write(wav, s.audio)
    tg = write_textgrid(textgrid_path(wav), s.plan)
    h5 = h5_path(wav)
    p, tr = s.plan, s.tracts
    with atomic_h5(h5, "utterance", prov) as f:
        f.attrs.update({"name": s.utterance.name, "duration_s": float(p.starts_s[-1] + p.durations_s[-1]),
                        "wav": Path(wav).name, "textgrid": tg.name,
                        "max_abs_volume_change": float(np.nanmax(np.abs(s.trajectory.volume_change))),
                        "inverted_bricks_max": int(s.trajectory.inverted.max()),
                        "max_beyond_wall_cm": float(s.beyond_wall_cm)})
        g = f.create_group("segments")
        g.create_dataset("label", data=np.array(p.labels, dtype="S"))
        g.create_dataset("start", data=p.starts_s).attrs["units"] = "s"
        g.create_dataset("duration", data=p.durations_s).attrs["units"] = "s"
        g.create_dataset("voiced", data=p.voiced)
        g.create_dataset("how", data=np.array(p.notes, dtype="S"))
        g.create_dataset("solution", data=np.array(p.solutions, dtype="S"))
        g.create_dataset("ep", data=s.segment_eps_cm).attrs["units"] = ("cm: tip, dorsum, jaw where each segment's "
                                                                        "forces lead (held from rest, jaw free)")
        g.attrs["force_course"] = s.force_course
        g.attrs["ramp_ms"] = s.ramp_ms
        g.attrs["activation_ms"] = np.asarray(s.activation_ms, float)
        g.attrs["lead_ms"] = s.lead_ms
        g.attrs["prepare_ms"] = s.prepare_ms
        g.create_dataset("lead", data=s.segment_lead_ms).attrs["units"] = ("ms: each segment's forces switch on this "
                                                                          "long before its sound")
        g.create_dataset("press", data=s.press).attrs["units"] = "factor on the solved target's tongue-muscle forces"
        g.create_dataset("lip_area", data=np.array([a for a, _ in p.lips])).attrs["units"] = "cm^2"
        g.create_dataset("lip_length", data=np.array([b for _, b in p.lips])).attrs["units"] = "cm"
        names = sorted({m for f_ in p.forces_n for m in f_})
        g.attrs["force_names"] = names
        g.create_dataset("forces", data=np.array([[f_.get(m, 0.0) for m in names] for f_ in p.forces_n])
                         ).attrs["units"] = "N (rows: segments; columns: force_names)"
        f.create_dataset("time", data=s.trajectory.time).attrs["units"] = "s"
        for name, xyz in s.control_points.items():
            f.create_dataset(f"control_points/{name}", data=xyz).attrs["units"] = "cm"
        m = f.create_group("muscles")
        m.attrs["names"] = s.muscle_names
        m.create_dataset("commanded", data=s.muscle_force_n, compression="gzip").attrs["units"] = "N"
        m.create_dataset("tension", data=units.dyn_to_newton(s.trajectory.muscle_force), compression="gzip"
                         ).attrs["units"] = "N"
        a = f.create_group("area_function")
        a.create_dataset("length", data=tr.af.length_cm, compression="gzip").attrs["units"] = "cm"
        a.create_dataset("area", data=tr.af.area_cm2, compression="gzip").attrs["units"] = "cm^2"
        a.attrs["order"] = "glottis to lips, the lip tube last"
        for k_, v in tr.controls.items():
            f.create_dataset(f"tract_controls/{k_}", data=v)
        f.create_dataset("formants", data=s.formants_hz).attrs["units"] = "Hz (NaN: none; a closed tract)"
        n = f.create_group("aerodynamics")
        n.create_dataset("glottis", data=s.glottis_cm2).attrs["units"] = "cm^2"
        n.create_dataset("flow", data=s.noise.flow_cm3_s).attrs["units"] = "cm^3/s"
        n.create_dataset("reynolds", data=s.noise.reynolds)
        n.create_dataset("noise_rms", data=s.noise.noise_rms_dyn_cm2).attrs["units"] = "dyn/cm^2"
        n.create_dataset("constriction", data=s.noise.constriction_cm2).attrs["units"] = "cm^2"
        n.create_dataset("noise_at", data=s.noise.at_cm).attrs["units"] = "cm from the glottis"
        f.create_dataset("volume_change", data=s.trajectory.volume_change).attrs["units"] = "fraction"
        f.create_dataset("inverted_bricks", data=s.trajectory.inverted)
        if s.trajectory.contact_count is not None:
            f.create_dataset("contact_count", data=s.trajectory.contact_count)
        f.create_dataset("positions", data=s.trajectory.x.astype(np.float32), compression="gzip"
                         ).attrs["units"] = "cm (every node, every frame)"
    return {"wav": Path(wav), "textgrid": tg, "h5": h5}


@dataclass
class Record:
    """An utterance file read back (what plots and checks need)."""

    attrs: dict
    labels: list[str]
    starts_s: np.ndarray
    durations_s: np.ndarray
    voiced: np.ndarray
    how: list[str]
    time_s: np.ndarray
    control_points: dict[str, np.ndarray]
    formants_hz: np.ndarray
    area_cm2: np.ndarray
    length_cm: np.ndarray
    noise_rms: np.ndarray
    positions_cm: np.ndarray
    volume_change: np.ndarray
    eps_cm: np.ndarray  # (K, 3, 3)
    commanded_n: np.ndarray  # (F, M)
    force_course: str
    ramp_ms: float
    activation_ms: tuple[float, float]
    lead_ms: float = 0.0
    prepare_ms: float = 0.0
    leads_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's own lead
    press: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's tongue-force factor


def read(path: Path | str) -> Record:
    with open_artifact(path, "utterance", STAGE.hint) as f:
        try:
            g = f["segments"]
            dec = lambda a: [v.decode() if isinstance(v, bytes) else str(v) for v in a]  # noqa: E731
            return Record(attrs=dict(f.attrs), labels=dec(g["label"][()]), starts_s=g["start"][()],
                          durations_s=g["duration"][()], voiced=g["voiced"][()], how=dec(g["how"][()]),
                          time_s=f["time"][()], control_points={k: v[()] for k, v in f["control_points"].items()},
                          formants_hz=f["formants"][()], area_cm2=f["area_function/area"][()],
                          length_cm=f["area_function/length"][()], noise_rms=f["aerodynamics/noise_rms"][()],
                          positions_cm=f["positions"][()], volume_change=f["volume_change"][()],
                          eps_cm=g["ep"][()], commanded_n=f["muscles/commanded"][()],
                          force_course=str(g.attrs.get("force_course", "static")),
                          ramp_ms=float(g.attrs.get("ramp_ms", 30.0)),
                          activation_ms=tuple(float(v) for v in g.attrs.get("activation_ms", (0.0, 0.0))),
                          lead_ms=float(g.attrs.get("lead_ms", 0.0)),
                          prepare_ms=float(g.attrs.get("prepare_ms", g.attrs.get("lead_ms", 0.0))),
                          # records from before segments had their own lead and press: the utterance's, none
                          leads_ms=g["lead"][()] if "lead" in g else np.full(len(g["label"]),
                                                                             float(g.attrs.get("lead_ms", 0.0))),
                          press=g["press"][()] if "press" in g else np.ones(len(g["label"])))
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {STAGE.hint}") from None


# --- the file-level entry ------------------------------------------------------------------------------

@dataclass
class SpeakResult:
    paths: dict[str, Path]
    spoken: Spoken | None  # None when the files were up to date
    up_to_date: bool = False


def _check_out(out: Path | str) -> Path:
    out = Path(out)
    if out.suffix.lower() != ".wav":
        raise ArticError(f"--out {out}: give a .wav file name")
    return out


def speak(utterance: Path | str, out: Path | str | None = None, maps: Path | str = "data/epmaps.h5",
          mesh: Path | str = "data/mesh.h5", acoustic_maps: Path | str | None = "data/acoustic_maps.h5",
          config: Path | str | None = None, solutions: Path | str | None = None, accept_nearest: bool = False,
          budget: int = 8, progress=None, say: Callable[[str], None] | None = None, jobs: int = 1,
          dynamic: Path | str | None = "data/dynamic.h5") -> SpeakResult:
    """Speak an utterance file: WAV, TextGrid and HDF5 (``out``: the WAV; default data/utterances/NAME.wav).
    A record that already holds this recipe (the utterance, its targets' solutions, mesh, config, code) is
    left alone.  ``dynamic``: the dynamic map, for targets at jaw positions the maps hold no nets for (read
    only for such a target)."""
    u = load_utterance(utterance)
    cfg = load_config(config)
    out = _check_out(out if out is not None else Path("data/utterances") / f"{u.name}.wav")
    m = mesh_stage.read(mesh, cfg)
    folder = Path(solutions) if solutions is not None else out.parent / "solutions"
    targets = _targets(u, utterance, cfg.muscles.max_force_n)
    # the recipe: what the targets are solved on and with, so an unchanged utterance is known without solving
    inputs = {"mesh": m.content_sha256, "utterance": digest(u.model_dump(mode="json")),
              "targets": [None if t is None else digest(t.model_dump(mode="json")) for t in targets]}
    if any(t is not None for t in targets):
        inputs["epmaps"] = stored_content_hash(maps) or ""
        if dynamic is not None and needs_dynamic(targets, cfg):
            inputs["dynamic"] = stored_content_hash(dynamic) or ""
        if any(t is not None and t.acoustic is not None for t in targets):
            inputs["acoustic_maps"] = (stored_content_hash(acoustic_maps) or "") if acoustic_maps is not None else ""
    prov = STAGE.provenance(cfg, inputs=inputs, params={"accept_nearest": accept_nearest, "budget": budget})
    paths = {"wav": out, "textgrid": textgrid_path(out), "h5": h5_path(out)}
    if up_to_date(paths["h5"], prov) and paths["wav"].is_file() and paths["textgrid"].is_file():
        return SpeakResult(paths, None, up_to_date=True)
    model = sim_stage.build(cfg, m.mesh, m.wall)
    check_forces(u, list(model.drivable()), str(utterance))
    p = plan(u, cfg, utterance, maps, mesh, acoustic_maps, config, folder, accept_nearest, budget, say, targets, jobs,
             dynamic)
    s = compute(u, p, cfg, m.mesh, m.wall, progress, model)
    return SpeakResult(write(out, s, prov), s)


# --- what an utterance did, measured ---------------------------------------------------------------------

def measures(rec: Record, samples: np.ndarray, rate_hz: int) -> dict:
    """Per segment: median F1/F2 of our tracks over its middle half, its level (dB) overall and above 3 kHz,
    and for tip, dorsum and jaw how far they still are from the segment's EP at its end (cm), the fraction of
    the way covered, and the time to cover 90 % of it (ms); the closures (frames with a zero area) and their
    level; peak speeds of the control points (cm/s); the commanded force's impulse (N s) and peak (N)."""
    from ..acoustics.measures import band_level_db, runs

    t = rec.time_s
    segs = []
    for lab, s0, d in zip(rec.labels, rec.starts_s, rec.durations_s):
        mid = (t >= s0 + 0.25 * d) & (t <= s0 + 0.75 * d)
        fm = rec.formants_hz[mid]
        med = [float(np.nanmedian(fm[:, k])) if np.isfinite(fm[:, k]).any() else float("nan") for k in (0, 1)]
        segs.append({"label": lab, "start_s": float(s0), "duration_s": float(d), "f1_hz": med[0], "f2_hz": med[1],
                     "level_db": band_level_db(samples, rate_hz, s0 + 0.25 * d, s0 + 0.75 * d),
                     "level_above_3khz_db": band_level_db(samples, rate_hz, s0 + 0.25 * d, s0 + 0.75 * d, 3000.0)})
    closed = rec.area_cm2.min(axis=1) <= 0.0
    closures = []
    for a, b in runs(closed):
        t0, t1 = float(t[a]), float(t[min(b, len(t) - 1)])
        closures.append({"start_s": t0, "end_s": t1, "duration_ms": 1e3 * (t1 - t0),
                         "level_db": band_level_db(samples, rate_hz, t0 + 0.005, max(t1 - 0.005, t0 + 0.01))})
    dt = np.diff(t)
    speeds = {name: float(np.max(np.linalg.norm(np.diff(xyz[:, :2], axis=0), axis=1) / dt)) if len(dt) else 0.0
              for name, xyz in rec.control_points.items()}
    cps = ("tip", "dorsum", "jaw")
    for k, seg in enumerate(segs):  # how far each control point still is from where the segment's forces lead
        end = min(np.searchsorted(t, seg["start_s"] + seg["duration_s"] - 1e-9), len(t) - 1)
        begin = np.searchsorted(t, seg["start_s"])
        for j, name in enumerate(cps):
            if name in rec.control_points and np.isfinite(rec.eps_cm[k, j]).all():
                ep = rec.eps_cm[k, j, :2]
                left = float(np.linalg.norm(rec.control_points[name][end, :2] - ep))
                away = float(np.linalg.norm(rec.control_points[name][begin, :2] - ep))
                seg[f"{name}_left_cm"] = left
                seg[f"{name}_reached"] = 1.0 - left / away if away > 1e-3 else 1.0
                # the time it takes to cover 90 % of the way (NaN: not within the segment)
                path = np.linalg.norm(rec.control_points[name][begin:end + 1, :2] - ep, axis=1)
                hit = np.flatnonzero(path <= 0.1 * away)
                seg[f"{name}_t90_ms"] = float(1e3 * (t[begin + hit[0]] - seg["start_s"])) if len(hit) else float("nan")
    total = rec.commanded_n.sum(axis=1)
    impulse = float(np.sum(0.5 * (total[1:] + total[:-1]) * dt)) if len(dt) else 0.0
    return {"segments": segs, "closures": closures, "peak_speed_cm_s": speeds, "force_impulse_n_s": impulse,
            "peak_total_force_n": float(total.max()) if len(total) else 0.0, "force_course": rec.force_course,
            "max_volume_change": float(np.nanmax(np.abs(rec.volume_change))),
            "min_constriction_cm2": float(rec.area_cm2.min())}
