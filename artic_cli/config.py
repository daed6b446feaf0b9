"""Configuration: YAML validated on load, with errors that name the key.

Keys carry their unit in their name (``_cm``, ``_kpa``, ``_ms``, ``_n``) so a
reader of a config never has to guess.  ``load_config`` reads and validates a
file into a frozen :class:`Config`; :class:`ConfigView` restricts one to the
top-level sections a stage declares, so a stage cannot depend on a section
its freshness key leaves out.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import yaml
from pydantic import Field, ValidationError, field_validator, model_validator

from .errors import ArticError
from .validation import DEFAULT_MAX_FORCE_N, Finite, Point2, Point3, Strict, describe, increasing, parse

DEFAULT_CONFIG = Path(__file__).resolve().parent.parent / "configs" / "default.yaml"

Outline = Annotated[list[Point2], Field(min_length=2)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]


class TongueGeometry(Strict):
    midsagittal_outline_cm: Outline
    gg_origin_cm: Point2
    half_width_cm: Positive = 1.0
    parasagittal_shrink: Annotated[float, Field(ge=0, lt=0.5)] = 0.08
    parasagittal_drop_cm: Finite = 0.15
    parasagittal_tip_recess_cm: NonNeg = 0.0
    tip_taper_sections: Annotated[int, Field(ge=1, le=20)] = 3
    radial_sections: Annotated[int, Field(ge=2, le=40)] = 10
    concentric_sections: Annotated[int, Field(ge=2, le=20)] = 6
    inner_fraction: Annotated[float, Field(gt=0, lt=0.9)] = 0.2


class WallSlice(Strict):
    z_cm: NonNeg
    palate: Outline
    pharynx: Outline
    mandible: Outline


class WallGeometry(Strict):
    lumen_reference_cm: Point2
    points_per_outline: Annotated[int, Field(ge=3, le=400)] = 24
    slices: Annotated[list[WallSlice], Field(min_length=2)]

    @field_validator("slices")
    @classmethod
    def _increasing_z(cls, v):
        zs = [s.z_cm for s in v]
        if zs[0] != 0.0 or any(b <= a for a, b in zip(zs, zs[1:])):
            raise ValueError("slices must start at z_cm: 0 and increase in z_cm")
        return v


class Speaker(Strict):
    name: str
    tongue: TongueGeometry
    wall: WallGeometry
    landmarks_cm: dict[str, Point3]


class TissueMaterial(Strict):
    density_g_cm3: Positive = 1.0
    youngs_modulus_kpa: Positive = 20.0
    viscosity_kpa_s: NonNeg = 2.0
    poisson_ratio: Annotated[float, Field(gt=0.0, lt=0.5)] = 0.49
    stiffening_strain: Positive = 0.2
    stiffening_rate: NonNeg = 0.0
    isotropic_truss: bool = True
    volume_constraint_gain: Annotated[float, Field(ge=1.0, le=1000.0)] = 1.0
    # the drawn rest shape carries the tongue's weight (cylinder rest lengths prestrained; false: the paper's
    # stress-free rest, which gravity sags before any muscle acts)
    rest_under_gravity: bool = False


class BoneMaterial(Strict):
    youngs_modulus_kpa: Positive = 9.6e6
    viscosity_kpa_s: NonNeg = 9.6e5
    mandible_mass_g: Positive = 150.0
    hyoid_mass_g: Positive = 5.0


class Materials(Strict):
    tongue: TissueMaterial
    bone: BoneMaterial = BoneMaterial()


class Simulation(Strict):
    dt_ms: Positive = 5.0
    scheme: Literal["houbolt", "bdf1"] = "houbolt"
    gravity_cm_s2: NonNeg = 980.0
    volume_constraint: bool = True
    fixed_node_sets: list[str] = ["anchor"]
    newton_tol_cm: Positive = 1.0e-5
    newton_max_iter: Annotated[int, Field(ge=1, le=200)] = 25
    refactor_rate: Annotated[float, Field(gt=0, lt=1)] = 0.25
    record_every: Annotated[int, Field(ge=1)] = 1
    # left-right symmetry: the articulator's midsagittal tongue nodes keep z = 0 (no antisymmetric buckling)
    midsagittal_symmetry: bool = False
    # the articulator's left half moves as the mirror image of its right half (exact under its symmetric loads):
    # the Newton systems have the right half's unknowns only
    mirror_symmetry: bool = False


class InferiorLongitudinalis(Strict):
    """IL's fibre in each plane from node (radial, level) ``start`` to the tip.  ``path: level``: up its
    radial line to ``level``, forward along that concentric level to radial 1, then up the tip's radial line
    to the tip; ``path: straight``: on each radial line the node nearest the straight line from ``start`` to
    the tip (``level`` unused), a band that pulls the tip toward the start without hooping round the GG
    tendon (docs/modelling.md)."""

    start: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=0)]] = (10, 2)
    level: Annotated[int, Field(ge=0)] = 2
    path: Literal["level", "straight"] = "level"

    @model_validator(mode="after")
    def _start_below_level(self):
        if self.path == "level" and self.start[1] > self.level:
            raise ValueError(f"start level {self.start[1]} lies above the level {self.level} IL runs along; "
                             "give a start level at or below it")
        return self


class StyloglossusFibre(Strict):
    entry: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]]  # (radial, level) where it enters the tongue
    level: Annotated[int, Field(ge=0)]  # the concentric level it runs along
    radials: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]]  # from, to (toward the tip)

    @field_validator("radials")
    @classmethod
    def _toward_tip(cls, v):
        if v[1] > v[0]:
            raise ValueError(f"radials {list(v)} run backward; give [from, to] with from >= to (radial 0 is the tip)")
        return v


class Muscles(Strict):
    thickness_cm2: dict[str, Positive] = {
        "GGa": 1.0, "GGm": 1.5, "GGp": 2.0, "HG": 1.5, "SG": 1.5, "SL": 1.0, "IL": 1.0, "T": 1.0, "V": 1.0,
        "GH": 0.5, "MH": 1.0, "temporalis_anterior": 2.0, "temporalis_posterior": 1.5, "masseter": 2.5,
        "medial_pterygoid": 2.0, "lateral_pterygoid_upper": 1.0, "lateral_pterygoid_lower": 1.0,
        "anterior_digastric": 1.0, "posterior_digastric": 1.0}
    passive_k1_ratio: NonNeg = 0.05
    maxwell_k2_ratio: Positive = 2.0
    maxwell_b2_ratio: Positive = 0.1
    # Eq. (9) evaluated at fibre strain / width: 1 is the paper's curve (active force zero below -18.5 %)
    force_length_width: Annotated[float, Field(ge=1.0, le=5.0)] = 1.0
    # routing (docs/modelling.md): the verticalis over this many radial sections from the tip; IL also midsagittally
    verticalis_sections: Annotated[int, Field(ge=1)] = 4
    # ... from the surface down to this concentric level (0: the GG tendon; the surface is the last level)
    verticalis_to_level: Annotated[int, Field(ge=0)] = 3
    il_midsagittal: bool = False
    inferior_longitudinalis: InferiorLongitudinalis = InferiorLongitudinalis()
    # SG's fibres in each parasagittal plane: from the styloid into the tongue at node (radial, level), then
    # forward along `level` from radial radials[0] to radials[1] (radial 0: the tip; level 0: the GG tendon)
    styloglossus: Annotated[list[StyloglossusFibre], Field(min_length=1)] = [
        StyloglossusFibre(entry=(8, 4), level=3, radials=(7, 1)), StyloglossusFibre(entry=(7, 5), level=5, radials=(6, 3))]
    groups: dict[str, dict[str, Positive]] = {
        "JO": {"lateral_pterygoid_upper": 0.25, "lateral_pterygoid_lower": 0.25, "anterior_digastric": 0.5},
        "JC": {"temporalis_anterior": 0.3, "temporalis_posterior": 0.2, "masseter": 0.3, "medial_pterygoid": 0.2},
        "T-SL": {"T": 0.5, "SL": 0.5}}  # a group's force shared by its muscles (docs/modelling.md)
    # Steady force (N) of muscles or groups in every state, on top of the control: the jaw closers'
    # postural tone holds the mandible at its reference height against gravity.
    postural_tone_n: dict[str, NonNeg] = {"JC": 2.1}
    max_force_n: Positive = DEFAULT_MAX_FORCE_N  # the largest force a schedule or target may ask of a muscle or load


class Jaw(Strict):
    link_area_cm2: Positive = 0.1
    eminence_slope_deg: Annotated[float, Field(ge=-80, le=0)] = -30.0
    guide_stiffness_n_per_cm: Positive = 1000.0
    fossa_stop: bool = True           # the condyle cannot slide back beyond its rest seat in the glenoid fossa
    fossa_stop_onset_cm: Positive = 0.01  # the stop's force rises smoothly over this depth (Newton stays smooth)
    passive_stiffness_n_per_cm: NonNeg = 0.5
    passive_relaxation_ms: NonNeg = 100.0  # jaw units' and straps' dashpots: this time x their spring
    strap_stiffness_n_per_cm: NonNeg = 10.0
    # the anterior digastric's fibre runs on through the hyoid sling to the mastoid, so its strain is taken over
    # the whole digastric; false: it ends at the sling, as the paper's (docs/modelling.md)
    digastric_through_sling: bool = False
    # where the digastric's sling is: ``fixed``, a point fixed at the hyoid body's rest end (the paper's "fixed
    # point"); ``hyoid``, the fibrous loop on the hyoid body itself, so the digastric's tension also lifts the
    # hyoid (docs/modelling.md)
    digastric_sling: Literal["fixed", "hyoid"] = "fixed"
    floor_link_area_cm2: Positive = 0.3
    # the floor's links to the mylohyoid lines (``floor_on_mylohyoid``): the floor of the mouth's stiffness,
    # which carries the tongue with the mandible as the jaw opens; null: ``floor_link_area_cm2`` (docs/modelling.md)
    sling_link_area_cm2: Positive | None = None
    # the planes in which the mandible carries the tongue's GG tendon line (innermost concentric line): all
    # three, or the midsagittal one only, where the genial tubercle is (docs/modelling.md)
    gg_tendon: Literal["all", "midsagittal"] = "all"
    # the tongue floor's links to the hyoid bear compression only, their tension levelling off over this
    # strain (the floor rests on the hyoid); null: full springs (docs/modelling.md)
    floor_slack_strain: Annotated[float, Field(gt=0, le=1)] | None = None
    # the strap muscles (sternohyoid, thyrohyoid) bear tension only, their push levelling off over this much
    # shortening (passive muscle pulls, it does not push); null: full springs both ways (docs/modelling.md)
    strap_slack_strain: Annotated[float, Field(gt=0, le=1)] | None = None
    # the tongue floor also hangs from the mylohyoid lines (the floor of the mouth): each floor node linked to
    # its two nearest mylohyoid points on the mandible, links like the floor's (docs/modelling.md)
    floor_on_mylohyoid: bool = False


class Contact(Strict):
    enabled: bool = True
    stiffness_n_per_cm: Positive = 1000.0
    tolerance_cm: Positive = 0.01


Pair = Annotated[list[str], Field(min_length=2, max_length=2)]


class Group(Strict):
    independent: str  # its force is the co-contraction level
    pair: Pair  # the agonist/antagonist pair


JAW_POSITIONS = {"rest": {}, "JO_0.5": {"JO": 0.5}, "JO_1.2": {"JO": 1.2}, "JO_2.5": {"JO": 2.5}, "JO_4": {"JO": 4.0},
                 "JO_6": {"JO": 6.0}, "JC_0.5": {"JC": 0.5}, "JC_1.5": {"JC": 1.5}, "JC_3": {"JC": 3.0}}


class EPMapSpec(Strict):
    """What ``artic ep-map`` computes (the paper's section IV.B)."""

    duration_ms: Positive = 300.0  # each equilibrium: the muscle force held this long from the jaw position's rest
    convergence_window_ms: Positive = 50.0
    convergence_tol_cm: Positive = 0.01  # converged: control points moved less than this over the last window
    early_stop_tol_cm: Positive = 0.002  # --fast: stop once they move less than this over a window
    # an EP still moving after duration_ms is held on for up to this long, stopping once it has settled
    # (0: the paper's fixed hold)
    extend_ms: NonNeg = 0.0
    # the mandible held where the jaw position's rest has it while tongue muscles act (the paper: jaw forces
    # held, the jaw free); also the muscle directions and k-closure experiments
    hold_jaw: bool = False
    jaw_positions: dict[str, dict[str, NonNeg]] = JAW_POSITIONS  # name -> jaw forces held (N)
    typical_jaw: str = "JO_0.5"
    levels_n: list[NonNeg] = [0.0, 0.1, 0.2, 0.4, 1.0, 2.5, 4.0, 6.0]
    muscles: list[str] = ["GGa", "GGm", "GGp", "HG", "SG", "SL", "IL", "V", "T", "MH", "GH", "T-SL"]
    pair_levels_n: list[Positive] = [0.5, 1.0, 2.0, 4.0]  # contour lines of a two-muscle net (plus 0)
    pairs_tip: list[Pair] = [["SL", "GGa"], ["SL", "IL"], ["SL", "GGp"], ["SL", "SG"], ["SL", "HG"],
                             ["T-SL", "GGa"], ["T-SL", "SL"], ["T-SL", "GGp"], ["GGp", "SG"], ["GGp", "HG"],
                             ["GGp", "IL"], ["GGa", "IL"], ["GGa", "SG"], ["GGm", "SG"], ["GGm", "HG"],
                             ["V", "SL"], ["HG", "SG"]]
    pairs_dorsum: list[Pair] = [["SG", "HG"], ["GGp", "HG"], ["GGm", "SG"], ["GGp", "SG"], ["MH", "SG"]]
    groups: list[Group] = [Group(independent="SG", pair=["GGp", "SL"]), Group(independent="GGp", pair=["GGa", "IL"]),
                           Group(independent="GGm", pair=["SL", "T-SL"]), Group(independent="T-SL", pair=["GGm", "HG"]),
                           Group(independent="HG", pair=["GGp", "SL"])]
    group_levels_n: list[Positive] = [0.1, 0.2, 0.5, 1.0]  # co-contraction levels of the independent muscle (plus 0)
    net_jaw_positions: list[str] = ["JO_0.5"]  # where the two- and three-muscle nets are built

    @field_validator("levels_n", "pair_levels_n", "group_levels_n")
    @classmethod
    def _increasing(cls, v):
        return increasing(v, "force levels must increase")


class MuscleFunctionSpec(Strict):
    """The paper's section IV.A.1 (Figs. 5 and 6): scattered starts, then one muscle from each."""

    start_combinations: list[Annotated[list[str], Field(min_length=1)]] = [
        ["GGp", "GGm", "GGa"], ["GGp", "SG", "GGa"], ["HG", "GGm", "GGa"], ["HG", "SG", "GGa"]]
    start_levels_n: list[NonNeg] = [0.0, 0.3, 0.8, 1.6, 3.2, 6.0]  # six levels, wider apart as they grow
    start_ms: Positive = 120.0
    muscles: list[str] = ["GGa", "GGm", "GGp", "HG", "SG", "SL", "IL", "V", "T", "MH"]
    drive_force_n: Positive = 4.0
    drive_ms: Positive = 150.0
    contact: bool = False  # the paper left the wall out of this study
    hold_jaw: bool = False  # the mandible held at its rest while tongue muscles act (false: free, as the paper)


class Cuboid(Strict):
    size_cm: Point3 = [6.0, 3.0, 2.0]
    bricks: Annotated[list[int], Field(min_length=3, max_length=3)] = [5, 3, 2]
    forces_n: list[NonNeg] = [0.1, 0.5, 1.0, 2.0, 3.0, 4.0]


class Sinus(Strict):
    """A paranasal sinus: a Helmholtz resonator (a neck, then a cavity of the volume) on the nasal tract."""

    name: str
    at_cm: NonNeg  # where its neck opens, from the nasal tract's velum end
    volume_cm3: Positive
    neck_length_cm: Positive
    neck_area_cm2: Positive


DH1994_AREAS_CM2 = [1.63, 2.07, 2.72, 3.59, 4.24, 3.26, 3.04, 3.04, 2.72, 2.5, 2.39, 2.39, 1.85, 0.76, 1.41, 1.74,
                    1.30, 1.74, 0.76]


class NasalTract(Strict):
    """The nasal tract behind the velopharyngeal port, from the port to the nostrils: Dang, Honda & Suzuki
    (1994, JASA 96: MRI of the nasal and paranasal cavities), 19 sections of 0.6 cm (11.4 cm), its narrowest
    place the nasal valve 3.3 cm behind the nostrils; the area function and the four sinuses (volumes, necks,
    where they open) as VocalTractLab (Birkholz) tabulates them (the names are ours, by their volumes)."""

    enabled: bool = True
    port_length_cm: Positive = 0.5  # the port itself: a short tube of the velum's opening area
    port_from_lips_cm: Positive = 8.5  # for a plain tube: where the port joins it, measured from the lips
    lengths_cm: Annotated[list[Positive], Field(min_length=1)] = [0.6] * 19
    areas_cm2: Annotated[list[Positive], Field(min_length=1)] = DH1994_AREAS_CM2
    sinuses_enabled: bool = True
    sinus_cavity_length_cm: Positive = 2.0  # each cavity as a closed tube this long (its own resonance > 4 kHz)
    sinuses: list[Sinus] = [
        Sinus(name="sphenoidal", at_cm=4.8, volume_cm3=11.3, neck_length_cm=0.3, neck_area_cm2=0.185),
        Sinus(name="frontal", at_cm=5.4, volume_cm3=6.8, neck_length_cm=0.3, neck_area_cm2=0.185),
        Sinus(name="maxillary", at_cm=6.6, volume_cm3=33.0, neck_length_cm=0.45, neck_area_cm2=0.145),
        Sinus(name="ethmoidal", at_cm=7.2, volume_cm3=6.2, neck_length_cm=1.0, neck_area_cm2=0.11)]

    @field_validator("areas_cm2")
    @classmethod
    def _same_length(cls, v, info):
        if len(v) != len(info.data.get("lengths_cm", v)):
            raise ValueError("needs one area per length in lengths_cm")
        return v


class PiriformFossa(Strict):
    """The two piriform fossae beside the larynx tube (Dang & Honda 1997, JASA 101: a side cavity that adds
    an antiresonance near 4-5 kHz and lowers the formants below it), as one closed side tube whose area
    tapers linearly to zero, parametrised as in VocalTractLab (Birkholz; its JD3 speaker: effective length
    2.5 cm, both fossae together 1.5 cm^3)."""

    enabled: bool = True
    # their entrance above the glottis, at the aryepiglottic folds; VocalTractLab couples them after the 4th of
    # its 16 pharynx sections (1.7-2.3 cm on its JD3 vowels), and the formants are sensitive to it (/e/ F2
    # 2163 Hz coupled at 1.73 cm, 2272 at 2.0)
    from_glottis_cm: Positive = 2.0
    length_cm: Positive = 2.5  # effective acoustic length, end correction included
    volume_cm3: Positive = 1.5  # both fossae
    sections: Annotated[int, Field(ge=1, le=40)] = 5


class Synthesis(Strict):
    """The time-domain synthesizer (:mod:`artic_cli.acoustics.synthesis`) and its LF source."""

    sample_rate_hz: Annotated[int, Field(ge=8000, le=96000)] = 44100
    glottal_reflection: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)] = 0.97
    section_loss: Annotated[float, Field(ge=0, lt=0.05, allow_inf_nan=False)] = 5e-4  # per section and sample
    lf_tp: Annotated[float, Field(gt=0.1, lt=0.8)] = 0.42  # LF timing, fractions of a period: flow peak
    lf_te: Annotated[float, Field(gt=0.2, lt=0.95)] = 0.56  # main excitation
    lf_ta: Annotated[float, Field(gt=0, lt=0.1)] = 0.012  # return phase


