"""Stage ``report``: ``reports/paper.md``, our results beside the paper's, every number computed from the
artefacts.  Its sections, and the stages each draws on, are listed in :data:`artic_cli.stages.table.REPORT`."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from ..errors import ArticError
from ..io.store import open_artifact, write_text_atomic
from .base import Stage

STAGE = Stage(name="report", module=__name__, sections=(), reads=("mesh", "cuboid", "sims", "tracts", "acoustics", "acousticmaps", "experiments", "musclefunction", "epmaps", "dynamic", "solve"), kind="report", hint="rerun 'artic report' (or 'make paper')")


@dataclass
class Row:
    item: str
    paper: str
    ours: str
    verdict: str


# make paper runs two stages at a time: a stage's own clock may have shared the cores
_BESIDE = "timed as make paper ran it, maybe beside another stage; make bench times it alone and splits the time"


def _extension(attrs) -> str:
    ext = float(attrs.get("extend_ms", 0.0))
    return f" and up to {ext:g} ms more" if ext > 0 else ""


def _verdict(ok: bool, detail: str) -> str:
    return ("agrees" if ok else "differs") + f" ({detail})"


def _within(ratio: float, tolerance: float) -> str:
    """Verdict on ours / paper's being within ``tolerance`` (a fraction) of 1."""
    return _verdict(abs(ratio - 1) <= tolerance, f"{ratio - 1:+.0%}, goal within {100 * tolerance:g} %")


def _sim(path: Path) -> h5py.File:
    return open_artifact(path, "simulation", f"rerun 'make paper' to produce {path}")


def tissue_rows(data: Path) -> list[Row]:
    rows: list[Row] = []
    cub_path = data / "cuboid.json"
    if not cub_path.is_file():
        raise ArticError(f"{cub_path} not found; run 'artic validate cuboid --json --out {cub_path}'")
    from .cuboid import read as read_cuboid

    cub = read_cuboid(cub_path)
    small = min(cub, key=lambda r: r["force_n"])
    up30 = [r for r in cub if r["axial_strain"] <= 0.30]
    nu_log = [r["poisson_ratio_log"] for r in up30]
    nu_eng = [r["poisson_ratio"] for r in up30]
    rel = small["elongation_cm"] / small["linear_elongation_cm"] - 1
    rows.append(Row(f"Cuboid: elongation at {small['force_n']:g} N vs F L/(E A)",
                    "(not given)", f"{small['elongation_cm']:.4f} cm vs {small['linear_elongation_cm']:.4f} cm",
                    _verdict(abs(rel) <= 0.15, f"{100 * rel:+.1f} %, goal within 15 %")))
    rows.append(Row("Cuboid: apparent Poisson ratio, Eq. (4) integrated (Hencky), strains <= 30 %",
                    "kept near 0.49", f"{min(nu_log):.3f} to {max(nu_log):.3f}",
                    _verdict(all(abs(n - 0.49) <= 0.03 for n in nu_log), "goal 0.49 +- 0.03")))
    rows.append(Row("Cuboid: apparent Poisson ratio, Eq. (4) with engineering strains, strains <= 30 %",
                    "kept near 0.49", f"{min(nu_eng):.3f} to {max(nu_eng):.3f}",
                    _verdict(all(abs(n - 0.49) <= 0.03 for n in nu_eng),
                             "a volume-keeping body cannot exceed 0.41 at 30 % in this measure")))
    with _sim(data / "sims" / "pull_2n.h5") as on, _sim(data / "sims" / "pull_2n_novol.h5") as off:
        von, voff = float(on.attrs["max_abs_volume_change"]), float(off.attrs["max_abs_volume_change"])
        ratio = float(on.attrs["wall_time_s"]) / float(on["time"][-1])
    rows.append(Row("Tongue volume change with the volume constraint (2 N pull, 300 ms)", "about 0.3 %",
                    f"{100 * von:.3f} %", _verdict(von <= 0.003, "goal <= 0.3 %")))
    rows.append(Row("Tongue volume change without the constraint (same run)", "about 5 %", f"{100 * voff:.2f} %",
                    _verdict(0.5 * 0.05 <= voff <= 2 * 0.05, "within a factor of two of 5 %")))
    with _sim(data / "sims" / "stress_7n.h5") as st:
        inv = int(st["inverted_bricks"][()].max())
        finite = bool(np.isfinite(st["nodes/positions"][()]).all())
        vst = float(st.attrs["max_abs_volume_change"])
    rows.append(Row("7 N on several node sets for 500 ms", "smooth, no divergence",
                    f"{'finite' if finite else 'NaN'}, {inv} inverted bricks, volume change {100 * vst:.3f} %",
                    _verdict(finite and inv == 0 and vst <= 0.003, "no NaN, no inversion, volume <= 0.3 %")))
    rows.append(Row("Computation speed (wall time per simulated second)", "about 40", f"{ratio:.3f}",
                    _verdict(ratio <= 40, f"{40 / ratio:.0f} times faster than the paper; {_BESIDE}")))
    return rows


