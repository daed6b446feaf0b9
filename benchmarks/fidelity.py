"""Fidelity scorecard: the muscles' behaviour against Dang & Honda (2004) for any config, in about 15 s.

    python benchmarks/fidelity.py [CONFIG] [--parts k,dir,t3,fig4,jaw,fm,settle] [--set KEY=VALUE ...]

--set overrides one config key by its dotted path (VALUE read as YAML, the whole config validated again),
e.g. --set jaw.sling_link_area_cm2=1.2 --set 'muscles.groups.JO={lateral_pterygoid_upper: 0.35, ...}'.

k: SG alone at 0.5-4 N, jaw at rest: first dorsum-region contact and the dorsum's gap to the wall (cm);
dir: the 16 definite directions of section IV.A.1 at 4 N (deg from the paper's; X: over 45 deg or a move
under 0.05 cm); t3: Table III from the 6-N equilibria at the rest jaw, normalised by the largest single
vector as the report does (GH included); k, dir and t3 hold the jaw when the config's epmap.hold_jaw says so; fig4: Table II peak speeds (SG 4 N + JO 3 N, 20 ms); jaw: the
eight jaw EPs (cm); fm: F1-F3 (Hz) of the rest tract and of a few held muscle sets; settle: how many floor-muscle
EPs (HG, GH, MH, GGp at 1-6 N) have not settled after the EP maps' hold, jaw free and held; hold300: the same
muscles at every map level with the jaw held and the paper's fixed 300-ms hold (what the EP-map tests assert);
fig7: Fig. 7's worst end-point spread (goal 0.05 cm); stress: the 7-N run's volume change (goal 0.3 %); t4:
Table IV's mean distances at JO_4 and JO_6 from single-vector maps (the typical JO_0.5 map carried by the best
rotation and shift; the worst muscles named; each position's incisor height from the rest jaw's; about 30 s);
the last five are not in the default parts.  Not part of make bench (it measures behaviour, not speed).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

import yaml

from artic_cli.config import load_config, parse_config
from artic_cli.errors import ArticError
from artic_cli.experiments import paper as P
from artic_cli.geometry.mesh import tongue_mesh
from artic_cli.geometry.wall import wall_surface
from artic_cli.mechanics.wall_query import wall_query
from artic_cli.mechanics.model import build_articulator
from artic_cli.mechanics.simulate import settle

CPS = ("tip", "dorsum")


def _gap(model, x, node) -> float:
    """The node's distance to the wall (cm); nan when the config has no contact."""
    if model.contact is None:
        return float("nan")
    return float(-wall_query(model.contact, x, np.array([node]))[2][0])


def k_closure(model, rest, audit, pts, hold) -> None:
    region = set(model.node_sets["dorsum_region"].tolist())
    for f in (0.5, 1.0, 1.5, 2.0, 3.0, 4.0):
        traj, end = audit.run(rest, {"SG": f}, 0.3, hold)
        hit = any(region & set(c.tolist()) for c in traj.contact_nodes)
        print(f"  SG {f:g} N: dorsum-region contact {'yes' if hit else 'no'}, dorsum gap {_gap(model, end.x, pts['dorsum']):.3f} cm")
        if hit:
            break


def directions(rest, audit, pts, hold) -> None:
    off = 0
    for m in ("GGa", "GGm", "GGp", "HG", "SG", "SL", "IL", "T", "V", "MH", "GH", "T-SL"):
        _, end = audit.run(rest, {m: 4.0}, 0.3, hold)
        cells = []
        for cp in CPS:
            d = end.x[pts[cp], :2] - rest.x[pts[cp], :2]
            ref = P.PAPER_DIRECTIONS.get(m, {}).get(cp)
            if ref is None:
                cells.append(f"{cp} {np.linalg.norm(d):.2f} cm (no definite direction)")
                continue
            err = np.degrees(np.arccos(np.clip(np.dot(d, ref) / max(np.linalg.norm(d), 1e-12), -1, 1)))
            bad = err > 45 or np.linalg.norm(d) < 0.05
            off += bad
            cells.append(f"{cp} {np.linalg.norm(d):.2f} cm {err:3.0f} deg{' X' if bad else ''}")
        print(f"  {m:5s} " + " | ".join(cells))
    print(f"  directions off: {off} of 16")


