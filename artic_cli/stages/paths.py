"""The default place of every artefact: the stage table's outputs with the data folder ``data`` and the report
folder ``reports`` (what ``make paper`` uses without ``OUT``), so a command's defaults and the Makefile's rules
name the same files."""

from __future__ import annotations

from pathlib import Path

from .table import REPORT_OUTPUT, STAGES

DATA = Path("data")
REPORTS = Path("reports")


def output(stage: str, name: str = "NAME") -> Path:
    """The default artefact of ``stage`` (for a stage run per item, the one of item ``name``)."""
    for s in STAGES:
        if s.name == stage:
            return Path(s.output.format(out=DATA, report=REPORTS, name=name))
    raise KeyError(stage)


def figure(stage: str, index: int = 0, name: str = "NAME") -> Path:
    """The default path of a stage's figure (its ``index``-th in the table)."""
    entry = next(s for s in STAGES if s.name == stage)
    return Path(entry.figures[index].path.format(out=DATA, report=REPORTS, name=name))


MESH = output("mesh")
EPMAPS = output("epmaps")
DYNAMIC = output("dynamic")
ACOUSTIC_MAPS = output("acousticmaps")
MUSCLE_FUNCTION = output("musclefunction")
SIMS = output("sims").parent
TRACTS = output("tracts").parent
TRACT_REST = output("tracts-rest")
SOLUTIONS = output("solve").parent
UTTERANCES = output("utterances").parent
REPORT = Path(REPORT_OUTPUT.format(report=REPORTS))
FIG1 = figure("mesh")
FIG7 = figure("experiments")
FIG8 = figure("epmaps")
FIG9 = figure("dynamic")
FIG12 = figure("solve", name="solution")