def _experiment(data: Path, name: str) -> dict[str, dict]:
    path = data / "experiments" / f"{name}.json"
    if not path.is_file():
        raise ArticError(f"{path} not found; run 'artic experiment {name} --out {path}' (or 'make paper')")
    try:
        doc = json.loads(path.read_text())
        return {r["name"]: r for r in doc["rows"]}
    except (ValueError, KeyError, TypeError):
        raise ArticError(f"{path} is not an experiment table; delete it and rerun 'make paper'") from None


def _audit_ok(rows: dict[str, dict]) -> tuple[bool, str]:
    vol = next(r for k, r in rows.items() if k.startswith("largest tongue volume change"))
    wall = rows["largest distance of a node beyond the wall"]
    inv = rows["inverted bricks (most in any frame)"]
    ok = vol["ours"] <= 0.3 and wall["ours"] <= wall["paper"] + 1e-12 and inv["ours"] == 0
    return ok, f"volume change <= {vol['ours']:.3f} %, <= {wall['ours']:.4f} cm beyond the wall, {inv['ours']:.0f} inverted"


def articulator_rows(data: Path) -> list[Row]:
    rows: list[Row] = []
    jaw = _experiment(data, "jaw-ep")
    eps = [r for k, r in jaw.items() if k.startswith(("JO", "JC"))]
    for r in eps:
        ratio = r["ours"] / r["paper"]
        rows.append(Row(f"Jaw EP, {r['name']} for 300 ms", f"{r['paper']:+.2f} cm", f"{r['ours']:+.3f} cm",
                        _within(ratio, 0.25)))
    jo = [r["ours"] for r in eps if r["name"].startswith("JO")]
    jc = [r["ours"] for r in eps if r["name"].startswith("JC")]
    mono = all(b < a for a, b in zip(jo, jo[1:])) and all(b > a for a, b in zip(jc, jc[1:]))
    rows.append(Row("Jaw EPs monotonic in JO and JC force", "yes", "yes" if mono else "no",
                    _verdict(mono, f"{len(jo)} JO and {len(jc)} JC levels")))
    f4 = _experiment(data, "fig4")
    for cp, paper in (("tip", 41), ("dorsum", 30), ("jaw", 8)):
        r = f4[f"SG+JO {cp} peak speed"]
        ratio = r["ours"] / paper
        rows.append(Row(f"Fig. 4 / Table II: SG 4 N + JO 3 N, {cp} peak speed in 20 ms", f"{paper} cm/s",
                        f"{r['ours']:.1f} cm/s", _within(ratio, 0.25)))
    md = _experiment(data, "muscle-directions")
    agree, differ = [], []
    for name, r in md.items():
        if "from the paper's" in r["note"]:
            err = float(r["note"].split(",")[1].split("deg")[0])
            (agree if err <= 45 else differ).append(f"{name} {err:.0f} deg")
    rows.append(Row("Section IV.A.1: 300-ms displacement direction of each muscle at 4 N, where the paper is definite",
                    "the stated directions", f"{len(agree)} of {len(agree) + len(differ)} within 45 deg",
                    _verdict(not differ, "differing: " + ", ".join(differ) if differ else "all within 45 deg")))
    kc = _experiment(data, "k-closure")
    r = kc["SG force at first dorsum-palate contact"]
    rows.append(Row("SG force at which the dorsum first touches the palate (jaw at rest)", "about 1.0 N",
                    "none up to 4 N" if r["ours"] is None else f"{r['ours']:g} N",
                    _verdict(r["ours"] is not None and 0.5 <= r["ours"] <= 2.0, r["note"] or "goal about 1 N")))
    for key, item, what in (("blade nodes on the alveolar ridge", "The blade on the alveolar ridge with a muscle set "
                             "at 4 N or less (jaw at rest)", "blade node(s) on it"),
                            ("tip on the lower incisors' lingual side", "The tip on the lower incisors' lingual "
                             "side with GGa (jaw at rest)", "")):
        r = kc.get(key)
        if r is None:  # an experiment file from before these rows
            continue
        n = r["ours"] or 0.0
        ours = (f"{n:g} {what}" if what else ("yes" if n else "no")) + "; " + r["note"].split(":")[0]
        rows.append(Row(item, "reached (goal)", ours, _verdict(n >= 1, r["note"])))
    st = _experiment(data, "stress")
    ok, detail = _audit_ok(st)
    rows.append(Row("7 N on GGp, SG, HG, SL, IL at once for 500 ms", "no divergence",
                    "finite" if st["finite positions"]["ours"] == 1 else "NaN", _verdict(ok, detail)))
    for name in ("jaw-ep", "fig4", "muscle-directions", "k-closure"):
        ok, detail = _audit_ok(_experiment(data, name))
        rows.append(Row(f"Every run of '{name}': volume, wall, bricks", "volume change about 0.3 %", detail,
                        _verdict(ok, "goal: volume <= 0.3 %, <= 0.01 cm beyond the wall, none inverted")))
    with _sim(data / "sims" / "art_sg_jo.h5") as f:
        span = float(f["time"][-1])
        ratio, cpu = float(f.attrs["wall_time_s"]) / span, float(f.attrs["cpu_time_s"]) / span
    rows.append(Row("Articulator speed (time per simulated second; SG 4 N + JO 3 N for 300 ms)", "about 40",
                    f"wall {ratio:.2f}, CPU {cpu:.2f}",
                    _verdict(ratio <= 40, f"{40 / ratio:.0f} times faster than the paper; our goal, <= 0.5 s per "
                                          f"simulated second alone on one core, is make bench's (docs/speed.md); "
                                          f"{_BESIDE}")))
    return rows


