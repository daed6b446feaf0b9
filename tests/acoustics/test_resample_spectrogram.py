"""Halving the sample rate and the spectrogram give scipy.signal's numbers, and a voice and its picture are
made without importing scipy.signal (2.6 s per process)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.signal import resample_poly, spectrogram as scipy_spectrogram

from artic_cli.acoustics.resample import half_rate
from artic_cli.acoustics.spectrogram import spectrogram


@pytest.mark.parametrize("n", [1, 2, 3, 40, 41, 1001, 26460])
def test_half_rate_is_resample_poly_by_one_half(n):
    y = np.random.default_rng(n).standard_normal(n)
    want = resample_poly(y, 1, 2)
    got = half_rate(y)
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)


@pytest.mark.parametrize("n, rate, nfft", [(44100, 44100, 512), (26460, 44100, 512), (1000, 22050, 513),
                                           (300, 44100, 512)])
def test_spectrogram_is_scipy_s_with_its_defaults(n, rate, nfft):
    y = np.random.default_rng(n).standard_normal(n) + 3.0  # an offset: each window's mean is removed
    nper = max(16, int(0.006 * rate))
    f, t, s = scipy_spectrogram(y, fs=rate, window="hann", nperseg=nper, noverlap=nper * 3 // 4, nfft=nfft)
    f2, t2, s2 = spectrogram(y, rate, nper, nper * 3 // 4, nfft)
    assert s2.shape == s.shape
    np.testing.assert_array_equal(f2, f)
    np.testing.assert_allclose(t2, t, rtol=0, atol=1e-12)
    if s.size:
        np.testing.assert_allclose(s2, s, rtol=1e-9, atol=1e-12 * s.max())


def test_a_voice_and_its_spectrogram_do_not_import_scipy_signal(tmp_path):
    code = ("import sys, numpy as np; from artic_cli.acoustics.tube import Tube; from artic_cli.config import "
            "load_config; from artic_cli.stages.synthesize import compute; "
            "from artic_cli.plots.acoustics import plot_spectrogram; "
            "a = compute(Tube(np.full(34, 0.5), np.full(34, 3.0)), load_config(), 0.2); "
            f"plot_spectrogram(a.samples, a.sample_rate_hz, r'{tmp_path / 's.png'}'); "
            "assert len(a.samples) == int(0.2 * a.sample_rate_hz), len(a.samples); "
            "print('scipy.signal' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
    assert (tmp_path / "s.png").stat().st_size > 10_000
