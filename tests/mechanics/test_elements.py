"""Cylinders, volume constraint, mass and calibration."""

import numpy as np
import pytest

from artic_cli.geometry.mesh import cuboid_mesh
from artic_cli.mechanics import elements
from artic_cli.mechanics.calibration import calibrate, effective_poisson, lattice_response
from artic_cli.mechanics.integrator import evaluation, forces
from artic_cli.mechanics.isotropy import isotropic_areas, moment_matrix
from artic_cli.mechanics.model import rest_state, zero_control
from artic_cli.mechanics.simulate import mechanical_energy


def test_youngs_modulus_is_constant_below_20_percent_and_rises_beyond(model):
    cyl = model.springs
    strain = np.linspace(-0.3, 0.5, len(cyl.i))
    e, de = elements.youngs_modulus(cyl, strain)
    low = strain <= 0.2
    assert np.allclose(e[low], cyl.youngs[low])
    assert (e[~low] > cyl.youngs[~low]).all()
    assert (np.diff(e[~low]) > 0).all()


def test_radius_law_sets_the_cross_section(model):
    # a cylinder stretched by 10 %: area shrinks by (1 - nu * 0.1)^2 (Eq. 4)
    x = model.mesh.nodes.copy()
    c = 0
    i, j = model.springs.i[c], model.springs.j[c]
    x[j] = x[i] + 1.1 * (x[j] - x[i])
    cs = elements.evaluate(model.springs, x)
    nu = model.springs.poisson[c]
    expect = model.springs.youngs[c] * 0.1 * model.springs.area0[c] * (1 - nu * 0.1) ** 2
    assert cs.elastic[c] == pytest.approx(expect, rel=1e-9)


def test_internal_force_is_minus_the_gradient_of_stored_energy(model):
    rng = np.random.default_rng(2)
    x = model.mesh.nodes + 0.05 * rng.standard_normal(model.mesh.nodes.shape)
    zero = np.zeros_like(x)
    f = forces(model, evaluation(model, rest_state(model), zero_control(model), x))  # at rest: no dashpot force
    eps = 1e-5
    for node, k in [(5, 0), (100, 1), (200, 2), (150, 0)]:
        y, z = x.copy(), x.copy()
        y[node, k] += eps
        z[node, k] -= eps
        grad = (mechanical_energy(model, y, zero) - mechanical_energy(model, z, zero)) / (2 * eps)
        assert -grad == pytest.approx(f[node, k], rel=2e-4, abs=1e-3)


def test_consistent_mass_carries_the_tongue_mass(model, cfg):
    total = cfg.materials.tongue.density_g_cm3 * model.mesh.volume
    assert model.node_mass.sum() == pytest.approx(total, rel=1e-12)
    m = model.mass.toarray()
    assert np.allclose(m, m.T) and (np.count_nonzero(m - np.diag(np.diag(m))) > 0)  # not lumped
    assert np.linalg.eigvalsh(m).min() > 0


def test_calibrated_lattice_has_table_i_modulus_and_poisson_ratio():
    scale, ratio = calibrate(0.49, True, 1.0)
    e, nu = lattice_response(ratio)
    assert e * scale == pytest.approx(1.0, rel=1e-6)
    assert nu == pytest.approx(0.49, abs=1e-6)
    # the volume-constraint gain tightens volume, keeping E
    s8, r8 = calibrate(0.49, True, 8.0)
    assert lattice_response(r8)[0] * s8 == pytest.approx(1.0, rel=1e-6)
    assert 0.49 < effective_poisson(0.49, True, 8.0) < 0.5


def test_isotropy_correction_removes_the_brick_shape_bias():
    """A pure truss on 2:1 bricks: stiffness along and across the long axis."""
    mesh = cuboid_mesh([2.0, 1.0, 1.0], [1, 1, 1])
    d = mesh.nodes[mesh.cylinders[:, 1]] - mesh.nodes[mesh.cylinders[:, 0]]
    length = np.linalg.norm(d, axis=1)
    g = moment_matrix(d / length[:, None])
    exps = [(4, 0, 0), (0, 4, 0)]
    from artic_cli.mechanics.isotropy import _EXPONENTS

    rows = [int(np.flatnonzero((_EXPONENTS == e).all(axis=1))[0]) for e in exps]
    paper = g[rows] @ (mesh.areas * length)
    iso = g[rows] @ (isotropic_areas(mesh.nodes, mesh.bricks)[0] * length)
    assert paper[0] / paper[1] > 2.0  # the paper's rule: much stiffer along x
    assert abs(iso[0] / iso[1] - 1.0) < abs(paper[0] / paper[1] - 1.0) / 3



