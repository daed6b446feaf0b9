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
    out = np.empty(len(f0_hz))
    phase = 0.0
    for k, f0 in enumerate(f0_hz):
        t = phase
        if t <= te:
            out[k] = e0 * math.exp(alpha * t) * math.sin(wg * t)
        else:
            out[k] = -(1.0 / (eps * ta)) * (math.exp(-eps * (t - te)) - math.exp(-eps * (1.0 - te)))
        phase += f0 / fs
        if phase >= 1.0:
            phase -= 1.0
    return out
