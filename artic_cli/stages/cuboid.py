"""Stage ``cuboid``: the paper's 6 x 3 x 2 cm test body pulled along x (section II.B.3), a JSON table."""

from __future__ import annotations

from pathlib import Path

from ..config import Config, load_config
from ..experiments.cuboid import CuboidRow, rows_as_dicts, run_cuboid
from ..io.store import read_doc, write_doc
from .base import Stage, up_to_date

STAGE = Stage(name="cuboid", module=__name__, sections=("materials", "simulation", "cuboid"), kind="cuboid",
              hint="rerun 'artic validate cuboid --out FILE'")


def compute(cfg: Config, forces_n: list[float] | None = None, volume_constraint: bool | None = None) -> list[CuboidRow]:
    return run_cuboid(STAGE.view(cfg), forces_n, volume_constraint)


def write(path: Path | str, rows: list[CuboidRow], prov=None) -> Path:
    return write_doc(path, {"kind": STAGE.kind, "rows": rows_as_dicts(rows)}, prov)


def read(path: Path | str) -> list[dict]:
    doc = read_doc(path, "cuboid table", STAGE.hint)
    return doc["rows"]


def validate_cuboid(config: Path | str | None = None, forces_n: list[float] | None = None,
                    volume_constraint: bool | None = None, out: Path | str | None = None) -> list[dict]:
    """The cuboid table as dicts; with ``out``, written there (left alone when it holds this recipe)."""
    cfg = load_config(config)
    prov = STAGE.provenance(cfg, params={"forces_n": forces_n, "volume_constraint": volume_constraint})
    if out is not None and up_to_date(out, prov):
        return read(out)
    rows = compute(cfg, forces_n, volume_constraint)
    if out is not None:
        write(out, rows, prov)
    return rows_as_dicts(rows)