def table_iii(rest, audit, pts, hold) -> None:
    amp = {}
    for m in (*P.PAPER_CONTRIBUTION, "GH"):
        _, end = audit.run(rest, {m: 6.0}, 0.3, hold)
        amp[m] = [float(np.linalg.norm(end.x[pts[cp]] - rest.x[pts[cp]])) for cp in CPS]
    top = [max(a[c] for a in amp.values()) for c in (0, 1)]
    good = 0
    for m, (pt, pd) in P.PAPER_CONTRIBUTION.items():
        ft, fd = amp[m][0] / top[0], amp[m][1] / top[1]
        ok = max(abs(ft - pt), abs(fd - pd)) <= 0.2
        good += ok
        print(f"  {m:5s} ours {ft:.2f} / {fd:.2f}  paper {pt:.2f} / {pd:.2f}  {'ok' if ok else 'X'}")
    print(f"  Table III rows within 0.2: {good} of {len(P.PAPER_CONTRIBUTION)}")


def fig4(rest, audit, pts) -> None:
    traj, _ = audit.run(rest, {"SG": 4.0, "JO": 3.0}, 0.02)
    for n, i in pts.items():
        v = float(np.linalg.norm(traj.v[:, i, :2], axis=1).max())
        print(f"  Table II {n}: {v:.1f} cm/s (paper {P.PAPER_FIG4_SG[n]:g}, {v / P.PAPER_FIG4_SG[n] - 1:+.0%})")


def jaw_eps(rest, audit, pts) -> None:
    for group, pairs in P.PAPER_JAW_EP.items():
        for force, paper in pairs:
            _, end = audit.run(rest, {group: force}, 0.3)
            dy = float(end.x[pts["jaw"], 1] - rest.x[pts["jaw"], 1])
            print(f"  jaw {group} {force:g} N: {dy:+.2f} cm (paper {paper:+.2f}, {dy / paper - 1:+.0%})")


def formants(cfg, model, rest, audit) -> None:
    from artic_cli.acoustics.tube import Tube
    from artic_cli.stages import acoustics as ac_stage
    from artic_cli.tract.areas import port_positions, tracts_of
    from artic_cli.tract.controls import controls_for
    from artic_cli.tract.shapes import shapes_of
    from artic_cli.tract.speaker import speaker_tract

    mesh = tongue_mesh(cfg.speaker.tongue)
    vt = speaker_tract(cfg)
    mandible = np.asarray(model.node_sets["mandible"])

    def of(x):
        shapes = shapes_of(x[None], np.zeros(1), mesh, model.rest, mandible)
        tr = tracts_of(vt, cfg.speaker.wall, shapes, controls_for(vt, np.zeros(1)))
        res = ac_stage.compute([Tube(tr.af.length_cm[0], tr.af.area_cm2[0])], cfg,
                               port_from_glottis_cm=port_positions(tr))
        return res.formants_hz[0][:3], float(tr.af.area_cm2[0].min())

    f, amin = of(rest.x)
    print(f"  rest: F1-F3 {np.round(f).astype(int)} Hz (male /e/ 500 / 1947), smallest area {amin:.2f} cm^2")
    for forces in ({"SG": 4.0}, {"GGp": 4.0}, {"HG": 4.0}, {"JO": 4.0, "HG": 2.0}, {"GGp": 4.0, "SL": 1.0}):
        _, end = audit.run(rest, forces, 0.3)
        f, amin = of(end.x)
        name = " + ".join(f"{m} {v:g} N" for m, v in forces.items())
        print(f"  {name}: F1-F3 {np.round(f).astype(int)} Hz, smallest area {amin:.2f} cm^2")


