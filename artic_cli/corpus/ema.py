"""An EMA-style table of an utterance's movement: the midsagittal control points (x anterior, y superior, cm;
origin at the upper incisor edge) at every frame of the simulation, with the lips' tube (aperture area cm^2,
protrusion length cm) beside them, as a CSV anyone can load."""

from __future__ import annotations

import numpy as np

POINTS = ("tip", "blade", "dorsum", "jaw")  # tongue tip, blade, dorsum, lower incisor


def ema_csv(time_s: np.ndarray, points_cm: dict[str, np.ndarray], lip_area_cm2: np.ndarray,
            lip_length_cm: np.ndarray) -> str:
    """One row per frame: ``time_s``, each point's ``_x_cm`` and ``_y_cm``, ``lip_area_cm2``, ``lip_length_cm``
    (4 decimals: 0.1 um, far below the model's own accuracy, so the text is the same for the same run)."""
    names = [n for n in POINTS if n in points_cm]
    head = ["time_s", *(f"{n}_{a}_cm" for n in names for a in ("x", "y")), "lip_area_cm2", "lip_length_cm"]
    cols = [np.asarray(time_s, float)]
    for n in names:
        xy = np.asarray(points_cm[n], float)
        cols += [xy[:, 0], xy[:, 1]]
    cols += [np.asarray(lip_area_cm2, float), np.asarray(lip_length_cm, float)]
    table = np.column_stack(cols)
    lines = [",".join(head)]
    lines += [",".join(f"{v:.4f}" if k else f"{v:.5f}" for k, v in enumerate(row)) for row in table]
    return "\n".join(lines) + "\n"