def function_rows(data: Path) -> tuple[list[Row], list[str]]:
    """Section IV.A.1 (Figs. 5 and 6) and Fig. 7."""
    from ..experiments.muscle_function import convergence
    from ..experiments.paper import PAPER_DIRECTIONS
    from .muscle_function import read as load_muscle_function

    rows: list[Row] = []
    mf = load_muscle_function(data / "muscle_function.h5")
    for r in convergence(mf):
        paper = PAPER_DIRECTIONS.get(r["muscle"], {}).get(r["point"])
        d = np.array(r["mean_end_from_rest_cm"])
        ang = float(np.degrees(np.arctan2(d[1], d[0])))
        if paper is not None:
            err = float(np.degrees(np.arccos(np.clip(d @ np.array(paper) / max(np.linalg.norm(d), 1e-12), -1, 1))))
            verdict = _verdict(err <= 45 and r["end_spread_cm"] < r["start_spread_cm"],
                               f"{err:.0f} deg from the paper's direction; spread {r['start_spread_cm']:.2f} -> "
                               f"{r['end_spread_cm']:.2f} cm")
            paper_txt = "converges, " + {(0, 1): "up", (0, -1): "down", (-1, 0): "back", (1, 0): "front"}.get(
                tuple(np.round(paper).astype(int)), f"{np.degrees(np.arctan2(paper[1], paper[0])):+.0f} deg")
        else:
            verdict = _verdict(r["end_spread_cm"] < r["start_spread_cm"],
                               f"spread {r['start_spread_cm']:.2f} -> {r['end_spread_cm']:.2f} cm; no definite "
                               "direction in the paper")
            paper_txt = "converges"
        rows.append(Row(f"Figs. 5/6: {r['muscle']} from {len(mf.starts)} starts, {r['point']}", paper_txt,
                        f"ends {np.linalg.norm(d):.2f} cm from rest at {ang:+.0f} deg, spread "
                        f"{r['end_spread_cm']:.3f} cm", verdict))
    f7 = _experiment(data, "fig7")
    spreads = [r for k, r in f7.items() if "spread" in k]
    worst = max(spreads, key=lambda r: r["ours"])
    rows.append(Row(f"Fig. 7: {len(spreads) // 2} muscle/force cases from four starting shapes, 400 ms",
                    "one EP per force, whatever the start", f"end points within {worst['ours']:.3f} cm "
                    f"(worst: {worst['name'].split(':')[0]})", _verdict(worst["ours"] <= 0.05, "goal <= 0.05 cm")))
    lines = ["![Fig. 5: tip](fig5_muscle_function_tip.png)", "![Fig. 6: dorsum](fig6_muscle_function_dorsum.png)",
             "![Fig. 7: trajectories](fig7_trajectories.png)", ""]
    return rows, lines


