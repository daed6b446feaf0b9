"""Shared fixtures: the default config, its mesh and model, a mesh file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from artic_cli.config import load_config
from artic_cli.geometry.mesh import tongue_mesh
from artic_cli.geometry.wall import wall_surface
from artic_cli.mechanics.model import build_model
from artic_cli.stages.mesh import build_mesh

ROOT = Path(__file__).resolve().parent.parent
LONGEST_FIRST = ("test_pipeline.py", "test_solver.py", "test_epmap.py")  # the modules that take longest


def praat_formants_near(wav, times, expected) -> tuple[list[float], list[float]]:
    """Praat (Burg: 5 formants below 5 kHz, 25-ms windows) on a WAV: each formant's median over ``times``, and
    for each ``expected`` value the one nearest it (Burg may insert spurious peaks, so not by index)."""
    parselmouth = pytest.importorskip("parselmouth")
    fm = parselmouth.Sound(str(wav)).to_formant_burg(0.01, 5, 5000, 0.025, 50)
    found = [f for f in (np.nanmedian([fm.get_value_at_time(j, t) for t in times]) for j in range(1, 6))
             if np.isfinite(f)]
    return [min(found, key=lambda f: abs(f - e)) for e in expected], found


def pytest_collection_modifyitems(items):
    """The longest modules first, so that two workers (``-n 2 --dist loadfile``) finish together."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def run_cli(*args):
    """``artic ARGS`` in-process; anything but a clean exit (a traceback) fails the test."""
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exception is None or isinstance(res.exception, SystemExit), repr(res.exception)
    return res


@pytest.fixture(scope="session")
def cfg():
    return load_config(ROOT / "configs" / "default.yaml")


@pytest.fixture(scope="session")
def mesh(cfg):
    return tongue_mesh(cfg.speaker.tongue)


@pytest.fixture(scope="session")
def wall(cfg):
    return wall_surface(cfg.speaker.wall)


@pytest.fixture(scope="session")
def model(cfg, mesh):
    return build_model(mesh, cfg.materials.tongue, cfg.simulation)


@pytest.fixture(scope="session")
def art(cfg, mesh, wall):
    """The whole articulator (tongue, jaw, hyoid, muscles, contact)."""
    from artic_cli.mechanics.model import build_articulator

    return build_articulator(cfg, mesh, wall)


def _articulator(cfg, mesh, wall, mirror: bool):
    from artic_cli.mechanics.model import build_articulator

    sim = cfg.simulation.model_copy(update={"mirror_symmetry": mirror})
    return build_articulator(cfg.model_copy(update={"simulation": sim}), mesh, wall)


@pytest.fixture(scope="session")
def art_whole(cfg, mesh, wall):
    """The articulator solved whole (``simulation.mirror_symmetry`` off)."""
    return _articulator(cfg, mesh, wall, False)


@pytest.fixture(scope="session")
def art_half(cfg, mesh, wall):
    """The articulator solved by halves: its left half moves as the mirror image of its right half."""
    return _articulator(cfg, mesh, wall, True)


@pytest.fixture(scope="session")
def mesh_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("mesh") / "mesh.h5"
    build_mesh(ROOT / "configs" / "default.yaml", out)
    return out


@pytest.fixture(scope="session")
def other_mesh_file(tmp_path_factory):
    """A mesh of another speaker (configs/speaker_small.yaml): different content."""
    out = tmp_path_factory.mktemp("other-mesh") / "mesh.h5"
    build_mesh(ROOT / "configs" / "speaker_small.yaml", out)
    return out


def set_force(model, sets: dict[str, tuple[float, float, float]]) -> np.ndarray:
    """Nodal force array (dyn) from {node set: total force in N}."""
    f = np.zeros((model.n_nodes, 3))
    for name, fn in sets.items():
        idx = model.node_set(name)
        f[idx] += np.asarray(fn) * 1e5 / len(idx)
    return f
