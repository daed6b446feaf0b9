"""The one place where units are converted.

Files and the command line use newtons, centimetres, milliseconds, kPa and
kPa*s.  The mechanics works in CGS (cm, g, s, dyn), the paper's own units,
so that Table I values enter with no hidden factors.
"""

DYN_PER_N = 1.0e5  # 1 N = 1e5 dyn
DYN_PER_CM2_PER_KPA = 1.0e4  # 1 kPa = 1e3 Pa = 1e4 dyn/cm^2
S_PER_MS = 1.0e-3
ERG_PER_J = 1.0e7


def newton_to_dyn(f):
    return f * DYN_PER_N


def dyn_to_newton(f):
    return f / DYN_PER_N


def kpa_to_cgs(p):
    """kPa (or kPa*s) to dyn/cm^2 (or dyn*s/cm^2)."""
    return p * DYN_PER_CM2_PER_KPA


def cgs_to_kpa(p):
    return p / DYN_PER_CM2_PER_KPA


def ms_to_s(t):
    return t * S_PER_MS


def s_to_ms(t):
    return t / S_PER_MS


def erg_to_joule(e):
    return e / ERG_PER_J


def hz_to_bark(f):
    """Frequency (Hz) to the Bark scale, Traunmueller (1990, JASA 88): z = 26.81 f / (1960 + f) - 0.53."""
    return 26.81 * f / (1960.0 + f) - 0.53


def bark_to_hz(z):
    """Inverse of :func:`hz_to_bark`."""
    return 1960.0 * (z + 0.53) / (26.28 - z)