def map_rows(data: Path) -> tuple[list[Row], list[str]]:
    """Section IV.B (EP maps, Table III, Table IV) and section V (solutions): rows and extra lines."""
    from ..control.dynamic import table_iv
    from ..control.epmap import contribution_factors, monotonic_exceptions
    from ..experiments.paper import PAPER_CONTRIBUTION
    from .dynamic import read as load_dynamic_map
    from .epmap import read as load_ep_maps

    rows: list[Row] = []
    maps = load_ep_maps(data / "epmaps.h5")
    n_eps = sum(n.converged.size for jm in maps.jaws.values() for fam in (jm.single, jm.pair, jm.group)
                for n in fam.values())
    unsettled = sum(int((~n.converged).sum()) for jm in maps.jaws.values() for fam in (jm.single, jm.pair, jm.group)
                    for n in fam.values())
    held = f"{maps.attrs.get('duration_ms', 300):g} ms{_extension(maps.attrs)}"
    rows.append(Row(f"EP maps: {len(maps.jaws)} jaw positions, {n_eps} EPs (with shared axes)", "nine jaw positions",
                    f"{unsettled} not settled in {held} (flagged, not used)",
                    _verdict(unsettled <= 0.02 * n_eps, "goal: flagged, at most 2 %")))
    jaw = "rest" if "rest" in maps.jaws else maps.typical_jaw
    c = contribution_factors(maps, jaw)
    mono = monotonic_exceptions(maps)
    factor = c["factor"]
    bad = [m for m in mono if factor[m.split()[1]][("tip", "dorsum").index(m.split()[2].rstrip(":"))] >= 0.3
           and m.startswith(jaw + " ")]
    rows.append(Row(f"EPs shift monotonically with force (jaw '{jaw}', vectors with contribution >= 0.3)", "yes",
                    f"{len(bad)} exceptions ({len(mono)} in small vectors at all jaw positions)",
                    _verdict(not bad, "see 'artic ep-map' output for each exception")))
    for m, (ft, fd) in factor.items():
        pt, pd = PAPER_CONTRIBUTION.get(m, (None, None))
        if pt is None:
            continue
        diff = max(abs(ft - pt), abs(fd - pd))
        rows.append(Row(f"Table III contribution factor of {m} (tip / dorsum)", f"{pt:.2f} / {pd:.2f}",
                        f"{ft:.2f} / {fd:.2f}", _verdict(diff <= 0.2, f"largest difference {diff:.2f}, "
                                                                      "goal within 0.2")))
    dm = load_dynamic_map(data / "dynamic.h5", maps_path=data / "epmaps.h5")
    for r in table_iv(dm):
        if r["paper_tip_cm"] is None:
            continue
        near = abs(r["position_cm"] - table_iv(dm)[dm.jaws.index(dm.typical)]["position_cm"]) <= 0.3
        goal = 0.05 if near else 0.15
        worst = max(r["error_tip_cm"], r["error_dorsum_cm"])
        rows.append(Row(f"Table IV: derived vs simulated map, jaw {r['jaw']} ({r['position_cm']:+.3f} cm)",
                        f"{r['paper_tip_cm']:.3f} / {r['paper_dorsum_cm']:.3f} cm",
                        f"{r['error_tip_cm']:.3f} / {r['error_dorsum_cm']:.3f} cm" +
                        ("" if r["loo_tip_cm"] is None else
                         f" (leave-one-out {r['loo_tip_cm']:.3f} / {r['loo_dorsum_cm']:.3f})"),
                        _verdict(worst <= goal, f"goal <= {goal:g} cm {'near the typical jaw' if near else ''}")))
    lines = ["![EP vectors and contour nets (Fig. 8)](fig8_epmap.png)",
             "![A jaw position's map, simulated and derived (Fig. 9)](fig9_dynamic_map.png)", ""]
    sols = sorted((data / "solutions").glob("*.yaml")) if (data / "solutions").is_dir() else []
    import yaml

    for path in sols:
        doc = yaml.safe_load(path.read_text())
        if not isinstance(doc, dict):
            continue
        name = doc.get("target", path.stem)
        if "unreachable" in doc:
            rows.append(Row(f"Target '{name}'", "reachable", "unreachable", _verdict(False, doc["unreachable"])))
            continue
        ch = doc["chosen"]
        ref = doc.get("refined", {})
        forces = ", ".join(f"{k} {v:g} N" for k, v in ref.get("forces_n", ch["forces_n"]).items())
        err = ref.get("crucial_error_cm", doc.get("verified", {}).get("crucial_error_cm"))
        tol = doc["crucial"]["tolerance_cm"]
        rows.append(Row(f"Target '{name}': {doc['crucial']['point']} to {doc['crucial']['at_cm']} cm "
                        f"({ch['family']} {ch['map']}, {doc['candidates_considered']} candidates)",
                        "crucial feature reached", f"{forces}; simulated error {err:.3f} cm after "
                                                   f"{ref.get('simulations', 1)} simulation(s)",
                        _verdict(err is not None and err <= tol, f"tolerance {tol:g} cm")))
        lines.append(f"![{name} (Fig. 12 style)](fig12_{path.stem}.png)")
    return rows, lines


def tissue_section(data: Path) -> tuple[list[Row], list[str]]:
    return tissue_rows(data), ["![Model configuration (Fig. 1)](fig1_mesh.png)", ""]


