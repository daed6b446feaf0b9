"""The nasal tract as the reflection-type line needs it: the config's area function (Dang, Honda & Suzuki
1994) cut into sections of the line's length, the port's sections (their area the velopharyngeal port's,
sample by sample), and the paranasal sinuses as Helmholtz resonators on the junctions where their necks open.

A sinus is a lumped shunt: the air in its neck (area A, length L) is a mass rho L per unit area, the cavity
(volume V) a spring rho c^2 A / V per unit area of neck (Flanagan 1972, ch. 3: the Helmholtz resonator,
f = c / (2 pi) sqrt(A / (V L))); the transfer function has the same neck and cavity as tubes
(:func:`artic_cli.acoustics.model.tract_of`), so both resonate alike below a few kHz.  The nasal walls yield
as the oral tract's (the transfer function gives every section the same wall), and the nostrils radiate
through the lips' load (a piston in a baffle) with the last section's area.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class NasalLine:
    at: int  # the main line's junction (after section ``at``) where the port opens
    areas_cm2: np.ndarray  # (m,) the branch's sections, the port's first (their area replaced sample by sample)
    port_sections: int  # how many of the first sections are the port
    sinus_junction: np.ndarray  # (m - 1,) int: the sinus on each of the branch's junctions, -1: none
    sinus_mass: np.ndarray  # (S,) rho L, g/cm^2
    sinus_stiffness: np.ndarray  # (S,) rho c^2 A / V, dyn/cm^3
    sinus_area_cm2: np.ndarray  # (S,) the neck's area
    nostril_area_cm2: float


def nasal_line(nt, junction: int, section_cm: float, rho: float, c: float) -> NasalLine:
    """The nasal tract of the config's ``acoustics.nasal`` section ``nt`` at the line's section length, its
    port opening after the main line's section ``junction``."""
    lengths = np.array([nt.port_length_cm, *nt.lengths_cm], dtype=float)
    areas = np.array([1.0, *nt.areas_cm2], dtype=float)
    edges = np.concatenate([[0.0], np.cumsum(lengths)])
    m = max(2, int(round(edges[-1] / section_cm)))
    centres = (np.arange(m) + 0.5) * section_cm
    k = np.clip(np.searchsorted(edges, centres, side="right") - 1, 0, len(areas) - 1)
    port = max(1, int(np.sum(k == 0)))
    out = areas[k]
    where = np.full(m - 1, -1, dtype=np.int64)
    mass, stiff, neck = [], [], []
    if nt.sinuses_enabled:
        for s in nt.sinuses:
            j = int(np.clip(round((nt.port_length_cm + s.at_cm) / section_cm) - 1, 0, m - 2))
            if where[j] >= 0:  # two necks on one junction: the next free one
                j = int(np.flatnonzero(where < 0)[np.argmin(np.abs(np.flatnonzero(where < 0) - j))])
            where[j] = len(mass)
            mass.append(rho * s.neck_length_cm)
            stiff.append(rho * c * c * s.neck_area_cm2 / s.volume_cm3)
            neck.append(s.neck_area_cm2)
    return NasalLine(at=int(junction), areas_cm2=out, port_sections=port, sinus_junction=where,
                     sinus_mass=np.array(mass, float), sinus_stiffness=np.array(stiff, float),
                     sinus_area_cm2=np.array(neck, float), nostril_area_cm2=float(areas[-1]))