class Acoustics(Strict):
    """Air, walls and losses of the frequency-domain tube model (CGS; Maeda 1982, Ishizaka et al. 1975;
    ../shared/reference/acoustics.md), each loss switchable."""

    sound_speed_cm_s: Positive = 35000.0
    air_density_g_cm3: Positive = 1.14e-3
    air_viscosity_dyn_s_cm2: Positive = 1.86e-4
    heat_conduction_cal_cm_s_c: Positive = 5.5e-5
    specific_heat_cal_g_c: Positive = 0.24
    adiabatic_constant: Annotated[float, Field(gt=1, le=2, allow_inf_nan=False)] = 1.4
    # Yielding walls per unit area.  Ishizaka et al. (1975)'s 1.5 g/cm^2, 1600 dyn s/cm^3, 3e5 dyn/cm^3 raise
    # F1 of VocalTractLab's /i/ tube by 23 % (258 Hz against 210 with rigid-wall agreement to 0.3 %);
    # VocalTractLab's values (Birkholz: a higher resistance keeps F1 of close vowels realistic) agree with its
    # transfer function to 0.3 % on a, e, i, o, u.
    wall_mass_g_cm2: Positive = 2.4
    wall_resistance_dyn_s_cm3: Positive = 5000.0
    wall_stiffness_dyn_cm3: Positive = 1.0e5
    viscous_losses: bool = True
    heat_losses: bool = True
    yielding_walls: bool = True
    radiation: bool = True  # the lips radiate (parallel R-L); off: an ideal open end
    velum_area_cm2: NonNeg = 0.0  # the velopharyngeal port's opening; 0: closed
    max_frequency_hz: Annotated[float, Field(gt=500, le=20000, allow_inf_nan=False)] = 5500.0
    frequency_step_hz: Annotated[float, Field(gt=0, le=50, allow_inf_nan=False)] = 5.0  # the stored transfer function's grid
    # the grid formants are searched on before each peak is refined (zooms: within 0.001 Hz of a 5-Hz search
    # on 200 test tubes, bandwidths within 0.04 Hz; a quarter of the work)
    formant_search_step_hz: Annotated[float, Field(gt=0, le=40, allow_inf_nan=False)] = 20.0
    formants: Annotated[int, Field(ge=1, le=8)] = 5
    nasal: NasalTract = NasalTract()
    piriform_fossa: PiriformFossa = PiriformFossa()
    synthesis: Synthesis = Synthesis()