def articulator_section(data: Path) -> tuple[list[Row], list[str]]:
    return articulator_rows(data), [
        "![SG 4 N + JO 3 N, 20 ms (Fig. 4 right)](fig4_sg.png) ![GGp 4 N + JO 3 N, 20 ms (Fig. 4 left)]"
        "(fig4_ggp.png)", "", "Animations: [fig4_sg.gif](fig4_sg.gif), [fig4_ggp.gif](fig4_ggp.gif).", "",
        "![SG 4 N + JO 3 N held for 300 ms](art_sg_jo.png)", ""]


def tract_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """The rest tract and the tracts of the articulator's simulations."""
    from . import vocal_tract as vt

    out_dir = Path("reports") if out_dir is None else out_dir
    rest = vt.read(data / "tracts" / "rest.h5")
    area, pos, reg = rest.af.constriction()
    length = float(rest.af.tract_length_cm[0])
    grid_area = rest.af.area_cm2[0, :rest.grid.n_lines]
    n_lip = len(rest.af.region) - rest.grid.n_lines
    rows = [Row("rest tract length, glottis to lips", "adult male, about 17 cm (16.5-18)",
                f"{length:.2f} cm ({rest.grid.n_lines} grid sections + {n_lip} lip sections)",
                _verdict(16.5 <= length <= 18.0, "16.5-18 cm")),
            Row("rest tract: smallest area (grid)", "open vowel [e]: no constriction",
                f"{grid_area.min():.2f} cm^2 at {pos[0]:.1f} cm ({rest.af.region_names[int(reg[0])]})",
                _verdict(grid_area.min() >= 0.15, "at least 0.15 cm^2"))]
    if rest.band_area_cm2 is not None:
        ratio = rest.band_area_cm2[0] / np.where(grid_area > 0, grid_area, np.nan)
        by_region = ", ".join(f"{name} {np.nanmedian(ratio[rest.grid.region == i]):.2f}"
                              for i, name in enumerate(rest.af.region_names[:-1]) if (rest.grid.region == i).any())
        med = float(np.nanmedian(ratio))
        rows.append(Row("rest tract: 3-D band area / power law", "the paper: midsagittal distances and laws",
                        f"median {med:.2f} ({by_region})", _verdict(0.5 <= med <= 2.0, "median within a factor 2")))
    lines = ["![The rest tract: midsagittal view, grid and area function](tract_rest.png)", ""]
    acoustics = data / "acoustics" / "rest.h5"
    if acoustics.is_file():
        from .acoustics import read as read_acoustics

        fm = read_acoustics(acoustics).formants_hz[0]
        for k, (target, name) in enumerate(((500.0, "F1"), (1947.0, "F2"))):
            err = fm[k] / target - 1
            rows.append(Row(f"rest tract [e] (default lips): {name}",
                            f"male Japanese /e/ {target:.0f} Hz (Jo's averages)", f"{fm[k]:.0f} Hz ({100 * err:+.0f} %)",
                            _verdict(abs(err) <= 0.15, "within 15 %, the speaker's check")))
        lines += ["![The rest tract's transfer function and formants](acoustics_rest.png)",
                  "![The rest tract voiced for 1 s (F0 115 Hz)](spectrogram_rest.png)", ""]
    amaps = data / "acoustic_maps.h5"
    if amaps.is_file():
        from .acoustic_map import JAPANESE_VOWELS
        from .acoustic_map import read as read_amaps

        am = read_amaps(amaps)
        pts = np.concatenate([am.points(j)[:, :2] for j in am.jaws])

        def within(points: np.ndarray) -> list[str]:
            return [v for v, (f1, f2) in JAPANESE_VOWELS.items()
                    if np.any((np.abs(points[:, 0] / f1 - 1) <= 0.1) & (np.abs(points[:, 1] / f2 - 1) <= 0.1))]

        reached = within(pts)
        # the lips are a control: the maps also hold every EP's formants with the config's mapped lip tubes
        lipped = {key: within(f[:, :2]) for key, f in am.points_with_lips().items()}
        every = [v for v in JAPANESE_VOWELS if v in reached or any(v in r for r in lipped.values())]
        with_lips = "".join(f"; with lips {a:g} cm^2 x {b:g} cm: {' '.join(r) or 'none'}"
                            for (a, b), r in lipped.items())
        rows.append(Row("EP maps in the F1-F2 plane (every jaw position; the lips a control)",
                        "male Japanese a i u e o",
                        f"{len(pts)} EPs: F1 {np.nanmin(pts[:, 0]):.0f}-{np.nanmax(pts[:, 0]):.0f} Hz, F2 "
                        f"{np.nanmin(pts[:, 1]):.0f}-{np.nanmax(pts[:, 1]):.0f} Hz; vowels within 10 %, default lips: "
                        f"{' '.join(reached) or 'none'}{with_lips}",
                        _verdict(len(every) == 5, "all five within 10 % with some lip tube of the maps")))
        lines += ["![The EP maps' vowel space](vowel_space.png)", ""]
    wav = data / "audio" / "rest.wav"
    if wav.is_file():
        import os

        lines += [f"Listen: [the rest tract, 1 s]({os.path.relpath(wav, out_dir)})", ""]
    for path in sorted((data / "tracts").glob("*.h5")):
        if path.stem == "rest":
            continue
        t = vt.read(path)
        a, p, r = t.af.constriction()
        k = int(np.argmin(a))
        sane = bool(np.isfinite(t.af.area_cm2).all() and (t.af.area_cm2 >= 0).all())
        rows.append(Row(f"{path.stem}: the narrowest frame of {t.n_frames}", "areas finite, >= 0, one per frame",
                        f"{a[k]:.3f} cm^2 at {p[k]:.1f} cm ({t.af.region_names[int(r[k])]}), "
                        f"t = {t.time_s[k] * 1e3:.0f} ms", _verdict(sane, "finite and >= 0")))
        lines.append(f"![{path.stem}: the last frame's tract](tract_{path.stem}.png)")
        if (data / "acoustics" / f"{path.stem}.h5").is_file():
            lines.append(f"![{path.stem}: formant tracks](acoustics_{path.stem}.png)")
    return rows, lines + [""]


