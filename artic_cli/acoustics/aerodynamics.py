"""The air through the tract, quasi-steady, and the turbulence noise it makes at the narrowest place.

The lungs push at pressure P through two orifices in series, the glottis (A_g) and the tract's narrowest
section (A_c); Bernoulli losses at both give the volume flow U = sqrt(2 P / rho) / sqrt(1 / A_g^2 + 1 / A_c^2)
(a closure, A_c = 0, stops it).  Across the constriction the air loses its kinetic pressure
dp = rho / 2 (U / A_c)^2.  Its Reynolds number is Re = (U / A_c) d / nu with d = 2 sqrt(A_c / pi) and nu the
kinematic viscosity.  Above a critical Reynolds number the jet is turbulent: a pressure source of RMS
gain dp (1 - (Re_c / Re)^2) just downstream (Stevens 1971; Flanagan 1972).  All CGS: cm, cm^2, dyn/cm^2, g.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Turbulence:
    flow_cm3_s: np.ndarray  # (F,) the mean flow
    reynolds: np.ndarray  # (F,) at the constriction
    noise_rms_dyn_cm2: np.ndarray  # (F,) the source's RMS pressure
    at_cm: np.ndarray  # (F,) where it acts, from the glottis (the constriction's downstream end)
    constriction_cm2: np.ndarray  # (F,) the narrowest area


def flow(lung_pressure: np.ndarray, glottis_cm2: np.ndarray, constriction_cm2: np.ndarray, rho: float) -> np.ndarray:
    """U (cm^3/s) through the glottis and the constriction in series."""
    ag, ac = np.asarray(glottis_cm2, float), np.asarray(constriction_cm2, float)
    speed = np.sqrt(2.0 * np.asarray(lung_pressure, float) / rho)
    with np.errstate(divide="ignore"):
        inv = 1.0 / np.maximum(ag, 1e-12) ** 2 + 1.0 / np.maximum(ac, 1e-12) ** 2
    return np.where(ac > 0, speed / np.sqrt(inv), 0.0)


def reynolds(u: np.ndarray, area_cm2: np.ndarray, rho: float, mu: float) -> np.ndarray:
    a = np.maximum(np.asarray(area_cm2, float), 1e-12)
    return (np.asarray(u, float) / a) * 2.0 * np.sqrt(a / np.pi) * rho / mu


def noise_rms(u: np.ndarray, area_cm2: np.ndarray, rho: float, mu: float, critical: float, gain: float) -> np.ndarray:
    """The turbulence source's RMS pressure (dyn/cm^2): zero below the critical Reynolds number."""
    a = np.maximum(np.asarray(area_cm2, float), 1e-12)
    re = reynolds(u, a, rho, mu)
    drop = 0.5 * rho * (np.asarray(u, float) / a) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        onset = np.where(re > critical, 1.0 - (critical / np.maximum(re, 1e-12)) ** 2, 0.0)
    return gain * drop * onset


def glottal_noise_rms(u: np.ndarray, glottis_cm2: np.ndarray, rho: float, mu: float, critical: float,
                      coefficient: float) -> np.ndarray:
    """Aspiration: the RMS pressure (dyn/cm^2) of the turbulence the glottal jet makes, Flanagan &
    Ishizaka (1976)'s source coefficient x r x (Re^2 - Re_c^2) above the critical Reynolds number with r
    uniform in [-1/2, 1/2] (as Sondhi & Schroeter 1987 give it; its RMS is 1 / sqrt(12)): it grows with the
    flow and the opening, so an abducted glottis (/h/, an aspirated release) is far noisier than a voicing
    one."""
    re = reynolds(np.abs(np.asarray(u, float)), glottis_cm2, rho, mu)
    return coefficient / np.sqrt(12.0) * np.maximum(re * re - critical * critical, 0.0)


def voice_gain(transglottal: np.ndarray, lung_pressure: float, glottis_cm2: np.ndarray, threshold: float,
               voiced_cm2: float, stops_cm2: float) -> np.ndarray:
    """The voice's amplitude (0-1) for the transglottal pressure and the glottis's mean opening: the folds
    vibrate above the phonation threshold pressure, their amplitude growing as sqrt(dP - P_th) past it (a
    Hopf onset: Lucero 1995) and the flow through them as sqrt(dP) (Bernoulli), both 1 at the lung pressure
    with the tract open; abducted past ``stops_cm2`` they do not meet and stop (linear from ``voiced_cm2``)."""
    dp = np.asarray(transglottal, float)
    onset = np.sqrt(np.clip((dp - threshold) / max(lung_pressure - threshold, 1e-9), 0.0, 1.0))
    flow = np.sqrt(np.clip(dp / lung_pressure, 0.0, 1.0))
    adduction = np.clip((stops_cm2 - np.asarray(glottis_cm2, float)) / max(stops_cm2 - voiced_cm2, 1e-9), 0.0, 1.0)
    return onset * flow * adduction
