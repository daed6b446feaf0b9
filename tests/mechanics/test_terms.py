"""The integrator's seam: a force term joins a model by being listed, without touching the integrator."""

from dataclasses import replace

import numpy as np
import pytest

from artic_cli.mechanics.integrator import step
from artic_cli.mechanics.model import FORCE_TERMS, build_model, rest_state, zero_control
from artic_cli.mechanics.term import ForceTerm


class AnchorSpring(ForceTerm):
    """A toy term: a linear spring of stiffness ``k`` (dyn/cm) from one node to a fixed point (cm)."""

    name = "anchor"

    def __init__(self, node: int, anchor: np.ndarray, k: float):
        self.node, self.anchor, self.k = node, np.asarray(anchor, float), float(k)

    def forces(self, model, ev, f):
        f[self.node] += self.k * (self.anchor - ev.x[self.node])

    def blocks(self, model, ev, out, signed=True):
        out[model.layout.assembly.n_pairs + self.node] += self.k * np.eye(3)


@pytest.fixture()
def lone_node(cfg, mesh):
    """The tongue with every node held but one, its cylinders without stiffness or damping: that node feels
    only gravity and whatever term is added."""
    node = int(mesh.node_sets["tip"][0])
    fixed = np.ones((len(mesh.nodes), 3), dtype=bool)
    fixed[node] = False
    m = build_model(mesh, cfg.materials.tongue, cfg.simulation, volume_constraint=False, fixed_dofs=fixed)
    limp = replace(m.springs, youngs=np.zeros_like(m.springs.youngs), viscosity=np.zeros_like(m.springs.viscosity))
    return replace(m, springs=limp), node


def test_an_added_term_pulls_its_node_to_the_closed_form_equilibrium(lone_node):
    """m x'' = k (a - x) + m g settles at x = a + m g / k; with the term's exact tangent each step of the
    linear problem converges in at most two Newton iterations."""
    model, node = lone_node
    k = 2.0e3  # dyn/cm: a period of 2 pi sqrt(m / k), some tens of ms for a node of a few tenths of a gram
    anchor = model.rest[node] + np.array([0.3, -0.2, 0.1])
    toy = replace(model, force_terms=FORCE_TERMS + (AnchorSpring(node, anchor, k),))
    assert [t.name for t in toy.terms][-1] == "anchor" and "anchor" not in [t.name for t in model.terms]
    state, ctl = rest_state(toy), zero_control(toy)
    iterations = []
    for _ in range(400):  # 2 s at the default 5-ms step: Houbolt's numerical damping has settled it
        state = step(toy, state, ctl)
        iterations.append(state.iterations)
    expect = anchor + toy.node_mass[node] * toy.gravity / k
    assert np.abs(state.x[node] - expect).max() < 1e-6
    assert max(iterations[1:]) <= 2
    others = np.setdiff1d(np.arange(toy.n_nodes), [node])
    assert np.array_equal(state.x[others], toy.rest[others])  # the held nodes did not move


def test_without_the_term_the_node_only_falls(lone_node):
    """The same model without the term: gravity alone accelerates the node (no spring holds it)."""
    model, node = lone_node
    state = rest_state(model)
    for _ in range(20):
        state = step(model, state, zero_control(model))
    drop = model.rest[node, 1] - state.x[node, 1]
    assert drop == pytest.approx(0.5 * abs(model.gravity[1]) * state.t ** 2, rel=0.05)