class AreaRegion(Strict):
    """One region of the distance-to-area law A = alpha d^beta (cm^2 from cm)."""

    name: str
    until_cm: Positive  # the region ends this far from the glottis along the grid's spine
    alpha: Positive
    beta: Annotated[float, Field(gt=0, le=4, allow_inf_nan=False)]


class LipControl(Strict):
    """The lip tube: a control input like a muscle force (its length and aperture area)."""

    length_cm: Annotated[float, Field(gt=0, le=3, allow_inf_nan=False)] = 1.0
    area_cm2: Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)] = 3.0


class TractGrid(Strict):
    """Grid lines normal to a fixed reference midline (the spine, glottis to incisors) in the midsagittal
    plane; on each line the distance between the inner contour (larynx front, epiglottis, tongue, lower
    incisor) and the outer one (pharyngeal wall, velum, palate, upper incisor)."""

    spine_cm: Annotated[list[Point2], Field(min_length=3)]
    spacing_cm: Annotated[float, Field(ge=0.05, le=1.0, allow_inf_nan=False)] = 0.3
    reach_cm: Annotated[float, Field(gt=0.5, le=6.0, allow_inf_nan=False)] = 3.0  # each side of the spine
    smoothing_cm: NonNeg = 0.6  # the spine is smoothed over this arc length before the normals are taken
    penetration_cm: Positive = 0.3  # tongue beyond the wall by up to this reads as a closure, not a miss
    # a tongue surface node this close to the wall (the contact's tolerance) closes the two grid lines either side
    # of it (0: the lines' crossings alone, which miss a contact between two lines)
    touch_cm: Annotated[float, Field(ge=0, le=0.1, allow_inf_nan=False)] = 0.01


