"""The vocal-tract wall surface."""

import numpy as np

from artic_cli.geometry.wall import PARTS


def test_wall_spans_five_slices_with_unit_outward_normals(wall):
    zs = np.unique(np.round(wall.vertices[:, 2], 9))
    assert np.allclose(zs, [-1.4, -0.7, 0.0, 0.7, 1.4])
    assert np.allclose(np.linalg.norm(wall.normals, axis=1), 1.0)
    # away from the lumen: palate up, pharyngeal wall back, mandible (lingual surface) forward
    mean = {p: wall.normals[wall.part_mask(p)].mean(axis=0) for p in PARTS}
    assert mean["palate"][1] > 0.5
    assert mean["pharynx"][0] < -0.8
    assert mean["mandible"][0] > 0.5


def test_wall_is_symmetric(wall):
    mirrored = wall.vertices * np.array([1, 1, -1])
    # every vertex has its mirror image among the vertices
    d = np.linalg.norm(wall.vertices[:, None, :] - mirrored[None, :, :], axis=2).min(axis=1)
    assert d.max() < 1e-12
    # and every triangle its mirror image among the triangles (the quads' diagonals mirror each other), with
    # the mirrored normal: the contact forces on a symmetric body are symmetric
    image = np.abs(wall.vertices[:, None, :] - mirrored[None, :, :]).sum(axis=2).argmin(axis=1)
    tris = {tuple(sorted(t)): k for k, t in enumerate(wall.triangles.tolist())}
    twins = [tris.get(tuple(sorted(image[t]))) for t in wall.triangles]
    assert None not in twins
    assert np.allclose(wall.normals[twins], wall.normals * [1, 1, -1])


def test_rest_tongue_surface_lies_below_the_palate(mesh, wall):
    surf = mesh.nodes[mesh.node_sets["midsagittal_surface"]]
    pal = wall.vertices[wall.triangles[wall.part_mask("palate")].ravel()]
    pal = pal[np.isclose(pal[:, 2], 0.0)]
    for p in surf:
        near = pal[np.abs(pal[:, 0] - p[0]) < 0.3]
        if len(near):
            assert p[1] < near[:, 1].min() - 0.2
