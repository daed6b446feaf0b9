"""Acoustic maps: the formants of every EP of the EP maps, for the config's lips and port and for each of
its mapped lip tubes."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import ArticError
from ..parallel import Sweep, run_sweep
from ..tract.formants import FORMANTS, NetAcoustics, net_acoustics
from ..tract.speaker import speaker_tract


@dataclass
class AcousticMaps:
    jaws: dict[str, dict[str, NetAcoustics]]  # jaw -> "rest" | "single/SG" | "pair/SG+HG" ... -> acoustics
    attrs: dict = field(default_factory=dict)
    # the config's other mapped lip tubes: (area cm^2, length cm) -> jaw -> net key -> formants (*grid, 4), Hz
    lips: dict[tuple[float, float], dict[str, dict[str, np.ndarray]]] = field(default_factory=dict)

    def formants_with(self, jaw: str, area_cm2: float, length_cm: float) -> dict[str, np.ndarray] | None:
        """Every EP's formants at ``jaw`` with that lip tube, if the maps hold it (None otherwise)."""
        held = self.lips.get(lip_key(area_cm2, length_cm))
        return None if held is None or jaw not in held else held[jaw]

    def points(self, jaw: str) -> np.ndarray:
        """(P, 4) every EP's formants at a jaw position (the rest first)."""
        return np.concatenate([n.formants_hz.reshape(-1, FORMANTS) for n in self.jaws[jaw].values()])

    def points_with_lips(self) -> dict[tuple[float, float], np.ndarray]:
        """(area cm^2, length cm) -> (P, 4) every EP's formants at every jaw position with that mapped lip tube."""
        return {key: np.concatenate([f.reshape(-1, FORMANTS) for nets in jaws.values() for f in nets.values()])
                for key, jaws in self.lips.items()}


def lip_key(area_cm2: float, length_cm: float) -> tuple[float, float]:
    """How a lip tube is looked up (cm^2, cm; rounded to 1e-6)."""
    return round(float(area_cm2), 6), round(float(length_cm), 6)


def net_task(cfg, mesh, model_rest: np.ndarray, mandible_nodes: np.ndarray, shapes: np.ndarray,
              settings: list[dict | None], bandwidths: bool = True) -> list[NetAcoustics]:
    """One net's acoustics with each lip and port setting (one task: its shapes travel once); bandwidths with
    the first setting only (the mapped lip tubes keep their formants)."""
    vt = speaker_tract(cfg)
    return [net_acoustics(vt, cfg, mesh, model_rest, mandible_nodes, shapes, over, bandwidths=bandwidths and k == 0)
            for k, over in enumerate(settings)]


def acoustic_maps(cfg, mesh, maps, progress: Callable[[int, int], None] | None = None, jaws: list[str] | None = None,
            overrides: dict | None = None, mapped_lips: bool = False, jobs: int = 1,
            bandwidths: bool = True) -> AcousticMaps:
    """Every EP's acoustics (``jaws``: those jaw positions only; ``overrides``: lip tube and port;
    ``mapped_lips``: also the formants with each of ``vocal_tract.mapped_lips``, the config's port), net by
    net on ``jobs`` workers (``progress``: nets done); ``bandwidths=False``: formants only."""
    vt = speaker_tract(cfg)
    if maps.model_rest is None or any(jm.rest_shape is None for jm in maps.jaws.values()):
        raise ArticError("the EP maps keep no shapes (an older artic built them); rerun 'artic ep-map'")
    chosen = {j: jm for j, jm in maps.jaws.items() if jaws is None or j in jaws}
    nets = [(jname, "rest", jm.rest_shape[None]) for jname, jm in chosen.items()]
    for jname, jm in chosen.items():
        for fam in ("single", "pair", "group"):
            for name, net in getattr(jm, fam).items():
                nets.append((jname, f"{fam}/{name}", net.shapes))
    settings = [(None, overrides)] + [
        (lip_key(lp.area_cm2, lp.length_cm), {"lip_area_cm2": float(lp.area_cm2), "lip_length_cm": float(lp.length_cm),
                                              "velum_port_cm2": float(vt.velum_port_cm2)})
        for lp in (vt.mapped_lips if mapped_lips else [])]
    overs = [over for _, over in settings]
    calls = [(cfg, mesh, maps.model_rest, maps.mandible_nodes, shapes, overs, bandwidths) for _, _, shapes in nets]
    if jobs > 1:
        done = run_sweep(net_task, calls, Sweep(jobs=jobs, progress=progress)).results
    else:
        done = []
        for k, call in enumerate(calls):
            if progress is not None:
                progress(k, len(calls))
            done.append(net_task(*call))
        if progress is not None:
            progress(len(calls), len(calls))
    out: dict[str, dict[str, NetAcoustics]] = {j: {} for j in chosen}
    held: dict[tuple[float, float], dict[str, dict[str, np.ndarray]]] = {}
    for (jname, key, _), results in zip(nets, done):
        for (lips, _), res in zip(settings, results):
            if lips is None:
                out[jname][key] = res
            else:
                held.setdefault(lips, {j: {} for j in chosen})[jname][key] = res.formants_hz
    return AcousticMaps(jaws=out, lips=held)


