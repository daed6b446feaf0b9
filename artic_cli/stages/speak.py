"""Stage ``utterances``: a sequence of targets in time -> muscle forces in time -> movement -> tract -> sound.

Each segment's target is solved once (``solve-target --refine``; cached by content under the solutions folder,
:func:`artic_cli.stages.solve_runs.solve_batch`); :mod:`artic_cli.speech` plans and speaks it.  Outputs: the WAV, a
Praat TextGrid (one interval per segment) and ``NAME.h5`` (forces, control points, area functions, formant
tracks, the noise source), each written atomically; the HDF5 file is the stage's freshness record and is
written last.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from .. import units
from ..config import DEFAULT_CONFIG, Config, load_config
from ..errors import ArticError
from ..io.result_cache import ResultCache
from ..io.fingerprint import code_hash, digest, sections_hash
from ..io.store import atomic_h5, open_artifact, stored_content_hash
from ..io.wav import write_wav
from ..mechanics.model import ARTICULATOR_SECTIONS, Model, State
from ..mechanics.simulate import settle
from ..speech.plan import Plan, needs_dynamic, plan, segment_targets, settle_answers
from ..speech.record import Record
from ..speech.speak import Spoken, speak_plan
from ..speech.textgrid import write_textgrid
from ..speech.inventory import DEFAULT as DEFAULT_INVENTORY
from ..speech.inventory import load_inventory
from ..speech.phones import realise, vowel_tongues
from ..speech.timing import Timing, timed, with_leads
from ..speech.utterance import Utterance, check_forces, load_utterance
from ..tract.places import section_places
from ..tract.speaker import speaker_tract
from . import mesh as mesh_stage
from . import loaded, paths
from . import simulate as sim_stage
from . import solve_runs
from .base import Stage, up_to_date

CACHE = "cache"  # beside the solutions: the articulator, its rest posture, where held force sets lead, timings
STAGE = Stage(name="utterances", module=__name__,
              sections=(*ARTICULATOR_SECTIONS, "epmap", "solver", "vocal_tract", "acoustics", "speech"),
              reads=("mesh", "epmaps", "acousticmaps"), kind="utterance", hint="rerun 'artic speak UTTERANCE.yaml'")


def compute(u: Utterance, p: Plan, cfg: Config, mesh, wall, progress=None, model=None, rest=None, known=None
            ) -> Spoken:
    """Simulate the plan's force course from the rest posture and voice it (``model``: the articulator of
    ``mesh``, ``wall`` and ``cfg``, if already built; ``rest``: its rest posture, if settled; ``known``: a cache
    of where force sets lead, :class:`ResultCache`)."""
    model = sim_stage.build(cfg, mesh, wall) if model is None else model
    return speak_plan(u, p, STAGE.view(cfg), model, progress, rest, known=known)


# --- files ---------------------------------------------------------------------------------------------

def textgrid_path(wav: Path | str) -> Path:
    return Path(wav).with_suffix(".TextGrid")


def h5_path(wav: Path | str) -> Path:
    return Path(wav).with_suffix(".h5")


AIR_UNITS = {"oral_pressure": "dyn/cm^2 (the cavity behind the narrowest place)", "glottal_flow": "cm^3/s",
             "nasal_flow": "cm^3/s", "voice_gain": "0-1 (the voice's amplitude)",
             "aspiration_rms": "dyn/cm^2 (the glottis's noise source)", "nose_cm2": "cm^2 (the nose's outlet)"}


def write(wav: Path | str, s: Spoken, prov=None) -> dict[str, Path]:
    """The WAV, the TextGrid, then the HDF5 record (last: it is what says the three are up to date)."""
    write_wav(wav, s.audio)
    tg = write_textgrid(textgrid_path(wav), s.plan, s.utterance.tiers)
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
        # the answers' file names in the solutions folder (not its path: the same utterance is the same record
        # wherever it is spoken)
        g.create_dataset("solution", data=np.array([Path(f_).name for f_ in p.solutions], dtype="S"))
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
        g.create_dataset("drive", data=s.drive).attrs["units"] = ("factor on the pulse that opens the segment's "
                                                                  "forces (speech.pulse_gain x this)")
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
        for name, unit in AIR_UNITS.items():
            if name in s.air:
                n.create_dataset(name, data=s.air[name]).attrs["units"] = unit
        f.create_dataset("volume_change", data=s.trajectory.volume_change).attrs["units"] = "fraction"
        f.create_dataset("inverted_bricks", data=s.trajectory.inverted)
        if s.trajectory.contact_count is not None:
            f.create_dataset("contact_count", data=s.trajectory.contact_count)
        f.create_dataset("positions", data=s.trajectory.x.astype(np.float32), compression="gzip"
                         ).attrs["units"] = "cm (every node, every frame)"
    return {"wav": Path(wav), "textgrid": tg, "h5": h5}


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
                          press=g["press"][()] if "press" in g else np.ones(len(g["label"])),
                          drive=g["drive"][()] if "drive" in g else np.ones(len(g["label"])))
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


def read_utterance(path: Path | str, inventory: Path | str | None = None) -> Utterance:
    """An utterance file: segments, or text (``text:``, spoken through the inventory's front end)."""
    from ..config import read_yaml
    from ..speech.text import text_utterance

    data = read_yaml(path, "utterance file")
    if isinstance(data, dict) and "text" in data:
        return text_utterance(data, str(path), load_inventory(inventory or DEFAULT_INVENTORY))
    return load_utterance(path)


def with_phonemes(u: Utterance, cfg: Config, inventory: Path | str | None = None, solve=None) -> Utterance:
    """The utterance with its phoneme segments made targets and controls (the inventory read only if it has
    any; its places checked against the config's tract); ``solve`` (targets -> answers) places a glide's tongue
    like its vowel's, as that vowel's target solves."""
    if not any(s.phoneme is not None for s in u.segments):
        return u
    inv = load_inventory(inventory or DEFAULT_INVENTORY)
    vt = speaker_tract(cfg)
    inv.check_places(section_places(vt)[1], str(inventory or DEFAULT_INVENTORY))
    return realise(u, inv, (float(vt.lips.area_cm2), float(vt.lips.length_cm)),
                   None if solve is None else vowel_tongues(inv, solve, cfg.muscles.max_force_n))


def speak(utterance: Path | str | Utterance, out: Path | str | None = None, maps: Path | str = paths.EPMAPS,
          mesh: Path | str = paths.MESH, acoustic_maps: Path | str | None = paths.ACOUSTIC_MAPS,
          config: Path | str | None = None, solutions: Path | str | None = None, accept_nearest: bool = False,
          budget: int = 8, progress=None, say: Callable[[str], None] | None = None, jobs: int = 1,
          dynamic: Path | str | None = paths.DYNAMIC, inventory: Path | str | None = None) -> SpeakResult:
    """Speak an utterance (a file, or one made in Python, e.g. from text by
    :func:`artic_cli.speech.text.utterance_of_text`): WAV, TextGrid and HDF5 (``out``: the WAV; default
    data/utterances/NAME.wav).  Phoneme segments are made from ``inventory`` (default
    configs/phonemes/japanese.yaml).  A record that already holds this recipe (the utterance, its targets'
    solutions, mesh, config, code) is left alone.  ``dynamic``: the dynamic map, for targets at jaw positions
    the maps hold no nets for (read only for such a target)."""
    source = None if isinstance(utterance, Utterance) else utterance
    u = utterance if source is None else read_utterance(source, inventory)
    cfg = load_config(config)
    out = _check_out(out if out is not None else paths.UTTERANCES / f"{u.name}.wav")
    folder = Path(solutions) if solutions is not None else out.parent / "solutions"
    solve_on = partial(solve_runs.solve_batch, maps=maps, mesh=mesh, acoustic_maps=acoustic_maps, config=config,
                       folder=folder, budget=budget, jobs=jobs)  # targets -> answers, the dynamic map given below
    u = with_phonemes(u, cfg, inventory, partial(solve_on, dynamic=None))
    m = mesh_stage.read(mesh, cfg)
    targets = segment_targets(u, source, cfg.muscles.max_force_n)
    # the recipe: what the targets are solved on and with, so an unchanged utterance is known without solving
    inputs = {"mesh": m.content_sha256, "utterance": digest(u.model_dump(mode="json")),
              "targets": [None if t is None else digest(t.model_dump(mode="json")) for t in targets]}
    if any(t is not None for t in targets):
        inputs["epmaps"] = stored_content_hash(maps) or ""
        if dynamic is not None and needs_dynamic(targets, cfg):
            inputs["dynamic"] = stored_content_hash(dynamic) or ""
        if any(t is not None and t.needs_tract for t in targets):
            inputs["acoustic_maps"] = (stored_content_hash(acoustic_maps) or "") if acoustic_maps is not None else ""
    prov = STAGE.provenance(cfg, inputs=inputs, params={"accept_nearest": accept_nearest, "budget": budget})
    files = {"wav": out, "textgrid": textgrid_path(out), "h5": h5_path(out)}
    if up_to_date(files["h5"], prov) and files["wav"].is_file() and files["textgrid"].is_file():
        return SpeakResult(files, None, up_to_date=True)
    scope = {"articulator": sim_stage.STAGE.provenance(cfg, inputs={"mesh": m.content_sha256}).recipe,
             "code": code_hash("artic_cli.speech.speak")}  # what the model, its rest posture and the EPs hang on
    caches = {kind: ResultCache(folder / CACHE, kind, scope) for kind in ("model", "rest", "ep", "timing")}
    model = loaded.once("articulator", lambda: articulator(cfg, m, caches["model"]), (mesh, config or DEFAULT_CONFIG))
    check_forces(u, list(model.drivable()), str(source or u.name))
    solve = partial(solve_on, dynamic=dynamic if dynamic is not None and needs_dynamic(targets, cfg) else None)
    view = STAGE.view(cfg)
    p = plan(u, view, targets, solve, accept_nearest, say)
    rest = rest_posture(model, caches["rest"])
    aim = partial(aim_answer, partial(solve, budget=AIM_BUDGET))
    u, timing = timed_once(u, p, view, model, rest, targets, caches["timing"], aim)
    if timing is not None and timing.plan is not None:
        p = timing.plan
    if timing is not None and say:
        how = f"{timing.rounds} round(s)" if timing.rounds else "as found before"
        say(f"timing: {how}; leads {', '.join(f'{v:.0f}' for v in timing.leads_ms)} ms; "
            f"presses {', '.join(f'{v:.2f}' for v in timing.press)}; "
            f"drives {', '.join(f'{v:.2f}' for v in timing.drive)}"
            + "".join(f"; segment {k} aimed at {a[0]:.0f} / {a[1]:.0f} Hz" for k, a in (timing.aims_hz or {}).items()))
    s = speak_plan(u, p, view, model, progress, rest, timing.trajectory if timing is not None else None,
                   caches["ep"])
    written = write(out, s, prov)
    for c in caches.values():  # kept only once the utterance is written
        c.commit()
    return SpeakResult(written, s)


def articulator(cfg: Config, m, cache: ResultCache):
    """The articulator of mesh file ``m`` (:func:`sim_stage.build`), kept in ``cache`` (scope: its recipe)."""
    model = cache.get_object("articulator")
    if model is None or not isinstance(model, Model):
        model = sim_stage.build(cfg, m.mesh, m.wall)
        cache.put_object("articulator", model)
    return model


AIM_BUDGET = 0  # simulations refining a vowel aimed in context: none, the rounds hear where it lands


def aim_answer(solve, t) -> tuple[dict[str, float], str, str]:
    """A vowel's target aimed in context (:mod:`artic_cli.speech.aims`) solved on the maps: (its forces, how they
    were found, its solution file); its nearest answer when out of reach."""
    forces, note, path = settle_answers([(0, t)], solve, True)[0]
    a = t.acoustic.formants_hz
    how = "the nearest answer" if note.startswith("unreachable") else "on the maps"
    return forces, f"aimed at {a[0]:.0f} / {a[1]:.0f} Hz in context ({how})", str(path)


def timed_once(u: Utterance, p: Plan, cfg: Config, model, rest, targets, cache: ResultCache, aim=None):
    """:func:`timed`, its leads, presses, drives and aimed vowels kept in ``cache`` by what they hang on (the
    utterance but its name and pitch, the plan, the config, the timing's code), so that the same utterance at
    another pitch or under another name is not timed again: (the utterance with its leads and presses, its
    timing, whose plan holds the forces its vowels aimed with; rounds 0 when found before)."""
    key = {"utterance": u.model_dump(mode="json", exclude={"name", "f0_hz"}), "forces": p.forces_n,
           "lips": p.lips, "ports": p.ports, "glottis": p.glottis_cm2, "voiced": p.voiced, "starts": p.starts_s,
           "durations": p.durations_s, "config": sections_hash(cfg, STAGE.sections),
           "code": code_hash("artic_cli.speech.timing")}
    hit = cache.get(key)
    n = (len(u.segments),)
    if hit is not None and hit.get("leads_ms", np.zeros(0)).shape == n == hit["press"].shape == hit.get(
            "drive", np.zeros(0)).shape:
        kept = json.loads(str(hit["plan"])) if "plan" in hit else {}
        aimed_plan = replace(p, **{k: kept[k] for k in ("forces_n", "notes", "solutions")}) if kept else None
        return with_leads(u, hit["leads_ms"], hit["press"], hit["drive"]), Timing(
            leads_ms=hit["leads_ms"].tolist(), press=hit["press"].tolist(), rounds=0, onset_late_ms={},
            released_early_ms={}, held_late_ms={}, drive=hit["drive"].tolist(), plan=aimed_plan,
            aims_hz={int(k): v for k, v in kept.get("aims_hz", {}).items()})
    out, timing = timed(u, p, cfg, model, rest, targets, aim=aim)
    if timing is not None:
        kept = {} if timing.plan is None else {"forces_n": timing.plan.forces_n, "notes": timing.plan.notes,
                                               "solutions": timing.plan.solutions, "aims_hz": timing.aims_hz}
        cache.put(key, {"leads_ms": np.asarray(timing.leads_ms, float), "press": np.asarray(timing.press, float),
                        "drive": np.asarray(timing.drive, float), "plan": np.array(json.dumps(kept))})
    return out, timing


def rest_posture(model, cache: ResultCache) -> State:
    """The model's rest posture (:func:`settle`), kept in ``cache`` (its scope: the model's recipe)."""
    hit = cache.get("rest posture")
    if hit is not None and hit.get("x", np.zeros(0)).shape == (model.n_nodes, 3):
        return State(t=0.0, x=hit["x"], v=np.zeros_like(hit["x"]), sigma2=hit.get("sigma2"),
                     fibre_strain=hit.get("fibre_strain"))
    rest = settle(model)
    cache.put("rest posture", {k: v for k, v in (("x", rest.x), ("sigma2", rest.sigma2),
                                                 ("fibre_strain", rest.fibre_strain)) if v is not None})
    return rest
