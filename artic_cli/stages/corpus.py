"""Stage ``corpus``: a list of texts -> every item spoken on a dask.distributed cluster -> an index and a card.

Each item is spoken by :func:`artic_cli.stages.speak.speak` on a worker into ``DIR/items/ID.*`` (WAV, TextGrid,
HDF5 record, EMA-style CSV), its targets' answers kept in one ``DIR/solutions`` folder that every worker reads
(a target is solved by one worker while the others wait for its answer).  A worker loads the maps, the mesh and
the model once (:mod:`.loaded`).  The client writes the index after every finished item; an item whose row
holds this recipe (its text, rate, accent, config, and the corpus's maps, mesh, inventory, config and code),
with its files as hashed, is done and not spoken again.  An item that cannot be spoken (bad text, an
unreachable target) is recorded with its error while the rest go on.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import DEFAULT_CONFIG
from ..corpus.card import dataset_card
from ..corpus.ema import ema_csv
from ..corpus.index import FINAL_EXITS, finished, item_hashes, read_index, write_index
from ..corpus.listing import Item, read_listing
from ..errors import ArticError, UnreachableTarget
from ..io.fingerprint import digest
from ..io.store import file_hash, stored_content_hash, write_text_atomic
from . import loaded, paths
from .base import Stage

STAGE = Stage(name="corpus", module=__name__, sections=(), reads=("mesh", "epmaps", "acousticmaps"), kind="corpus",
              hint="rerun 'artic corpus LIST --out DIR'")
SUFFIXES = (".wav", ".TextGrid", ".h5", ".ema.csv")


@dataclass(frozen=True)
class Setup:
    """What every item is spoken with (paths as given; the workers must see the same files)."""

    maps: str = str(paths.EPMAPS)
    mesh: str = str(paths.MESH)
    acoustic_maps: str | None = str(paths.ACOUSTIC_MAPS)
    dynamic: str | None = str(paths.DYNAMIC)
    config: str | None = None
    inventory: str | None = None
    budget: int = 8
    solutions: str | None = None  # where the targets' answers are kept (default: the corpus's solutions/)
    accept_nearest: bool = False  # an unreachable target's nearest answer spoken (else the item is unreachable)

    def shared(self) -> dict:
        """The content of what every item's recipe shares (the code, the artefacts, the configs)."""
        from ..speech.inventory import DEFAULT

        for name, p in (("maps", self.maps), ("mesh", self.mesh), ("acoustic maps", self.acoustic_maps)):
            if p is not None and stored_content_hash(p) is None:
                raise ArticError(f"{name} {p} is missing or unreadable; build it first (make data/epmaps.h5 "
                                 "data/acoustic_maps.h5 data/dynamic.h5)")
        return {"code": STAGE.provenance(None).code_sha256, "mesh": stored_content_hash(self.mesh),
                "epmaps": stored_content_hash(self.maps),
                "acoustic_maps": None if self.acoustic_maps is None else stored_content_hash(self.acoustic_maps),
                "dynamic": None if self.dynamic is None else stored_content_hash(self.dynamic),
                "config": file_hash(self.config or DEFAULT_CONFIG),
                "inventory": file_hash(self.inventory or DEFAULT), "budget": self.budget,
                **({"accept_nearest": True} if self.accept_nearest else {})}


def recipe(item: Item, shared: dict) -> str:
    return digest({"item": {**item.as_dict(), "config": None if item.config is None else file_hash(item.config)},
                   "shared": shared})


# --- one item, on a worker -----------------------------------------------------------------------------

def speak_item(item: Item, setup: Setup, out: str, key: str) -> dict:
    """Speak one item into ``out/items``: its index row (status, error, files, hashes, wall time) and whether
    it was simulated (``spoke``: False when its files already held this recipe)."""
    t0 = time.perf_counter()
    row = _row(item, key)
    try:
        row.update(_spoken(item, setup, Path(out)))
        row.update(status="ok", exit_code=0, error=None)
    except Exception as err:  # noqa: BLE001 - every failure becomes the item's row; the corpus goes on
        _remove(Path(out), item.id)
        row.update(_failure(err))
    row["wall_s"] = round(time.perf_counter() - t0, 2)
    row["worker"] = (os.getpid(), _peak_mb())
    return row


