"""The semicontinuum tongue mesh, the cylinder weighting rule and brick volumes."""

from itertools import combinations

import numpy as np
import pytest

from artic_cli.geometry.hexahedra import REF, corner_jacobians, volume_gradients, volumes
from artic_cli.geometry.mesh import cuboid_mesh


def test_tongue_has_120_bricks_and_231_nodes(mesh):
    assert mesh.nodes.shape == (231, 3)
    assert mesh.bricks.shape == (120, 8)
    assert mesh.grid == (11, 7, 3)
    assert set(np.unique(np.round(mesh.nodes[:, 2], 9))) == {-1.0, 0.0, 1.0}


def test_every_brick_holds_its_28_cylinders_merged_once(mesh):
    pairs = {tuple(p) for p in mesh.cylinders}
    assert len(pairs) == len(mesh.cylinders)  # no duplicates
    kinds = {"edge": 0, "face": 0, "body": 0}
    for b in mesh.bricks:
        for a, c in combinations(range(8), 2):
            assert tuple(sorted((b[a], b[c]))) in pairs
            differ = int(np.abs(REF[a] - REF[c]).sum() / 2)
            kinds[{1: "edge", 2: "face", 3: "body"}[differ]] += 1
    assert kinds == {"edge": 12 * 120, "face": 12 * 120, "body": 4 * 120}
    # interior sharing as in the paper: body diagonals 1 brick, face diagonals <= 2, edges <= 4
    assert mesh.share.max() == 4 and set(np.unique(mesh.share)) <= {1, 2, 4}


def test_cylinder_volumes_fill_the_tongue(mesh):
    assert mesh.volume > 20.0
    assert abs(mesh.cylinder_volume - mesh.volume) / mesh.volume < 1e-9


def test_bricks_are_positively_oriented(mesh):
    assert (corner_jacobians(mesh.nodes, mesh.bricks) > 0).all()


def test_control_points_are_surface_nodes_of_the_midsagittal_plane(mesh, cfg):
    tip = mesh.nodes[mesh.node_sets["tip"][0]]
    assert np.allclose(tip, [*cfg.speaker.tongue.midsagittal_outline_cm[0], 0.0])
    surface = mesh.node_sets["midsagittal_surface"]
    assert mesh.node_sets["dorsum"][0] == surface[4]  # fifth surface node from the tip
    assert mesh.nodes[surface[4], 1] > 0.5  # under the palate


def test_cuboid_geometry():
    c = cuboid_mesh([6.0, 3.0, 2.0], [5, 3, 2])
    assert c.nodes.shape == (72, 3) and c.bricks.shape == (30, 8)
    assert c.volume == pytest.approx(36.0, rel=1e-12)
    assert c.cylinder_volume == pytest.approx(36.0, rel=1e-12)


def test_brick_volume_is_exact_and_its_gradient_matches_finite_differences():
    rng = np.random.default_rng(1)
    box = (REF + 1) / 2 * np.array([2.0, 3.0, 4.0])
    assert volumes(box, np.arange(8)[None])[0] == pytest.approx(24.0, rel=1e-14)
    x = box + 0.2 * rng.standard_normal(box.shape)
    b = np.arange(8)[None]
    # exact: divergence theorem over the 6 bilinear faces, each split into 4 triangles by its centre
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    v, grad = volume_gradients(x, b)
    eps = 1e-6
    fd = np.zeros_like(x)
    for a in range(8):
        for k in range(3):
            y = x.copy()
            y[a, k] += eps
            z = x.copy()
            z[a, k] -= eps
            fd[a, k] = (volumes(y, b)[0] - volumes(z, b)[0]) / (2 * eps)
    assert np.abs(fd - grad[0]).max() < 1e-7
    # a flat-faced brick: trilinear volume equals the polyhedron's
    sheared = box @ np.array([[1, 0.3, 0], [0, 1, 0.2], [0, 0, 1.0]])
    poly = 0.0
    for f in faces:
        p = sheared[f]
        c = p.mean(axis=0)
        for i in range(4):
            poly += np.dot(c, np.cross(p[i], p[(i + 1) % 4])) / 6.0
    assert volumes(sheared, b)[0] == pytest.approx(abs(poly), rel=1e-12)
