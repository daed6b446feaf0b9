"""Running again from part-way (mechanics/resume.py): a run resumed from an earlier run's snapshot where their
controls first differ is the same, frame for frame, as the whole run made again (its energy and work, sums
carried on from the joint, to rounding); a run with nothing changed is the earlier one."""

from __future__ import annotations

import numpy as np

from artic_cli.mechanics.model import Control
from artic_cli.mechanics.resume import first_difference, resumed
from artic_cli.mechanics.simulate import run, settle

DT, STEPS, EVERY, SNAP = 0.005, 40, 2, 8


def _course(art, switch_s: float):
    """The jaw opened (JO 3 N), then at ``switch_s`` the tongue pulled back (HG 2 N) with the jaw closing."""
    names = list(art.muscle_names)
    a, b = np.zeros(len(names)), np.zeros(len(names))
    a[[k for k, n in enumerate(names) if n.startswith("JO")]] = 3e5 / max(sum(n.startswith("JO") for n in names), 1)
    b[[k for k, n in enumerate(names) if n.startswith("HG")]] = 2e5 / max(sum(n.startswith("HG") for n in names), 1)
    zero = np.zeros((art.n_nodes, 3))
    return lambda t: Control(node_force=zero, muscle_force=a if t < switch_s else b)


def test_a_resumed_run_is_the_whole_run_made_again(art):
    rest = settle(art)
    early, late = _course(art, 0.06), _course(art, 0.12)
    prior, _ = run(art, rest, late, STEPS * DT, DT, record_every=EVERY, snapshots_every=SNAP)
    k = first_difference(late, early, rest.t, DT, STEPS)
    assert k == 13  # the first step whose middle lies past 60 ms
    again = resumed(art, prior, early, STEPS * DT, DT, EVERY, k, snapshots_every=SNAP)
    whole, _ = run(art, rest, early, STEPS * DT, DT, record_every=EVERY, snapshots_every=SNAP)
    assert again.stats["resumed_at_step"] == 8  # the latest snapshot before step 13
    for name in ("time", "x", "v", "volume", "muscle_force", "muscle_length", "inverted", "contact_count"):
        assert np.array_equal(getattr(again, name), getattr(whole, name)), name
    for name in ("energy", "work"):  # sums carried on from the joint: the same to rounding
        np.testing.assert_allclose(getattr(again, name), getattr(whole, name), rtol=1e-12, atol=1e-9)
    assert not np.array_equal(again.x, prior.x)  # and the change did change the movement
    assert sorted(again.snapshots) == sorted(whole.snapshots) == list(range(0, STEPS + 1, SNAP))
    assert again.stats["steps"] == STEPS


def test_a_run_with_nothing_changed_is_the_earlier_one(art):
    rest = settle(art)
    c = _course(art, 0.06)
    prior, _ = run(art, rest, c, STEPS * DT, DT, record_every=EVERY, snapshots_every=SNAP)
    assert first_difference(c, c, rest.t, DT, STEPS) == STEPS + 1
    assert resumed(art, prior, c, STEPS * DT, DT, EVERY, STEPS + 1) is prior
