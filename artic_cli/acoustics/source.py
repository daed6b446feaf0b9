"""The glottal source: Fant, Liljencrants & Lin's (1985) LF model of the glottal flow derivative.

One period T0 = 1 / F0 with the timing ratios ``tp`` (flow peak), ``te`` (main excitation) and ``ta`` (return
phase), as fractions of T0: E(t) = E0 exp(a t) sin(pi t / tp) up to te, then an exponential return
-(Ee / (eps ta)) (exp(-eps (t - te)) - exp(-eps (T0 - te))) to the period's end.  ``eps`` solves
eps ta = 1 - exp(-eps (T0 - te)), ``a`` makes the net flow of a period zero.  Default ratios: a modal
male voice (Fant 1995's Rd about 1: tp 0.42, te 0.56, ta 0.012).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq


def _lf_shape(tp: float, te: float, ta: float) -> tuple[float, float]:
    """(alpha, eps) of a unit period."""
    tc = 1.0
    eps = brentq(lambda e: e * ta - 1.0 + math.exp(-e * (tc - te)), 1e-6, 1e6) if ta > 0 else 1e6
    wg = math.pi / tp

    def net_flow(alpha: float) -> float:
        e0 = -1.0 / (math.exp(alpha * te) * math.sin(wg * te))  # Ee = 1 at te
        a2w2 = alpha * alpha + wg * wg
        open_part = e0 * (math.exp(alpha * te) * (alpha * math.sin(wg * te) - wg * math.cos(wg * te)) + wg) / a2w2
        ret = -(1.0 / (eps * ta)) * ((1.0 - math.exp(-eps * (tc - te))) / eps - (tc - te) * math.exp(-eps * (tc - te)))
        return open_part + ret

    lo, hi = -50.0, 200.0
    alpha = brentq(net_flow, lo, hi)
    return alpha, eps


def lf_flow_derivative(f0_hz: np.ndarray, fs: float, tp: float = 0.42, te: float = 0.56, ta: float = 0.012) -> np.ndarray:
    """The glottal flow derivative, sample by sample, for an F0 per sample (Hz): periods follow each other
    with their own length; the peak excitation is -1."""
    alpha, eps = _lf_shape(tp, te, ta)
    wg = math.pi / tp
    e0 = -1.0 / (math.exp(alpha * te) * math.sin(wg * te))
    # the phase within the current period, each sample advancing by its own F0 / fs
    phase = np.concatenate([[0.0], np.cumsum(np.asarray(f0_hz, dtype=float) / fs)[:-1]]) % 1.0
    opening = e0 * np.exp(alpha * phase) * np.sin(wg * phase)
    closing = -(1.0 / (eps * ta)) * (np.exp(-eps * (phase - te)) - math.exp(-eps * (1.0 - te)))
    return np.where(phase <= te, opening, closing)
