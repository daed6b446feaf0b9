"""Tracts and formants of a grid of articulator shapes: the plain function that maps and solvers ask for the
sound of a shape (the EPs of a net, a simulated force set)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..acoustics.analysis import analyse
from ..acoustics.tube import Tube
from .areas import port_positions, tracts_of
from .controls import controls_for
from .shapes import shapes_of

FORMANTS = 4


@dataclass
class NetAcoustics:
    formants_hz: np.ndarray  # (*grid, 4)
    bandwidths_hz: np.ndarray  # (*grid, 4)
    area_cm2: np.ndarray  # (*grid, sections)
    length_cm: np.ndarray  # (*grid, sections)
    min_area_cm2: np.ndarray  # (*grid,)


def net_acoustics(vt, cfg, mesh, model_rest: np.ndarray, mandible_nodes: np.ndarray, shapes: np.ndarray,
                  overrides: dict | None = None, bandwidths: bool = True) -> NetAcoustics:
    """Tracts and formants of a grid of shapes (*grid, N, 3); ``overrides``: lip tube and port controls;
    ``bandwidths=False``: NaN bandwidths (the formants in two thirds of the time)."""
    grid = shapes.shape[:-2]
    flat = shapes.reshape(-1, *shapes.shape[-2:]).astype(float)
    sh = shapes_of(flat, np.zeros(len(flat)), mesh, model_rest, mandible_nodes)
    t = tracts_of(vt, cfg.speaker.wall, sh, controls_for(vt, sh.time_s, overrides=overrides))
    tubes = [Tube(t.af.length_cm[k], t.af.area_cm2[k]) for k in range(t.n_frames)]
    ports = port_positions(t)
    ac = analyse(tubes, cfg.acoustics, velum_area_cm2=t.controls["velum_port_cm2"], port_from_glottis_cm=ports,
                 spectra=False, bandwidths=bandwidths)
    return NetAcoustics(formants_hz=ac.formants_hz[:, :FORMANTS].reshape(*grid, FORMANTS),
                        bandwidths_hz=ac.bandwidths_hz[:, :FORMANTS].reshape(*grid, FORMANTS),
                        area_cm2=t.af.area_cm2.reshape(*grid, -1), length_cm=t.af.length_cm.reshape(*grid, -1),
                        min_area_cm2=t.af.area_cm2.min(axis=1).reshape(grid))