def settling(cfg, model, rest) -> None:
    """The floor muscles' EPs at the rest jaw, held as the EP maps hold them (epmap.duration_ms and its
    settling test), with the jaw free and held: how many levels still move more than the tolerance."""
    from artic_cli.control.equilibrium import equilibrium_point

    for hold in (False, True):
        spec = cfg.epmap.model_copy(update={"hold_jaw": hold})
        cells, bad = [], 0
        for m in ("HG", "GH", "MH", "GGp"):
            drifts = [equilibrium_point(model, rest, {m: f}, spec).drift_cm for f in (1.0, 2.5, 4.0, 6.0)]
            n = sum(d >= spec.convergence_tol_cm for d in drifts)
            bad += n
            cells.append(f"{m} {n} (worst {max(drifts):.3f} cm)")
        print(f"  jaw {'held' if hold else 'free'}: unsettled of 4 levels: {', '.join(cells)}; {bad} of 16")


def fixed_hold(cfg, model, rest) -> None:
    """Every map level of the floor muscles, the jaw held, the paper's fixed hold (no extension)."""
    from artic_cli.control.equilibrium import equilibrium_point

    spec = cfg.epmap.model_copy(update={"hold_jaw": True, "extend_ms": 0.0})
    bad = 0
    for m in ("HG", "GH", "MH", "GGp"):
        drifts = {f: equilibrium_point(model, rest, {m: f}, spec).drift_cm for f in spec.levels_n if f > 0}
        late = {f: d for f, d in drifts.items() if d >= spec.convergence_tol_cm}
        bad += len(late)
        print(f"  {m}: " + " ".join(f"{f:g} N {d:.4f}{'*' if f in late else ''}" for f, d in drifts.items()))
    print(f"  unsettled after {spec.duration_ms:g} ms (*, moved >= {spec.convergence_tol_cm:g} cm over the last "
          f"window): {bad}")


def table_iv(cfg, model) -> None:
    """Table IV on single-vector maps: each open jaw position's EPs against the typical map's, carried by the
    least-squares rotation and shift (``control.dynamic``'s fit), per control point."""
    from artic_cli.control.dynamic import PAPER_TABLE_IV, procrustes_2d, rotation
    from artic_cli.control.equilibrium import equilibrium_point, jaw_rest

    spec = cfg.epmap
    muscles, levels = list(spec.muscles), [f for f in spec.levels_n if f > 0]

    w = list(model.control_points().values())
    rest_jaw = jaw_rest(model, {}).x[w][2, 1]

    def cloud(jaw_forces):
        start = jaw_rest(model, jaw_forces)
        eps = {(m, 0.0): start.x[w] for m in muscles}
        eps |= {(m, f): equilibrium_point(model, start, {**jaw_forces, m: f}, spec).x for m in muscles for f in levels}
        return (np.array([[eps[(m, f)][c, :2] for m in muscles for f in (0.0, *levels)] for c in (0, 1)]),
                start.x[w][2, 1] - rest_jaw)

    typical, _ = cloud(spec.jaw_positions[spec.typical_jaw])
    for jaw in ("JO_4", "JO_6"):
        q_all, height = cloud(spec.jaw_positions[jaw])
        cells = [f"incisor {height:+.3f} cm"]
        for c, cp in enumerate(CPS):
            p, q = typical[c], q_all[c]
            theta, _ = procrustes_2d(p, q)
            d = np.linalg.norm((p - p.mean(axis=0)) @ rotation(theta).T + q.mean(axis=0) - q, axis=1)
            per = d.reshape(len(muscles), -1).mean(axis=1)
            worst = ", ".join(f"{muscles[k]} {per[k]:.2f}" for k in np.argsort(-per)[:3])
            cells.append(f"{cp} {d.mean():.3f} cm (paper {PAPER_TABLE_IV[jaw][1 + c]:.3f}; worst {worst})")
        print(f"  {jaw}: " + " | ".join(cells))


