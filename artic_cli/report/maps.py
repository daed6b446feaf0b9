"""The report's maps section: EP maps, Table III, dynamic maps (Table IV) and the target solver (sections IV.B and V)."""

from __future__ import annotations

from pathlib import Path


from .rows import Row, extension, verdict


def map_rows(data: Path) -> tuple[list[Row], list[str]]:
    """Section IV.B (EP maps, Table III, Table IV) and section V (solutions): rows and extra lines."""
    from ..control.dynamic import table_iv
    from ..control.epmap import contribution_factors, monotonic_exceptions
    from ..experiments.paper import PAPER_CONTRIBUTION
    from ..stages.dynamic import read as load_dynamic_map
    from ..stages.epmap import read as load_ep_maps

    rows: list[Row] = []
    maps = load_ep_maps(data / "epmaps.h5")
    n_eps = sum(n.converged.size for jm in maps.jaws.values() for fam in (jm.single, jm.pair, jm.group)
                for n in fam.values())
    unsettled = sum(int((~n.converged).sum()) for jm in maps.jaws.values() for fam in (jm.single, jm.pair, jm.group)
                    for n in fam.values())
    held = f"{maps.attrs.get('duration_ms', 300):g} ms{extension(maps.attrs)}"
    rows.append(Row(f"EP maps: {len(maps.jaws)} jaw positions, {n_eps} EPs (with shared axes)", "nine jaw positions",
                    f"{unsettled} not settled in {held} (flagged, not used)",
                    verdict(unsettled <= 0.02 * n_eps, "goal: flagged, at most 2 %")))
    jaw = "rest" if "rest" in maps.jaws else maps.typical_jaw
    c = contribution_factors(maps, jaw)
    mono = monotonic_exceptions(maps)
    factor = c["factor"]
    bad = [m for m in mono if factor[m.split()[1]][("tip", "dorsum").index(m.split()[2].rstrip(":"))] >= 0.3
           and m.startswith(jaw + " ")]
    rows.append(Row(f"EPs shift monotonically with force (jaw '{jaw}', vectors with contribution >= 0.3)", "yes",
                    f"{len(bad)} exceptions ({len(mono)} in small vectors at all jaw positions)",
                    verdict(not bad, "see 'artic ep-map' output for each exception")))
    for m, (ft, fd) in factor.items():
        pt, pd = PAPER_CONTRIBUTION.get(m, (None, None))
        if pt is None:
            continue
        diff = max(abs(ft - pt), abs(fd - pd))
        rows.append(Row(f"Table III contribution factor of {m} (tip / dorsum)", f"{pt:.2f} / {pd:.2f}",
                        f"{ft:.2f} / {fd:.2f}", verdict(diff <= 0.2, f"largest difference {diff:.2f}, "
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
                        verdict(worst <= goal, f"goal <= {goal:g} cm {'near the typical jaw' if near else ''}")))
    lines = ["![EP vectors and contour nets (Fig. 8)](fig8_epmap.png)",
             "![A jaw position's map, simulated and derived (Fig. 9)](fig9_dynamic_map.png)", ""]
    sols = sorted((data / "solutions").glob("*.yaml")) if (data / "solutions").is_dir() else []
    from ..validation import load_yaml

    for path in sols:
        doc = load_yaml(path.read_text())
        if not isinstance(doc, dict):
            continue
        name = doc.get("target", path.stem)
        if "unreachable" in doc:
            rows.append(Row(f"Target '{name}'", "reachable", "unreachable", verdict(False, doc["unreachable"])))
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
                        verdict(err is not None and err <= tol, f"tolerance {tol:g} cm")))
        lines.append(f"![{name} (Fig. 12 style)](fig12_{path.stem}.png)")
    return rows, lines


def map_section(data: Path) -> tuple[list[Row], list[str]]:
    rows, extra = map_rows(data)
    return rows, extra + [""]