def _row(item: Item, key: str) -> dict:
    """An item's index row as the list gives it (its config is part of the recipe, not a column)."""
    return {"id": item.id, "text": item.text, "rate": item.rate, "accent": item.accent, "recipe_sha256": key}


def _peak_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def _failure(err: BaseException) -> dict:
    if isinstance(err, UnreachableTarget):
        status, code = "unreachable", 3
    elif isinstance(err, ArticError):
        status, code = "failed", err.exit_code
    else:  # a crash: tried again on the next run
        status, code = "failed", 1
    text = str(err) if isinstance(err, ArticError) else f"{type(err).__name__}: {err}"
    text = text.removeprefix("--text: ")  # the item's text, not a command-line option, is what it names
    return {"status": status, "exit_code": code, "error": " ".join(text.split())[:500], "spoke": False}


def _spoken(item: Item, setup: Setup, out: Path) -> dict:
    from ..speech.inventory import DEFAULT, load_inventory
    from ..speech.text import utterance_of_text
    from . import speak as speak_stage

    inventory = setup.inventory or DEFAULT
    inv = loaded.once("inventory", lambda: load_inventory(inventory), (inventory,))
    u = utterance_of_text(item.text, inv, name=item.id, rate=item.rate, accent=item.accent)
    items = out / "items"
    items.mkdir(parents=True, exist_ok=True)
    res = speak_stage.speak(u, items / f"{item.id}.wav", setup.maps, setup.mesh, setup.acoustic_maps,
                            item.config or setup.config, setup.solutions or out / "solutions", setup.accept_nearest,
                            setup.budget, dynamic=setup.dynamic, inventory=setup.inventory)
    rec = speak_stage.read(res.paths["h5"])
    ema = items / f"{item.id}.ema.csv"
    write_text_atomic(ema, ema_csv(rec.time_s, _points(rec, setup, item), *_lips(res.paths["h5"])))
    files = {"wav": f"items/{item.id}.wav", "textgrid": f"items/{res.paths['textgrid'].name}",
             "h5": f"items/{res.paths['h5'].name}", "ema": f"items/{ema.name}"}
    from ..io.wav import read_wav

    _, rate = read_wav(res.paths["wav"])
    return {"phones": " ".join(lab or "_" for lab in rec.labels),
            "duration_s": round(float(rec.attrs["duration_s"]), 4), "sample_rate_hz": int(rate), **files,
            **item_hashes(out, files), "spoke": not res.up_to_date}


def _points(rec, setup: Setup, item: Item) -> dict[str, np.ndarray]:
    """The record's tip, dorsum and jaw, and the blade: the midsagittal surface node between tip and dorsum."""
    from ..config import load_config
    from . import mesh as mesh_stage

    config = item.config or setup.config or DEFAULT_CONFIG
    mesh = loaded.once("mesh", lambda: mesh_stage.read(setup.mesh, load_config(config)).mesh, (setup.mesh, config))
    surface = mesh.node_sets["midsagittal_surface"]
    pts = {name: np.asarray(xyz)[:, :2] for name, xyz in rec.control_points.items()}
    pts["blade"] = rec.positions_cm[:, int(surface[2]), :2]
    return pts


def _lips(h5: Path) -> tuple[np.ndarray, np.ndarray]:
    import h5py

    with h5py.File(h5, "r") as f:
        return f["tract_controls/lip_area_cm2"][()], f["tract_controls/lip_length_cm"][()]


def _remove(out: Path, ident: str) -> None:
    for suffix in SUFFIXES:
        (out / "items" / f"{ident}{suffix}").unlink(missing_ok=True)


# --- the corpus, from the client -----------------------------------------------------------------------

@dataclass
class CorpusResult:
    rows: list[dict]
    spoken: int = 0  # items simulated in this run
    kept: int = 0  # items already done (their rows kept)
    failed: list[dict] = field(default_factory=list)  # rows not ok
    peak_mb: dict[int, float] = field(default_factory=dict)  # each worker's (pid) peak resident memory, MB
    interrupted: bool = False