def map_section(data: Path) -> tuple[list[Row], list[str]]:
    rows, extra = map_rows(data)
    return rows, extra + [""]


def vowel_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """The five vowels: target, simulated formants (refined, else the nearest force set's), forces, sound."""
    import os

    from ..config import read_yaml

    out_dir = Path("reports") if out_dir is None else out_dir
    rows: list[Row] = []
    lines = ["Each vowel is a formant target (male Japanese averages) solved on the EP maps with `--refine`: "
             "F1 within 10 % and F2 within 7 %.  An unreachable vowel shows its nearest force set, simulated.", ""]
    pictures: list[str] = []
    for path in sorted((data / "vowels").glob("*.yaml")):
        doc = read_yaml(path, "vowel solution")
        res = doc.get("refined") or doc.get("verified") or {}
        goal = doc.get("acoustic", {}).get("formants_hz", [np.nan, np.nan])
        f = res.get("formants_hz", [np.nan, np.nan])
        err = res.get("errors_pct", [np.nan, np.nan])
        forces = res.get("forces_n") or (doc.get("chosen") or doc.get("nearest") or {}).get("forces_n", {})
        wav = path.with_suffix(".wav")
        sound = f"[{wav.name}]({os.path.relpath(wav, out_dir)})" if wav.is_file() else ""
        lips = doc.get("lips", {})
        pictures.append(f"![/{doc['target']}/: formants and area function](vowel_{path.stem}.png)")
        lines.append(f"* /{doc['target']}/: target F1 / F2 {goal[0]:.0f} / {goal[1]:.0f} Hz, ours {f[0]:.0f} / "
                     f"{f[1]:.0f} Hz ({err[0]:+.1f} %, {err[1]:+.1f} %); forces "
                     f"{', '.join(f'{k} {v:g} N' for k, v in forces.items()) or 'none'}; lips "
                     f"{lips.get('area_cm2', np.nan):g} cm^2, {lips.get('length_cm', np.nan):g} cm" +
                     (f"; listen: {sound}" if sound else ""))
        ok = bool(res.get("within_tolerance")) and "unreachable" not in doc
        how = "unreachable by the maps: nearest force set simulated" if "unreachable" in doc else (
            "refined by simulation" if "refined" in doc else "verified by simulation")
        rows.append(Row(f"/{doc['target']}/: F1 / F2", f"{goal[0]:.0f} / {goal[1]:.0f} Hz",
                        f"{f[0]:.0f} / {f[1]:.0f} Hz ({err[0]:+.1f} %, {err[1]:+.1f} %; {how})",
                        _verdict(ok, "F1 within 10 %, F2 within 7 %")))
    return rows, lines + [""] + pictures + [""]


EMA_PEAK_CM_S = {"tip": 40.0, "dorsum": 32.0, "jaw": 12.0}  # Table II's EMA ranges the paper cites


