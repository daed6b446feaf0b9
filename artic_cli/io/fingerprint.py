"""Content fingerprints: what an artefact holds, which config sections and which source code made it.

* :func:`digest` hashes plain data as canonical JSON;
* :func:`sections_hash` hashes the named sections of a validated config (defaults included);
* :func:`h5_content_hash` hashes an HDF5 file's datasets and attributes, leaving out its provenance
  (:data:`PROVENANCE_ATTRS`: when, by which version, how long, from what);
* :func:`code_hash` hashes the syntax trees of a module and every ``artic_cli`` module it imports,
  docstrings and comments left out, so a comment or docstring edit changes no result's key.

Plots, the command line and the plumbing (:data:`NOT_RESULTS`) are never part of a result: their modules are
not followed.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
from pathlib import Path
from typing import Iterable

import numpy as np

PACKAGE = "artic_cli"
PACKAGE_DIR = Path(__file__).resolve().parent.parent
# never change a result, so never followed: pictures, the command line, and the plumbing (config values are
# hashed by section, file layouts are versioned by the store's schema version)
NOT_RESULTS = ("artic_cli.plots", "artic_cli.cli", "artic_cli.config", "artic_cli.errors", "artic_cli.io",
               "artic_cli.parallel", "artic_cli.pipeline", "artic_cli.stages.base", "artic_cli.stages.table")

# root attributes that say where an artefact came from, not what it holds
PROVENANCE_ATTRS = frozenset({"created", "package_version", "content_sha256", "recipe_sha256", "inputs_json",
                              "config_sections_sha256", "code_sha256", "wall_time_s"})


def digest(data) -> str:
    """sha256 of ``data`` as canonical JSON (sorted keys, no spaces)."""
    blob = json.dumps(data, sort_keys=True, separators=(",", ":"), default=_plain)
    return hashlib.sha256(blob.encode()).hexdigest()


def _plain(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot fingerprint {type(obj).__name__}")


def sections_hash(cfg, sections: Iterable[str]) -> str:
    """Hash of the named top-level sections of a validated config (what a stage reads, nothing else)."""
    return digest({s: getattr(cfg, s).model_dump(mode="json") for s in sorted(sections)})


# --- HDF5 ---------------------------------------------------------------------------------------------

def _update_value(h, value) -> None:
    arr = np.asarray(value)
    if arr.dtype.kind in "OSU":
        items = arr.ravel().tolist()
        h.update(repr([i.decode() if isinstance(i, bytes) else str(i) for i in items]).encode())
        h.update(repr(arr.shape).encode())
    else:
        h.update(f"{arr.dtype.str}{arr.shape}".encode())
        h.update(np.ascontiguousarray(arr).tobytes())


def _update_attrs(h, attrs, skip=frozenset()) -> None:
    for key in sorted(attrs):
        if key in skip:
            continue
        h.update(f"@{key}=".encode())
        _update_value(h, attrs[key])


def h5_content_hash(f) -> str:
    """sha256 of what an open HDF5 file holds: every dataset's name, type, shape and values and every
    attribute, except the root's provenance attributes."""
    import h5py

    h = hashlib.sha256()
    _update_attrs(h, f.attrs, PROVENANCE_ATTRS)
    names: list[str] = []
    f.visit(names.append)
    for name in sorted(names):
        obj = f[name]
        h.update(f"/{name}".encode())
        _update_attrs(h, obj.attrs)
        if isinstance(obj, h5py.Dataset):
            _update_value(h, obj[()])
    return h.hexdigest()


# --- source code ----------------------------------------------------------------------------------------

def module_path(name: str) -> Path:
    rel = Path(*name.split(".")[1:])
    pkg = PACKAGE_DIR / rel / "__init__.py"
    return pkg if pkg.is_file() else PACKAGE_DIR / rel.with_suffix(".py")


