"""The formant finder's peak picking is scipy.signal.find_peaks's (prominence), without importing scipy.signal."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from scipy.signal import find_peaks, lfilter

from artic_cli.acoustics.formants import prominent_peaks
from artic_cli.acoustics.synthesis import _leaky_integral


def test_prominent_peaks_are_scipy_s_on_random_curves_with_plateaus():
    rng = np.random.default_rng(7)
    for trial in range(300):
        n = int(rng.integers(3, 200))
        y = np.cumsum(rng.standard_normal(n)) if trial % 2 else rng.standard_normal(n)
        y = np.round(y, int(rng.integers(0, 3)))  # rounding makes plateaus, some at the ends
        for prominence in (0.0, 0.5, 1.0, 3.0):
            np.testing.assert_array_equal(prominent_peaks(y, prominence), find_peaks(y, prominence=prominence)[0],
                                          err_msg=f"trial {trial}, prominence {prominence}")


def test_prominent_peaks_of_a_transfer_function_in_db():
    f = np.arange(50.0, 5500.0, 5.0)
    poles = [(500.0, 50.0), (1500.0, 70.0), (2500.0, 90.0), (3500.0, 110.0), (4400.0, 130.0)]
    h = np.prod([1.0 / np.abs(1 - (f / p) ** 2 + 1j * f * b / p**2) for p, b in poles], axis=0)
    db = 20 * np.log10(h)
    np.testing.assert_array_equal(prominent_peaks(db, 1.0), find_peaks(db, prominence=1.0)[0])
    assert len(prominent_peaks(db, 1.0)) == 5


def test_the_leaky_integral_is_lfilter_s():
    x = np.random.default_rng(3).standard_normal(5000)
    np.testing.assert_allclose(_leaky_integral(x, 1 / 44100.0, 0.999), lfilter([1 / 44100.0], [1.0, -0.999], x),
                               rtol=1e-12, atol=1e-15)


def test_computing_formants_does_not_import_scipy_signal():
    code = ("import sys, numpy as np; from artic_cli.acoustics.tube import Tube; from artic_cli.config import "
            "load_config; from artic_cli.stages.acoustics import compute; "
            "r = compute([Tube(np.full(34, 0.5), np.full(34, 3.0))], load_config()); "
            "assert abs(r.formants_hz[0][0] - 500) < 30, r.formants_hz[0]; print('scipy.signal' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_formants_without_bandwidths_are_the_same_frequencies():
    from artic_cli.acoustics.chain import Air
    from artic_cli.acoustics.formants import formants
    from artic_cli.acoustics.transfer import transfer
    from artic_cli.acoustics.tube import Tube
    from artic_cli.config import load_config
    from artic_cli.acoustics.model import tract_of

    ac = load_config().acoustics
    rng = np.random.default_rng(7)
    for _ in range(5):
        tube = Tube(np.full(40, 0.43), rng.uniform(0.3, 5.0, 40))
        tract = tract_of(tube, ac, None, False, None)
        mag = lambda f, t=tract: np.abs(transfer(t, f, Air()))  # noqa: E731
        full = formants(mag, ac.max_frequency_hz, ac.formant_search_step_hz, ac.formants)
        lean = formants(mag, ac.max_frequency_hz, ac.formant_search_step_hz, ac.formants, bandwidths=False)
        np.testing.assert_array_equal(lean[0], full[0])
        assert np.isnan(lean[1]).all() and np.isfinite(full[1][np.isfinite(full[0])]).all()
