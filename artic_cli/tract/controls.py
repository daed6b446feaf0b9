"""The tract's control inputs frame by frame: the lip tube (area, length), the velopharyngeal port, the
glottis's mean opening and the cavity's active enlargement."""

from __future__ import annotations

import numpy as np

from ..config import VocalTract
from ..schedule import TractEntry, tract_controls
from ..validation import check_number


def default_controls(vt: VocalTract) -> dict[str, float]:
    """The config's lip tube, port and glottis (cm^2, cm), the cavity not enlarged (cm^3)."""
    return {"lip_area_cm2": vt.lips.area_cm2, "lip_length_cm": vt.lips.length_cm, "velum_port_cm2": vt.velum_port_cm2,
            "glottis_cm2": vt.glottis_cm2, "cavity_expansion_cm3": 0.0}


def controls_for(vt: VocalTract, time_s: np.ndarray, entries: list[TractEntry] | None = None,
                 overrides: dict[str, float | None] | None = None) -> dict[str, np.ndarray]:
    """The tract controls per frame: the config's defaults, overridden by options, then a schedule's entries."""
    start = default_controls(vt)
    for k, v in (overrides or {}).items():
        if v is not None:
            start[k] = float(v)
    return tract_controls(entries or [], start, time_s)


def check_overrides(lip_area: float | None, lip_length: float | None, velum_port: float | None) -> dict:
    """The command line's lip and port values, checked (cm^2, cm), as control overrides."""
    check_number("--lip-area", lip_area, ge=0, le=10, unit="cm^2")
    check_number("--lip-length", lip_length, gt=0, le=3, unit="cm")
    check_number("--velum-port", velum_port, ge=0, le=10, unit="cm^2")
    return {"lip_area_cm2": lip_area, "lip_length_cm": lip_length, "velum_port_cm2": velum_port}
