"""Speaking a plan: forces in time -> movement -> tract -> sound.

Each segment's forces switch on its lead before its sound with a raised-cosine ramp and hold until the next
segment's (:mod:`.course`); the whole course is simulated from the rest posture with contact; each recorded
frame gives an area function (lips and velum from the targets, then the utterance's own course) and formants;
the frames drive the time-domain synthesizer with the LF voice (off in voiceless segments) and a turbulence
noise source at the narrowest place (:mod:`artic_cli.acoustics.aerodynamics`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from .. import units
from ..acoustics.aerodynamics import Turbulence
from ..acoustics.analysis import analyse
from ..acoustics.tube import Tube
from ..acoustics.sources import Larynx, synthesize_speech
from ..acoustics.voice import Audio
from ..config import Config
from ..errors import ArticError, NotPhysical
from ..geometry.anatomy import TONGUE_MUSCLES
from ..mechanics.loads import muscle_force_vector, muscle_shares
from ..mechanics.model import Control, Model
from ..mechanics.resume import first_difference, resumed
from ..mechanics.simulate import Trajectory, problems, run, settle
from ..schedule import TractEntry, tract_controls
from ..tract.areas import Tracts, port_positions, tracts_of
from ..tract.controls import controls_for
from ..tract.shapes import shapes_of_model
from ..tract.speaker import speaker_tract
from .course import activated, course, pulse_step
from .expansion import expansion_entries
from .plan import Plan
from .utterance import Utterance


@dataclass
class Spoken:
    utterance: Utterance
    plan: Plan
    trajectory: Trajectory
    tracts: Tracts
    formants_hz: np.ndarray  # (F, n)
    noise: Turbulence
    glottis_cm2: np.ndarray
    audio: Audio
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
    drive: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's opening pulse's factor
    air: dict[str, np.ndarray] = field(default_factory=dict)  # per frame: the cavity's pressure, flows, voice gain


@dataclass
class Course:
    """The force course of a plan: the muscle forces (dyn) at any time of the course's clock, which starts
    ``prep_s`` before the sound."""

    force_at: Callable[[float], np.ndarray]
    vectors: np.ndarray  # (K, M) each segment's held forces, dyn
    how: str  # static or pulse_step
    ramp_s: float
    lead_s: float
    leads_s: np.ndarray  # (K,)
    prep_s: float
    duration_s: float  # of the sound


def equilibria(model: Model, rest, vectors: np.ndarray, hold_s: float, dt_s: float, known=None) -> np.ndarray:
    """(K, 3, 3) tip, dorsum and jaw (cm) after holding each segment's forces ``hold_s`` from the rest posture
    with the jaw free: where its static forces take the articulators (NaN when ``hold_s`` is 0).  ``known``: a
    cache of earlier answers for this model and rest posture (``get(key)``, ``put(key, arrays)``), if any."""
    out = np.full((len(vectors), 3, 3), np.nan)
    if hold_s <= 0:
        return out
    pts = model.control_points()
    zero = np.zeros((model.n_nodes, 3))
    seen: dict[bytes, np.ndarray] = {}
    for k, v in enumerate(vectors):
        rounded = np.round(v, 6)
        key = rounded.tobytes()
        if key not in seen:
            name = {"forces_dyn": rounded, "hold_s": hold_s, "dt_s": dt_s}
            hit = known.get(name) if known is not None else None
            if hit is not None and hit.get("ep_cm", np.zeros(0)).shape == (3, 3):
                seen[key] = hit["ep_cm"]
            else:
                _, end = run(model, rest, lambda t, v=v: Control(node_force=zero, muscle_force=v), hold_s, dt_s)
                seen[key] = np.array([end.x[pts[n]] for n in ("tip", "dorsum", "jaw")])
                if known is not None:
                    known.put(name, {"ep_cm": seen[key]})
        out[k] = seen[key]
    return out


def ramp_weights(starts_s: np.ndarray, values: np.ndarray, ramp_s: float, t: np.ndarray) -> np.ndarray:
    """A per-segment value (K,) at times ``t``, moving to each segment's value over ``ramp_s`` from its start."""
    f = course(starts_s, np.asarray(values, float)[:, None], ramp_s, initial=np.asarray(values[:1], float))
    return np.array([f(float(x))[0] for x in t])