def _slack_links(delta=0.01, n=400):
    strain = np.linspace(-0.05, 0.05, n)
    cyl = elements.CylinderSet(i=np.zeros(n, dtype=np.int64), j=np.ones(n, dtype=np.int64), l0=np.full(n, 1.5),
                               area0=np.full(n, 0.3), youngs=np.full(n, 2.0e5), viscosity=np.zeros(n),
                               poisson=np.zeros(n), knee=np.full(n, np.inf), rate=np.zeros(n), n_nodes=2,
                               slack=np.full(n, delta))
    return cyl, strain


@pytest.mark.parametrize("delta", [0.01, -0.01])
def test_a_slack_link_bears_one_side_fully_and_levels_off_on_the_other(delta):
    # delta > 0: pushes fully, its pull levels off (the floor); delta < 0: pulls fully, its push levels off (straps)
    cyl, strain = _slack_links(delta)
    e, de = elements.youngs_modulus(cyl, strain)
    tension = e * strain * cyl.area0
    full = cyl.youngs * cyl.area0
    whole = strain * delta <= 0
    assert np.allclose(tension[whole], full[whole] * strain[whole])  # the side it bears: the whole spring
    assert np.all(np.diff(tension) >= -1e-9)  # monotone: no negative stiffness for Newton
    assert np.allclose(tension[strain / delta >= 1], full[0] * delta / 2)  # the ceiling, E0 A d / 2
    assert np.abs(tension[~whole]).max() <= full[0] * abs(delta) / 2 * (1 + 1e-12)
    # the tangent the integrator uses is the derivative of the tension, across both joints (0 and d)
    cs = elements.CylinderState(n=np.tile([1.0, 0, 0], (len(strain), 1)), length=cyl.l0 * (1 + strain),
                                strain=strain, elastic=tension, shrink=np.ones_like(strain), e=e, de=de)
    numeric = np.gradient(tension, strain * cyl.l0[0])
    inner = (np.abs(strain) > 2e-3) & (np.abs(strain - delta) > 2e-3)
    assert np.allclose(elements.axial_stiffness(cyl, cs)[inner], numeric[inner], rtol=1e-3, atol=1e-6 * full[0])


@pytest.mark.parametrize("delta", [0.005, -0.005])
def test_a_slack_link_gives_the_same_numbers_compiled_and_in_numpy_and_its_energy_integrates_its_tension(delta):
    cyl, strain = _slack_links(delta)
    x = np.zeros((2, 3))  # one link along x
    for s in (-0.03, -0.004, -0.002, 0.002, 0.004, 0.02):
        x[1] = [1.5 * (1 + s), 0, 0]
        one = elements.CylinderSet(**{f: getattr(cyl, f)[:1] for f in ("i", "j", "l0", "area0", "youngs",
                                                                      "viscosity", "poisson", "knee", "rate")},
                                   n_nodes=2, slack=cyl.slack[:1])
        a, b = elements.evaluate(one, x), elements.evaluate_numpy(one, x)
        assert a.elastic == pytest.approx(b.elastic, rel=1e-12) and a.e == pytest.approx(b.e, rel=1e-12)
        assert a.de == pytest.approx(b.de, rel=1e-12)
    w = elements.strain_energy(cyl, strain)
    e, _ = elements.youngs_modulus(cyl, strain)
    tension = e * strain * cyl.area0
    scale = np.abs(tension).max()
    assert np.allclose(np.gradient(w, strain * cyl.l0[0])[1:-1], tension[1:-1], rtol=2e-3, atol=1e-3 * scale)


