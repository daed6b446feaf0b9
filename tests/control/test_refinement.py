"""The refinement's quasi-Newton (control/verify.broyden) on features with a known law."""

from __future__ import annotations

import numpy as np

from artic_cli.control.verify import MAX_STEP_N, broyden

TRUE = np.array([[1.15, -0.20], [-0.62, 0.30]])  # d(feature)/d(force), cm/N
NEAR_SINGULAR = np.array([[1.151, -0.200], [-0.623, 0.104]])  # what a map can give (determinant -0.005)


def _linear(jac_true):
    calls = []

    def measure(forces):
        calls.append(dict(forces))
        x = np.array([forces["A"], forces["B"]])
        return jac_true @ x, None

    return measure, calls


def test_a_nearly_singular_map_jacobian_does_not_throw_a_close_start_away():
    goal = TRUE @ np.array([1.0, 1.0])
    measure, calls = _linear(TRUE)
    start = {"A": 0.95, "B": 1.05}
    e0 = float(np.linalg.norm(goal - measure(start)[0]))
    r = broyden(measure, NEAR_SINGULAR, start, ["A", "B"], goal, lambda e, _: e <= 0.005, budget=8)
    assert r.error <= 0.005 < e0 and r.simulations <= 8
    # no trial strays beyond the first step's length from the best point found before it
    steps = [np.hypot(c["A"] - 0.95, c["B"] - 1.05) for c in calls[1:]]
    assert max(steps) < MAX_STEP_N


def test_a_good_jacobian_converges_in_one_step():
    goal = TRUE @ np.array([2.0, 0.5])
    measure, _ = _linear(TRUE)
    r = broyden(measure, TRUE, {"A": 1.5, "B": 1.0}, ["A", "B"], goal, lambda e, _: e <= 1e-9, budget=8)
    assert r.error <= 1e-9 and r.simulations == 2  # the start and one step


def test_forces_stay_within_their_range():
    goal = TRUE @ np.array([-1.0, 7.0])  # outside 0..6 N
    measure, calls = _linear(TRUE)
    broyden(measure, TRUE, {"A": 1.0, "B": 1.0}, ["A", "B"], goal, lambda e, _: e <= 1e-9, budget=6, upper=6.0)
    assert all(0.0 <= c[k] <= 6.0 for c in calls for k in "AB")
