"""An utterance's record as read back from its file: what plots and measures need."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Record:
    """An utterance file read back (what plots and checks need)."""

    attrs: dict
    labels: list[str]
    starts_s: np.ndarray
    durations_s: np.ndarray
    voiced: np.ndarray
    how: list[str]
    time_s: np.ndarray
    control_points: dict[str, np.ndarray]
    formants_hz: np.ndarray
    area_cm2: np.ndarray
    length_cm: np.ndarray
    noise_rms: np.ndarray
    positions_cm: np.ndarray
    volume_change: np.ndarray
    eps_cm: np.ndarray  # (K, 3, 3)
    commanded_n: np.ndarray  # (F, M)
    force_course: str
    ramp_ms: float
    activation_ms: tuple[float, float]
    lead_ms: float = 0.0
    prepare_ms: float = 0.0
    leads_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's own lead
    press: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's tongue-force factor
    drive: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (K,) each segment's opening pulse's factor
