"""Assembly: compiled kernels against numpy, the node-level tangent, carried points."""

import numpy as np
import pytest

from artic_cli import jit


def test_compiled_kernels_give_the_numpy_numbers(art):
    """The numba loops (cylinders, bricks, guard, fibres) reproduce the numpy path, including a guarded corner:
    every term's forces, the banded tangent, fibre gradients and states."""
    from dataclasses import replace

    from artic_cli.mechanics.integrator import evaluation, forces, tangent
    from artic_cli.mechanics.model import Control, rest_state
    from artic_cli.mechanics.muscles import length_gradients, muscle_forces

    if not jit.AVAILABLE:
        pytest.skip("numba not installed: only the numpy path runs")
    rng = np.random.default_rng(3)
    x = art.rest + rng.normal(0, 0.05, art.rest.shape)
    b = art.bricks[7]
    x[b[6]] = x[b[0]] + 0.2 * (x[b[6]] - x[b[0]])  # squash one brick so that the guard acts
    v = rng.normal(0, 1.0, x.shape)
    ms = art.muscles
    start = replace(rest_state(art), sigma2=np.full(ms.n_fibres, 50.0), fibre_strain=np.full(ms.n_fibres, -0.01))
    ctl = Control(node_force=np.zeros_like(x), muscle_force=np.full(len(art.muscle_names), 2.0e5))
    out = {}
    for flag in (False, True):
        jit.USE_KERNELS = flag
        try:
            ev = evaluation(art, start, ctl, x, v, 0.005, 367.0)
            f = forces(art, ev)
            k = tangent(art, ev, 8e4)
            grad, guard = ev.parts["volume"]
            fs = ev.parts["muscles"]["fs"]
            lg = length_gradients(ms, fs, np.arange(0, ms.n_fibres, 7), art.n_nodes)
            fm = muscle_forces(ms, fs)
        finally:
            jit.USE_KERNELS = True
        out[flag] = (f, grad, guard, k.band, k.b, k.c, lg, fm, fs.seg_length, fs.strain, fs.sigma2, fs.tension)
    assert out[True][2] is not None and len(out[True][2][0]) == len(out[False][2][0]) > 0
    for a, c in zip(out[False], out[True]):
        if isinstance(a, tuple):
            for p, q in zip(a, c):
                assert np.allclose(p, q, rtol=1e-10, atol=1e-12)
        else:
            assert np.allclose(a, c, rtol=1e-10, atol=1e-9 * np.abs(a).max())


@pytest.mark.parametrize("which", ["art_whole", "art_half"])
def test_node_level_assembly_is_t_transpose_k_t_of_the_element_blocks(which, request):
    """Random symmetric element blocks (cylinders and links, bricks, fibre segments) summed per node pair and
    folded to flat storage give the stored parts of T^T K T, K assembled densely element by element; also when
    the left half's nodes are folded onto their mirror images."""
    from artic_cli.mechanics.assembly import pair_blocks, sparse_blocks

    art = request.getfixturevalue(which)
    rng = np.random.default_rng(11)
    n, asm, pat, ms = art.n_nodes, art.layout.assembly, art.layout.pattern, art.muscles

    def sym(k):
        a = rng.normal(size=(k, 3, 3))
        return a + a.transpose(0, 2, 1)

    k_cyl, k_seg = sym(len(art.springs.i)), sym(len(ms.seg_i))
    grad, w = rng.normal(size=(len(art.bricks), 8, 3)), rng.uniform(0.5, 2.0, len(art.bricks))
    blocks = np.zeros((asm.n_pairs + n, 3, 3))
    asm.add_pairs(blocks, art.springs.i, art.springs.j, asm.cyl_pair, k_cyl)
    asm.add_bricks(blocks, art.bricks, grad, w)
    asm.add_pairs(blocks, ms.seg_i, ms.seg_j, asm.seg_pair, k_seg)
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


def test_carried_points_move_rigidly_with_the_mandible(art):
    """Incisor, muscle origins and the tongue's GG origin line stay the same affine combination of the mandible's
    four frame nodes through a jaw-opening simulation, the frame deforms only by bone strain, and the incisor
    stays in the midsagittal plane."""
    from artic_cli.mechanics.loads import muscle_force_vector
    from artic_cli.mechanics.model import Control
    from artic_cli.mechanics.simulate import run, settle

    rest = settle(art)
    ctl = Control(node_force=np.zeros((art.n_nodes, 3)), muscle_force=muscle_force_vector(art, {"JO": 3.0, "SG": 4.0}))
    traj, end = run(art, rest, lambda t: ctl, 0.1)
    car = art.carried
    frame = car.masters[0]
    moved = np.linalg.norm(end.x[art.node_set("jaw")] - rest.x[art.node_set("jaw")])
    assert moved > 0.1  # the jaw did open
    placed = car.place(end.x.copy())
    assert np.abs(placed - end.x).max() < 1e-9  # exactly carried by the frame
    span = lambda x: np.linalg.norm(x[frame][:, None] - x[frame][None], axis=2)  # noqa: E731
    assert np.abs(span(end.x) - span(rest.x)).max() < 1e-3  # the frame itself: only the bone links' own strain
    assert abs(end.x[art.node_set("jaw")][0, 2]) < 1e-3

