"""Artefacts on disk: written atomically with their provenance, read back with checks.

Every HDF5 artefact carries at its root ``kind``, ``schema_version`` and ``content_sha256`` (a hash of what
it holds: :func:`artic_cli.io.fingerprint.h5_content_hash`), and its provenance: ``recipe_sha256`` (the
stage, the config sections it read, the content hashes of the artefacts it read, its code and its
parameters), ``inputs_json`` and ``created``.  Writing goes to a temporary file beside the target, renamed
over it only when complete, so an interrupted run never leaves a half-written file a later stage would
trust.  A rewrite whose content equals the file it replaces keeps that file's modification time, so
``make`` sees nothing new downstream.  Lengths are stored in cm, forces in N, times in s; each dataset says
so in its ``units`` attribute.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import h5py
import numpy as np

from .. import __version__
from ..config import Speaker, parse_speaker
from ..errors import ArticError
from ..geometry.mesh import Mesh
from ..geometry.wall import PARTS, WallSurface
from .fingerprint import digest, h5_content_hash

SCHEMA_VERSION = 2


@dataclass(frozen=True)
class Provenance:
    """What an artefact was made from: the stage, its config sections' hash, its inputs' content hashes,
    its code's hash and its parameters.  ``recipe`` hashes all of them: equal recipes, equal results."""

    stage: str
    sections_sha256: str = ""
    inputs: dict = field(default_factory=dict)  # name -> content_sha256 of an artefact (or of a user file)
    code_sha256: str = ""
    params: dict = field(default_factory=dict)

    @property
    def recipe(self) -> str:
        return digest({"stage": self.stage, "sections": self.sections_sha256, "inputs": self.inputs,
                       "code": self.code_sha256, "params": self.params, "schema": SCHEMA_VERSION})

    def attrs(self) -> dict:
        return {"recipe_sha256": self.recipe, "config_sections_sha256": self.sections_sha256,
                "code_sha256": self.code_sha256, "inputs_json": json.dumps(self.inputs, sort_keys=True),
                "package_version": __version__,
                "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}


def read_array(group: h5py.Group, name: str) -> np.ndarray:
    """A whole dataset of ``group`` through h5py's low-level API: artefacts of many small datasets (the EP
    maps hold about a thousand) load in a third of the time the high-level one spends on each one's Python
    wrapper."""
    d = h5py.h5d.open(group.id, name.encode())
    out = np.empty(d.shape, dtype=d.dtype)
    if out.size:
        d.read(h5py.h5s.ALL, h5py.h5s.ALL, out)
    return out[()] if out.ndim == 0 else out


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: Path | str, suffix: str = ".tmp", same_content=None) -> Iterator[Path]:
    """A temporary file beside ``path`` that replaces it (with ordinary permissions) only on success.
    ``same_content(old, new)``: when it says the two hold the same, the old file's mtime is kept."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; artefacts are for sharing
        keep = None
        if same_content is not None and path.is_file():
            with contextlib.suppress(Exception):
                if same_content(path, Path(tmp)):
                    st = path.stat()
                    keep = (st.st_atime_ns, st.st_mtime_ns)
        os.replace(tmp, path)
        if keep is not None:
            os.utime(path, ns=keep)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _is_h5(path: Path) -> bool:
    with open(path, "rb") as fh:
        return fh.read(8) == b"\x89HDF\r\n\x1a\n"


def stored_content_hash(path: Path | str) -> str | None:
    """The ``content_sha256`` an artefact records (HDF5 root attribute or JSON/YAML ``provenance``), or None."""
    path = Path(path)
    try:
        if _is_h5(path):
            with h5py.File(path, "r") as f:
                v = f.attrs.get("content_sha256")
                return None if v is None else str(v)
        doc = _read_doc(path)
        return (doc.get("provenance") or {}).get("content_sha256") if isinstance(doc, dict) else None
    except Exception:  # noqa: BLE001 - unreadable: no usable hash
        return None


def stored_recipe(path: Path | str) -> str | None:
    """The ``recipe_sha256`` an artefact records, or None (missing, unreadable, or from an older artic)."""
    path = Path(path)
    if not path.is_file():
        return None
    try:
        if _is_h5(path):
            with h5py.File(path, "r") as f:
                if f.attrs.get("schema_version") != SCHEMA_VERSION or "content_sha256" not in f.attrs:
                    return None
                v = f.attrs.get("recipe_sha256")
                return None if v is None else str(v)
        doc = _read_doc(path)
        return (doc.get("provenance") or {}).get("recipe_sha256") if isinstance(doc, dict) else None
    except Exception:  # noqa: BLE001
        return None


def _same_h5(old: Path, new: Path) -> bool:
    return stored_content_hash(old) == stored_content_hash(new) is not None


@contextlib.contextmanager
def atomic_h5(path: Path | str, kind: str, provenance: Provenance | None = None) -> Iterator[h5py.File]:
    """Open a temporary HDF5 file that replaces ``path`` only on success, with its content hash and
    provenance at the root."""
    with atomic_path(path, same_content=_same_h5) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs.update({"kind": kind, "schema_version": SCHEMA_VERSION})
            if provenance is not None:
                f.attrs.update(provenance.attrs())
            yield f
            f.attrs["content_sha256"] = h5_content_hash(f)


def content_hash_of(path: Path | str, kind: str, hint: str) -> str:
    """The content hash an artefact of ``kind`` records; an ArticError naming the fix if it has none."""
    with open_artifact(path, kind, hint) as f:
        v = f.attrs.get("content_sha256")
    if v is None:
        raise ArticError(f"{path} records no content hash; {hint}")
    return str(v)


def open_artifact(path: Path | str, kind: str, hint: str, allow_invalid: bool = False) -> h5py.File:
    """Open an artefact for reading; any problem is one ArticError naming the fix.  An artefact marked
    invalid (``valid = false``: its result is not physical) is refused unless ``allow_invalid``."""
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
    if not allow_invalid and not bool(f.attrs.get("valid", True)):
        reason = f.attrs.get("invalid_reason", "")
        f.close()
        raise ArticError(f"{path} is marked invalid, its result is not physical ({reason}); fix the run that made "
                         "it (smaller forces or step) and rerun")
    return f


def _dataset(group: h5py.Group, name: str, data, units: str | None = None) -> None:
    ds = group.create_dataset(name, data=data)
    if units:
        ds.attrs["units"] = units


MESH_HINT = "rebuild it with 'artic build-mesh'"


def save_mesh(path: Path | str, mesh: Mesh, wall: WallSurface, speaker: Speaker,
              provenance: Provenance | None = None) -> None:
    """The mesh and wall with the ``speaker`` section they were built from (nothing else of the config)."""
    with atomic_h5(path, "mesh", provenance) as f:
        f.attrs["speaker_json"] = json.dumps(speaker.model_dump(mode="json"), sort_keys=True)
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


@dataclass
class MeshFile:
    mesh: Mesh
    wall: WallSurface
    speaker: Speaker
    content_sha256: str


def load_mesh(path: Path | str, expect: Speaker | None = None) -> MeshFile:
    """Mesh, wall and the speaker section that built them; checks the speaker matches ``expect``."""
    with open_artifact(path, "mesh", MESH_HINT) as f:
        try:
            speaker = parse_speaker(json.loads(f.attrs["speaker_json"]), f"{path} (embedded speaker)")
            t, w = f["tongue"], f["wall"]
            mesh = Mesh(nodes=t["nodes"][()], bricks=t["bricks"][()], cylinders=t["cylinders"][()],
                        share=t["share"][()], areas=t["areas"][()],
                        node_sets={k: v[()] for k, v in t["node_sets"].items()}, kind="tongue",
                        grid=tuple(int(g) for g in t.attrs["grid"]))
            wall = WallSurface(vertices=w["vertices"][()], triangles=w["triangles"][()],
                               normals=w["normals"][()], part=w["part"][()])
            content = str(f.attrs["content_sha256"])
        except (KeyError, OSError, ValueError, TypeError):
            raise ArticError(f"{path} is missing mesh data (truncated or from another tool); {MESH_HINT}") from None
    if expect is not None and digest(expect.model_dump(mode="json")) != digest(speaker.model_dump(mode="json")):
        raise ArticError(f"{path} was built from another speaker geometry than the config's; "
                         f"{MESH_HINT} --config <your config>")
    return MeshFile(mesh, wall, speaker, content)


def file_hash(path: Path | str) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def write_text_atomic(path: Path | str, text: str) -> Path:
    """Write a text file (a figure index, a CSV) through a temporary file and a rename."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def _read_doc(path: Path):
    from ..validation import load_yaml

    text = Path(path).read_text()
    return json.loads(text) if Path(path).suffix == ".json" else load_yaml(text)


