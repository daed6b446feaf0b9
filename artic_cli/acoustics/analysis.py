"""Transfer function, radiated spectrum, formants and bandwidths of tubes (section II.A's vocal tract as an
area function), frame by frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .formants import formants
from .model import air_of, frequencies, tract_of
from .transfer import radiated_pressure, transfer
from .tube import Tube


@dataclass
class Acoustics:
    """Frames x frequencies: the transfer function U_lips / U_glottis and the radiated pressure (dB), and
    frames x formants: their frequencies and -3 dB bandwidths (Hz; NaN where there are fewer peaks)."""

    frequency_hz: np.ndarray  # (F,)
    transfer_db: np.ndarray  # (T, F)
    pressure_db: np.ndarray  # (T, F)
    formants_hz: np.ndarray  # (T, K)
    bandwidths_hz: np.ndarray  # (T, K)
    time_s: np.ndarray | None = None  # (T,) for a time series
    min_area_cm2: np.ndarray | None = None  # (T,) each frame's smallest section (near 0: a closure)


def analyse(tubes: list[Tube], ac, lossless: bool = False, velum_area_cm2=None,
            port_from_glottis_cm=None, progress=None, spectra: bool = True, bandwidths: bool = True) -> Acoustics:
    """Every tube's acoustics under the config's ``acoustics`` section ``ac``; ``velum_area_cm2`` and
    ``port_from_glottis_cm``: one value for all tubes or one per tube (None: the config's port area, and its
    distance from the lips for a plain tube).  ``spectra=False``:
    formants and bandwidths only (the stored transfer function and pressure spectrum are half the work; their
    arrays are then empty); ``bandwidths=False``: NaN bandwidths (a third of the formant search)."""
    air = air_of(ac, lossless)
    f = frequencies(ac)
    tf, pr, fm, bw = [], [], [], []
    per = lambda v, k: v[k] if isinstance(v, (list, tuple, np.ndarray)) else v  # noqa: E731
    for k, tube in enumerate(tubes):
        if progress is not None:
            progress(k, len(tubes))
        velum, port = per(velum_area_cm2, k), per(port_from_glottis_cm, k)
        tract = tract_of(tube, ac, None if velum is None else float(velum), lossless,
                         None if port is None else float(port))
        if spectra:
            h = transfer(tract, f, air)
            tf.append(20 * np.log10(np.maximum(np.abs(h), 1e-12)))
            pr.append(20 * np.log10(np.maximum(np.abs(radiated_pressure(h, f, air)), 1e-30) / 2e-4))
        fk, bk = formants(lambda x, t=tract: np.abs(transfer(t, x, air)), ac.max_frequency_hz,
                          ac.formant_search_step_hz, ac.formants, lossless=lossless, bandwidths=bandwidths)
        fm.append(fk)
        bw.append(bk)
    if progress is not None:
        progress(len(tubes), len(tubes))
    if not spectra:
        f = np.zeros(0)
        tf = pr = np.zeros((len(tubes), 0))
    return Acoustics(f, np.array(tf), np.array(pr), np.array(fm), np.array(bw),
                     min_area_cm2=np.array([float(np.min(t.area_cm2)) for t in tubes]))
