"""The muscle routing: bilateral muscles stay on their own side."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.errors import ArticError
from artic_cli.geometry.anatomy import build_body


@pytest.mark.parametrize("muscle", ["SG", "HG", "IL", "MH", "GH", "posterior_digastric", "masseter"])
def test_a_bilateral_muscle_never_crosses_the_midline(cfg, muscle):
    body = build_body(cfg)
    sides = []
    for fibre in body.fibres[muscle]:
        z = body.nodes[fibre, 2]
        off = z[np.abs(z) > 1e-9]  # midsagittal nodes (MH's and GH's tongue ends) belong to both sides
        if not len(off) and muscle == "IL" and cfg.muscles.il_midsagittal:
            continue  # IL's midsagittal fibre
        assert len(off) and (np.all(off > 0) or np.all(off < 0)), (muscle, z)
        sides.append(np.sign(off[0]))
    assert sides.count(1.0) == sides.count(-1.0)  # as many fibres left as right


def test_the_anterior_digastric_ends_at_the_sling_or_runs_on_to_the_mastoid(cfg):
    paper, through = build_body(cfg), build_body(cfg, digastric_through_sling=True)
    fixed = set(through.fixed.tolist())
    for a, b in zip(paper.fibres["anterior_digastric"], through.fibres["anterior_digastric"]):
        assert len(a) == 2 and len(b) == 3 and np.array_equal(a, b[:2])
        assert {int(b[1]), int(b[2])} <= fixed  # sling and mastoid: the added segment never changes length
        post = [f for f in through.fibres["posterior_digastric"] if np.sign(through.nodes[f[0], 2]) == np.sign(
            through.nodes[b[2], 2])]
        assert int(b[2]) == int(post[0][0])  # the mastoid end of the same side's posterior belly


def test_a_sling_on_the_hyoid_passes_the_digastric_through_the_hyoid_body(cfg):
    fixed, loop = (build_body(cfg, digastric_through_sling=True, digastric_sling=k) for k in ("fixed", "hyoid"))
    body_ends = set(loop.hyoid[:2].tolist())
    for a, b in zip(fixed.fibres["anterior_digastric"], loop.fibres["anterior_digastric"]):
        assert int(a[1]) in set(fixed.fixed.tolist()) and int(b[1]) in body_ends  # a skull point, then the hyoid's
        assert int(b[1]) not in set(loop.fixed.tolist())  # ... which moves
        np.testing.assert_allclose(fixed.nodes[a[1]], loop.nodes[b[1]])  # at the same rest place
        assert np.sign(loop.nodes[b[1], 2]) == np.sign(loop.nodes[b[0], 2])  # on the fibre's own side
    assert len(loop.nodes) == len(fixed.nodes) - 2  # no skull points for the sling


def test_verticalis_extent_and_a_midsagittal_il_follow_the_config(cfg):
    body = build_body(cfg, verticalis_sections=6, il_midsagittal=True)
    paper = build_body(cfg)
    assert len(body.fibres["V"]) == 3 * 6 and len(paper.fibres["V"]) == 3 * 4  # one fibre per plane and section
    mid = [f for f in body.fibres["IL"] if np.allclose(body.nodes[f, 2], 0.0)]
    assert len(body.fibres["IL"]) == 3 and len(mid) == 1 and len(paper.fibres["IL"]) == 2
    with pytest.raises(ArticError, match="muscles.verticalis_sections"):
        build_body(cfg, verticalis_sections=11)


def test_verticalis_depth_follows_the_config(cfg):
    """Each verticalis fibre runs down its radial line from the surface to muscles.verticalis_to_level."""
    nc = cfg.speaker.tongue.concentric_sections
    for level in (3, 1):
        body = build_body(cfg, verticalis_to_level=level)
        assert all(len(f) == nc - level + 1 for f in body.fibres["V"])
        r = np.linalg.norm(body.nodes[[f[-1] for f in body.fibres["V"]], :2] - cfg.speaker.tongue.gg_origin_cm, axis=1)
        top = np.linalg.norm(body.nodes[[f[0] for f in body.fibres["V"]], :2] - cfg.speaker.tongue.gg_origin_cm, axis=1)
        assert np.all(r < top)  # downward, toward the GG origin
    with pytest.raises(ArticError, match="muscles.verticalis_to_level"):
        build_body(cfg, verticalis_to_level=nc)


def test_the_mandible_carries_the_gg_tendon_in_every_plane_or_in_the_midline_only(cfg):
    every, mid = build_body(cfg), build_body(cfg, gg_tendon="midsagittal")
    anchor = every.mesh.node_sets["anchor"]
    n_lines = cfg.speaker.tongue.radial_sections + 1
    held_every = np.intersect1d(every.carried, anchor)
    held_mid = np.intersect1d(mid.carried, anchor)
    assert len(held_every) == 3 * n_lines and len(held_mid) == n_lines
    assert np.allclose(mid.nodes[held_mid, 2], 0.0)  # the genial tubercle's plane
    assert np.array_equal(np.setdiff1d(every.carried, anchor), np.setdiff1d(mid.carried, anchor))  # bones alike


def test_the_floor_hangs_from_the_mylohyoid_lines_when_asked(cfg, mesh):
    """jaw.floor_on_mylohyoid: each floor node also linked to its two nearest mylohyoid points, which lie
    above it (a sling in tension, not a strut), mirrored left to right."""
    from artic_cli.geometry.anatomy import LINK_KINDS, build_body

    kinds = {on: build_body(cfg, mesh, floor_on_mylohyoid=on) for on in (False, True)}
    floor, sling = LINK_KINDS.index("floor"), LINK_KINDS.index("sling")
    plain = kinds[False].links[kinds[False].link_kind == floor]
    body = kinds[True]
    assert (body.links[body.link_kind == floor] == plain).all() and not (kinds[False].link_kind == sling).any()
    myl = {body.names[f"mylohyoid_{p}_{s}"] for p in ("front", "mid", "back") for s in ("l", "r")}
    added = body.links[body.link_kind == sling]
    assert len(added) == len(plain) and set(added[:, 1].tolist()) <= myl
    assert (body.nodes[added[:, 1], 1] > body.nodes[added[:, 0], 1] + 0.5).all()  # each point above its node
    assert np.isclose(body.nodes[added[:, 1], 2].sum(), 0.0)  # left and right alike


def test_styloglossus_follows_its_configured_routes(cfg, mesh):
    """muscles.styloglossus: each fibre runs styloid -> entry node -> forward along its level, per side; a
    route that leaves the tongue or runs backward is named."""
    from artic_cli.config import Muscles, StyloglossusFibre
    from artic_cli.geometry.mesh import tongue_node_index

    nr, nc, _ = mesh.grid
    routes = cfg.muscles.styloglossus
    body = build_body(cfg, mesh, sg_routes=routes)
    paper = build_body(cfg, mesh)  # the schema's routes
    assert len(body.fibres["SG"]) == 2 * len(routes) and len(paper.fibres["SG"]) == 2 * len(Muscles().styloglossus)
    styloid = {body.names["styloid_l"], body.names["styloid_r"]}
    for fibre, route in zip(body.fibres["SG"][:len(routes)], routes):  # the left side's fibres come first
        assert int(fibre[0]) in styloid
        k, j, p = (np.asarray(a) for a in np.unravel_index(fibre[1:], (nr, nc, 3)))
        assert (k[0], j[0]) == tuple(route.entry) and (j[1:] == route.level).all()
        assert list(k[1:]) == list(range(route.radials[0], route.radials[1] - 1, -1)) and len(set(p)) == 1
        assert np.array_equal(fibre[1:], tongue_node_index(k, j, p, nc - 1))
    with pytest.raises(ArticError, match=r"muscles.styloglossus\[0\].entry leaves the tongue"):
        build_body(cfg, mesh, sg_routes=[StyloglossusFibre(entry=(nr, 2), level=2, radials=(3, 1))])
    with pytest.raises(ValueError, match="run backward"):
        StyloglossusFibre(entry=(7, 5), level=2, radials=(1, 6))


def test_il_route_follows_the_config(cfg):
    """IL from muscles.inferior_longitudinalis.start up to its level, forward along it, up the tip line."""
    from artic_cli.config import InferiorLongitudinalis
    from artic_cli.geometry.mesh import tongue_node_index

    nc = cfg.speaker.tongue.concentric_sections
    node = lambda k, j, p: int(tongue_node_index(k, j, p, nc))  # noqa: E731
    old = build_body(cfg).fibres["IL"][0]  # the key's default: along level 2 from radial 10
    p = int(old[0]) % 3  # the first fibre's plane (node numbers run plane fastest)
    assert list(old) == [node(k, 2, p) for k in range(10, 0, -1)] + [node(0, j, p) for j in range(3, nc + 1)]
    low = build_body(cfg, il_route=InferiorLongitudinalis(start=(8, 0), level=1)).fibres["IL"][0]
    assert list(low) == [node(8, 0, p)] + [node(k, 1, p) for k in range(8, 0, -1)] + [
        node(0, j, p) for j in range(2, nc + 1)]
    with pytest.raises(ValueError, match="start level 3 lies above"):
        InferiorLongitudinalis(start=(8, 3), level=1)
    with pytest.raises(ArticError, match="muscles.inferior_longitudinalis"):
        build_body(cfg, il_route=InferiorLongitudinalis(start=(11, 0), level=1))


def test_a_straight_il_runs_from_its_start_to_the_tip_near_the_chord(cfg):
    """path: straight: one node per radial line from the start to the tip, each the line's node nearest the
    chord, so the fibre bends less than the level route does."""
    from artic_cli.config import InferiorLongitudinalis
    from artic_cli.geometry.mesh import tongue_node_index

    nc = cfg.speaker.tongue.concentric_sections
    body = build_body(cfg, il_route=InferiorLongitudinalis(start=(8, 3), path="straight"))
    for fibre in body.fibres["IL"]:
        k, j, p = (np.asarray(a) for a in np.unravel_index(fibre, (cfg.speaker.tongue.radial_sections + 1, nc + 1, 3)))
        assert list(k) == list(range(8, -1, -1)) and len(set(p)) == 1
        assert (k[0], j[0]) == (8, 3) and (k[-1], j[-1]) == (0, nc)  # the start, then the tip (surface node)
        x = body.nodes[fibre]
        d = (x[-1] - x[0]) / np.linalg.norm(x[-1] - x[0])
        off = np.linalg.norm(np.cross(x - x[0], d), axis=1)
        for kk, jj, o in zip(k[1:-1], j[1:-1], off[1:-1]):  # no other node of its radial line lies nearer
            others = body.nodes[tongue_node_index(kk, np.arange(nc + 1), p[0], nc)]
            assert o <= np.linalg.norm(np.cross(others - x[0], d), axis=1).min() + 1e-12
        assert off.max() < 0.3  # cm: within about half a brick of the chord
    level = build_body(cfg, il_route=InferiorLongitudinalis(start=(8, 3), level=3)).fibres["IL"][0]
    x = body.nodes[level]
    d = (x[-1] - x[0]) / np.linalg.norm(x[-1] - x[0])
    assert np.linalg.norm(np.cross(x - x[0], d), axis=1).max() > 0.5  # the level route arcs round the tendon
    InferiorLongitudinalis(start=(8, 3), level=1, path="straight")  # the level is unused: no complaint