def fig7_spread(model) -> None:
    rows = [r for r in P.fig7(model) if "spread" in r.name]
    worst = max(rows, key=lambda r: r.ours)
    print(f"  worst spread {worst.ours:.3f} cm ({worst.name.split(':')[0]}; goal 0.05 cm)")


def stress_volume(model) -> None:
    rows = {r.name: r.ours for r in P.stress(model)}
    vol = next(v for k, v in rows.items() if "volume" in k)
    print(f"  7 N run: volume change {vol:.3f} % (goal 0.3 %), finite {bool(rows.get('finite positions', 0))}")


def with_overrides(cfg, sets: list[str]):
    """``cfg`` with each ``KEY=VALUE`` applied at its dotted path (VALUE parsed as YAML), validated again."""
    data = cfg.model_dump(mode="json")
    for item in sets:
        key, sep, value = item.partition("=")
        if not sep:
            raise ArticError(f"--set {item!r}: give KEY=VALUE, e.g. jaw.sling_link_area_cm2=1.2")
        *path, last = key.split(".")
        node = data
        for part in path:
            if not isinstance(node.get(part), dict):
                raise ArticError(f"--set {key}: the config has no section {part!r} there; see configs/default.yaml")
            node = node[part]
        node[last] = yaml.safe_load(value)
    return parse_config(data, "--set")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("config", nargs="?", default=None)
    ap.add_argument("--parts", default="k,dir,t3,fig4,jaw,fm")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a config key by its dotted path (VALUE as YAML)")
    args = ap.parse_args()
    parts = args.parts.split(",")
    t0 = time.perf_counter()
    try:
        cfg = with_overrides(load_config(args.config), args.set)
    except ArticError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None
    model = build_articulator(cfg, tongue_mesh(cfg.speaker.tongue), wall_surface(cfg.speaker.wall))
    rest = settle(model)
    pts = model.control_points()
    audit = P.Audit(model)
    hold = cfg.epmap.hold_jaw
    print(f"rest: dorsum {_gap(model, rest.x, pts['dorsum']):.3f} cm from the wall"
          f"{'; tongue muscles with the jaw held (epmap.hold_jaw)' if hold else ''}")
    for key, title, fn in (("k", "k-closure", lambda: k_closure(model, rest, audit, pts, hold)),
                           ("dir", "directions (4 N)", lambda: directions(rest, audit, pts, hold)),
                           ("t3", "Table III (6 N, rest jaw)", lambda: table_iii(rest, audit, pts, hold)),
                           ("fig4", "Table II", lambda: fig4(rest, audit, pts)),
                           ("jaw", "jaw EPs", lambda: jaw_eps(rest, audit, pts)),
                           ("fm", "formants", lambda: formants(cfg, model, rest, audit)),
                           ("settle", "settling after epmap.duration_ms (cm moved over the last window)",
                            lambda: settling(cfg, model, rest)),
                           ("hold300", "map levels, jaw held, fixed hold (cm moved over the last window)",
                            lambda: fixed_hold(cfg, model, rest)),
                           ("t4", "Table IV (single-vector maps; goal 0.15 cm)", lambda: table_iv(cfg, model)),
                           ("fig7", "Fig. 7 (one EP per force)", lambda: fig7_spread(model)),
                           ("stress", "7 N on GGp, SG, HG, SL, IL", lambda: stress_volume(model))):
        if key in parts:
            print(title)
            fn()
    print("audit: " + "; ".join(f"{r.name} {r.ours:.3g}" for r in audit.rows()) +
          f" [{time.perf_counter() - t0:.0f} s]")


if __name__ == "__main__":
    main()
