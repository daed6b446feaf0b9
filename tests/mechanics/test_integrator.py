"""Quality bars of the simulation engine (issue: the semicontinuum tongue)."""

import numpy as np

from artic_cli.mechanics.model import Control, build_model, rest_state, with_options
from artic_cli.mechanics.simulate import equilibrate, run
from conftest import set_force

PULL_2N = {"blade": (1.4, 1.4, 0.0)}
STRESS_7N = {"blade": (7.0, 0.0, 0.0), "dorsum_region": (0.0, 7.0, 0.0), "root": (-7.0, 0.0, 0.0)}


def _run(model, forces, duration, dt=None):
    ctl = Control(node_force=set_force(model, forces))
    return run(model, rest_state(model), lambda t: ctl, duration, dt)[0]


def test_gravity_equilibrium_converges_and_does_not_depend_on_dt(model):
    ctl = Control(node_force=np.zeros((model.n_nodes, 3)))
    ends = []
    for dt in (0.005, 0.0025):
        state, ok = equilibrate(model, rest_state(model), ctl, dt=dt, tol=1e-3, max_time=3.0)
        assert ok, f"no equilibrium under gravity with dt = {dt}"
        assert np.linalg.norm(state.v) < 1e-2
        ends.append(state.x)
    sag = np.linalg.norm(ends[0] - model.mesh.nodes, axis=1).max()
    assert 0.0 < sag < 0.5  # the tongue settles, but keeps its shape
    assert np.linalg.norm(ends[0] - ends[1], axis=1).max() < 0.02


def test_halving_dt_changes_the_300ms_position_by_less_than_half_a_mm(model):
    a = _run(model, PULL_2N, 0.3, 0.005)
    b = _run(model, PULL_2N, 0.3, 0.0025)
    assert np.linalg.norm(a.x[-1] - model.mesh.nodes, axis=1).max() > 0.3  # it really moves
    assert np.linalg.norm(a.x[-1] - b.x[-1], axis=1).max() < 0.05


def test_shortcuts_cost_little_accuracy(model):
    """Modified Newton (factor reuse) at the default tolerance vs full Newton at 1e-9 cm."""
    fast = _run(model, PULL_2N, 0.3)
    exact_model = with_options(model, tol=1e-9, refactor_rate=1e-12, max_iter=60)
    exact = _run(exact_model, PULL_2N, 0.3)
    # the factor really is reused: most steps and iterations run on an old factorisation
    assert fast.stats["refactors"] < fast.stats["steps"] / 2
    assert fast.stats["refactors"] < exact.stats["refactors"] / 5
    assert np.linalg.norm(fast.x - exact.x, axis=2).max() < 1e-3


def test_7n_stress_stays_finite_upright_and_passive(model):
    t = _run(model, STRESS_7N, 0.5)
    assert np.isfinite(t.x).all()
    assert t.inverted.max() == 0
    # energy bounded: what is stored and moving never exceeds the work done on the tongue
    assert (t.energy <= t.work + 1e-6 * np.abs(t.work).max() + 1.0).all()
    assert np.isfinite(t.energy).all() and t.energy.max() > 0
    assert np.abs(t.volume_change).max() <= 0.003


def test_volume_constraint_holds_volume_and_its_absence_shows_the_drift(cfg, mesh, model):
    on = _run(model, PULL_2N, 0.3)
    off_model = build_model(mesh, cfg.materials.tongue, cfg.simulation, volume_constraint=False)
    off = _run(off_model, PULL_2N, 0.3)
    on_max, off_max = np.abs(on.volume_change).max(), np.abs(off.volume_change).max()
    assert on_max <= 0.003
    assert off_max > 0.02  # the paper: about 5 % without the constraint
    print(f"volume change: {100 * on_max:.3f} % with the constraint, {100 * off_max:.2f} % without")


def test_both_schemes_settle_on_one_static_equilibrium(model):
    """Houbolt and backward Euler integrate differently but must settle on the same equilibrium, and there
    the tissue's forces balance the load and gravity (the static equations, which no time scheme enters)."""
    from artic_cli.mechanics.integrator import evaluation, forces

    ctl = Control(node_force=set_force(model, PULL_2N))
    ends = {}
    for scheme in ("houbolt", "bdf1"):
        m = with_options(model, scheme=scheme)
        ends[scheme], ok = equilibrate(m, rest_state(m), ctl, dt=0.01, tol=1e-3, max_time=5.0)
        assert ok, scheme
    assert np.linalg.norm(ends["houbolt"].x - ends["bdf1"].x, axis=1).max() < 0.005
    for s in ends.values():
        ev = evaluation(model, s, ctl, s.x)  # at rest: no dashpot force
        unbalanced = (forces(model, ev) + forces(model, ev, varying=False))[~model.fixed]
        assert np.abs(unbalanced).max() < 0.01 * np.abs(ctl.node_force).max()  # 1 % of the largest nodal load