def segment_vectors(u: Utterance, p: Plan, model: Model, max_force_n: float) -> np.ndarray:
    """(K, M) each segment's muscle forces (dyn), its tongue muscles and jaw closers (the ``JC`` group) pressed by
    the segment's ``press`` (a press stops at the muscles' largest force)."""
    names = list(model.drivable())
    for k, f in enumerate(p.forces_n):
        bad = [m for m in f if m not in names]
        if bad:
            raise ArticError(f"segment {k}: muscle '{bad[0]}' is unknown; valid: {', '.join(names)}")
    pressed = set(TONGUE_MUSCLES) | {"JC"}
    return np.array([muscle_force_vector(model, {m: min(v * seg.press, max(v, max_force_n)) if m in pressed else v
                                                 for m, v in f.items()})
                     for f, seg in zip(p.forces_n, u.segments)])


def default_leads_ms(u: Utterance, cfg: Config) -> tuple[float, float]:
    """The lead and the first segment's preparation (ms) a segment has unless it or its utterance gives one:
    the config's, or 0 and 0 with the static course (the paper's controller: each target's forces switched on at
    its segment's start and held)."""
    how = cfg.speech.force_course if u.force_course is None else u.force_course
    return (0.0, 0.0) if how == "static" else (cfg.speech.lead_ms, cfg.speech.prepare_ms)


def force_course(u: Utterance, p: Plan, model: Model, cfg: Config) -> Course:
    """The plan's forces in time: every segment's forces switch on its lead before its sound (the utterance's
    or the config's, or its own); the first one's ``prep`` (>= its lead) before it, during a silent lead-in
    that the record leaves out (a speaker sets the articulators before voicing)."""
    sp = cfg.speech
    vectors = segment_vectors(u, p, model, cfg.muscles.max_force_n)
    ramp_s = units.ms_to_s(sp.ramp_ms if u.ramp_ms is None else u.ramp_ms)
    how = sp.force_course if u.force_course is None else u.force_course
    lead_ms, prepare_ms = default_leads_ms(u, cfg)
    lead = units.ms_to_s(lead_ms if u.lead_ms is None else u.lead_ms)
    leads = units.ms_to_s(np.array(u.leads_ms(lead_ms)))
    prep = max(leads[0], units.ms_to_s(prepare_ms if u.prepare_ms is None else u.prepare_ms))
    duration = float(p.starts_s[-1] + p.durations_s[-1])
    starts = np.asarray(p.starts_s, float) - leads + prep
    starts[0] = 0.0
    for k in range(1, len(starts)):
        if starts[k] <= starts[k - 1]:
            raise ArticError(f"segments[{k}]: its forces would switch on {units.s_to_ms(leads[k]):g} ms before its "
                             f"sound, not after segment {k - 1}'s; shorten its lead_ms or lengthen segment {k - 1}")
    sets = vectors
    if how == "pulse_step":
        names = list(model.drivable())
        for k, pair in enumerate(sp.pulse_antagonists):
            bad = [m for m in pair if m not in names]
            if bad:
                raise ArticError(f"speech.pulse_antagonists[{k}]: '{bad[0]}' is not a muscle or group; valid: "
                                 f"{', '.join(names)}")
        pairs = [(muscle_shares(model, a), muscle_shares(model, b)) for a, b in sp.pulse_antagonists]
        durations = np.diff(np.r_[starts, duration + prep])  # how long each segment's forces act
        gains = sp.pulse_gain * np.array([seg.drive for seg in u.segments])
        starts, sets = pulse_step(starts, durations, vectors, units.ms_to_s(sp.pulse_ms), gains,
                                  units.newton_to_dyn(cfg.muscles.max_force_n), pairs)
    force_at = course(starts, sets, ramp_s)
    if sp.activation_rise_ms > 0 or sp.activation_fall_ms > 0:
        force_at = activated(force_at, duration + prep, units.ms_to_s(sp.activation_rise_ms),
                             units.ms_to_s(sp.activation_fall_ms))
    return Course(force_at=force_at, vectors=vectors, how=how, ramp_s=ramp_s, lead_s=lead, leads_s=leads,
                  prep_s=prep, duration_s=duration)


