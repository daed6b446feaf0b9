"""Mirror symmetry: solving one half of the articulator gives the whole one's motion."""

import numpy as np
import pytest

from artic_cli.errors import ArticError
from artic_cli.geometry.mirror import mirror_images


@pytest.fixture(scope="module")
def pair(art_whole, art_half):
    return art_whole, art_half


def test_every_node_has_its_mirror_image(art):
    image = mirror_images(art.rest, art.names)
    assert (image[image] == np.arange(art.n_nodes)).all()
    assert np.allclose(art.rest[image], art.rest * [1.0, 1.0, -1.0], atol=1e-9)
    assert image[art.names["condyle_l"]] == art.names["condyle_r"]
    on_plane = np.flatnonzero(image == np.arange(art.n_nodes))
    assert len(on_plane) > 0 and np.abs(art.rest[on_plane, 2]).max() < 1e-9


def test_a_lopsided_body_is_refused(art):
    nodes = art.rest.copy()
    nodes[5, 2] += 0.1
    with pytest.raises(ArticError, match="not left-right symmetric.*mirror_symmetry: false"):
        mirror_images(nodes, art.names)


def test_the_half_has_fewer_unknowns_and_a_narrower_band(pair):
    whole, half = pair
    assert half.layout.pattern.n_free < 0.65 * whole.layout.pattern.n_free
    assert half.layout.pattern.u < whole.layout.pattern.u
    t = half.layout.pattern.reduce.toarray()
    x = np.random.default_rng(2).normal(size=half.layout.pattern.n_free)
    moved = (t @ x).reshape(-1, 3)  # any move of the free dofs is mirror-symmetric (the carried points are so
    image = mirror_images(half.rest, half.names)  # only for the mandible's rigid moves)
    own = np.setdiff1d(np.arange(half.n_nodes), half.carried.nodes)
    assert np.allclose(moved[image[own]], moved[own] * [1.0, 1.0, -1.0], atol=1e-12)
    plane = own[image[own] == own]
    assert len(plane) > 0 and np.abs(moved[plane, 2]).max() == 0.0 and np.abs(moved[own]).max() > 0.1


def test_the_half_moves_as_the_whole_with_contact(pair):
    """Jaw opening with SG and GGp against the wall (contact on), 100 ms: the same nodes within the Newton
    tolerance's reach, and the whole articulator itself stays mirror-symmetric (its wall reaction on the mandible
    is spread over an uneven set of bone nodes, the only lopsided thing in it)."""
    from artic_cli.mechanics.loads import muscle_force_vector
    from artic_cli.mechanics.model import Control
    from artic_cli.mechanics.simulate import run, settle

    ends = []
    for art in pair:
        rest = settle(art)
        ctl = Control(node_force=np.zeros((art.n_nodes, 3)),
                      muscle_force=muscle_force_vector(art, {"JO": 2.0, "SG": 4.0, "GGp": 1.0}))
        _, end = run(art, rest, lambda t: ctl, 0.1)
        ends.append(end.x)
    whole, half = ends
    image = mirror_images(pair[0].rest, pair[0].names)
    assert np.abs(whole[image] * [1.0, 1.0, -1.0] - whole).max() < 2e-3  # 0.0008 cm measured
    assert np.abs(half - whole).max() < 2e-3  # 0.0012 cm measured
    assert np.abs(whole - pair[0].rest).max() > 0.3  # it did move


def test_a_sideways_load_on_a_halved_articulator_is_refused(art_half, art_whole):
    from artic_cli.mechanics.loads import control_from_newtons

    with pytest.raises(ArticError, match="not left-right symmetric.*mirror_symmetry: false"):
        control_from_newtons(art_half, {"SL": 4.0}, loads_n={"tip": (0.0, 0.0, 0.2)})
    control_from_newtons(art_half, {"SL": 4.0}, loads_n={"tip": (0.1, -0.2, 0.0)})  # in the plane: symmetric
    control_from_newtons(art_whole, {"SL": 4.0}, loads_n={"tip": (0.0, 0.0, 0.2)})


def test_the_dorsum_pressed_on_the_palate_stays_mirrored(pair):
    """6 N up on the dorsum for 200 ms: nodes slide along the palate, and the wall projects them every step.
    The halved articulator stays exactly symmetric (a mirrored node has no dofs, so a projection of its own
    would stay with it: it did, up to 3.5 cm, before the projection was mirrored) and with the whole one, whose
    wall is mirror-symmetric too (0.0002 cm apart; 0.037 cm while the wall's quads were all split along the
    same diagonal)."""
    from artic_cli.mechanics.loads import control_from_newtons
    from artic_cli.mechanics.simulate import run, settle

    ends = []
    for art in pair:
        ctl = control_from_newtons(art, loads_n={"dorsum_region": (-1.0, 6.0, 0.0)})
        traj, end = run(art, settle(art), lambda t: ctl, 0.2)
        ends.append(traj.x)
    whole, half = ends
    image = mirror_images(pair[0].rest, pair[0].names)
    # 0.00004 cm: the midsagittal nodes' projections move them off their plane, and the mandible's carried points
    # follow an uneven frame of four bone nodes (exact while the bone is rigid, its links strain a little)
    assert np.abs(half[:, image] * [1.0, 1.0, -1.0] - half).max() < 1e-4
    assert np.abs(half - whole).max() < 2e-3
    assert np.abs(whole[:, image] * [1.0, 1.0, -1.0] - whole).max() < 2e-3
    assert np.abs(whole[-1] - whole[0]).max() > 0.5  # it did move


def test_mirror_twin_fibres_enter_newton_as_one_term(art_half):
    """Every fibre has a mirror twin (itself when on or across the midline); a twin pair's folded length
    gradients are one column, so the rank-one part of Newton's matrix keeps one term of twice the stiffness
    and comes out the same as with every fibre on its own."""
    from dataclasses import replace

    from artic_cli.control.equilibrium import control_for
    from artic_cli.mechanics.integrator import evaluation, forces, step
    from artic_cli.mechanics.model import rest_state
    from artic_cli.mechanics.muscles import MuscleTerm

    twin = art_half.fibre_twin
    n = art_half.muscles.n_fibres
    assert twin is not None and (twin[twin] == np.arange(n)).all() and 0 < (twin == np.arange(n)).sum() < n
    ms = art_half.muscles
    assert (ms.fibre_muscle[twin] == ms.fibre_muscle).all() and np.allclose(ms.fibre_l0[twin], ms.fibre_l0)
    ctl = control_for(art_half, {"SG": 3.0, "HG": 2.0, "GGp": 1.0})
    s = rest_state(art_half)
    for _ in range(6):
        s = step(art_half, s, ctl)
    red_t = art_half.layout.pattern.reduce_t

    def fibre_columns(model):
        ev = evaluation(model, s, ctl, s.x)
        forces(model, ev)  # each term's part of the iterate
        return MuscleTerm().rank_one(model, ev)

    merged = fibre_columns(art_half)
    apart = fibre_columns(replace(art_half, fibre_twin=None))
    assert 0 < len(merged[1]) < len(apart[1])
    g1, g0 = red_t @ merged[0], red_t @ apart[0]
    a1, a0 = g1 @ np.diag(merged[1]) @ g1.T, g0 @ np.diag(apart[1]) @ g0.T
    assert np.abs(a1 - a0).max() <= 1e-9 * np.abs(a0).max()