class VocalTract(Strict):
    """The speaker's vocal tract beyond the tongue mesh and the contact wall (midsagittal, cm; the speaker
    frame): what the area function needs (the paper's section II.A: tongue, lips, teeth, hard palate,
    velum, pharyngeal wall, larynx).  The velum is the part of the wall's midsagittal palate behind
    ``hard_palate_end_x_cm``; the lower incisor and the lower lip move with the mandible; the larynx front
    follows the tongue root's lowest node (the vallecula) forward and back, by ``larynx_follows_root`` of
    its move at the epiglottis tip, tapering to nothing at the glottis (0: fixed in the head frame), and
    stays ``larynx_wall_gap_cm`` clear of the posterior wall."""

    hard_palate_end_x_cm: Finite = -5.2
    velum_nasal_surface_cm: Outline  # the velum's posterior surface, hard palate end to the uvula (drawn)
    velum_port_cm2: NonNeg = 0.0  # the velopharyngeal port's default opening (a control input; 0: closed)
    velum_port_line_cm: Annotated[list[Point2], Field(min_length=2, max_length=2)]  # the oral tract's top behind the velum
    pharynx_lower_cm: Outline  # the posterior wall below the contact wall's pharynx, down to the glottis
    larynx_front_cm: Outline  # glottis front, the laryngeal vestibule, the epiglottis to its tip
    larynx_follows_root: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.0  # see the docstring
    larynx_wall_gap_cm: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] = 0.3
    upper_incisor_cm: Outline  # labial surface down to the incisor edge
    lower_incisor_cm: Outline  # edge down the labial surface (with the mandible)
    upper_lip_cm: Outline
    lower_lip_cm: Outline  # with the mandible
    lips: LipControl = LipControl()
    # other lip tubes whose formants the acoustic maps hold beside the default's (each costs about the default
    # map's time again): a formant target with one of them is solved without computing its jaw position's EPs
    mapped_lips: list[LipControl] = []
    lip_sections: Annotated[int, Field(ge=1, le=10)] = 2
    grid: TractGrid
    area_law_source: str = ""
    area_law: Annotated[list[AreaRegion], Field(min_length=1)]

    @field_validator("area_law")
    @classmethod
    def _ascending(cls, v):
        ends = [r.until_cm for r in v]
        if ends != sorted(ends) or len(set(ends)) != len(ends):
            raise ValueError("regions must be listed from the glottis with rising until_cm")
        return v


