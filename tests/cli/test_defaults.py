"""Every command's default artefact paths are the stage table's (one place names where artefacts live)."""

from __future__ import annotations

from pathlib import Path

import click
import typer.main

from artic_cli.cli.main import app
from artic_cli.stages.paths import DATA, REPORTS, figure, output
from artic_cli.stages.table import REPORT_OUTPUT, STAGES


def _table_paths() -> set[Path]:
    """Every artefact and figure the table names, with the default folders (item stages: their folder)."""
    out = {Path(REPORT_OUTPUT.format(report=REPORTS)), DATA}
    for s in STAGES:
        path = output(s.name)
        out.add(path.parent if "{name}" in s.output else path)
        for k, f in enumerate(s.figures):
            out.add(figure(s.name, k, "solution") if "{name}" in f.path else figure(s.name, k))
    return out


def _defaults(group: click.Group, prefix: str = ""):
    for name, cmd in group.commands.items():
        if isinstance(cmd, click.Group):
            yield from _defaults(cmd, f"{prefix}{name} ")
            continue
        for p in cmd.params:
            if isinstance(p.default, Path) and p.default.parts[:1] in (("data",), ("reports",)):
                yield f"{prefix}{name} {p.opts[0]}", p.default


def test_every_default_artefact_path_is_one_the_stage_table_names():
    defaults = list(_defaults(typer.main.get_command(app)))
    assert len(defaults) >= 20  # mesh, maps, dynamic, acoustic maps, muscle function, figures, the report, ...
    known = _table_paths()
    off = [(where, str(p)) for where, p in defaults if p not in known]
    assert not off, f"defaults not from the stage table: {off}"


def test_the_table_paths_are_the_makefile_defaults():
    # the constants the commands use are the table's entries formatted with make's OUT=data and reports/
    assert output("mesh") == Path("data/mesh.h5") and output("epmaps") == Path("data/epmaps.h5")
    assert output("acousticmaps") == Path("data/acoustic_maps.h5")
    assert figure("mesh") == Path("reports/fig1_mesh.png")
