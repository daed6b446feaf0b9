"""``artic``: the application, its error handling and its progress display; the commands live in the topic
modules beside it (:mod:`.main` registers them).

Each command is a thin shell over a stage module (:mod:`artic_cli.stages`) or
a plot.  Exit statuses: 0 done, 2 bad input (one line on stderr), 3 target
not reached (the answer is written), 4 result not physical (the file is
written and marked invalid), 130 interrupted.
"""

from __future__ import annotations

import contextlib
import functools
import sys

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..errors import ArticError

EXIT_STATUSES = ("Exit status: 0 done; 2 bad input (one line names the problem and the fix, nothing written); "
                 "3 target not reached (the answer is written); 4 result not physical (the file is written and "
                 "marked invalid); 130 interrupted.")
app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="A physiological articulatory model of the tongue, jaw and hyoid (after Dang & Honda 2004).",
                  epilog=EXIT_STATUSES)
validate_app = typer.Typer(no_args_is_help=True, help="Check the tissue model against the paper's test bodies.")
app.add_typer(validate_app, name="validate", help="Check the tissue model against the paper's test bodies (cuboid).")
plot_app = typer.Typer(no_args_is_help=True, help="Pictures of the artefacts.")
app.add_typer(plot_app, name="plot", help="Pictures of the artefacts (mesh, simulations, maps, solutions, ...).")

out_console = Console(width=None if sys.stdout.isatty() else 120)
err_console = Console(stderr=True)


def interrupted(err: BaseException) -> bool:
    """Whether ``err`` is a Ctrl-C: a KeyboardInterrupt, or the SystemError numba raises when the interrupt
    lands while compiled code is calling back into Python (the KeyboardInterrupt is then its cause)."""
    seen = set()
    while err is not None and id(err) not in seen:
        if isinstance(err, KeyboardInterrupt):
            return True
        seen.add(id(err))
        err = err.__cause__ or err.__context__
    return False


@contextlib.contextmanager
def exit_on_interrupt(message: str):
    """Turn a Ctrl-C (see :func:`interrupted`) into ``message`` on stderr and exit status 130."""
    try:
        yield
    except (KeyboardInterrupt, SystemError) as err:
        if not interrupted(err):
            raise
        err_console.print(message)
        raise typer.Exit(130) from None


def handle_errors(fn):
    """Turn ArticError into one line on stderr and its exit status; a Ctrl-C into one line and 130."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            with exit_on_interrupt("interrupted; no partial output was kept"):
                return fn(*args, **kwargs)
        except ArticError as err:
            err_console.print(f"[bold red]error:[/] {err}", highlight=False, soft_wrap=True)
            raise typer.Exit(err.exit_code) from None

    return wrapper


def with_progress(label: str, work, plain: bool = False):
    """Run ``work(update)`` under a progress bar (terminal) or progress lines (``plain``, for logs)."""
    bar, update = progress_bar(label, plain)
    if bar is None:
        return work(update)
    with bar:
        return work(update)


def print_table(title: str, columns: tuple[str, ...], rows, left: tuple[str, ...] = ()) -> None:
    table = Table(title=title)
    for col in columns:
        table.add_column(col, justify="left" if col in left else "right")
    for r in rows:
        table.add_row(*r)
    out_console.print(table)


def progress_bar(label: str, plain: bool = False):
    """A rich progress bar (done/total, ETA) when stderr is a terminal, else None; with ``plain``, lines at
    every tenth of the work instead (for logs)."""
    if not sys.stderr.isatty():
        if not plain:
            return None, None
        import time

        start, last = time.perf_counter(), [-1]

        def log(done: int, total: int) -> None:
            tenth = 10 * done // max(total, 1)
            if tenth != last[0] and done:
                last[0] = tenth
                el = time.perf_counter() - start
                eta = el / done * (total - done)
                err_console.print(f"{label}: {done}/{total} ({100 * done // total} %), elapsed {el:.0f} s, "
                                  f"eta {eta:.0f} s", highlight=False)

        return None, log
    bar = Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   TextColumn("eta"), TimeRemainingColumn(), console=err_console, transient=True)
    task = bar.add_task(label, total=None)

    def update(done: int, total: int) -> None:
        bar.update(task, completed=done, total=total)

    return bar, update
