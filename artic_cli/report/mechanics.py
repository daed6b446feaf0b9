"""The report's tissue, articulator and muscle-function sections (the paper's sections II-IV.A)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import ArticError
from .rows import BESIDE, Row, sim_file, verdict, within


def tissue_rows(data: Path) -> list[Row]:
    rows: list[Row] = []
    cub_path = data / "cuboid.json"
    if not cub_path.is_file():
        raise ArticError(f"{cub_path} not found; run 'artic validate cuboid --json --out {cub_path}'")
    from ..stages.cuboid import read as read_cuboid

    cub = read_cuboid(cub_path)
    small = min(cub, key=lambda r: r["force_n"])
    up30 = [r for r in cub if r["axial_strain"] <= 0.30]
    nu_log = [r["poisson_ratio_log"] for r in up30]
    nu_eng = [r["poisson_ratio"] for r in up30]
    rel = small["elongation_cm"] / small["linear_elongation_cm"] - 1
    rows.append(Row(f"Cuboid: elongation at {small['force_n']:g} N vs F L/(E A)",
                    "(not given)", f"{small['elongation_cm']:.4f} cm vs {small['linear_elongation_cm']:.4f} cm",
                    verdict(abs(rel) <= 0.15, f"{100 * rel:+.1f} %, goal within 15 %")))
    rows.append(Row("Cuboid: apparent Poisson ratio, Eq. (4) integrated (Hencky), strains <= 30 %",
                    "kept near 0.49", f"{min(nu_log):.3f} to {max(nu_log):.3f}",
                    verdict(all(abs(n - 0.49) <= 0.03 for n in nu_log), "goal 0.49 +- 0.03")))
    rows.append(Row("Cuboid: apparent Poisson ratio, Eq. (4) with engineering strains, strains <= 30 %",
                    "kept near 0.49", f"{min(nu_eng):.3f} to {max(nu_eng):.3f}",
                    verdict(all(abs(n - 0.49) <= 0.03 for n in nu_eng),
                             "a volume-keeping body cannot exceed 0.41 at 30 % in this measure")))
    with sim_file(data / "sims" / "pull_2n.h5") as on, sim_file(data / "sims" / "pull_2n_novol.h5") as off:
        von, voff = float(on.attrs["max_abs_volume_change"]), float(off.attrs["max_abs_volume_change"])
        ratio = float(on.attrs["wall_time_s"]) / float(on["time"][-1])
    rows.append(Row("Tongue volume change with the volume constraint (2 N pull, 300 ms)", "about 0.3 %",
                    f"{100 * von:.3f} %", verdict(von <= 0.003, "goal <= 0.3 %")))
    rows.append(Row("Tongue volume change without the constraint (same run)", "about 5 %", f"{100 * voff:.2f} %",
                    verdict(0.5 * 0.05 <= voff <= 2 * 0.05, "within a factor of two of 5 %")))
    with sim_file(data / "sims" / "stress_7n.h5") as st:
        inv = int(st["inverted_bricks"][()].max())
        finite = bool(np.isfinite(st["nodes/positions"][()]).all())
        vst = float(st.attrs["max_abs_volume_change"])
    rows.append(Row("7 N on several node sets for 500 ms", "smooth, no divergence",
                    f"{'finite' if finite else 'NaN'}, {inv} inverted bricks, volume change {100 * vst:.3f} %",
                    verdict(finite and inv == 0 and vst <= 0.003, "no NaN, no inversion, volume <= 0.3 %")))
    rows.append(Row("Computation speed (wall time per simulated second)", "about 40", f"{ratio:.3f}",
                    verdict(ratio <= 40, f"{40 / ratio:.0f} times faster than the paper; {BESIDE}")))
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
                        within(ratio, 0.25)))
    jo = [r["ours"] for r in eps if r["name"].startswith("JO")]
    jc = [r["ours"] for r in eps if r["name"].startswith("JC")]
    mono = all(b < a for a, b in zip(jo, jo[1:])) and all(b > a for a, b in zip(jc, jc[1:]))
    rows.append(Row("Jaw EPs monotonic in JO and JC force", "yes", "yes" if mono else "no",
                    verdict(mono, f"{len(jo)} JO and {len(jc)} JC levels")))
    f4 = _experiment(data, "fig4")
    for cp, paper in (("tip", 41), ("dorsum", 30), ("jaw", 8)):
        r = f4[f"SG+JO {cp} peak speed"]
        ratio = r["ours"] / paper
        rows.append(Row(f"Fig. 4 / Table II: SG 4 N + JO 3 N, {cp} peak speed in 20 ms", f"{paper} cm/s",
                        f"{r['ours']:.1f} cm/s", within(ratio, 0.25)))
    md = _experiment(data, "muscle-directions")
    agree, differ = [], []
    for name, r in md.items():
        if "from the paper's" in r["note"]:
            err = float(r["note"].split(",")[1].split("deg")[0])
            (agree if err <= 45 else differ).append(f"{name} {err:.0f} deg")
    rows.append(Row("Section IV.A.1: 300-ms displacement direction of each muscle at 4 N, where the paper is definite",
                    "the stated directions", f"{len(agree)} of {len(agree) + len(differ)} within 45 deg",
                    verdict(not differ, "differing: " + ", ".join(differ) if differ else "all within 45 deg")))
    kc = _experiment(data, "k-closure")
    r = kc["SG force at first dorsum-palate contact"]
    rows.append(Row("SG force at which the dorsum first touches the palate (jaw at rest)", "about 1.0 N",
                    "none up to 4 N" if r["ours"] is None else f"{r['ours']:g} N",
                    verdict(r["ours"] is not None and 0.5 <= r["ours"] <= 2.0, r["note"] or "goal about 1 N")))
    for key, item, what in (("blade nodes on the alveolar ridge", "The blade on the alveolar ridge with a muscle set "
                             "at 4 N or less (jaw at rest)", "blade node(s) on it"),
                            ("tip on the lower incisors' lingual side", "The tip on the lower incisors' lingual "
                             "side with GGa (jaw at rest)", "")):
        r = kc.get(key)
        if r is None:  # an experiment file from before these rows
            continue
        n = r["ours"] or 0.0
        ours = (f"{n:g} {what}" if what else ("yes" if n else "no")) + "; " + r["note"].split(":")[0]
        rows.append(Row(item, "reached (goal)", ours, verdict(n >= 1, r["note"])))
    st = _experiment(data, "stress")
    ok, detail = _audit_ok(st)
    rows.append(Row("7 N on GGp, SG, HG, SL, IL at once for 500 ms", "no divergence",
                    "finite" if st["finite positions"]["ours"] == 1 else "NaN", verdict(ok, detail)))
    for name in ("jaw-ep", "fig4", "muscle-directions", "k-closure"):
        ok, detail = _audit_ok(_experiment(data, name))
        rows.append(Row(f"Every run of '{name}': volume, wall, bricks", "volume change about 0.3 %", detail,
                        verdict(ok, "goal: volume <= 0.3 %, <= 0.01 cm beyond the wall, none inverted")))
    with sim_file(data / "sims" / "art_sg_jo.h5") as f:
        span = float(f["time"][-1])
        ratio, cpu = float(f.attrs["wall_time_s"]) / span, float(f.attrs["cpu_time_s"]) / span
    rows.append(Row("Articulator speed (time per simulated second; SG 4 N + JO 3 N for 300 ms)", "about 40",
                    f"wall {ratio:.2f}, CPU {cpu:.2f}",
                    verdict(ratio <= 40, f"{40 / ratio:.0f} times faster than the paper; our goal, <= 0.5 s per "
                                          f"simulated second alone on one core, is make bench's (docs/speed.md); "
                                          f"{BESIDE}")))
    return rows


def function_rows(data: Path) -> tuple[list[Row], list[str]]:
    """Section IV.A.1 (Figs. 5 and 6) and Fig. 7."""
    from ..experiments.muscle_function import convergence
    from ..experiments.paper import PAPER_DIRECTIONS
    from ..stages.muscle_function import read as load_muscle_function

    rows: list[Row] = []
    mf = load_muscle_function(data / "muscle_function.h5")
    for r in convergence(mf):
        paper = PAPER_DIRECTIONS.get(r["muscle"], {}).get(r["point"])
        d = np.array(r["mean_end_from_rest_cm"])
        ang = float(np.degrees(np.arctan2(d[1], d[0])))
        if paper is not None:
            err = float(np.degrees(np.arccos(np.clip(d @ np.array(paper) / max(np.linalg.norm(d), 1e-12), -1, 1))))
            said = verdict(err <= 45 and r["end_spread_cm"] < r["start_spread_cm"],
                            f"{err:.0f} deg from the paper's direction; spread {r['start_spread_cm']:.2f} -> "
                            f"{r['end_spread_cm']:.2f} cm")
            paper_txt = "converges, " + {(0, 1): "up", (0, -1): "down", (-1, 0): "back", (1, 0): "front"}.get(
                tuple(np.round(paper).astype(int)), f"{np.degrees(np.arctan2(paper[1], paper[0])):+.0f} deg")
        else:
            said = verdict(r["end_spread_cm"] < r["start_spread_cm"],
                            f"spread {r['start_spread_cm']:.2f} -> {r['end_spread_cm']:.2f} cm; no definite "
                            "direction in the paper")
            paper_txt = "converges"
        rows.append(Row(f"Figs. 5/6: {r['muscle']} from {len(mf.starts)} starts, {r['point']}", paper_txt,
                        f"ends {np.linalg.norm(d):.2f} cm from rest at {ang:+.0f} deg, spread "
                        f"{r['end_spread_cm']:.3f} cm", said))
    f7 = _experiment(data, "fig7")
    spreads = [r for k, r in f7.items() if "spread" in k]
    worst = max(spreads, key=lambda r: r["ours"])
    rows.append(Row(f"Fig. 7: {len(spreads) // 2} muscle/force cases from four starting shapes, 400 ms",
                    "one EP per force, whatever the start", f"end points within {worst['ours']:.3f} cm "
                    f"(worst: {worst['name'].split(':')[0]})", verdict(worst["ours"] <= 0.05, "goal <= 0.05 cm")))
    lines = ["![Fig. 5: tip](fig5_muscle_function_tip.png)", "![Fig. 6: dorsum](fig6_muscle_function_dorsum.png)",
             "![Fig. 7: trajectories](fig7_trajectories.png)", ""]
    return rows, lines


def tissue_section(data: Path) -> tuple[list[Row], list[str]]:
    return tissue_rows(data), ["![Model configuration (Fig. 1)](fig1_mesh.png)", ""]


def articulator_section(data: Path) -> tuple[list[Row], list[str]]:
    return articulator_rows(data), [
        "![SG 4 N + JO 3 N, 20 ms (Fig. 4 right)](fig4_sg.png) ![GGp 4 N + JO 3 N, 20 ms (Fig. 4 left)]"
        "(fig4_ggp.png)", "", "Animations: [fig4_sg.gif](fig4_sg.gif), [fig4_ggp.gif](fig4_ggp.gif).", "",
        "![SG 4 N + JO 3 N held for 300 ms](art_sg_jo.png)", ""]
