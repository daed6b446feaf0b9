"""External forces: the control's nodal loads and gravity on every node's mass.  They do not depend on the
positions, so they are evaluated once a step and enter the residual as its known part."""

from __future__ import annotations

import numpy as np

from .term import Evaluation, ForceTerm


class ExternalTerm(ForceTerm):
    """Loads (the control's ``node_force``, dyn) and gravity (node mass x g)."""

    name = "external"
    varies = False

    def prepare(self, model, state, control, h: float) -> np.ndarray:
        return control.node_force + model.node_mass[:, None] * model.gravity

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        f += ev.step[self.name]
