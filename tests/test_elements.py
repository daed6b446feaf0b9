"""Cylinders, volume constraint, mass and calibration."""

import numpy as np
import pytest

from artic_cli.geometry.mesh import cuboid_mesh
from artic_cli.mechanics import elements
from artic_cli.mechanics.calibration import calibrate, effective_poisson, lattice_response
from artic_cli.mechanics.integrator import internal_forces
from artic_cli.mechanics.isotropy import isotropic_areas, moment_matrix
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
    f, *_ = internal_forces(model, x)
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


def test_compiled_kernels_give_the_numpy_numbers(art):
    """The numba loops (cylinders, bricks, guard) reproduce the numpy path, including a guarded corner."""
    from artic_cli.mechanics import elements, kernels
    from artic_cli.mechanics.integrator import internal_forces, tangent
    from artic_cli.mechanics.muscles import fibre_state

    if not kernels.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    rng = np.random.default_rng(3)
    x = art.rest + rng.normal(0, 0.05, art.rest.shape)
    b = art.bricks[7]
    x[b[6]] = x[b[0]] + 0.2 * (x[b[6]] - x[b[0]])  # squash one brick so that the guard acts
    v = rng.normal(0, 1.0, x.shape)
    frame = elements.damping_frame(art.springs, art.rest)
    act = np.full(len(art.muscle_names), 2.0e5)
    ms = art.muscles
    out = {}
    for flag in (False, True):
        elements.USE_KERNELS = flag
        try:
            f, cs, vol, grad, guard = internal_forces(art, x, v, frame)
            fs = fibre_state(ms, x, act, np.zeros(ms.n_fibres), np.zeros(ms.n_fibres), 0.005)
            k = tangent(art, cs, frame, grad, fs, act, 0.005, 8e4, 367.0)
        finally:
            elements.USE_KERNELS = True
        out[flag] = (f, vol, grad, guard, k.band, k.b, k.c)
    assert out[True][3] is not None and len(out[True][3][0]) == len(out[False][3][0]) > 0
    for a, c in zip(out[False], out[True]):
        if isinstance(a, tuple):
            for p, q in zip(a, c):
                assert np.allclose(p, q, rtol=1e-10, atol=1e-12)
        else:
            assert np.allclose(a, c, rtol=1e-10, atol=1e-9 * np.abs(a).max())


def test_node_level_assembly_is_t_transpose_k_t_of_the_element_blocks(art):
    """Random symmetric element blocks (cylinders and links, bricks, fibre segments) summed per node pair and
    folded to flat storage give the stored parts of T^T K T, K assembled densely element by element."""
    from artic_cli.mechanics.assembly import pair_blocks, sparse_blocks

    rng = np.random.default_rng(11)
    n, asm, pat, ms = art.n_nodes, art.assembly, art.pattern, art.muscles

    def sym(k):
        a = rng.normal(size=(k, 3, 3))
        return a + a.transpose(0, 2, 1)

    k_cyl, k_seg = sym(len(art.springs.i)), sym(len(ms.seg_i))
    grad, w = rng.normal(size=(len(art.bricks), 8, 3)), rng.uniform(0.5, 2.0, len(art.bricks))
    blocks = asm.blocks(n, (art.springs.i, art.springs.j), k_cyl, art.bricks, grad, w, (ms.seg_i, ms.seg_j), k_seg)
    mat = pat.unpack(asm.operator @ blocks.ravel())
    g = grad.reshape(len(w), 24)
    dense = (sparse_blocks(np.column_stack([art.springs.i, art.springs.j]), pair_blocks(k_cyl), n)
             + sparse_blocks(art.bricks, w[:, None, None] * g[:, :, None] * g[:, None, :], n)
             + sparse_blocks(np.column_stack([ms.seg_i, ms.seg_j]), pair_blocks(k_seg), n))
    t = pat.reduce.toarray()
    want = t.T @ dense.toarray() @ t
    nc, u = pat.n_core, pat.u
    i, j = np.triu_indices(nc)
    inside = j - i <= u
    assert np.abs(want[:nc, :nc][np.abs(np.subtract.outer(np.arange(nc), np.arange(nc))) > u]).max() == 0.0
    scale = np.abs(want).max()
    assert np.allclose(mat.band[u + i[inside] - j[inside], j[inside]], want[i[inside], j[inside]], atol=1e-12 * scale)
    assert np.allclose(mat.b, want[:nc, nc:], atol=1e-12 * scale)
    assert np.allclose(mat.c, want[nc:, nc:], atol=1e-12 * scale)
    assert len(art.carried.nodes) > 0 and pat.n_border > 0  # folding and border were exercised


