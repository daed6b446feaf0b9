"""Contact with the wall: compiled fibre and wall kernels, the exact closest-triangle query."""

import numpy as np
import pytest

from artic_cli import jit
from artic_cli.mechanics import wall_query


def test_compiled_fibre_and_wall_kernels_give_the_numpy_numbers(art):
    """Fibre tensions and forces, and the closest wall points, are the same with and without numba."""

    from artic_cli.mechanics.muscles import fibre_state, muscle_forces

    if not jit.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    rng = np.random.default_rng(5)
    x = art.rest + rng.normal(0, 0.05, art.rest.shape)
    act = np.full(len(art.muscle_names), 2.0e5)
    ms, cm = art.muscles, art.contact
    out = {}
    for flag in (False, True):
        jit.USE_KERNELS = flag
        try:
            fs = fibre_state(ms, x, act, np.zeros(ms.n_fibres), np.zeros(ms.n_fibres), 0.005)
            near = wall_query.wall_query(cm, x)
        finally:
            jit.USE_KERNELS = True
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

    cm = art.contact
    rng = np.random.default_rng(7)
    x = art.rest.copy()
    pivot = x[cm.jaw_nodes].mean(axis=0)
    turn = Rotation.from_euler("z", -6.0, degrees=True).as_matrix()
    x[cm.jaw_nodes] = (x[cm.jaw_nodes] - pivot) @ turn.T + pivot
    r, t = wall_query.rigid_motion(cm.jaw_rest, x[cm.jaw_nodes])
    corners = cm.corners.copy()
    jaw = cm.wall.part == PARTS.index("mandible")
    corners[jaw] = corners[jaw] @ r.T + t
    outside = 0
    for _ in range(40):
        y = x.copy()
        y[cm.nodes] += rng.normal(0.0, 0.5, (len(cm.nodes), 3))
        y[cm.nodes[:3]] += 4.0  # beyond the grids' reach
        q, _, _, _ = wall_query.wall_query(cm, y)
        p = y[cm.nodes]
        k = len(corners)
        near = wall_query.closest_on_triangles(np.repeat(p, k, axis=0), *(np.tile(corners[:, i], (len(p), 1))
                                                                          for i in range(3)))
        best = np.linalg.norm(near.reshape(len(p), k, 3) - p[:, None], axis=2).min(axis=1)
        assert np.linalg.norm(q - p, axis=1) == pytest.approx(best, abs=1e-9)
        cell = np.floor((p - cm.fixed_grid.lo) / cm.fixed_grid.spacing)
        outside += int(((cell < 0) | (cell >= cm.fixed_grid.dims)).any(axis=1).sum())
    assert outside >= 40 * 3  # the brute-force fallback was exercised too


def test_compiled_candidate_grid_lists_the_numpy_candidates(art):
    """The compiled grid builder (bounding spheres) and the numpy one (KD-tree balls) list the same triangles
    for every voxel."""

    if not jit.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    cm = art.contact
    lo, hi = cm.fixed_grid.lo, cm.fixed_grid.lo + cm.fixed_grid.spacing * cm.fixed_grid.dims
    grids = {}
    for flag in (False, True):
        jit.USE_KERNELS = flag
        try:
            grids[flag] = wall_query.candidate_grid(cm.corners, cm.jaw_grid.tris, lo, hi)
        finally:
            jit.USE_KERNELS = True
    assert np.array_equal(grids[False].offsets, grids[True].offsets)
    assert np.array_equal(grids[False].cands, grids[True].cands)
    assert 3 < len(grids[True].cands) / (len(grids[True].offsets) - 1) < 60  # a real short list per voxel



def test_the_wall_normal_turns_smoothly_round_a_seam_and_mirrors(art):
    """Points beyond the palate on either side of the wall's parasagittal seam (z = +-0.7 cm), mirror images of
    each other, get mirror-image normals, and the normal turns continuously as a point crosses the seam (the
    two triangles' own normals differ by 16 deg there); the signed gap is the distance to the wall."""

    cm = art.contact
    p = np.array([[-2.932, 1.70, z] for z in np.linspace(0.60, 0.80, 81)])  # 0.0025 cm apart across z = 0.7
    both = np.vstack([p, p * [1.0, 1.0, -1.0]])
    x = np.vstack([art.rest, both])
    idx = np.arange(len(art.rest), len(x))
    for flag in (True, False):
        jit.USE_KERNELS = flag
        try:
            q, n, g, _ = wall_query.wall_query(cm, x, idx)
        finally:
            jit.USE_KERNELS = True
        a, b = n[:len(p)], n[len(p):]
        assert np.allclose(b, a * [1.0, 1.0, -1.0], atol=1e-9)  # mirror points, mirror normals
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
        steps = np.degrees(np.arccos(np.clip((a[1:] * a[:-1]).sum(axis=1), -1.0, 1.0)))
        assert np.degrees(np.arccos(a[0] @ a[-1])) > 10.0 and steps.max() < 3.0  # it turns, without a jump
        assert (g > 0).all() and np.allclose(g, np.linalg.norm(x[idx] - q, axis=1), atol=1e-12)