class Noise(Strict):
    """Turbulence noise at the tract's narrowest place (frication and bursts; artic_cli/acoustics/aerodynamics.py):
    a pressure source just downstream of the constriction whose RMS is ``gain`` times the kinetic pressure drop
    across it (Stevens 1971: the source strength follows the pressure drop), switched on where the Reynolds
    number passes ``critical_reynolds`` (Flanagan 1972: about 1800), growing as 1 - (Re_c / Re)^2."""

    enabled: bool = True
    critical_reynolds: Annotated[float, Field(gt=0, le=1e5, allow_inf_nan=False)] = 1800.0
    gain: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.05
    seed: Annotated[int, Field(ge=0)] = 0


class Speech(Strict):
    """How an utterance is spoken (``artic speak``): the force course, the glottis and the lungs."""

    ramp_ms: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] = 30.0  # each target's forces ramp in over this
    # each segment's muscle forces switch on this long before its sound starts (the first at t = 0): speech
    # muscles' EMG leads the acoustic event (0: at the segment's start, as the paper's controller switches them)
    lead_ms: Annotated[float, Field(ge=0, le=300, allow_inf_nan=False)] = 0.0
    # the first segment's forces switch on this long before the sound, in silence (at least lead_ms): a speaker
    # sets the articulators before voicing starts; 0 = lead_ms
    prepare_ms: Annotated[float, Field(ge=0, le=1000, allow_inf_nan=False)] = 0.0
    # the muscles' force follows the course with first-order activation dynamics, rising and falling with these
    # time constants (beyond the paper, whose forces follow their commands at once: 0, 0)
    activation_rise_ms: Annotated[float, Field(ge=0, le=200, allow_inf_nan=False)] = 0.0
    activation_fall_ms: Annotated[float, Field(ge=0, le=200, allow_inf_nan=False)] = 0.0
    lip_ramp_ms: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] = 60.0  # the lips and velum move over this
    voicing_ramp_ms: Annotated[float, Field(ge=1, le=200, allow_inf_nan=False)] = 20.0  # voice on / off
    lung_pressure_kpa: Annotated[float, Field(gt=0, le=4, allow_inf_nan=False)] = 0.8  # 8 cm H2O, speech at normal effort
    glottal_area_voiced_cm2: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.05  # its mean while voicing (mean flow about 180 cm^3/s)
    glottal_area_voiceless_cm2: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.3  # abducted
    glottal_flow_peak_cm3_s: Annotated[float, Field(gt=0, le=2000, allow_inf_nan=False)] = 300.0  # the voice's AC flow
    # the paper's controller holds each target's forces ("static"); "pulse_step" opens each segment with a
    # pulse of F + pulse_gain (F - F_before) for pulse_ms (beyond the paper: reaching the target in time)
    force_course: Literal["static", "pulse_step"] = "static"
    pulse_ms: Annotated[float, Field(gt=0, le=200, allow_inf_nan=False)] = 40.0
    pulse_gain: Annotated[float, Field(ge=0, le=5, allow_inf_nan=False)] = 1.0
    # muscle or group pairs whose pulses cross over: a pulse that would pull one side below zero drives the other
    pulse_antagonists: list[Annotated[list[str], Field(min_length=2, max_length=2)]] = [["JO", "JC"]]
    reach_hold_ms: Annotated[float, Field(ge=0, le=2000, allow_inf_nan=False)] = 400.0  # each set held this long
    # from rest gives its EP, the place the segment heads for (0: not measured)
    frame_ms: Annotated[float, Field(gt=0, le=50, allow_inf_nan=False)] = 5.0  # tract frames (the sound's)
    formant_frame_ms: Annotated[float, Field(gt=0, le=50, allow_inf_nan=False)] = 10.0  # formant tracks, between: linear
    noise: Noise = Noise()


