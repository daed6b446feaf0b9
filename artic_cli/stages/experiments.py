"""Stage ``experiments``: the paper's numeric experiments (section III and Fig. 7), one JSON table each.

A table's rows set ours beside the paper's; Fig. 7's file also holds the control-point paths its picture
is drawn from (``figure``), so the picture is redrawn without rerunning the experiment.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..config import load_config
from ..errors import ArticError
from ..experiments.paper import EXPERIMENTS, HELD_JAW_EXPERIMENTS, Row, rows_as_dicts
from ..io.store import read_doc, write_doc
from ..mechanics.model import ARTICULATOR_SECTIONS, Model
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date
from .simulate import build

STAGE = Stage(name="experiments", module=__name__, sections=(*ARTICULATOR_SECTIONS, "epmap"), reads=("mesh",),
              kind="experiment", hint="rerun 'artic experiment NAME --out FILE' (or 'make paper')")


def compute(model: Model, name: str, hold_jaw: bool = False) -> tuple[list[Row], dict]:
    """The experiment's rows and, for Fig. 7, its paths (cm) by muscle; ``hold_jaw`` (the EP maps' switch)
    holds the jaw in the experiments made of single tongue-muscle EPs."""
    if name not in EXPERIMENTS:
        raise ArticError(f"unknown experiment '{name}'; valid: {', '.join(EXPERIMENTS)}")
    figure: dict = {}
    if name == "fig7":
        rows = EXPERIMENTS[name](model, figure=figure)
    elif name in HELD_JAW_EXPERIMENTS:
        rows = EXPERIMENTS[name](model, hold=hold_jaw)
    else:
        rows = EXPERIMENTS[name](model)
    return rows, figure


def _figure_json(figure: dict) -> dict:
    return {m: {"forces_n": list(d["forces"]), "paths_cm": np.round(np.asarray(d["paths"]), 6).tolist(),
                "layout": "(force, start, frame, point tip/dorsum/jaw, xyz)"} for m, d in figure.items()}


def write(path: Path | str, name: str, rows: list[Row], figure: dict | None = None, prov=None) -> Path:
    doc = {"kind": STAGE.kind, "experiment": name, "rows": rows_as_dicts(rows)}
    if figure:
        doc["figure"] = _figure_json(figure)
    return write_doc(path, doc, prov)


def read(path: Path | str) -> dict:
    """``experiment``, ``rows`` (name, ours, paper, unit, note) and, for Fig. 7, ``figure``."""
    doc = read_doc(path, "experiment table", STAGE.hint)
    if "rows" not in doc:
        raise ArticError(f"{path} is not an experiment table; {STAGE.hint}")
    return doc


def figure_paths(doc: dict) -> dict:
    """Fig. 7's paths as arrays, in the layout :func:`artic_cli.plots.muscle_function.plot_fig7` draws."""
    return {m: {"forces": d["forces_n"], "paths": np.asarray(d["paths_cm"])} for m, d in doc["figure"].items()}


def run_experiment(name: str, mesh: Path | str = paths.MESH, config: Path | str | None = None,
                   out: Path | str | None = None) -> dict:
    """Run one experiment on a mesh file and a config; with ``out``, write its table (left alone when it
    holds this recipe).  Returns the table as :func:`read` gives it."""
    if name not in EXPERIMENTS:
        raise ArticError(f"unknown experiment '{name}'; valid: {', '.join(EXPERIMENTS)}")
    cfg = load_config(config)
    m = mesh_stage.read(mesh, cfg)
    prov = STAGE.provenance(cfg, inputs={"mesh": m.content_sha256}, params={"experiment": name},
                            code_roots=("artic_cli.experiments.paper",),
                            sections=STAGE.sections if name in HELD_JAW_EXPERIMENTS else ARTICULATOR_SECTIONS)
    if out is not None and up_to_date(out, prov):
        return read(out)
    rows, figure = compute(build(cfg, m.mesh, m.wall), name, STAGE.view(cfg).epmap.hold_jaw)
    if out is not None:
        write(out, name, rows, figure, prov)
        return read(out)
    doc = {"experiment": name, "rows": rows_as_dicts(rows)}
    if figure:
        doc["figure"] = _figure_json(figure)
    return doc
