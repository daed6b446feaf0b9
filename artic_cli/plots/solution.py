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