class Laps:
    """Wall time of each named part, one after another (s)."""

    def __init__(self):
        self.times: dict[str, float] = {}
        self.clock = time.perf_counter()

    def __call__(self, name: str) -> None:
        now = time.perf_counter()
        self.times[name] = now - self.clock
        self.clock = now


SNAPSHOT_FRAMES = 4  # a trajectory kept to resume from (timing's rounds) holds its state every so many frames


def course_trajectory(model: Model, c: Course, cfg: Config, rest, progress=None, lap=None, prior=None,
                      resumable: bool = False) -> Trajectory:
    """The course simulated from ``rest``: the lead-in, then the sound's frames (its clock at the sound's
    start).  ``resumable``: the trajectory keeps snapshots to resume from; ``prior``: (an earlier course, its
    resumable trajectory from the same ``rest``): the steps whose forces the two share are not simulated
    again (:mod:`..mechanics.resume`; the frames are the same)."""
    zero = np.zeros((model.n_nodes, 3))
    dt = units.ms_to_s(cfg.simulation.dt_ms)
    every = max(1, int(round(units.ms_to_s(cfg.speech.frame_ms) / dt)))
    lead_in = lambda f: (lambda t: Control(node_force=zero, muscle_force=f(t)))  # noqa: E731
    voiced = lambda f, prep: (lambda t: Control(node_force=zero, muscle_force=f(t + prep)))  # noqa: E731
    n_prep, n_sound = int(round(c.prep_s / dt)), max(1, int(round(c.duration_s / dt)))
    if prior is not None:
        old, traj = prior
        same_clock = (old.prep_s, old.duration_s) == (c.prep_s, c.duration_s) and 0 in traj.snapshots
        if same_clock and first_difference(lead_in(old.force_at), lead_in(c.force_at), 0.0, dt, n_prep) > n_prep:
            k = first_difference(voiced(old.force_at, old.prep_s), voiced(c.force_at, c.prep_s), 0.0, dt, n_sound)
            return resumed(model, traj, voiced(c.force_at, c.prep_s), c.duration_s, dt, every, k,
                           snapshots_every=every * SNAPSHOT_FRAMES, keep_partial=True)
    start = rest
    if c.prep_s > 0:  # the lead-in: the first segment's forces act before the sound starts
        _, start = run(model, rest, lead_in(c.force_at), c.prep_s, dt)
        start = replace(start, t=0.0)
        if lap is not None:
            lap("lead-in")
    traj, _ = run(model, start, voiced(c.force_at, c.prep_s), c.duration_s, dt, record_every=every,
                  progress=progress, keep_partial=True,
                  snapshots_every=every * SNAPSHOT_FRAMES if resumable else 0)
    return traj


def move(model: Model, c: Course, cfg: Config, lap: Laps, progress=None, rest=None, simulated=None, known=None
         ) -> tuple[Trajectory, np.ndarray, float]:
    """The course simulated from the rest posture (``rest``, settled here if not given; ``simulated``: its
    trajectory, if already simulated): the trajectory (its clock at the sound's start), where each segment's
    forces lead (cm; ``known``: a cache of them, :func:`equilibria`) and how far any node got beyond the wall
    (cm)."""
    sp = cfg.speech
    rest = settle(model) if rest is None else rest
    lap("rest posture")
    dt = units.ms_to_s(cfg.simulation.dt_ms)
    eps = equilibria(model, rest, c.vectors, units.ms_to_s(sp.reach_hold_ms), dt, known)
    lap("segment EPs")
    traj = course_trajectory(model, c, cfg, rest, progress, lap) if simulated is None else simulated
    lap("simulation")
    beyond = 0.0
    if model.contact is not None:  # how far any contact node got beyond the wall (cm)
        from ..mechanics.contact import farthest_beyond_wall

        beyond = max(0.0, farthest_beyond_wall(model.contact, traj.x))
    return traj, eps, beyond


