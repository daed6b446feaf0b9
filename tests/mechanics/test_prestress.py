"""The drawn rest tongue carries its weight (materials.tongue.rest_under_gravity)."""

from __future__ import annotations

import numpy as np

from artic_cli.mechanics.model import build_articulator, build_model
from artic_cli.mechanics.prestress import carrying_tensions, equilibrium_operator, rest_lengths_for
from artic_cli.mechanics.simulate import settle


def _with(cfg, **tongue):
    return cfg.model_copy(update={"materials": cfg.materials.model_copy(
        update={"tongue": cfg.materials.tongue.model_copy(update=tongue)})})


def test_carrying_tensions_cancel_the_load_at_the_free_nodes(model):
    cyl, x = model.springs, model.rest
    load = model.node_mass[:, None] * np.array([0.0, -980.0, 0.0])
    free = np.where(~model.fixed.all(axis=1))[0]
    t = carrying_tensions(cyl, x, load, free)
    force = (equilibrium_operator(cyl, x) @ t).reshape(-1, 3)
    assert np.abs(force[free] + load[free]).max() < 1e-6 * np.abs(load).max()
    assert np.abs(t).max() > 0


def test_rest_lengths_hold_the_tension_exactly(model):
    cyl, x = model.springs, model.rest
    tension = cyl.youngs * cyl.area0 * np.linspace(-0.1, 0.3, len(cyl))  # strains into the stiffening range
    from dataclasses import replace

    from artic_cli.mechanics.elements import evaluate

    held = evaluate(replace(cyl, l0=rest_lengths_for(cyl, x, tension)), x).elastic
    assert np.allclose(held, tension, rtol=1e-9, atol=1e-9)


def test_the_drawn_tongue_stays_put_under_gravity_only_when_it_carries_its_weight(cfg, mesh):
    soft = _with(cfg, youngs_modulus_kpa=5.0)
    sags = [np.abs(settle(build_model(mesh, c.materials.tongue, c.simulation)).x - mesh.nodes).max()
            for c in (_with(soft, rest_under_gravity=False), _with(soft, rest_under_gravity=True))]
    assert sags[0] > 0.05  # a stress-free 5-kPa tongue sags before any muscle acts
    assert sags[1] < 1e-4


def test_in_the_articulator_the_tongue_moves_only_as_the_jaw_settles(cfg, mesh, wall):
    """At 5 kPa the stress-free tongue sags 0.27 cm beyond the mandible's own settling (0.08 cm); carrying its
    weight, it moves with the mandible (0.10 cm at most)."""
    c = _with(cfg, youngs_modulus_kpa=5.0)
    art = {on: build_articulator(_with(c, rest_under_gravity=on), mesh, wall) for on in (False, True)}
    beyond = {}
    for on, a in art.items():
        x = settle(a).x
        jaw = a.node_sets["mandible"]
        beyond[on] = np.abs(x[: a.n_tongue] - a.rest[: a.n_tongue]).max() - np.abs(x[jaw] - a.rest[jaw]).max()
    assert beyond[False] > 0.2 and beyond[True] < 0.05, beyond
    # only the tongue's cylinders and the floor's links change their rest lengths
    from artic_cli.geometry.anatomy import LINK_KINDS, build_body

    changed = art[True].springs.l0 != art[False].springs.l0
    kinds = build_body(cfg, mesh, floor_on_mylohyoid=cfg.jaw.floor_on_mylohyoid).link_kind
    n_floor = int(np.isin(kinds, [LINK_KINDS.index("floor"), LINK_KINDS.index("sling")]).sum())
    assert changed[: len(mesh.cylinders)].any() and 0 < changed[len(mesh.cylinders):].sum() <= n_floor


def test_the_tongue_alone_keeps_its_midline_in_its_plane_when_the_config_says_so(cfg, mesh):
    """simulation.midsagittal_symmetry holds the midsagittal nodes' z in the tongue alone as in the
    articulator: with a bulk penalty four times the default, a 2-N blade pull buckled the 10-kPa midline
    0.10 cm sideways, one way under Houbolt and the other under BDF1."""
    mid = mesh.node_sets["midsagittal"]
    for on in (True, False):
        sim = cfg.simulation.model_copy(update={"midsagittal_symmetry": on})
        fixed = build_model(mesh, cfg.materials.tongue, sim).fixed
        assert fixed[mid, 2].all() == on
        assert not fixed[np.setdiff1d(np.arange(len(mesh.nodes)), mid), 2].all()
