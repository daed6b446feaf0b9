"""``artic corpus``: a list of texts spoken on a dask.distributed cluster, resumable, with an index and a card."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from ..errors import ArticError
from ..stages import paths
from ..validation import check_number
from .app import app, err_console, handle_errors, out_console


@app.command("corpus")
@handle_errors
def corpus_cmd(
    listing: Path = typer.Argument(..., help="The items: a text file of 'id<TAB>text' lines (optional columns: "
                                             "rate, accent, config) or a CSV with those columns."),
    out: Path = typer.Option(..., "--out", help="The corpus folder: items/ID.{wav,TextGrid,h5,ema.csv}, "
                                                "index.csv, index.jsonl, README.md (the dataset card), solutions/."),
    jobs: int = typer.Option(os.cpu_count() or 1, "--jobs", help="Workers of the local cluster (default: the "
                                                                 "machine's cores)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="A running dask scheduler's address (e.g. "
                                            "tcp://10.0.0.5:8786) to speak on its workers instead of a local "
                                            "cluster; they must see --out and the maps at the same paths."),
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps the targets are solved on."),
    dynamic: Path = typer.Option(paths.DYNAMIC, "--dynamic", help="Dynamic map (place targets off the mapped jaws)."),
    acoustic_maps: Path = typer.Option(paths.ACOUSTIC_MAPS, "--acoustic-maps", help="Formants of every EP."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh from 'artic build-mesh'."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config of every item without its own."),
    inventory: Optional[Path] = typer.Option(None, "--inventory", help="Phoneme inventory (default "
                                                                       "configs/phonemes/japanese.yaml)."),
    solutions: Optional[Path] = typer.Option(None, "--solutions", help="Where the targets' answers are kept "
                                             "(default: DIR/solutions); corpora may share one."),
    budget: int = typer.Option(8, "--budget", help="Most simulations each target's refinement may spend."),
    accept_nearest: bool = typer.Option(False, "--accept-nearest", help="Speak an unreachable target's nearest "
                                        "answer instead of recording the item as unreachable."),
):
    """Speak every item of LIST into --out, on a dask.distributed cluster: each item's WAV, TextGrid, HDF5
    record and EMA CSV, one row of the index per item.  Run again, it speaks only what is not done (an
    interrupted run goes on where it stopped).  Exit 3 if any item failed or was unreachable (its row says why)."""
    from ..stages.corpus import Setup, run_corpus

    check_number("--jobs", jobs, ge=1)
    check_number("--budget", budget, ge=1)
    if out.exists() and not out.is_dir():
        raise ArticError(f"--out {out} is a file; give a folder")
    ab = lambda p: None if p is None else str(Path(p).absolute())  # noqa: E731 - the workers' paths
    setup = Setup(maps=ab(maps), mesh=ab(mesh), acoustic_maps=ab(acoustic_maps), dynamic=ab(dynamic),
                  config=ab(config), inventory=ab(inventory), budget=budget,
                  solutions=ab(solutions), accept_nearest=accept_nearest)
    say = lambda m: err_console.print(m, highlight=False, soft_wrap=True)  # noqa: E731
    start = time.perf_counter()
    bar, update = _progress()
    try:
        if bar is None:
            res = run_corpus(listing, out, setup, jobs, scheduler, update, say)
        else:
            with bar:
                res = run_corpus(listing, out, setup, jobs, scheduler, update, say)
    except KeyboardInterrupt:
        err_console.print(f"interrupted; the finished items are in {out / 'index.csv'}, run the same command "
                          "again to go on", highlight=False, soft_wrap=True)
        raise typer.Exit(130) from None
    ok = len(res.rows) - len(res.failed)
    out_console.print(f"{out}: {ok} of {len(res.rows)} items spoken ({res.spoken} this run, {res.kept} already "
                      f"done), {len(res.failed)} not; index {out / 'index.csv'}, card {out / 'README.md'} "
                      f"({time.perf_counter() - start:.1f} s"
                      + (f"; peak memory per worker {max(res.peak_mb.values()):.0f} MB" if res.peak_mb else "") + ")",
                      highlight=False)
    if res.failed:
        raise typer.Exit(3)


def _progress():
    """A bar (items done of all, failures, ETA) on a terminal, else a line per finished item."""
    if not sys.stderr.isatty():
        start, first = time.perf_counter(), []

        def line(done: int, total: int, failed: int) -> None:
            if not first:  # the items already done when the run starts
                first.append(done)
                return
            el = time.perf_counter() - start
            eta = el / max(done - first[0], 1) * (total - done)
            err_console.print(f"corpus: {done}/{total} items, {failed} failed, elapsed {el:.0f} s, eta {eta:.0f} s",
                              highlight=False)

        return None, line
    bar = Progress(TextColumn("corpus"), BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[failed]} failed"),
                   TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn(), console=err_console, transient=True)
    task = bar.add_task("corpus", total=None, failed=0)

    def update(done: int, total: int, failed: int) -> None:
        bar.update(task, completed=done, total=total, failed=failed)

    return bar, update