def tracts_of_run(u: Utterance, p: Plan, model: Model, traj: Trajectory, cfg: Config) -> Tracts:
    """The tract of every frame: the lips and port of each segment's target (the config's before the first; each
    moves over ``lip_ramp_ms`` centred on its segment's start) and each segment's glottis, then the utterance's
    own course."""
    vt = speaker_tract(cfg)
    shapes = shapes_of_model(model, traj.x, traj.time)
    lip_ramp = cfg.speech.lip_ramp_ms
    entries = [TractEntry(at_ms=max(float(s * 1e3) - lip_ramp / 2, 0.0), ramp_ms=lip_ramp if k else 0.0,
                          lip_area_cm2=a, lip_length_cm=l,
                          velum_port_cm2=port)
               for k, (s, (a, l), port, solved) in enumerate(zip(p.starts_s, p.lips, p.ports, p.solutions))
               if solved]  # a segment of given forces asks nothing of the lips and the port
    voicing_ramp = cfg.speech.voicing_ramp_ms
    entries += [TractEntry(at_ms=float(s * 1e3), ramp_ms=voicing_ramp if k else 0.0, glottis_cm2=float(g))
                for k, (s, g) in enumerate(zip(p.starts_s, p.glottis_cm2))]
    tracts = tracts_of(vt, cfg.speaker.wall, shapes, controls_for(vt, traj.time, entries + list(u.tract)))
    grow = expansion_entries(u.segments, p.starts_s, traj.time, tracts.af.area_cm2.min(axis=1))
    if grow:  # the cavity's enlargement moves no wall of the area function: only its own course is redrawn
        tracts.controls["cavity_expansion_cm3"] = tract_controls(list(u.tract) + grow, {"cavity_expansion_cm3": 0.0},
                                                                 traj.time)["cavity_expansion_cm3"]
    return tracts


def formant_tracks(tracts: Tracts, time_s: np.ndarray, cfg: Config) -> np.ndarray:
    """(F, K) formants (Hz) on a coarser grid of frames (the last one always), linear between; NaN where the
    tract is closed."""
    sp = cfg.speech
    stride = max(1, int(round(sp.formant_frame_ms / sp.frame_ms)))
    picked = np.unique(np.r_[np.arange(0, tracts.n_frames, stride), tracts.n_frames - 1])
    at = formants_at(tracts, picked, cfg)
    formants_hz = np.stack([np.interp(time_s, time_s[picked], at[:, j]) for j in range(at.shape[1])], axis=1)
    formants_hz[tracts.af.area_cm2.min(axis=1) <= 0] = np.nan  # a closed tract has none
    return formants_hz


def formants_at(tracts: Tracts, frames: np.ndarray, cfg: Config) -> np.ndarray:
    """(len(frames), K) formants (Hz) of the tract at the frames ``frames`` (their ports open as the course has
    them); NaN where the tract is closed."""
    tubes = [Tube(tracts.af.length_cm[k], tracts.af.area_cm2[k]) for k in frames]
    ac = analyse(tubes, cfg.acoustics, velum_area_cm2=tracts.controls["velum_port_cm2"][frames],
                 port_from_glottis_cm=port_positions(tracts)[frames], spectra=False, bandwidths=False)
    out = np.array(ac.formants_hz, float)
    out[tracts.af.area_cm2[frames].min(axis=1) <= 0] = np.nan
    return out