def test_the_floor_links_go_slack_only_when_the_config_says_so(cfg, mesh, wall):
    from artic_cli.geometry.anatomy import LINK_KINDS, build_body
    from artic_cli.mechanics.model import build_articulator

    n_floor = int((build_body(cfg, mesh).link_kind == LINK_KINDS.index("floor")).sum())
    springs = cfg.jaw.model_copy(update={"strap_slack_strain": None})  # the straps' own slack: the next test
    full = build_articulator(cfg.model_copy(update={"jaw": springs}), mesh, wall)
    slack = build_articulator(cfg.model_copy(update={"jaw": springs.model_copy(update={"floor_slack_strain": 0.005})}),
                              mesh, wall)
    assert np.isinf(full.springs.slack_strain).all() == (cfg.jaw.floor_slack_strain is None)
    assert np.isfinite(slack.springs.slack_strain).sum() == n_floor > 0
    assert np.allclose(slack.springs.slack_strain[np.isfinite(slack.springs.slack_strain)], 0.005)


def test_the_straps_pull_only_when_the_config_says_so(cfg, mesh, wall):
    from artic_cli.geometry.anatomy import LINK_KINDS, build_body
    from artic_cli.mechanics.model import build_articulator

    body = build_body(cfg, mesh)
    straps = {tuple(sorted(p)) for p, k in zip(body.links.tolist(), body.link_kind) if k == LINK_KINDS.index("strap")}
    jaw = cfg.jaw.model_copy(update={"strap_slack_strain": 0.004, "floor_slack_strain": None})
    model = build_articulator(cfg.model_copy(update={"jaw": jaw}), mesh, wall)
    d = model.springs.slack_strain
    pairs = [tuple(sorted(p)) for p in zip(model.springs.i.tolist(), model.springs.j.tolist())]
    assert len(straps) == 4 and {p for p, v in zip(pairs, d) if np.isfinite(v)} == straps
    assert np.allclose(d[np.isfinite(d)], -0.004)  # negative: the push side gives way


def test_the_sling_links_take_their_own_area_only_when_the_config_gives_one(cfg, mesh, wall):
    from artic_cli.geometry.anatomy import LINK_KINDS, build_body
    from artic_cli.mechanics.model import build_articulator

    body = build_body(cfg, mesh, floor_on_mylohyoid=True)
    kind = {tuple(sorted(p)): k for p, k in zip(body.links.tolist(), body.link_kind)}
    floor, sling = LINK_KINDS.index("floor"), LINK_KINDS.index("sling")

    def areas(**jaw):
        model = build_articulator(cfg.model_copy(update={"jaw": cfg.jaw.model_copy(update={
            "floor_on_mylohyoid": True, "floor_link_area_cm2": 0.3, **jaw})}), mesh, wall)
        pairs = [tuple(sorted(p)) for p in zip(model.springs.i.tolist(), model.springs.j.tolist())]
        a = model.springs.area0
        return ({round(float(v), 9) for p, v in zip(pairs, a) if kind.get(p) == floor},
                {round(float(v), 9) for p, v in zip(pairs, a) if kind.get(p) == sling})

    assert areas(sling_link_area_cm2=None) == ({0.3}, {0.3})
    assert areas(sling_link_area_cm2=1.2) == ({0.3}, {1.2})


@pytest.mark.parametrize("delta", [0.01, -0.01])
def test_a_slack_link_damps_in_proportion_to_its_tangent_on_the_side_it_gives_way(delta):
    cyl, strain = _slack_links(delta, n=5)
    cyl = elements.CylinderSet(**{f: getattr(cyl, f) for f in ("i", "j", "l0", "area0", "youngs", "poisson", "knee",
                                                              "rate")}, viscosity=np.full(5, 3.0), n_nodes=2,
                               slack=cyl.slack)
    for s, share in ((-0.5 * delta, 1.0), (0.0, 1.0), (0.5 * delta, 0.5), (delta, 0.0), (3 * delta, 0.0)):
        x = np.array([[0.0, 0, 0], [1.5 * (1 + s), 0, 0]])
        one = elements.CylinderSet(**{f: getattr(cyl, f)[:1] for f in ("i", "j", "l0", "area0", "youngs", "viscosity",
                                                                      "poisson", "knee", "rate")},
                                   n_nodes=2, slack=cyl.slack[:1])
        full = 3.0 * 0.3 / 1.5
        assert elements.damping_frame(one, x).c[0] == pytest.approx(share * full, abs=1e-12)