class Config(Strict):
    schema_version: Literal[1]
    speaker: Speaker
    materials: Materials
    simulation: Simulation = Simulation()
    muscles: Muscles = Muscles()
    jaw: Jaw = Jaw()
    contact: Contact = Contact()
    cuboid: Cuboid = Cuboid()
    epmap: EPMapSpec = EPMapSpec()
    muscle_function: MuscleFunctionSpec = MuscleFunctionSpec()
    acoustics: Acoustics = Acoustics()
    vocal_tract: VocalTract | None = None  # the speaker's tract (required by 'artic vocal-tract')
    speech: Speech = Speech()



def parse_config(data: object, source: Path | str = "<config>") -> Config:
    if not isinstance(data, dict):
        raise ArticError(f"{source}: config must be a YAML mapping; see configs/default.yaml")
    try:
        return Config.model_validate(data)
    except ValidationError as err:
        raise ArticError("config error: " + describe(err, Config, str(source)) + "; fix the key and rerun") from None


def read_yaml(path: Path | str, what: str = "file") -> object:
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"{what} not found: {path}; give an existing path")
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise ArticError(f"{path}: malformed YAML{where}; fix the syntax and rerun") from None


def load_config(path: Path | str | None = None) -> Config:
    path = Path(path) if path is not None else DEFAULT_CONFIG
    return parse_config(read_yaml(path, "config"), path)


def parse_speaker(data: object, source: str = "<speaker>") -> Speaker:
    return parse(Speaker, data, source, "speaker section", "rebuild the mesh with 'artic build-mesh'")


SECTIONS = tuple(Config.model_fields)


class ConfigView:
    """A config restricted to ``sections``: reading any other top-level section raises (a stage that did
    that would go stale without noticing)."""

    def __init__(self, cfg: Config, sections):
        unknown = set(sections) - set(SECTIONS)
        if unknown:
            raise ValueError(f"unknown config sections {sorted(unknown)}")
        if isinstance(cfg, ConfigView):
            cfg = cfg.full
        self.full, self.sections = cfg, frozenset(sections)

    def __getattr__(self, name: str):
        if name in SECTIONS and name not in self.sections:
            raise AttributeError(f"config section '{name}' was not declared by this stage "
                                 f"(declared: {', '.join(sorted(self.sections))})")
        return getattr(self.full, name)
