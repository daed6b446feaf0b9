"""From the config's ``acoustics`` section and a tube to what the transfer function needs: the air, the
tract with its side branches, and the frequencies."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .chain import LOSSLESS, Air
from .transfer import Branch, Tract
from .tube import Tube


def air_of(ac, lossless: bool = False) -> Air:
    """The :class:`Air` of a config's acoustics section; ``lossless``: the ideal hard-walled tube."""
    air = Air(c=ac.sound_speed_cm_s, rho=ac.air_density_g_cm3, mu=ac.air_viscosity_dyn_s_cm2,
              kappa=ac.heat_conduction_cal_cm_s_c, cp=ac.specific_heat_cal_g_c, eta=ac.adiabatic_constant,
              wall_mass=ac.wall_mass_g_cm2, wall_resistance=ac.wall_resistance_dyn_s_cm3,
              wall_stiffness=ac.wall_stiffness_dyn_cm3, viscous=ac.viscous_losses, heat=ac.heat_losses,
              walls=ac.yielding_walls, radiation=ac.radiation)
    return replace(LOSSLESS, c=ac.sound_speed_cm_s) if lossless else air


def tract_of(tube: Tube, ac, velum_area_cm2: float | None = None, lossless: bool = False,
             port_from_glottis_cm: float | None = None) -> Tract:
    """The tube with the piriform fossae and (with the velum open) the nasal tract, as the config says.
    The ideal lossless tube has no branches."""
    branches = []
    if lossless:
        return Tract(tube, branches)
    pf = ac.piriform_fossa
    if pf.enabled and tube.total_length_cm > pf.from_glottis_cm:
        n = pf.sections
        top = 2.0 * pf.volume_cm3 / pf.length_cm  # the area at the entrance: a linear taper to zero holds the volume
        area = top * (1.0 - (np.arange(n) + 0.5) / n)
        branches.append(Branch(pf.from_glottis_cm, Tube(np.full(n, pf.length_cm / n), area), radiating=False))
    velum = ac.velum_area_cm2 if velum_area_cm2 is None else velum_area_cm2
    nt = ac.nasal
    if nt.enabled and velum > 0:
        at = tube.total_length_cm - nt.port_from_lips_cm if port_from_glottis_cm is None else port_from_glottis_cm
        nasal = Tube(np.array([nt.port_length_cm, *nt.lengths_cm]), np.array([velum, *nt.areas_cm2]))
        sinuses = tuple(Branch(nt.port_length_cm + s.at_cm,
                               Tube(np.array([s.neck_length_cm, nt.sinus_cavity_length_cm]),
                                    np.array([s.neck_area_cm2, s.volume_cm3 / nt.sinus_cavity_length_cm])))
                        for s in nt.sinuses) if nt.sinuses_enabled else ()
        branches.append(Branch(max(at, 0.0), nasal, radiating=True, branches=sinuses))
    return Tract(tube, branches)


def frequencies(ac, count: int | None = None) -> np.ndarray:
    """The frequency grid of a stored transfer function (Hz)."""
    step = ac.frequency_step_hz
    return np.arange(step, ac.max_frequency_hz + step / 2, step) if count is None else \
        np.linspace(ac.max_frequency_hz / count, ac.max_frequency_hz, count)