def _exists(name: str) -> bool:
    return name == PACKAGE or (name.startswith(PACKAGE + ".") and module_path(name).is_file())


def _imports_of(name: str, tree: ast.Module) -> frozenset[str]:
    """The artic_cli modules ``name`` (parsed: ``tree``) imports, at any depth of its code (function-level
    imports too)."""
    is_pkg = module_path(name).name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if _exists(a.name))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base_parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(base_parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            if not base.startswith(PACKAGE):
                continue
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.add(sub if _exists(sub) else base)
    return frozenset(m for m in out if _exists(m))


# each module's imports and code hash, kept on disk by its file's size and modification time (parsing and
# hashing 80 modules costs 2 s of every command's start otherwise); a damaged or unwritable cache is remade
CODE_CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "artic" / (
    "code-" + hashlib.sha256(str(PACKAGE_DIR).encode()).hexdigest()[:12] + ".json")
_changed: list[bool] = [False]


@functools.lru_cache(maxsize=None)
def _code_cache() -> dict:
    try:
        data = json.loads(CODE_CACHE.read_text())
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def _save_code_cache() -> None:
    if not _changed[0]:
        return
    try:
        CODE_CACHE.parent.mkdir(parents=True, exist_ok=True)
        tmp = CODE_CACHE.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(_code_cache()))
        tmp.replace(CODE_CACHE)
        _changed[0] = False
    except OSError:
        pass


@functools.lru_cache(maxsize=None)
def _module_facts(name: str) -> tuple[str, frozenset[str]]:
    """(code hash, imported artic_cli modules) of module ``name``: from the cache while its file is unchanged."""
    path = module_path(name)
    st = path.stat()
    sig = [st.st_mtime_ns, st.st_size]
    hit = _code_cache().get(str(path))
    if isinstance(hit, dict) and hit.get("sig") == sig:
        return hit["hash"], frozenset(hit["imports"])
    tree = ast.parse(path.read_text(), filename=str(path))
    imports = _imports_of(name, tree)
    code = hashlib.sha256(ast.dump(_strip_docstrings(tree), annotate_fields=False).encode()).hexdigest()
    _code_cache()[str(path)] = {"sig": sig, "hash": code, "imports": sorted(imports)}
    _changed[0] = True
    return code, imports


def _imports(name: str) -> frozenset[str]:
    return _module_facts(name)[1]


def module_closure(*roots: str, within: str | None = None) -> list[str]:
    """``roots`` and every artic_cli module they import, transitively; plots and the CLI are not followed, and
    neither are a package ``__init__``'s own imports (they only re-export).  ``within``: follow only modules
    of that package instead (e.g. ``artic_cli.plots`` for what a plot module draws with)."""
    seen: set[str] = set()
    todo = [r for r in roots]
    while todo:
        name = todo.pop()
        skip = (not name.startswith(within)) if within else any(name == p or name.startswith(p + ".")
                                                                 for p in NOT_RESULTS)
        if name in seen or skip:
            continue
        seen.add(name)
        if module_path(name).name != "__init__.py" or name in roots:
            todo.extend(_imports(name) - seen)
    return sorted(seen)


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
                    and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
    return tree


def source_hash(text: str) -> str:
    """Hash of Python source as its syntax tree without docstrings: comments, docstrings and layout do not
    count."""
    tree = _strip_docstrings(ast.parse(text))
    return hashlib.sha256(ast.dump(tree, annotate_fields=False).encode()).hexdigest()


@functools.lru_cache(maxsize=None)
def code_hash(*roots: str) -> str:
    """Hash of the code of ``roots`` and of what they import (syntax trees without docstrings or comments)."""
    out = digest({m: _module_facts(m)[0] for m in module_closure(*roots)})
    _save_code_cache()
    return out


def source_files(*roots: str) -> list[Path]:
    """The files of :func:`module_closure` (for the Makefile's prerequisites)."""
    return [module_path(m) for m in module_closure(*roots)]