def sound(u: Utterance, p: Plan, tracts: Tracts, time_s: np.ndarray, duration_s: float, cfg: Config
          ) -> tuple[Audio, Turbulence, np.ndarray, dict[str, np.ndarray]]:
    """The sound of the frames with the glottis, the port and the lungs of the course (voiceless segments
    open the glottis, :func:`tracts_of_run`): (audio, the turbulence per frame, the glottal area cm^2, the
    air per frame: the cavity's pressure, the flows, the voice's gain, the noise levels)."""
    sp, aco = cfg.speech, cfg.acoustics
    voicing = ramp_weights(p.starts_s, p.voiced.astype(float), units.ms_to_s(sp.voicing_ramp_ms), time_s)
    glottis = tracts.controls["glottis_cm2"]
    larynx = Larynx(glottis_cm2=glottis, port_cm2=tracts.controls["velum_port_cm2"],
                    port_at_cm=float(np.mean(port_positions(tracts))),
                    lung_pressure=units.kpa_to_cgs(sp.lung_pressure_kpa), voicing=voicing, noise=sp.noise,
                    voiced_cm2=cfg.vocal_tract.glottis_cm2, expansion_cm3=tracts.controls.get("cavity_expansion_cm3"))
    out = synthesize_speech(tracts.af.length_cm, tracts.af.area_cm2, time_s, aco, duration_s, larynx,
                            contour=[(float(a), float(b)) for a, b in u.f0_hz] if len(u.f0_hz) > 1 else None,
                            f0_hz=float(u.f0_hz[0][1]), flow_peak_cm3_s=sp.glottal_flow_peak_cm3_s)
    air = out.air
    tb = Turbulence(flow_cm3_s=air["constriction_flow"], reynolds=air["reynolds"], noise_rms_dyn_cm2=air["noise_rms"],
                    at_cm=air["noise_at"], constriction_cm2=air["constriction"])
    return out.audio, tb, glottis, air


def speak_plan(u: Utterance, p: Plan, cfg: Config, model: Model, progress=None, rest=None, simulated=None,
               known=None) -> Spoken:
    """Simulate the plan's force course on ``model`` from the rest posture (``rest``, if settled already;
    ``simulated``: the course's trajectory from it, if simulated already; ``known``: a cache of where held
    forces lead, :func:`equilibria`) and voice it."""
    c = force_course(u, p, model, cfg)
    lap = Laps()
    traj, eps, beyond = move(model, c, cfg, lap, progress, rest, simulated, known)
    bad = problems(traj, model.volume_constraint)
    if bad:
        raise NotPhysical(f"utterance '{u.name}': the simulation is not physical ({'; '.join(bad)}); nothing written")
    tracts = tracts_of_run(u, p, model, traj, cfg)
    lap("tract")
    formants_hz = formant_tracks(tracts, traj.time, cfg)
    lap("formant tracks")
    audio, tb, glottis, air = sound(u, p, tracts, traj.time, c.duration_s, cfg)
    lap("sound")
    sp = cfg.speech
    commanded = np.array([c.force_at(float(t) + c.prep_s) for t in traj.time])
    return Spoken(utterance=u, plan=p, trajectory=traj, tracts=tracts, formants_hz=formants_hz, noise=tb,
                  glottis_cm2=glottis, audio=audio, air=air,
                  control_points={name: traj.x[:, idx] for name, idx in model.control_points().items()},
                  muscle_names=list(model.muscle_names), muscle_force_n=units.dyn_to_newton(commanded),
                  timings_s=lap.times, segment_eps_cm=eps, beyond_wall_cm=beyond, force_course=c.how,
                  ramp_ms=units.s_to_ms(c.ramp_s), activation_ms=(sp.activation_rise_ms, sp.activation_fall_ms),
                  lead_ms=units.s_to_ms(c.lead_s), prepare_ms=units.s_to_ms(c.prep_s),
                  segment_lead_ms=units.s_to_ms(c.leads_s), press=np.array([seg.press for seg in u.segments]),
                  drive=np.array([seg.drive for seg in u.segments]))