def doc_content_hash(doc: dict) -> str:
    return digest({k: v for k, v in doc.items() if k != "provenance"})


def write_doc(path: Path | str, doc: dict, provenance: Provenance | None = None) -> Path:
    """A JSON (``.json``) or YAML artefact, its ``provenance`` (with the content hash) under that key; a
    rewrite with the same content keeps the old file's mtime."""
    import yaml

    path = Path(path)
    body = {k: v for k, v in doc.items() if k != "provenance"}
    prov = dict(provenance.attrs()) if provenance is not None else {}
    prov["content_sha256"] = doc_content_hash(body)
    body["provenance"] = prov
    text = (json.dumps(body, indent=1, default=float) if path.suffix == ".json"
            else yaml.safe_dump(body, sort_keys=False))
    with atomic_path(path, same_content=lambda old, new: stored_content_hash(old) == prov["content_sha256"]) as tmp:
        tmp.write_text(text)
    return path


def read_doc(path: Path | str, what: str, hint: str) -> dict:
    """A JSON/YAML artefact written by :func:`write_doc`; one ArticError naming the fix if it is not one."""
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"{what} not found: {path}; {hint}")
    try:
        doc = _read_doc(path)
    except Exception:  # noqa: BLE001 - any parse failure is a damaged file
        raise ArticError(f"{path} is not a readable {what} (damaged or truncated); {hint}") from None
    if not isinstance(doc, dict) or "provenance" not in doc:
        raise ArticError(f"{path} is not a {what} written by this artic; {hint}")
    return doc

