"""The paper's numeric experiments (section III), each beside the paper's figure.

Every experiment starts from the rest posture (equilibrium under gravity,
no muscle force) of the whole articulator and returns rows of plain numbers
(cm, cm/s, N), so that the CLI can print them and tests can check them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..geometry.wall import PARTS
from ..mechanics.contact import farthest_beyond_wall
from ..mechanics.wall_query import closest_on_triangles, wall_query
from ..mechanics.jaw_hold import fresh_start, hold_jaw
from ..mechanics.loads import control_from_newtons
from ..mechanics.model import Model
from ..mechanics.simulate import run, settle

PAPER_JAW_EP = {"JO": ((0.5, -0.16), (1.2, -0.37), (2.5, -0.76), (4.0, -1.10), (6.0, -1.42)),
                "JC": ((0.5, 0.09), (1.5, 0.21), (3.0, 0.47))}
# Table III: contribution factors (tip, dorsum)
PAPER_CONTRIBUTION = {"GGa": (0.37, 0.39), "GGm": (0.58, 0.72), "GGp": (0.68, 0.74), "HG": (0.74, 0.86),
                      "SG": (0.94, 1.0), "SL": (1.0, 0.45), "IL": (0.69, 0.13), "V": (0.36, 0.43), "T": (0.31, 0.22),
                      "T-SL": (0.65, 0.17), "MH": (0.21, 0.36)}
PAPER_FIG4_SG = {"tip": 41.0, "dorsum": 30.0, "jaw": 8.0}  # Table II, cm/s
# Section IV.A.1: definite directions (unit vectors in x, y) of the tip and dorsum for each muscle
_D = {"up": (0, 1), "down": (0, -1), "back": (-1, 0), "front": (1, 0)}


def _dir(*words: str) -> tuple[float, float]:
    v = np.sum([_D[w] for w in words], axis=0).astype(float)
    return tuple(v / np.linalg.norm(v))


PAPER_DIRECTIONS = {
    "GGa": {"tip": _dir("down")},
    "GGm": {"tip": _dir("front", "down"), "dorsum": _dir("front", "down")},
    "GGp": {"tip": _dir("front", "up"), "dorsum": _dir("front", "up")},
    "HG": {"tip": _dir("back"), "dorsum": _dir("back", "down")},
    "SG": {"tip": _dir("back"), "dorsum": _dir("back", "up")},
    "IL": {"tip": _dir("back", "down"), "dorsum": _dir("back", "up")},
    "SL": {"tip": _dir("up", "back"), "dorsum": _dir("back", "down")},
    "V": {"tip": _dir("down"), "dorsum": _dir("down", "front")},
    "MH": {"dorsum": _dir("up", "front")},
}


@dataclass
class Row:
    name: str
    ours: float
    paper: float | None
    unit: str
    note: str = ""


class Audit:
    """Worst volume change, wall penetration and inverted-brick count over every run of an experiment."""

    def __init__(self, model: Model):
        self.model = model
        self.volume = 0.0
        self.penetration = -np.inf
        self.inverted = 0
        self.runs = 0

    def run(self, rest, forces_n: dict[str, float], duration: float, hold: bool = False):
        """Hold the forces from ``rest`` (``hold``: with the mandible held where ``rest`` has it)."""
        model = self.model
        if hold:
            model, rest = hold_jaw(model, rest.x), fresh_start(rest)
        ctl = control_from_newtons(model, forces_n)
        traj, end = run(model, rest, lambda t: ctl, duration)
        self.runs += 1
        self.volume = max(self.volume, float(np.abs(traj.volume_change).max()))
        self.inverted = max(self.inverted, int(traj.inverted.max()))
        if self.model.contact is not None:
            self.penetration = max(self.penetration, farthest_beyond_wall(self.model.contact, traj.x))
        return traj, end

    def rows(self) -> list[Row]:
        tol = self.model.contact.tolerance if self.model.contact is not None else None
        return [Row(f"largest tongue volume change ({self.runs} runs)", 100 * self.volume, 0.3, "%"),
                Row("largest distance of a node beyond the wall", max(self.penetration, 0.0), tol, "cm",
                    "bound: the contact tolerance"),
                Row("inverted bricks (most in any frame)", float(self.inverted), 0.0, "count")]


def jaw_ep(model: Model, duration: float = 0.3) -> list[Row]:
    rest = settle(model)
    jaw = model.control_points()["jaw"]
    audit = Audit(model)
    rows = []
    for group, pairs in PAPER_JAW_EP.items():
        for force, paper in pairs:
            _, end = audit.run(rest, {group: force}, duration)
            rows.append(Row(f"{group} {force:g} N", float(end.x[jaw, 1] - rest.x[jaw, 1]), paper, "cm",
                            f"residual speed {np.linalg.norm(end.v[jaw]):.2f} cm/s"))
    return rows + audit.rows()


def fig4(model: Model) -> list[Row]:
    rest = settle(model)
    pts = model.control_points()
    audit = Audit(model)
    rows = []
    for muscle in ("GGp", "SG"):
        traj, _ = audit.run(rest, {muscle: 4.0, "JO": 3.0}, 0.02)
        for name, i in pts.items():
            disp = float(np.linalg.norm(traj.x[-1, i, :2] - traj.x[0, i, :2]))
            speed = float(np.linalg.norm(traj.v[:, i, :2], axis=1).max())
            paper = PAPER_FIG4_SG[name] if muscle == "SG" else None
            rows.append(Row(f"{muscle}+JO {name} displacement", disp, None, "cm"))
            rows.append(Row(f"{muscle}+JO {name} peak speed", speed, paper, "cm/s"))
    return rows + audit.rows()


def muscle_directions(model: Model, force: float = 4.0, duration: float = 0.3, hold: bool = False) -> list[Row]:
    """Section IV.A.1's directions: each tongue muscle alone from rest (``hold``: the jaw held at rest)."""
    rest = settle(model)
    pts = model.control_points()
    audit = Audit(model)
    rows = []
    for muscle in ("GGa", "GGm", "GGp", "HG", "SG", "SL", "IL", "T", "V", "GH", "MH", "T-SL"):
        _, end = audit.run(rest, {muscle: force}, duration, hold)
        for cp in ("tip", "dorsum"):
            d = end.x[pts[cp], :2] - rest.x[pts[cp], :2]
            paper = PAPER_DIRECTIONS.get(muscle, {}).get(cp)
            angle = float(np.degrees(np.arctan2(d[1], d[0])))
            err = None
            if paper is not None:
                cosang = np.dot(d, paper) / max(np.linalg.norm(d), 1e-12)
                err = float(np.degrees(np.arccos(np.clip(cosang, -1, 1))))
            rows.append(Row(f"{muscle} {cp}", float(np.linalg.norm(d)), None, "cm",
                            f"direction {angle:+.0f} deg" + (f", {err:.0f} deg from the paper's" if err is not None
                                                             else ", paper: no definite direction")))
    return rows + audit.rows()


