"""Fig. 12: a target with a crucial and indecisive features, the candidates and the chosen force set."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt

from .common import save_figure


def plot_solution(doc: dict, target, jm, path: Path | str) -> Path:
    if "unreachable" in doc:
        return _plot_unreachable(doc, target, jm, path)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5))
    chosen = doc["chosen"]
    muscles = list(dict.fromkeys([m for c in doc["candidates"][:1] for m in c["forces_n"]]))
    features = {target.crucial.point: ("crucial", target.crucial.at_cm, target.crucial.tolerance_cm)}
    for i in target.indecisive:
        features[i.point] = ("indecisive", i.at_cm, None)
    for c, (ax, cp) in enumerate(zip(axes, ("tip", "dorsum"))):
        ax.plot(*jm.rest[c, :2], "ko", ms=5, label="rest (this jaw position)")
        for m in muscles:
            if m in jm.single:
                xy = jm.single[m].x[:, c, :2]
                ax.plot(xy[:, 0], xy[:, 1], "-o", ms=2.5, lw=1.2, label=f"EP vector {m}")
        for k, cand in enumerate(doc["candidates"], start=1):
            p = cand["predicted_cm"][cp]
            ax.plot(*p, "o", ms=12, mfc="none", mec="0.5")
            ax.annotate(str(k), p, ha="center", va="center", fontsize=7, color="0.3")
        p = chosen["predicted_cm"][cp]
        ax.plot(*p, "o", ms=13, mfc="none", mec="#c0392b", mew=2, label="chosen (predicted)")
        if "refined" in doc or "verified" in doc:
            r = doc.get("refined", doc.get("verified"))["reached_cm"][cp]
            ax.plot(*r, "x", ms=10, mew=2, color="#1f4e79", label="reached by simulation")
        if cp in features:
            kind, at, tol = features[cp]
            ax.plot(*at, "*", ms=14, color="#e67e22", label=f"{kind} target")
            if tol:
                ax.add_patch(plt.Circle(at, tol, fill=False, ls="--", color="#e67e22"))
        ax.set_aspect("equal")
        ax.set_title(f"{cp}", fontsize=10)
        ax.set_xlabel("x (cm), anterior +")
        ax.set_ylabel("y (cm), superior +")
        ax.grid(alpha=0.25)
        ax.legend(fontsize=7, loc="best")
    forces = ", ".join(f"{k} {v:g} N" for k, v in doc.get("refined", chosen)["forces_n"].items())
    fig.suptitle(f"{doc['target']}: {chosen['family']} {chosen['map']} -> {forces} "
                 f"(numbers: the {len(doc['candidates'])} cheapest candidates)", fontsize=10)
    return save_figure(fig, path)


def _plot_unreachable(doc: dict, target, jm, path: Path | str) -> Path:
    """The target against every EP vector of the jaw position: where it lies outside the mapped region."""
    c = ("tip", "dorsum").index(target.crucial.point)
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    ax.plot(*jm.rest[c, :2], "ko", ms=5, label="rest")
    for m, net in jm.single.items():
        xy = net.x[:, c, :2]
        ax.plot(xy[:, 0], xy[:, 1], "-", lw=1, label=m)
    ax.plot(*target.crucial.at_cm, "*", ms=14, color="#e67e22", label="crucial target (unreachable)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm), anterior +")
    ax.set_ylabel("y (cm), superior +")
    ax.grid(alpha=0.25)
    ax.legend(fontsize=7)
    ax.set_title(doc["unreachable"][:110] + ("..." if len(doc["unreachable"]) > 110 else ""), fontsize=7)
    return save_figure(fig, path)


def plot_acoustic_solution(doc: dict, target, path: Path | str) -> Path:
    """A vowel's answer: the F1-F2 plane (target and its tolerance, the candidates, the simulated result)
    beside the simulated area function."""
    import numpy as np

    fig, (ax, af_ax) = plt.subplots(1, 2, figsize=(12, 5))
    goal = target.acoustic.formants_hz
    tol = target.acoustic.tolerance
    ax.add_patch(plt.Rectangle((goal[1] * (1 - tol[1]), goal[0] * (1 - tol[0])), 2 * goal[1] * tol[1],
                               2 * goal[0] * tol[0], fc="#fde3c8", ec="#e67e22", label="target and tolerance"))
    ax.plot(goal[1], goal[0], "*", ms=14, color="#e67e22")
    cands = doc.get("candidates") or ([doc["nearest"]] if "nearest" in doc else [])
    for k, c in enumerate(cands, start=1):
        f = c["predicted_formants_hz"]
        ax.plot(f[1], f[0], "o", ms=11, mfc="none", mec="0.5", label="candidates (maps)" if k == 1 else None)
        ax.annotate(str(k), (f[1], f[0]), ha="center", va="center", fontsize=7, color="0.3")
    res = None
    for key, style in (("verified", ("s", "#2c7fb8")), ("refined", ("D", "#238b45"))):
        if key in doc:
            res = doc[key]
            f = res["formants_hz"]
            ax.plot(f[1], f[0], style[0], ms=9, color=style[1], label=f"{key} by simulation")
    ax.set_xlabel("F2 (Hz)")
    ax.set_ylabel("F1 (Hz)")
    ax.invert_xaxis()
    ax.invert_yaxis()  # the phoneticians' vowel chart: front left, high up
    status = "out of reach: nearest" if "unreachable" in doc else "reached" if (res or {}).get("within_tolerance") \
        else "not within tolerance"
    ax.set_title(f"/{doc['target']}/: F1 {goal[0]:g}, F2 {goal[1]:g} Hz ({status})")
    ax.legend(fontsize=8, loc="lower left")
    if res is not None and res.get("area_function"):
        lengths = np.asarray(res["area_function"]["length_cm"])
        areas = np.asarray(res["area_function"]["area_cm2"])
        edges = np.concatenate([[0.0], np.cumsum(lengths)])
        af_ax.stairs(areas, edges, fill=True, color="#9ecae1", ec="#3182bd")
        af_ax.set_xlabel("distance from the glottis (cm)")
        af_ax.set_ylabel("area (cm^2)")
        lips = doc.get("lips", {})
        af_ax.set_title(f"simulated area function (lips {lips.get('area_cm2', float('nan')):g} cm^2, "
                        f"{lips.get('length_cm', float('nan')):g} cm)")
    else:
        af_ax.text(0.5, 0.5, "no simulation (solve with --verify or --refine)", ha="center", va="center",
                   transform=af_ax.transAxes)
        af_ax.set_axis_off()
    return save_figure(fig, path)
