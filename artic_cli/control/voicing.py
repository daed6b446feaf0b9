"""A simulator that also gives the vocal tract and formants of the force set it holds (what acoustic targets
are verified and refined with)."""

from __future__ import annotations

from ..tract.formants import net_acoustics
from ..tract.speaker import speaker_tract
from .verify import Simulator


class Voicer:
    """A :class:`Simulator` with the speaker's tract: ``voice`` gives formants, control points and the area
    function of a held force set."""

    def __init__(self, sim: Simulator, cfg):
        self.sim, self.cfg = sim, cfg
        self.vt = speaker_tract(cfg)
        self.mesh_sha256 = sim.mesh_sha256

    @property
    def simulation(self) -> Simulator:
        return self.sim

    def reach(self, jaw_forces: dict[str, float], forces: dict[str, float]):
        return self.sim.reach(jaw_forces, forces)

    def voice(self, jaw_forces: dict[str, float], forces: dict[str, float], lips: tuple[float, float],
              port: float) -> dict:
        """Formants (Hz), the tip and dorsum reached (cm) and the area function (cm, cm^2) of the held forces
        with the lip tube ``lips`` (cm^2, cm) and the port ``port`` (cm^2)."""
        x, cp = self.sim.shape(jaw_forces, forces)
        rest, mandible = self.sim.model_rest()
        n = net_acoustics(self.vt, self.cfg, self.sim.mesh, rest, mandible, x[None], {
            "lip_area_cm2": lips[0], "lip_length_cm": lips[1], "velum_port_cm2": port})
        r = lambda v: [round(float(a), 4) for a in v]  # noqa: E731
        return {"formants_hz": [float(v) for v in n.formants_hz[0]],
                "reached_cm": {"tip": r(cp[0, :2]), "dorsum": r(cp[1, :2])},
                "area_function": {"length_cm": r(n.length_cm[0]), "area_cm2": r(n.area_cm2[0]),
                                  "order": "glottis to lips, the lip tube last"}}
