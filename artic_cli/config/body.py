"""The config's sections for the body and its control: speaker geometry, materials, simulation, muscles, jaw,
contact, the cuboid test, EP maps and the muscle-function study."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from ..validation import DEFAULT_MAX_FORCE_N, Finite, Point2, Point3, Strict, increasing

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


class SolverSpec(Strict):
    """How an answer is checked: its forces (jaw and tongue) switched on together from the rest posture and
    held ``verify_ms``, the jaw free, as ``artic simulate`` and ``artic speak`` move them;
    ``verify_hold_jaw``: the maps' condition instead (the jaw position's rest, its mandible held)."""

    verify_ms: Annotated[float, Field(gt=0, le=5000, allow_inf_nan=False)] = 400.0
    verify_hold_jaw: bool = False
    # a constriction's refinement scales its candidate's tongue forces up to this (N; at least the maps' top
    # level): a stop presses beyond the EPs the maps hold, the jaw held there, to seal with the jaw free
    press_max_force_n: Annotated[float, Field(gt=0, le=50, allow_inf_nan=False)] = 8.0


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