def touching(model: Model, traj, end, part: str) -> dict[int, np.ndarray]:
    """{node: end position (cm)} of the nodes a run had in contact whose nearest wall triangle (at the end)
    belongs to ``part`` (palate, pharynx or mandible)."""
    cor, out = model.contact.corners, {}
    for c in sorted({int(c) for cs in traj.contact_nodes for c in cs}):
        q = closest_on_triangles(np.repeat(end.x[c][None], len(cor), 0), cor[:, 0], cor[:, 1], cor[:, 2])
        if PARTS[model.contact.wall.part[int(np.argmin(np.linalg.norm(q - end.x[c], axis=1)))]] == part:
            out[c] = end.x[c]
    return out


BLADE_FORCES = {"GGp": 4.0, "SL": 2.0, "T": 2.0}  # a set at 4 N or less that raises the blade to the ridge
ALVEOLAR_X = -1.6  # cm: the palate within this far behind the upper incisor edge is the alveolar ridge
TIP_FORCES = {"GGa": 2.0}  # GGa pulls the tip down behind the lower incisors


def _listed(forces: dict[str, float]) -> str:
    return ", ".join(f"{m} {f:g} N" for m, f in forces.items())


def k_closure(model: Model, forces=(0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0), duration: float = 0.3,
              hold: bool = False, reach: bool = True) -> list[Row]:
    """Smallest SG force at which the dorsum region touches the palate (jaw at rest; ``hold``: held there);
    with ``reach``, also whether the blade reaches the alveolar ridge (:data:`BLADE_FORCES`) and the tip the
    lower incisors' lingual side (:data:`TIP_FORCES`), each held for ``duration`` from rest."""
    rest = settle(model)
    dorsum_region = set(model.node_sets["dorsum_region"].tolist())
    dorsum = model.control_points()["dorsum"]
    audit = Audit(model)
    found, gap = None, None
    for force in forces:
        traj, end = audit.run(rest, {"SG": force}, duration, hold)
        if any(dorsum_region & set(c.tolist()) for c in traj.contact_nodes):
            found = force
            break
        gap = float(-wall_query(model.contact, end.x, np.array([dorsum]))[2][0])
    note = "" if found is not None else f"no contact up to {forces[-1]:g} N; dorsum still {gap:.2f} cm from the wall"
    rows = [Row("SG force at first dorsum-palate contact", float("nan") if found is None else found, 1.0, "N", note)]
    if reach:
        traj, end = audit.run(rest, BLADE_FORCES, duration, hold)
        on = {n: p for n, p in touching(model, traj, end, "palate").items() if p[0] > ALVEOLAR_X}
        blade = set(model.node_sets["blade"].tolist())
        note = (f"{_listed(BLADE_FORCES)}: " + (", ".join(f"node {n} at ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f})" for n, p in on.items())
                               if on else "none") + f" (alveolar: x > {ALVEOLAR_X:g} cm)")
        rows.append(Row("blade nodes on the alveolar ridge", float(len(blade & set(on))), None, "count", note))
        tip = model.control_points()["tip"]
        traj, end = audit.run(rest, TIP_FORCES, duration, hold)
        on = touching(model, traj, end, "mandible")
        note = f"{_listed(TIP_FORCES)}: tip at ({end.x[tip, 0]:.2f}, {end.x[tip, 1]:.2f}) cm; {len(on)} node(s) on the mandible"
        rows.append(Row("tip on the lower incisors' lingual side", float(tip in on), 1.0, "bool", note))
    return rows + audit.rows()