class EPFormants:
    """The formant oracle of acoustic targets: ``(jaw, lip area cm^2, lip length cm, port cm^2) -> FormantNets``
    (every EP's formants at a jaw position), and of constriction targets: ``areas(jaw)``.  The stored acoustic maps answer for the config's lips and port and
    its mapped lip tubes; other lips or ports are computed from the EPs' shapes, one jaw position at a time
    (0.4 s for a jaw position's vectors, 4.5 s with its nets); each answer is kept."""

    def __init__(self, cfg, mesh, load_maps: Callable[[], object], stored: AcousticMaps | None = None,
                 read_areas: Callable[[], AcousticMaps] | None = None):
        vt = speaker_tract(cfg)
        self.cfg, self.mesh, self.load_maps, self.stored = cfg, mesh, load_maps, stored
        self.read_areas = read_areas  # the stored maps with their area functions, read when first asked ...
        self.stored_areas: AcousticMaps | None = None  # ... and kept
        self.defaults = (float(vt.lips.area_cm2), float(vt.lips.length_cm), float(vt.velum_port_cm2))
        self.cache: dict = {}
        self.whole = None  # the maps with the EPs' shapes, read once when other lips or ports need them

    def whole_maps(self):
        """The maps with the EPs' shapes (read once, kept)."""
        if self.whole is None:
            self.whole = self.load_maps()
        return self.whole

    def areas(self, jaw: str) -> dict:
        """Every EP's area function at a jaw position with the config's lips and port: net key -> (*grid, S)
        cm^2 (the stored acoustic maps', else computed from the EPs' shapes; kept)."""
        key = ("areas", jaw)
        if key not in self.cache:
            if self.read_areas is not None and self.stored_areas is None:
                self.stored_areas = self.read_areas()
            held = self.stored_areas
            if held is not None and jaw in held.jaws:
                self.cache[key] = {k: n.area_cm2 for k, n in held.jaws[jaw].items()}
            else:
                nets = acoustic_maps(self.cfg, self.mesh, self.whole_maps(), jaws=[jaw], bandwidths=False).jaws[jaw]
                self.cache[key] = {k: n.area_cm2 for k, n in nets.items()}
        return self.cache[key]

    def __call__(self, jaw: str, area: float, length: float, port: float) -> dict:
        key = (jaw, *lip_key(area, length), round(port, 6))
        if key not in self.cache:
            self.cache[key] = self._formants(key, jaw, area, length, port)
        return self.cache[key]

    def _formants(self, key: tuple, jaw: str, area: float, length: float, port: float) -> dict:
        stored = self.stored
        mapped = stored is not None and key[3] == round(self.defaults[2], 6)  # the acoustic maps hold the port
        held = stored.formants_with(jaw, area, length) if mapped else None  # one of its mapped lip tubes
        if mapped and jaw in stored.jaws and key[1:3] == lip_key(*self.defaults[:2]):
            return {k: n.formants_hz for k, n in stored.jaws[jaw].items()}
        if held is not None:
            return held
        nets = acoustic_maps(self.cfg, self.mesh, self.whole_maps(), jaws=[jaw], overrides={
            "lip_area_cm2": area, "lip_length_cm": length, "velum_port_cm2": port}, bandwidths=False).jaws[jaw]
        return {k: n.formants_hz for k, n in nets.items()}
