"""Artefacts on disk: HDF5 written atomically, read back with checks.

Every artefact carries ``kind``, ``schema_version``, ``package_version``,
``config_hash`` and ``created`` attributes at its root.  Writing goes to a
temporary file beside the target, renamed over it only when complete, so an
interrupted run never leaves a half-written file a later stage would trust.
Lengths are stored in cm, forces in N, times in s; each dataset says so in
its ``units`` attribute.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import tempfile
from pathlib import Path
from typing import Iterator

import h5py
import numpy as np

from .. import __version__
from ..config import Config, config_hash, geometry_hash, parse_config
from ..errors import ArticError
from ..geometry.mesh import Mesh
from ..geometry.wall import PARTS, WallSurface

SCHEMA_VERSION = 1


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: Path | str, suffix: str = ".tmp") -> Iterator[Path]:
    """A temporary file beside ``path`` that replaces it (with ordinary permissions) only on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; artefacts are for sharing
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_h5(path: Path | str, kind: str, cfg_hash: str = "") -> Iterator[h5py.File]:
    """Open a temporary HDF5 file that replaces ``path`` only on success."""
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs.update({"kind": kind, "schema_version": SCHEMA_VERSION, "package_version": __version__,
                            "config_hash": cfg_hash,
                            "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")})
            yield f


def open_artifact(path: Path | str, kind: str, hint: str) -> h5py.File:
    """Open an artefact for reading; any problem is one ArticError naming the fix."""
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"{kind} file not found: {path}; {hint}")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise ArticError(f"{path} is not a readable HDF5 file (corrupted or truncated); {hint}") from None
    try:
        got_kind = f.attrs.get("kind")
        version = f.attrs.get("schema_version")
    except Exception:  # noqa: BLE001 - h5py raises assorted errors on damaged headers
        f.close()
        raise ArticError(f"{path} has damaged metadata; {hint}") from None
    if got_kind != kind:
        f.close()
        raise ArticError(f"{path} holds '{got_kind}', not a {kind}; {hint}")
    if version != SCHEMA_VERSION:
        f.close()
        raise ArticError(f"{path} was written with schema version {version}, this artic reads {SCHEMA_VERSION}; {hint}")
    return f


def _dataset(group: h5py.Group, name: str, data, units: str | None = None) -> None:
    ds = group.create_dataset(name, data=data)
    if units:
        ds.attrs["units"] = units


MESH_HINT = "rebuild it with 'artic build-mesh'"


def save_mesh(path: Path | str, mesh: Mesh, wall: WallSurface, cfg: Config) -> None:
    import yaml

    h = config_hash(cfg)
    with atomic_h5(path, "mesh", h) as f:
        f.attrs["config_yaml"] = yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False)
        f.attrs["geometry_hash"] = geometry_hash(cfg)
        t = f.create_group("tongue")
        _dataset(t, "nodes", mesh.nodes, "cm")
        _dataset(t, "bricks", mesh.bricks)
        _dataset(t, "cylinders", mesh.cylinders)
        _dataset(t, "share", mesh.share)
        _dataset(t, "areas", mesh.areas, "cm^2")
        t.attrs["grid"] = np.asarray(mesh.grid)
        t.attrs["volume_cm3"] = mesh.volume
        sets = t.create_group("node_sets")
        for name, idx in mesh.node_sets.items():
            sets.create_dataset(name, data=idx)
        w = f.create_group("wall")
        _dataset(w, "vertices", wall.vertices, "cm")
        _dataset(w, "triangles", wall.triangles)
        _dataset(w, "normals", wall.normals)
        _dataset(w, "part", wall.part)
        w.attrs["parts"] = list(PARTS)
        w.attrs["normals"] = "unit, pointing out of the lumen (into the wall)"


def load_mesh(path: Path | str, expect: Config | None = None) -> tuple[Mesh, WallSurface, Config]:
    """Mesh, wall and the config that built them; checks the config matches ``expect``."""
    with open_artifact(path, "mesh", MESH_HINT) as f:
        try:
            import yaml

            cfg = parse_config(yaml.safe_load(f.attrs["config_yaml"]), f"{path} (embedded config)")
            t, w = f["tongue"], f["wall"]
            mesh = Mesh(nodes=t["nodes"][()], bricks=t["bricks"][()], cylinders=t["cylinders"][()],
                        share=t["share"][()], areas=t["areas"][()],
                        node_sets={k: v[()] for k, v in t["node_sets"].items()}, kind="tongue",
                        grid=tuple(int(g) for g in t.attrs["grid"]))
            wall = WallSurface(vertices=w["vertices"][()], triangles=w["triangles"][()],
                               normals=w["normals"][()], part=w["part"][()])
            stored_hash = f.attrs["geometry_hash"]
        except (KeyError, OSError, ValueError, TypeError):
            raise ArticError(f"{path} is missing mesh data (truncated or from another tool); {MESH_HINT}") from None
    if expect is not None and stored_hash != geometry_hash(expect):
        raise ArticError(f"{path} was built from another speaker geometry (hash {stored_hash[:12]}, "
                         f"config {geometry_hash(expect)[:12]}); {MESH_HINT} --config <your config>")
    return mesh, wall, cfg


def file_hash(path: Path | str) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def write_text_atomic(path: Path | str, text: str) -> Path:
    """Write a text artefact through a temporary file and a rename."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path