def stress(model: Model, force: float = 7.0, duration: float = 0.5) -> list[Row]:
    rest = settle(model)
    audit = Audit(model)
    traj, _ = audit.run(rest, {m: force for m in STRESS_MUSCLES}, duration)
    return [Row("finite positions", float(np.isfinite(traj.x).all()), 1.0, "bool",
                f"{force:g} N on each of {', '.join(STRESS_MUSCLES)} for {duration * 1e3:g} ms"),
            Row("nodes projected back onto the wall", float(traj.projected.sum()), None, "count")] + audit.rows()


STRESS_MUSCLES = ("GGp", "SG", "HG", "SL", "IL")
FIG7_STARTS = (("SL", "GGa"), ("SG", "HG"), ("GGp", "GGm"), ("IL", "V"))  # four starting shapes, 5 N each


def fig7_paths(model: Model, muscles=("GGp", "GGm", "SG"), forces=(1.0, 2.0, 3.5, 5.0), duration: float = 0.4):
    """Fig. 7: for each muscle and force, the tip/dorsum/jaw paths (F, 4 starts, T, 3, 3) from four starting
    shapes (two-muscle combinations at 5 N each, 300 ms) under that force alone; and the audit."""
    rest = settle(model)
    audit = Audit(model)
    watch = list(model.control_points().values())
    starts = [audit.run(rest, {m: 5.0 for m in combo}, 0.3)[1] for combo in FIG7_STARTS]
    data = {}
    for muscle in muscles:
        paths = np.array([[audit.run(s, {muscle: f}, duration)[0].x[:, watch] for s in starts] for f in forces])
        data[muscle] = {"forces": list(forces), "paths": paths}
    return data, audit


def fig7(model: Model, muscles=("GGp", "GGm", "SG"), forces=(1.0, 2.0, 3.5, 5.0), duration: float = 0.4,
         figure: dict | None = None) -> list[Row]:
    """Fig. 7: one muscle from four different starting shapes reaches one EP per force level; ``figure``
    (a dict) receives the paths for the picture."""
    data, audit = fig7_paths(model, muscles, forces, duration)
    rows = []
    for muscle, d in data.items():
        for f_i, force in enumerate(d["forces"]):
            for c, cp in enumerate(("tip", "dorsum")):
                p = d["paths"][f_i, :, -1, c]
                spread = max(float(np.linalg.norm(a - b)) for a in p for b in p)
                moved = float(np.linalg.norm(d["paths"][f_i, :, -1, c] - d["paths"][f_i, :, 0, c], axis=1).min())
                rows.append(Row(f"{muscle} {force:g} N {cp}: spread of the four end points", spread, None, "cm",
                                f"starts {' / '.join('+'.join(cb) for cb in FIG7_STARTS)} at 5 N; "
                                f"each moved at least {moved:.2f} cm"))
    if figure is not None:
        figure.update(data)
    return rows + audit.rows()


EXPERIMENTS = {"jaw-ep": jaw_ep, "fig4": fig4, "muscle-directions": muscle_directions, "k-closure": k_closure,
               "stress": stress, "fig7": fig7}
HELD_JAW_EXPERIMENTS = ("muscle-directions", "k-closure")  # single EPs of tongue muscles: held as the maps are


def rows_as_dicts(rows: list[Row]) -> list[dict]:
    """Plain dicts for JSON (a NaN becomes null: JSON has no NaN)."""
    out = []
    for r in rows:
        d = asdict(r)
        d["ours"] = None if d["ours"] is None or not np.isfinite(d["ours"]) else d["ours"]
        out.append(d)
    return out


__all__ = ["EXPERIMENTS", "Row", "rows_as_dicts"]