def run_corpus(listing: Path | str, out: Path | str, setup: Setup = Setup(), jobs: int = 2,
               scheduler: str | None = None, progress: Callable[[int, int, int], None] | None = None,
               say: Callable[[str], None] | None = None) -> CorpusResult:
    """Speak every item of ``listing`` not yet done in ``out`` on ``jobs`` local workers (or the cluster at
    ``scheduler``); the index after each item, the dataset card at the end (also when interrupted)."""
    items = read_listing(listing)
    out = Path(out)
    shared = setup.shared()
    keys = {it.id: recipe(it, shared) for it in items}
    old = read_index(out)
    rows = {it.id: old[it.id] for it in items if finished(out, old.get(it.id), keys[it.id])}
    todo = [it for it in items if it.id not in rows]
    for it in todo:  # a spoken item whose files changed or went since: its files go, so it is spoken again
        was = old.get(it.id)
        if was is not None and was.get("recipe_sha256") == keys[it.id] and was.get("status") == "ok":
            _remove(out, it.id)
    res = CorpusResult(rows=[], kept=len(rows))
    out.mkdir(parents=True, exist_ok=True)
    order = [it.id for it in items]
    try:
        if todo:
            _run(todo, setup, out, keys, jobs, scheduler, rows, res, order, progress, len(items), say)
        elif say:
            say(f"nothing to do: all {len(items)} items of {listing} are done in {out}")
    except KeyboardInterrupt:
        res.interrupted = True
        raise
    finally:
        res.rows = [rows[i] for i in order if i in rows]
        res.failed = [r for r in res.rows if r.get("status") != "ok"]
        write_index(out, res.rows)
        write_text_atomic(out / "README.md", dataset_card(out.name, res.rows, _facts(listing, setup, shared),
                                                          _symbols(setup)))
    return res


def _run(todo: list[Item], setup: Setup, out: Path, keys: dict, jobs: int, scheduler: str | None, rows: dict,
         res: CorpusResult, order: list[str], progress, total: int, say) -> None:
    from dask.distributed import as_completed

    from ..parallel import dask_client

    if progress:
        progress(len(rows), total, sum(r.get("status") != "ok" for r in rows.values()))
    with dask_client(jobs, scheduler, "or leave --scheduler out (a local cluster)") as client:
        futures = {client.submit(speak_item, it, setup, str(out.resolve()), keys[it.id], pure=False): it
                   for it in todo}
        for fut in as_completed(futures):
            it = futures[fut]
            try:
                row = fut.result()
            except Exception as err:  # noqa: BLE001 - a lost worker (KilledWorker) or a task that cannot run
                row = {**_row(it, keys[it.id]), **_failure(err), "wall_s": None}
            res.spoken += bool(row.pop("spoke", False))
            pid, mb = row.pop("worker", (None, 0.0))
            if pid is not None:
                res.peak_mb[pid] = max(res.peak_mb.get(pid, 0.0), mb)
            rows[it.id] = row
            write_index(out, [rows[i] for i in order if i in rows])
            if say and row["status"] != "ok":
                say(f"{it.id}: {row['status']}: {row['error']}")
            if progress:
                progress(len(rows), total, sum(r.get("status") != "ok" for r in rows.values()))


def _facts(listing, setup: Setup, shared: dict) -> dict:
    from .. import __version__

    return {"artic version": __version__, "code sha256": shared["code"],
            "config": str(setup.config or DEFAULT_CONFIG), "config sha256": shared["config"],
            "mesh content sha256": shared["mesh"], "EP maps content sha256": shared["epmaps"],
            "acoustic maps content sha256": shared["acoustic_maps"], "dynamic map content sha256": shared["dynamic"],
            "inventory sha256": shared["inventory"], "list": str(listing), "list sha256": file_hash(listing),
            "refinement budget (simulations per target)": setup.budget,
            "unreachable targets": "their nearest answers spoken" if setup.accept_nearest else "the item not spoken"}


def _symbols(setup: Setup) -> list[str]:
    from ..speech.inventory import DEFAULT, load_inventory

    return list(load_inventory(setup.inventory or DEFAULT).phonemes)


__all__ = ["Setup", "CorpusResult", "run_corpus", "speak_item", "recipe", "FINAL_EXITS"]