def test_compiled_fibre_and_wall_kernels_give_the_numpy_numbers(art):
    """Fibre tensions and forces, and the closest wall points, are the same with and without numba."""
    from artic_cli.mechanics import contact, elements, kernels
    from artic_cli.mechanics.muscles import fibre_state, muscle_forces

    if not kernels.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    rng = np.random.default_rng(5)
    x = art.rest + rng.normal(0, 0.05, art.rest.shape)
    act = np.full(len(art.muscle_names), 2.0e5)
    ms, cm = art.muscles, art.contact
    out = {}
    for flag in (False, True):
        elements.USE_KERNELS = flag
        try:
            fs = fibre_state(ms, x, act, np.zeros(ms.n_fibres), np.zeros(ms.n_fibres), 0.005)
            near = contact.wall_query(cm, x)
        finally:
            elements.USE_KERNELS = True
        out[flag] = (fs.n, fs.strain, fs.tension, muscle_forces(ms, fs), *near)
    for a, c in zip(out[False], out[True]):
        assert np.allclose(a, c, rtol=1e-12, atol=1e-12)
    assert np.ptp(out[True][-2]) > 0.1  # the gaps differ from node to node: a real query


def test_wall_query_finds_the_closest_wall_point_exactly(art):
    """The voxel candidate lists never miss the closest triangle: against a brute-force search over every
    triangle (the mandible's moved rigidly with a 6 degree jaw rotation), for points scattered around the
    tongue surface and some outside the grids."""
    from scipy.spatial.transform import Rotation

    from artic_cli.geometry.wall import PARTS
    from artic_cli.mechanics import contact

    cm = art.contact
    rng = np.random.default_rng(7)
    x = art.rest.copy()
    pivot = x[cm.jaw_nodes].mean(axis=0)
    turn = Rotation.from_euler("z", -6.0, degrees=True).as_matrix()
    x[cm.jaw_nodes] = (x[cm.jaw_nodes] - pivot) @ turn.T + pivot
    r, t = contact.rigid_motion(cm.jaw_rest, x[cm.jaw_nodes])
    corners = cm.corners.copy()
    jaw = cm.wall.part == PARTS.index("mandible")
    corners[jaw] = corners[jaw] @ r.T + t
    outside = 0
    for _ in range(40):
        y = x.copy()
        y[cm.nodes] += rng.normal(0.0, 0.5, (len(cm.nodes), 3))
        y[cm.nodes[:3]] += 4.0  # beyond the grids' reach
        q, _, _, _ = contact.wall_query(cm, y)
        p = y[cm.nodes]
        k = len(corners)
        near = contact.closest_on_triangles(np.repeat(p, k, axis=0), *(np.tile(corners[:, i], (len(p), 1))
                                                                          for i in range(3)))
        best = np.linalg.norm(near.reshape(len(p), k, 3) - p[:, None], axis=2).min(axis=1)
        assert np.linalg.norm(q - p, axis=1) == pytest.approx(best, abs=1e-9)
        cell = np.floor((p - cm.fixed_grid.lo) / cm.fixed_grid.spacing)
        outside += int(((cell < 0) | (cell >= cm.fixed_grid.dims)).any(axis=1).sum())
    assert outside >= 40 * 3  # the brute-force fallback was exercised too


def test_compiled_candidate_grid_lists_the_numpy_candidates(art):
    """The compiled grid builder (bounding spheres) and the numpy one (KD-tree balls) list the same triangles
    for every voxel."""
    from artic_cli.mechanics import contact, elements, kernels

    if not kernels.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    cm = art.contact
    lo, hi = cm.fixed_grid.lo, cm.fixed_grid.lo + cm.fixed_grid.spacing * cm.fixed_grid.dims
    grids = {}
    for flag in (False, True):
        elements.USE_KERNELS = flag
        try:
            grids[flag] = contact.candidate_grid(cm.corners, cm.jaw_grid.tris, lo, hi)
        finally:
            elements.USE_KERNELS = True
    assert np.array_equal(grids[False].offsets, grids[True].offsets)
    assert np.array_equal(grids[False].cands, grids[True].cands)
    assert 3 < len(grids[True].cands) / (len(grids[True].offsets) - 1) < 60  # a real short list per voxel


def test_carried_points_move_rigidly_with_the_mandible(art):
    """Incisor, muscle origins and the tongue's GG origin line keep their distances to the mandible's nodes
    through a jaw-opening simulation, and the incisor stays in the midsagittal plane."""
    from artic_cli.mechanics.loads import muscle_force_vector
    from artic_cli.mechanics.model import Control
    from artic_cli.mechanics.simulate import run, settle

    rest = settle(art)
    ctl = Control(node_force=np.zeros((art.n_nodes, 3)), muscle_force=muscle_force_vector(art, {"JO": 3.0, "SG": 4.0}))
    traj, end = run(art, rest, lambda t: ctl, 0.1)
    car = art.carried
    jaw = art.node_set("mandible")
    before = np.linalg.norm(rest.x[car.nodes][:, None] - rest.x[jaw][None], axis=2)
    after = np.linalg.norm(end.x[car.nodes][:, None] - end.x[jaw][None], axis=2)
    moved = np.linalg.norm(end.x[art.node_set("jaw")] - rest.x[art.node_set("jaw")])
    assert moved > 0.1  # the jaw did open
    assert np.abs(after - before).max() < 1e-3  # rigid: only the mandible links' own strain
    assert abs(end.x[art.node_set("jaw")][0, 2]) < 1e-3