def utterance_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """Each spoken utterance: its segments (how their forces were found, F1 / F2), closures, noise, speeds, the
    sound and its TextGrid; rows for the measures speech needs."""
    import os

    from ..acoustics.measures import band_level_db
    from . import speak as speak_stage
    from .synthesize import read_wav

    out_dir = Path("reports") if out_dir is None else out_dir
    rows: list[Row] = []
    records = [(path, speak_stage.read(path)) for path in sorted((data / "utterances").glob("*.h5"))]
    first = records[0][1] if records else None
    ramp = f"{first.ramp_ms:g} ms" if first else "the configured ramp"
    rise, fall = first.activation_ms if first else (0.0, 0.0)
    lag = (f", the muscles following them through first-order activation dynamics ({rise:g} ms rising, {fall:g} ms "
           "falling; the paper's forces follow at once)") if rise > 0 or fall > 0 else ""
    lines = ["Each utterance is a list of targets with durations (`configs/utterances/`), spoken by `artic speak "
             f"--accept-nearest`: every target solved once, its forces ramped in over {ramp} and held (the paper's "
             "static forces) or opened with a pulse (`pulse_step`, beyond the paper), switched on at the segment's "
             "start or a lead before it (each line names its course and lead, a segment its own lead and a stop "
             f"its press on the solved forces){lag}, the whole simulated with contact, then "
             "tract, formants and sound (LF voice, off in voiceless segments; turbulence noise at the narrowest "
             "place).  Formants are our transfer function's, medians over each segment's middle half.", ""]
    pictures: list[str] = []
    for path, rec in records:
        wav = path.with_suffix(".wav")
        y, rate = read_wav(wav)
        m = speak_stage.measures(rec, y, rate)
        name = str(rec.attrs.get("name", path.stem))
        own = [(f", {lead:g} ms ahead" if lead != rec.lead_ms else "") + (f", pressed x{f:g}" if f != 1.0 else "")
               for lead, f in zip(rec.leads_ms, rec.press)]
        segs = "; ".join(f"{s['label']} ({h}{o}) F1 / F2 {s['f1_hz']:.0f} / {s['f2_hz']:.0f} Hz"
                         for s, h, o in zip(m["segments"], rec.how, own))
        clos = ", ".join(f"{c['duration_ms']:.0f} ms at {c['start_s']:.2f} s" for c in m["closures"]) or "none"
        sp = m["peak_speed_cm_s"]
        tg = path.with_suffix(".TextGrid")
        lines.append(f"* /{name}/ ({rec.force_course} forces, {rec.lead_ms:g} ms ahead): {segs}; closures: {clos}; "
                     f"narrowest {m['min_constriction_cm2']:.2f} cm^2; peak "
                     f"speeds tip / dorsum / jaw {sp.get('tip', np.nan):.1f} / {sp.get('dorsum', np.nan):.1f} / "
                     f"{sp.get('jaw', np.nan):.1f} cm/s; listen: [{wav.name}]({os.path.relpath(wav, out_dir)}), "
                     f"[{tg.name}]({os.path.relpath(tg, out_dir)})")
        pictures.append(f"![/{name}/: spectrogram, formant tracks, tip / dorsum / jaw heights]"
                        f"(utterance_{path.stem}.png)")
        vowels = [s for s in m["segments"] if s["label"] not in ("k", "t", "s", "p")]
        vowel_db = float(np.mean([s["level_db"] for s in vowels])) if vowels else np.nan
        if name == "aia":
            f2 = [s["f2_hz"] for s in m["segments"]]
            rise, fall = f2[1] - f2[0], f2[1] - f2[2]
            rows.append(Row("/aia/: F2 rise /a/ -> /i/, fall /i/ -> /a/", ">= 600 Hz each (goal)",
                            f"{rise:+.0f} / {fall:+.0f} Hz", _verdict(rise >= 600 and fall >= 600, ">= 600 Hz")))
        if name in ("aka", "ata", "apa"):
            c = max(m["closures"], key=lambda c: c["duration_ms"]) if m["closures"] else None
            ours = "no closure"
            if c is not None:
                burst = band_level_db(y, rate, c["end_s"], c["end_s"] + 0.015, 3000.0)
                ours = (f"{c['duration_ms']:.0f} ms, {c['level_db'] - vowel_db:+.0f} dB against the vowels; the "
                        f"release's first 15 ms above 3 kHz {burst - vowel_db:+.0f} dB against the vowels' level")
            ok = c is not None and 40 <= c["duration_ms"] <= 120 and c["level_db"] - vowel_db <= -30
            rows.append(Row(f"/{name}/: closure", "40-120 ms, >= 30 dB below the vowels (goal)", ours,
                            _verdict(ok, "a stop")))
        if name == "asa":
            s_ = [s for s in m["segments"] if s["label"] == "s"]
            vowel_hf = float(np.mean([s["level_above_3khz_db"] for s in vowels]))
            hf = s_[0]["level_above_3khz_db"] - vowel_hf if s_ else np.nan
            rows.append(Row("/asa/: level above 3 kHz, /s/ against the vowels", ">= +20 dB (goal)", f"{hf:+.1f} dB",
                            _verdict(bool(hf >= 20), "frication")))
        if name.startswith("aia"):
            def ms(v: float) -> str:
                return f"{v:.0f}" if np.isfinite(v) else "not in the segment"

            t90 = "; ".join(f"{s['label']} " + " / ".join(ms(s.get(f'{c}_t90_ms', np.nan)) for c in
                                                           ("tip", "dorsum", "jaw")) for s in m["segments"])
            lines.append(f"  * {m['force_course']} forces: time to cover 90 % of the way to each segment's EP "
                         f"(tip / dorsum / jaw, ms): {t90}; commanded force impulse {m['force_impulse_n_s']:.2f} "
                         f"N s, peak total {m['peak_total_force_n']:.1f} N")
        fast = {k: sp.get(k, np.nan) for k in EMA_PEAK_CM_S}
        ok = all(fast[k] <= 1.5 * v for k, v in EMA_PEAK_CM_S.items())
        rows.append(Row(f"/{name}/: peak speeds tip / dorsum / jaw", "<= 40 / 32 / 12 cm/s (EMA, Table II) +50 %",
                        " / ".join(f"{fast[k]:.1f}" for k in EMA_PEAK_CM_S) + " cm/s",
                        _verdict(ok, "each at most 50 % above the EMA peak")))
        inv, beyond = int(rec.attrs.get("inverted_bricks_max", 0)), float(rec.attrs.get("max_beyond_wall_cm", np.nan))
        rows.append(Row(f"/{name}/: volume change, inverted bricks, beyond the wall", "<= 0.3 %, none, <= 0.01 cm "
                        "(goal)", f"{100 * m['max_volume_change']:.3f} %, {inv}, {beyond:.4f} cm",
                        _verdict(m["max_volume_change"] <= 0.003 and inv == 0 and beyond <= 0.01,
                                 "the tissue stays physical")))
    return rows, lines + [""] + pictures + [""]


