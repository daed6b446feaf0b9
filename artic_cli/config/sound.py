"""The config's sections for sound: acoustics (air, walls, nasal tract, synthesis), the vocal tract and speech."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator

from ..validation import Finite, Point2, Strict
from .body import NonNeg, Outline, Positive


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


class Sources(Strict):
    """The synthesis's sources beyond the LF voice and the frication noise, each switchable for comparison
    (docs/modelling.md, "Sources"): the nasal branch, the air in time (the cavity's pressure as a state:
    the voice follows the transglottal pressure and the glottis's opening, a release's burst), the voice bar,
    aspiration at the glottis."""

    nasal_branch: bool = True  # the nasal tract as a side branch of the line, sounding at the nostrils
    # the voice's amplitude follows the transglottal pressure and the glottis's adduction (off: a switch per
    # segment, voiced or not, ramped over speech.voicing_ramp_ms)
    aerodynamic_voicing: bool = True
    # below this transglottal pressure the folds stop vibrating (Westbury & Keating 1986: 2 cm H2O)
    phonation_threshold_kpa: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.2
    # the folds vibrate fully at vocal_tract.glottis_cm2 and not at all from this opening on
    voicing_stops_at_cm2: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.2
    bursts: bool = True  # the cavity's pressure as a state and a release's flow transient (off: quasi-steady)
    # the walls' resistance as the cavity behind a closure sees them (the line's own is for the formants'
    # bandwidths): Ishizaka, French & Flanagan (1975)'s measured 1600 dyn s/cm^3
    cavity_wall_resistance_dyn_s_cm3: Annotated[float, Field(gt=0, le=1e5, allow_inf_nan=False)] = 1600.0
    voice_bar: bool = True  # the yielding walls' volume velocity radiates through the neck and cheeks
    aspiration: bool = True  # turbulence at the glottis (Flanagan's model)
    # its pressure source's RMS per squared Reynolds number above the critical one (dyn/cm^2; Flanagan &
    # Ishizaka 1976, the coefficient as Sondhi & Schroeter 1987 use it)
    aspiration_coefficient: Annotated[float, Field(ge=0, le=1e-3, allow_inf_nan=False)] = 2e-6
    seed: Annotated[int, Field(ge=0)] = 1  # the aspiration noise's


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
    sources: Sources = Sources()


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
    # the glottis's mean opening (a control input): adducted, as while voicing (mean flow about 180 cm^3/s at
    # 0.8 kPa); a voiceless segment opens it to speech.glottal_area_voiceless_cm2
    glottis_cm2: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.05
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
    # the lips and velum move over this, centred on each segment's start
    lip_ramp_ms: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] = 60.0
    voicing_ramp_ms: Annotated[float, Field(ge=1, le=200, allow_inf_nan=False)] = 20.0  # voice on / off
    lung_pressure_kpa: Annotated[float, Field(gt=0, le=4, allow_inf_nan=False)] = 0.8  # 8 cm H2O, speech at normal effort
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
