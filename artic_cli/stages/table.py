"""The one stage table: every stage's module, command, inputs and outputs, its figures, and the report's
sections.  ``python -m artic_cli.pipeline`` renders the Makefile's rules from it, so a new stage is one new
module plus its entry here.

Placeholders: ``{out}`` the data folder, ``{report}`` the report folder, ``{config}`` the config file,
``{name}`` one item of the stage's ``items`` list (a schedule, an experiment, a target) from the pipeline
definition (``pipelines/paper.yaml``).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Figure:
    path: str  # the picture (under {report})
    command: str  # artic command that draws it from the artefacts (figures of one command are drawn in one go)
    option: str  # how the command is given this figure's path
    module: str  # the plot module
    inputs: tuple[str, ...] = ()  # artefacts it is drawn from (besides the stage's output)
    items: str = ""  # only for the items of this pipeline list (default: every item of the stage)


@dataclass(frozen=True)
class StageEntry:
    name: str  # make target
    module: str  # artic_cli.stages.<module>
    output: str  # the artefact
    command: str  # the artic command that makes it
    inputs: tuple[str, ...] = ()  # other artefacts and user files it reads
    items: str = ""  # pipeline list the stage runs once per item of
    ok_status: tuple[int, ...] = (0,)  # exit statuses that still count as done (3: target unreachable, answer written)
    figures: tuple[Figure, ...] = field(default_factory=tuple)
    # `make paper` runs it alone: "first" before every stage it does not read, "last" after everything that does
    # not read it.  For stages that keep both cores busy by themselves: beside another stage each slows the other.
    alone: str = ""


MESH = "{out}/mesh.h5"
MAPS = "{out}/epmaps.h5"
DYN = "{out}/dynamic.h5"

SIM_PLOT = "plot simulation {output} --mesh {mesh} --config {config}"
MF_PLOT = "plot muscle-function {output}"

# in the order `make -j` should start them: the EP maps' chain (maps, acoustic maps, vowels, utterances) is the
# longest path
STAGES: tuple[StageEntry, ...] = (
    StageEntry("mesh", "artic_cli.stages.mesh", MESH, "build-mesh --config {config} --out {output}",
               figures=(Figure("{report}/fig1_mesh.png", "plot mesh --mesh {output} --config {config}", "--out {figure}",
                               "artic_cli.plots.mesh", ("{out}/.config/vocal_tract.json",)),)),
    StageEntry("epmaps", "artic_cli.stages.epmap", MAPS,
               "ep-map --mesh {mesh} --config {config} --out {output} --jobs 2 --cache {out}/cache", inputs=(MESH,),
               alone="first",
               figures=(Figure("{report}/fig8_epmap.png", "plot ep-map --maps {output}", "--out {figure}",
                               "artic_cli.plots.epmap"),)),
    StageEntry("dynamic", "artic_cli.stages.dynamic", DYN, "dynamic-map --maps {maps} --out {output}",
               inputs=(MAPS,),
               figures=(Figure("{report}/fig9_dynamic_map.png", "plot dynamic-map --maps {maps} --dynamic {output} "
                               "--jaw $(FIG9_JAW)", "--out {figure}", "artic_cli.plots.dynamic", (MAPS,)),)),
    StageEntry("acousticmaps", "artic_cli.stages.acoustic_map", "{out}/acoustic_maps.h5",
               "acoustic-map --maps {maps} --mesh {mesh} --config {config} --out {output}", inputs=(MAPS, MESH),
               figures=(Figure("{report}/vowel_space.png", "plot acoustic-map {output}", "--out {figure}",
                               "artic_cli.plots.acoustic_map"),)),
    StageEntry("vowels", "artic_cli.stages.solve", "{out}/vowels/{name}.yaml",
               "solve-target configs/targets/vowels/{name}.yaml --maps {maps} --mesh {mesh} --config {config} "
               "--acoustic-maps {out}/acoustic_maps.h5 --refine --out {output}",
               inputs=(MAPS, MESH, "{out}/acoustic_maps.h5", "configs/targets/vowels/{name}.yaml"), items="vowels",
               ok_status=(0, 3),
               figures=(Figure("{report}/vowel_{name}.png", "plot solution {output} --target "
                               "configs/targets/vowels/{name}.yaml", "--out {figure}", "artic_cli.plots.solution",
                               ("configs/targets/vowels/{name}.yaml",)),)),
    StageEntry("utterances", "artic_cli.stages.speak", "{out}/utterances/{name}.h5",
               "speak configs/utterances/{name}.yaml --maps {maps} --dynamic {dynamic} --mesh {mesh} "
               "--config {config} --acoustic-maps {out}/acoustic_maps.h5 --accept-nearest "
               "--out {out}/utterances/{name}.wav",
               inputs=(MAPS, DYN, MESH, "{out}/acoustic_maps.h5", "configs/utterances/{name}.yaml",
                       "configs/phonemes/japanese.yaml",
                       "$(wildcard configs/targets/vowels/*.yaml configs/targets/consonants/*.yaml)"),
               items="utterances",
               figures=(Figure("{report}/utterance_{name}.png", "plot utterance {output}", "--out {figure}",
                               "artic_cli.plots.utterance"),)),
    StageEntry("utterances-words", "artic_cli.stages.speak", "{out}/words/{name}.h5",
               "speak configs/words/{name}.yaml --maps {maps} --dynamic {dynamic} --mesh {mesh} "
               "--config {config} --acoustic-maps {out}/acoustic_maps.h5 --accept-nearest "
               "--solutions {out}/utterances/solutions --out {out}/words/{name}.wav",
               inputs=(MAPS, DYN, MESH, "{out}/acoustic_maps.h5", "configs/words/{name}.yaml",
                       "configs/phonemes/japanese.yaml"),
               items="words",
               figures=(Figure("{report}/word_{name}.png", "plot utterance {output}", "--out {figure}",
                               "artic_cli.plots.utterance"),)),
    StageEntry("vowels-audio", "artic_cli.stages.synthesize", "{out}/vowels/{name}.wav",
               "synthesize --solution {out}/vowels/{name}.yaml --duration 0.6 --f0-contour "
               "configs/voice/f0_fall_125_100.csv --config {config} --out {output}",
               inputs=("{out}/vowels/{name}.yaml", "configs/voice/f0_fall_125_100.csv"), items="vowels"),
    StageEntry("solve", "artic_cli.stages.solve", "{out}/solutions/{name}.yaml",
               "solve-target {target} --maps {maps} --dynamic {dynamic} --mesh {mesh} --config {config} --verify "
               "--refine --out {output}", inputs=(MAPS, DYN, MESH, "configs/targets/{name}.yaml"), items="targets",
               ok_status=(0, 3),
               figures=(Figure("{report}/fig12_{name}.png", "plot solution {output} --target {target} --maps {maps} "
                               "--dynamic {dynamic}", "--out {figure}", "artic_cli.plots.solution",
                               (MAPS, DYN, "configs/targets/{name}.yaml")),)),
    StageEntry("cuboid", "artic_cli.stages.cuboid", "{out}/cuboid.json",
               "validate cuboid --config {config} --out {output}"),
    StageEntry("sims-tissue", "artic_cli.stages.simulate", "{out}/sims/{name}.h5",
               "simulate --tongue-only --schedule {schedule} --mesh {mesh} --config {config} --out {output}",
               inputs=(MESH, "configs/schedules/{name}.yaml"), items="tissue_schedules",
               figures=(Figure("{report}/sim_{name}.png", SIM_PLOT, "--out {figure}", "artic_cli.plots.simulation",
                               (MESH,)),)),
    StageEntry("sims-novol", "artic_cli.stages.simulate", "{out}/sims/{name}_novol.h5",
               "simulate --tongue-only --schedule {schedule} --mesh {mesh} --config {config} --out {output} "
               "--no-volume-constraint", inputs=(MESH, "configs/schedules/{name}.yaml"),
               items="tissue_without_constraint"),
    StageEntry("sims", "artic_cli.stages.simulate", "{out}/sims/{name}.h5",
               "simulate --schedule {schedule} --mesh {mesh} --config {config} --out {output}",
               inputs=(MESH, "configs/schedules/{name}.yaml"), items="articulator_schedules",
               figures=(Figure("{report}/{name}.png", SIM_PLOT, "--out {figure}", "artic_cli.plots.simulation",
                               (MESH,)),
                        Figure("{report}/{name}.gif", SIM_PLOT, "--animate {figure}", "artic_cli.plots.animation",
                               (MESH,), items="animated"))),
    StageEntry("tracts-rest", "artic_cli.stages.vocal_tract", "{out}/tracts/rest.h5",
               "vocal-tract --rest --mesh {mesh} --config {config} --out {output}", inputs=(MESH,),
               figures=(Figure("{report}/tract_rest.png", "plot vocal-tract {output}", "--out {figure}",
                               "artic_cli.plots.vocal_tract"),)),
    StageEntry("tracts", "artic_cli.stages.vocal_tract", "{out}/tracts/{name}.h5",
               "vocal-tract --sim {out}/sims/{name}.h5 --mesh {mesh} --config {config} --out {output}",
               inputs=(MESH, "{out}/sims/{name}.h5"), items="tract_schedules",
               figures=(Figure("{report}/tract_{name}.png", "plot vocal-tract {output}", "--out {figure}",
                               "artic_cli.plots.vocal_tract"),)),
    StageEntry("acoustics-rest", "artic_cli.stages.acoustics", "{out}/acoustics/rest.h5",
               "acoustics --tracts {out}/tracts/rest.h5 --config {config} --out {output}",
               inputs=("{out}/tracts/rest.h5",),
               figures=(Figure("{report}/acoustics_rest.png", "plot acoustics {output}", "--out {figure}",
                               "artic_cli.plots.acoustics"),)),
    StageEntry("acoustics", "artic_cli.stages.acoustics", "{out}/acoustics/{name}.h5",
               "acoustics --tracts {out}/tracts/{name}.h5 --config {config} --out {output}",
               inputs=("{out}/tracts/{name}.h5",), items="tract_schedules",
               figures=(Figure("{report}/acoustics_{name}.png", "plot acoustics {output}", "--out {figure}",
                               "artic_cli.plots.acoustics"),)),
    StageEntry("audio-rest", "artic_cli.stages.synthesize", "{out}/audio/rest.wav",
               "synthesize --tracts {out}/tracts/rest.h5 --config {config} --duration 1.0 --f0 115 --out {output}",
               inputs=("{out}/tracts/rest.h5",),
               figures=(Figure("{report}/spectrogram_rest.png", "plot audio {output}", "--out {figure}",
                               "artic_cli.plots.acoustics"),)),
    StageEntry("experiments", "artic_cli.stages.experiments", "{out}/experiments/{name}.json",
               "experiment {name} --mesh {mesh} --config {config} --out {output}", inputs=(MESH,),
               items="experiments",
               figures=(Figure("{report}/fig7_trajectories.png", "plot experiment {output}", "--out {figure}",
                               "artic_cli.plots.muscle_function", items="fig7"),)),
    StageEntry("musclefunction", "artic_cli.stages.muscle_function", "{out}/muscle_function.h5",
               "muscle-function --mesh {mesh} --config {config} --out {output} --jobs 2 --cache {out}/cache",
               inputs=(MESH,), alone="last",
               figures=(Figure("{report}/fig5_muscle_function_tip.png", MF_PLOT, "--tip {figure}",
                               "artic_cli.plots.muscle_function"),
                        Figure("{report}/fig6_muscle_function_dorsum.png", MF_PLOT, "--dorsum {figure}",
                               "artic_cli.plots.muscle_function"))),
)


@dataclass(frozen=True)
class ReportSection:
    key: str  # function in artic_cli.stages.report.SECTIONS
    title: str
    stages: tuple[str, ...]  # the stages whose artefacts and figures it shows


REPORT: tuple[ReportSection, ...] = (
    ReportSection("tissue", "The semicontinuum tongue (section II)", ("mesh", "cuboid", "sims-tissue", "sims-novol")),
    ReportSection("articulator", "Muscles, jaw-hyoid complex and contact (section III)", ("sims", "experiments")),
    ReportSection("tract", "The vocal tract and its sound (section II.A)",
                  ("tracts-rest", "tracts", "acoustics-rest", "acoustics", "audio-rest", "acousticmaps")),
    ReportSection("function", "Muscle function and equilibrium positions (section IV.A)",
                  ("musclefunction", "experiments")),
    ReportSection("maps", "EP maps, dynamic maps and the target solver (sections IV.B and V)",
                  ("epmaps", "dynamic", "solve")),
    ReportSection("vowels", "Vowels from formant targets (beyond the paper)", ("vowels", "vowels-audio")),
    ReportSection("utterances", "Utterances from target sequences (beyond the paper)", ("utterances",)),
    ReportSection("words", "Words from text (beyond the paper)", ("utterances-words",)),
    ReportSection("run", "This run", ()),
)
REPORT_MODULE = "artic_cli.stages.report"
REPORT_OUTPUT = "{report}/paper.md"
