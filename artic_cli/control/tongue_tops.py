"""Where every EP of the maps has the tongue highest (an acoustic target's ``tongue_highest``): net key
("single/M", "pair/A+B", "group/I+A+B", as the formants') -> (*grid, 2) highest points (x, y cm), computed
from the EPs' shapes once per jaw position and kept, and the model's rest tongue's, the classes' reference."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..tract.shapes import surface_nodes
from ..tract.tongue_top import highest_point, highest_points


class TongueTops:
    def __init__(self, mesh, load_maps: Callable[[], object]):
        self.surface = surface_nodes(mesh)[0]
        self.load_maps, self.maps, self.cache = load_maps, None, {}  # cache: jaw position -> its nets' tops
        self.rest_top: np.ndarray | None = None

    def _maps(self):
        if self.maps is None:
            self.maps = self.load_maps()
        return self.maps

    @property
    def rest(self) -> np.ndarray:
        """(2,) the model's rest tongue's highest point (cm)."""
        if self.rest_top is None:
            m = self._maps()
            shape = m.model_rest if m.model_rest is not None else next(iter(m.jaws.values())).rest_shape
            self.rest_top = highest_point(np.asarray(shape)[self.surface, :2])
        return self.rest_top

    def __call__(self, jaw: str) -> dict[str, np.ndarray]:
        if jaw not in self.cache:
            jm = self._maps().jaws[jaw]
            nets = {f"{family}/{name}": net for family in ("single", "pair", "group")
                    for name, net in getattr(jm, family).items()}
            self.cache[jaw] = {k: highest_points(net.shapes, self.surface) for k, net in nets.items()
                               if net.shapes is not None}
        return self.cache[jaw]


__all__ = ["TongueTops"]