PAPER_GOAL_MIN = 15.0  # make paper from scratch on two cores (the vowels issue's goal)
PAPER_RUN_ENV = "ARTIC_PAPER_RUN"  # set by the Makefile for make paper: "START_EPOCH_S FROM_SCRATCH(0|1) JOBS"


def paper_run(value: str | None) -> tuple[float, bool, int] | None:
    """``ARTIC_PAPER_RUN``'s start (s since the epoch), whether OUT held no artefact then, stages at a time."""
    parts = (value or "").split()
    if len(parts) != 3:
        return None
    try:
        start, scratch, jobs = float(parts[0]), parts[1] == "1", int(parts[2])
    except ValueError:
        return None
    return (start, scratch, jobs) if np.isfinite(start) and jobs >= 1 else None


def run_section(data: Path, now_s: float | None = None) -> tuple[list[Row], list[str]]:
    """How long this ``make paper`` took, from its start to this report (the report is its last step)."""
    run = paper_run(os.environ.get(PAPER_RUN_ENV))
    item = "make paper's wall time, from its start to this report"
    goal = f"<= {PAPER_GOAL_MIN:g} min from scratch on 2 cores (goal)"
    if run is None:
        return [Row(item, goal, "not timed", "not compared (the report was written outside make paper)")], []
    start, scratch, jobs = run
    minutes = ((time.time() if now_s is None else now_s) - start) / 60.0
    ours = f"{minutes:.1f} min ({jobs} stage{'s' if jobs > 1 else ''} at a time{', from scratch' if scratch else ''})"
    if not scratch:
        return [Row(item, goal, ours, "not compared (OUT held artefacts: only what changed was rebuilt)")], []
    return [Row(item, goal, ours, _verdict(minutes <= PAPER_GOAL_MIN, f"goal <= {PAPER_GOAL_MIN:g} min"))], []


SECTIONS = {"tissue": tissue_section, "articulator": articulator_section, "tract": tract_section,
            "function": function_rows,
            "maps": map_section, "vowels": vowel_section, "utterances": utterance_section, "run": run_section}


def write_report(data: Path | str = "data", out: Path | str = "reports/paper.md") -> Path:
    from .table import REPORT

    data, out = Path(data), Path(out)
    lines = ["# artic beside Dang & Honda (2004)", "",
             "Generated by `make paper` from the artefacts in `" + str(data) + "`; every figure below is "
             "computed by the run, none typed in."]
    for section in REPORT:
        fn = SECTIONS[section.key]
        rows, extra = fn(data, out.parent) if section.key in ("tract", "vowels", "utterances") else fn(data)
        lines += ["", f"## {section.title}", ""] + extra
        lines += ["| item | paper | ours | verdict |", "|---|---|---|---|"]
        lines += [f"| {r.item} | {r.paper} | {r.ours} | {r.verdict} |" for r in rows]
    lines.append("")
    return write_text_atomic(out, "\n".join(lines))
