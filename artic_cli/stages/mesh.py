"""Stage ``mesh``: the tongue mesh (bricks and cylinders) and the vocal-tract wall from the speaker geometry."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..config import Config, load_config
from ..geometry.mesh import Mesh, tongue_mesh
from ..geometry.wall import WallSurface, wall_surface
from ..io.store import MESH_HINT, MeshFile, load_mesh, save_mesh
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="mesh", module=__name__, sections=("speaker",), kind="mesh", hint=MESH_HINT)


@dataclass
class MeshResult:
    mesh: Mesh
    wall: WallSurface


def compute(cfg: Config) -> MeshResult:
    view = STAGE.view(cfg)
    return MeshResult(tongue_mesh(view.speaker.tongue), wall_surface(view.speaker.wall))


def write(path: Path | str, result: MeshResult, cfg: Config) -> None:
    save_mesh(path, result.mesh, result.wall, cfg.speaker, STAGE.provenance(cfg))


def read(path: Path | str, cfg: Config | None = None) -> MeshFile:
    """The mesh, the wall, the speaker section and the content hash; with ``cfg``, checks it is the
    speaker's."""
    return load_mesh(path, expect=None if cfg is None else cfg.speaker)


@dataclass
class MeshSummary:
    path: Path
    nodes: int
    bricks: int
    cylinders: int
    volume_cm3: float
    cylinder_volume_cm3: float
    wall_triangles: int
    up_to_date: bool


def build_mesh(config: Path | str | None = None, out: Path | str = paths.MESH) -> MeshSummary:
    """Build the mesh of a config's speaker into ``out``; a file holding the same recipe is left alone."""
    cfg = load_config(config)
    fresh = up_to_date(out, STAGE.provenance(cfg))
    if fresh:
        m = read(out, cfg)
        result = MeshResult(m.mesh, m.wall)
    else:
        result = compute(cfg)
        write(out, result, cfg)
    mesh, wall = result.mesh, result.wall
    return MeshSummary(Path(out), len(mesh.nodes), len(mesh.bricks), len(mesh.cylinders), mesh.volume,
                       mesh.cylinder_volume, len(wall.triangles), fresh)
