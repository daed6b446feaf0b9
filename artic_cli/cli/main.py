"""``artic``: the command line.

Each command is a thin shell over a stage module (:mod:`artic_cli.stages`) or
a plot.  Exit statuses: 0 done, 2 bad input (one line on stderr), 3 target
not reached (the answer is written), 4 result not physical (the file is
written and marked invalid), 130 interrupted.
"""

from __future__ import annotations

import contextlib
import functools
import json
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import List, Optional

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..errors import ArticError
from ..validation import DEFAULT_MAX_FORCE_N, check_number

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


def _with_progress(label: str, work, plain: bool = False):
    """Run ``work(update)`` under a progress bar (terminal) or progress lines (``plain``, for logs)."""
    bar, update = _progress(label, plain)
    if bar is None:
        return work(update)
    with bar:
        return work(update)


def _print_table(title: str, columns: tuple[str, ...], rows, left: tuple[str, ...] = ()) -> None:
    table = Table(title=title)
    for col in columns:
        table.add_column(col, justify="left" if col in left else "right")
    for r in rows:
        table.add_row(*r)
    out_console.print(table)


def _progress(label: str, plain: bool = False):
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


@app.command("build-mesh")
@handle_errors
def build_mesh_cmd(
    config: Optional[Path] = typer.Option(None, "--config", help="Speaker config (YAML); default configs/default.yaml."),
    out: Path = typer.Option(Path("data/mesh.h5"), "--out", help="Mesh artefact to write (HDF5)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw the midsagittal view (PNG), like Fig. 1."),
):
    """Build the tongue mesh (bricks + cylinders) and the vocal-tract wall."""
    from ..stages.mesh import build_mesh

    s = build_mesh(config, out)
    if plot:
        _plot_mesh(out, plot, config)
    rel = abs(s.cylinder_volume_cm3 - s.volume_cm3) / s.volume_cm3
    verb = f"{s.path} is up to date (same speaker geometry and code)" if s.up_to_date else f"wrote {s.path}"
    out_console.print(f"{verb}: {s.nodes} nodes, {s.bricks} bricks, {s.cylinders} cylinders, "
                      f"tongue volume {s.volume_cm3:.3f} cm^3 (cylinders {s.cylinder_volume_cm3:.3f} cm^3, "
                      f"rel. diff {rel:.1e}), wall {s.wall_triangles} triangles"
                      + (f"; figure {plot}" if plot else ""), highlight=False)


@app.command("simulate")
@handle_errors
def simulate_cmd(
    schedule: Path = typer.Option(..., "--schedule", help="Load schedule (YAML): node sets, forces in N, onset/duration in ms."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time in s (default: the schedule's duration_ms)."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step in s (default: the config's dt_ms)."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config the mesh was built from."),
    out: Optional[Path] = typer.Option(None, "--out", help="Output (HDF5); default data/sims/<schedule>.h5."),
    volume_constraint: Optional[bool] = typer.Option(None, "--volume-constraint/--no-volume-constraint",
                                                     help="Override the config's volume constraint."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw start and end shapes (PNG)."),
    tongue_only: bool = typer.Option(False, "--tongue-only", help="The tongue alone, its fixed node sets held."),
    contact: Optional[bool] = typer.Option(None, "--contact/--no-contact", help="Override the config's wall contact."),
    animate: Optional[Path] = typer.Option(None, "--animate", help="Also write a short animation (GIF)."),
):
    """Move the model under a schedule of muscle forces and loads; write trajectories."""
    from ..stages.simulate import simulate

    args = (schedule, duration, dt, mesh, config, out, volume_constraint)
    r = _with_progress("simulating", lambda update: simulate(*args, update, tongue_only=tongue_only, contact=contact))
    if plot or animate:
        _plot_simulation(r.path, r.model, r.wall, plot, animate)
    if r.up_to_date:
        out_console.print(f"{r.path} is up to date (same mesh, config sections, schedule, options and code); "
                          f"max |volume change| {100 * r.max_volume_change:.3f} %", highlight=False)
        _refuse_unphysical(r)
        return
    t = r.trajectory
    sim_time = t.time[-1] - t.time[0]
    out_console.print(
        f"wrote {r.path}: {t.stats['steps']} steps of {t.stats['dt'] * 1e3:g} ms, wall {t.stats['wall_time_s']:.3f} s "
        f"({t.stats['wall_time_s'] / sim_time:.3f} s per simulated s), max |volume change| "
        f"{100 * r.max_volume_change:.3f} % (constraint {'on' if r.model.volume_constraint else 'off'}), "
        f"inverted bricks {int(t.inverted.max())}" + (f"; figure {plot}" if plot else "")
        + (f"; animation {animate}" if animate else ""), highlight=False)
    _refuse_unphysical(r)


def _refuse_unphysical(r) -> None:
    if r.problems:
        from ..errors import NotPhysical

        raise NotPhysical(f"{r.path} is not physical and is marked invalid: {'; '.join(r.problems)}; lower the "
                          "forces or the step (--dt) and rerun")


@validate_app.command("cuboid")
@handle_errors
def validate_cuboid_cmd(
    force: Optional[List[float]] = typer.Option(None, "--force", help="Pulling force in N (repeat); default from the config."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config for materials (default configs/default.yaml)."),
    volume_constraint: Optional[bool] = typer.Option(None, "--volume-constraint/--no-volume-constraint"),
    as_json: bool = typer.Option(False, "--json", help="Print the table as JSON."),
    out: Optional[Path] = typer.Option(None, "--out", help="Also write the rows as JSON to this file."),
):
    """Pull the paper's 6 x 3 x 2 cm cuboid: strains, Poisson ratio (Eq. 4), volume change."""

    for f in force or []:
        check_number("--force", f, ge=0, le=DEFAULT_MAX_FORCE_N, unit="N")
    from ..stages.cuboid import validate_cuboid

    dicts = validate_cuboid(config, force, volume_constraint, out)
    rows = [SimpleNamespace(**d) for d in dicts]
    if as_json:
        out_console.print_json(json.dumps(dicts))
        return
    table = Table(title="Cuboid 6 x 3 x 2 cm pulled along x (paper section II.B.3)",
                  caption="nu: Eq. (4) with engineering strains; nu log: Eq. (4) integrated (Hencky strains)")
    for col in ("F (N)", "axial", "lateral", "nu", "nu log", "dV", "dL (cm)", "FL/EA (cm)", "conv."):
        table.add_column(col, justify="right")
    for r in rows:
        table.add_row(f"{r.force_n:g}", f"{r.axial_strain:.4f}", f"{r.lateral_strain:.4f}", f"{r.poisson_ratio:.3f}",
                      f"{r.poisson_ratio_log:.3f}", f"{100 * r.volume_change:+.3f} %", f"{r.elongation_cm:.4f}",
                      f"{r.linear_elongation_cm:.4f}", "yes" if r.converged else "NO")
    out_console.print(table)


@app.command("experiment")
@handle_errors
def experiment_cmd(
    name: str = typer.Argument(..., help="jaw-ep, fig4, muscle-directions, k-closure, stress or fig7."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config the mesh was built from."),
    as_json: bool = typer.Option(False, "--json", help="Print the table as JSON."),
    out: Optional[Path] = typer.Option(None, "--out", help="Also write the rows as JSON to this file."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="fig7 only: draw the trajectories (PNG)."),
):
    """Reproduce one of the paper's numeric experiments, ours beside the paper's."""
    from ..experiments.paper import EXPERIMENTS
    from ..stages.experiments import run_experiment

    if name not in EXPERIMENTS:
        raise ArticError(f"unknown experiment '{name}'; valid: {', '.join(EXPERIMENTS)}")
    if plot is not None and name != "fig7":
        raise ArticError(f"--plot is for 'fig7'; experiment '{name}' prints a table only")
    doc = run_experiment(name, mesh, config, out)
    if plot is not None:
        _plot_fig7(doc, plot)
    rows = [SimpleNamespace(**r) for r in doc["rows"]]
    if as_json:
        out_console.print_json(json.dumps(doc["rows"]))
        return
    _print_table(f"experiment {name}: ours beside Dang & Honda (2004)", ("quantity", "ours", "paper", "unit", "note"),
                 [(r.name, "n/a" if r.ours is None else f"{r.ours:.3g}", "" if r.paper is None else f"{r.paper:g}",
                   r.unit, r.note) for r in rows], left=("quantity", "note"))


@app.command("ep-map")
@handle_errors
def ep_map_cmd(
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config the mesh was built from (its 'epmap' "
                                                                 "section says what to compute)."),
    out: Path = typer.Option(Path("data/epmaps.h5"), "--out", help="EP maps to write (HDF5)."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers (processes)."),
    backend: str = typer.Option("loky", "--backend", help="loky (this machine) or dask (a dask.distributed "
                                                          "cluster; a local one over loopback without --scheduler)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Address of a dask scheduler, "
                                                                     "e.g. tcp://10.0.0.5:8786."),
    fast: bool = typer.Option(False, "--fast", help="Stop each equilibrium once it has settled instead of "
                                                    "holding the full duration (agrees within 0.02 cm)."),
    cache: Optional[Path] = typer.Option(None, "--cache", help="Where finished EPs are kept for resuming "
                                                               "(default: <out folder>/cache)."),
    force: bool = typer.Option(False, "--force", help="Rewrite the map file even if it is up to date."),
):
    """Equilibrium-position maps at every jaw position (the paper's section IV.B), in parallel, resumable."""
    from ..stages.epmap import build_ep_maps
    from ..experiments.paper import PAPER_CONTRIBUTION

    with exit_on_interrupt(f"interrupted; {out} was not touched, finished equilibria are cached and a rerun "
                           "resumes from them"):
        r = _with_progress("equilibria", lambda update: build_ep_maps(mesh, config, out, jobs, backend, scheduler, fast,
                                                                      cache, update, force), plain=True)
    if r.up_to_date:
        out_console.print(f"{r.path} is up to date (same mesh, config and map spec); nothing to do "
                          "(--force rewrites it)", highlight=False)
        return
    out_console.print(f"wrote {r.path}: {r.total} equilibria ({r.computed} computed, {r.cached} from the cache) "
                      f"in {r.wall_time_s:.1f} s with {jobs} {backend} worker(s)", highlight=False)
    if r.unconverged:
        out_console.print("[yellow]not settled (flagged 'converged = false' in the file, never used silently):[/] "
                          + "; ".join(r.unconverged), highlight=False)
    else:
        out_console.print("every equilibrium settled (control points moved < tolerance over the last window)")
    if r.not_monotonic:
        out_console.print("[yellow]EP vectors not monotonic:[/] " + "; ".join(r.not_monotonic), highlight=False)
    c = r.contribution
    rows = []
    for m, (ft, fd) in c["factor"].items():
        pt, pd = PAPER_CONTRIBUTION.get(m, (None, None))
        at, ad = c["amplitude_cm"][m]
        rows.append((m, f"{ft:.2f}", "" if pt is None else f"{pt:.2f}", f"{fd:.2f}",
                     "" if pd is None else f"{pd:.2f}", f"{at:.3f}", f"{ad:.3f}"))
    _print_table(f"Contribution factors (Table III), jaw position '{c['jaw']}'",
                 ("muscle", "tip", "paper tip", "dorsum", "paper dorsum", "tip amplitude cm", "dorsum amplitude cm"),
                 rows, left=("muscle",))


@app.command("muscle-function")
@handle_errors
def muscle_function_cmd(
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'muscle_function' section sets the "
                                                                 "grid; thin start_levels_n for a quick run)."),
    out: Path = typer.Option(Path("data/muscle_function.h5"), "--out", help="Starts and end points (HDF5)."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers."),
    cache: Optional[Path] = typer.Option(None, "--cache", help="Where finished starts are kept for resuming."),
    plot_dir: Optional[Path] = typer.Option(None, "--plot-dir", help="Also draw Figs. 5 and 6 into this folder."),
):
    """Section IV.A.1: each muscle at 4 N for 150 ms from scattered starts (Figs. 5 and 6)."""
    from ..experiments.muscle_function import convergence
    from ..stages.muscle_function import build_muscle_function

    with exit_on_interrupt(f"interrupted; {out} was not touched, finished starts are cached and a rerun resumes"):
        mf, wall, cached, distinct, fresh = _with_progress(
            "starts", lambda update: build_muscle_function(mesh, config, out, jobs, cache, update), plain=True)
    if fresh:
        out_console.print(f"{out} is up to date (same mesh, config sections and code): {len(mf.starts)} starts x "
                          f"{len(mf.muscles)} muscles", highlight=False)
    else:
        out_console.print(f"wrote {out}: {len(mf.starts)} starts ({distinct} distinct force sets, {cached} from the "
                          f"cache) x {len(mf.muscles)} muscles in {wall:.1f} s", highlight=False)
    table = Table(title=f"Where each muscle drives the control points ({mf.drive_n:g} N, {mf.drive_ms:g} ms)")
    for col in ("muscle", "point", "start spread cm", "end spread cm", "mean end - rest, x / y cm"):
        table.add_column(col, justify="left" if col in ("muscle", "point") else "right")
    for r in convergence(mf):
        dx, dy = r["mean_end_from_rest_cm"]
        table.add_row(r["muscle"], r["point"], f"{r['start_spread_cm']:.3f}", f"{r['end_spread_cm']:.3f}",
                      f"{dx:+.3f} / {dy:+.3f}")
    out_console.print(table)
    if plot_dir is not None:
        from ..plots.muscle_function import plot_muscle_function

        for point, fig in (("tip", "fig5_muscle_function_tip.png"), ("dorsum", "fig6_muscle_function_dorsum.png")):
            out_console.print(f"wrote {plot_muscle_function(mf, point, Path(plot_dir) / fig)}", highlight=False)


@plot_app.command("muscle-function")
@handle_errors
def plot_muscle_function_cmd(
    study: Path = typer.Argument(Path("data/muscle_function.h5"), help="Result of 'artic muscle-function'."),
    tip: Optional[Path] = typer.Option(None, "--tip", help="Fig. 5: the tip (PNG)."),
    dorsum: Optional[Path] = typer.Option(None, "--dorsum", help="Fig. 6: the dorsum (PNG)."),
):
    """Figs. 5 and 6: where each muscle drives the tip and the dorsum from scattered starts."""
    from ..plots.muscle_function import plot_muscle_function
    from ..stages.muscle_function import read

    if tip is None and dorsum is None:
        raise ArticError("nothing to draw; give --tip PNG and/or --dorsum PNG")
    mf = read(study)
    for point, path in (("tip", tip), ("dorsum", dorsum)):
        if path is not None:
            out_console.print(f"wrote {plot_muscle_function(mf, point, path)}", highlight=False)


@plot_app.command("vocal-tract")
@handle_errors
def plot_vocal_tract_cmd(
    tracts: Path = typer.Argument(..., help="Result of 'artic vocal-tract'."),
    out: Optional[Path] = typer.Option(None, "--out", help="The midsagittal tract beside its area function (PNG)."),
    frame: Optional[int] = typer.Option(None, "--frame", help="The frame to draw (default: the last)."),
    animate: Optional[Path] = typer.Option(None, "--animate", help="Every frame (GIF)."),
):
    """The midsagittal tract with its grid lines beside the area function; or an animation."""
    from ..plots.vocal_tract import animate_tracts, plot_tract
    from ..stages.vocal_tract import pick_frame, read

    if out is None and animate is None:
        raise ArticError("nothing to draw; give --out PNG and/or --animate GIF")
    t = read(tracts)
    if out is not None:
        out_console.print(f"wrote {plot_tract(t, pick_frame(t, frame), out)}", highlight=False)
    if animate is not None:
        out_console.print(f"wrote {animate_tracts(t, animate)}", highlight=False)


@plot_app.command("acoustics")
@handle_errors
def plot_acoustics_cmd(
    result: Path = typer.Argument(..., help="Result of 'artic acoustics --out'."),
    out: Path = typer.Option(..., "--out", help="The transfer function with its formants, or for several frames "
                                                "the formant tracks (PNG)."),
    frame: Optional[int] = typer.Option(None, "--frame", help="Draw this frame's transfer function instead."),
):
    """The transfer function with the formants marked, or the formant tracks of a time series."""
    from ..plots.acoustics import plot_tracks, plot_transfer
    from ..stages.acoustics import read
    from ..stages.vocal_tract import pick_frame

    r = read(result)
    n = len(r.formants_hz)
    if n > 1 and frame is None:
        path = plot_tracks(r, out, title=f"{result.stem}: formant tracks")
    else:
        path = plot_transfer(r, pick_frame(n, frame), out, title=result.stem)
    out_console.print(f"wrote {path}", highlight=False)


@plot_app.command("audio")
@handle_errors
def plot_audio_cmd(
    wav: Path = typer.Argument(..., help="A WAV file (from 'artic synthesize')."),
    out: Path = typer.Option(..., "--out", help="Its spectrogram (PNG)."),
):
    """The spectrogram of a sound."""
    from ..plots.acoustics import plot_spectrogram
    from ..stages.synthesize import read_wav

    samples, rate = read_wav(wav)
    out_console.print(f"wrote {plot_spectrogram(samples, rate, out, title=wav.name)}", highlight=False)


@app.command("acoustic-map")
@handle_errors
def acoustic_map_cmd(
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps from 'artic ep-map' (with shapes)."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="The mesh the maps were built on."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config ('vocal_tract' and 'acoustics')."),
    out: Path = typer.Option(Path("data/acoustic_maps.h5"), "--out", help="Formants and area functions (HDF5)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="The vowel space: every EP in the F1-F2 plane (PNG)."),
    force: bool = typer.Option(False, "--force", help="Recompute even if the file is up to date."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers (net by net)."),
):
    """Every EP's area function and formants F1-F4 (with the config's lips and its mapped lip tubes): the EP
    maps made acoustic."""
    from ..stages.acoustic_map import JAPANESE_VOWELS, acoustic_map

    check_number("--jobs", jobs, ge=1)
    r = _with_progress("nets", lambda update: acoustic_map(maps, mesh, config, out, update, force, jobs))
    rows = []
    for jname in r.maps.jaws:
        p = r.maps.points(jname)
        rows.append((jname, str(len(p)), f"{np.nanmin(p[:, 0]):.0f}-{np.nanmax(p[:, 0]):.0f}",
                     f"{np.nanmin(p[:, 1]):.0f}-{np.nanmax(p[:, 1]):.0f}"))
    _print_table("the EP maps' formants", ("jaw", "EPs", "F1 Hz", "F2 Hz"), rows, left=("jaw",))
    if plot is not None:
        from ..plots.acoustic_map import plot_vowel_space

        out_console.print(f"wrote {plot_vowel_space(r.maps, plot, JAPANESE_VOWELS)}", highlight=False)
    out_console.print(f"{'up to date' if r.up_to_date else 'wrote'} {r.path}", highlight=False)


@plot_app.command("acoustic-map")
@handle_errors
def plot_acoustic_map_cmd(
    result: Path = typer.Argument(Path("data/acoustic_maps.h5"), help="Result of 'artic acoustic-map'."),
    out: Path = typer.Option(..., "--out", help="The vowel space (PNG)."),
):
    """Every EP in the F1-F2 plane, jaw position by jaw position, with the Japanese vowels."""
    from ..plots.acoustic_map import plot_vowel_space
    from ..stages.acoustic_map import JAPANESE_VOWELS, read

    out_console.print(f"wrote {plot_vowel_space(read(result), out, JAPANESE_VOWELS)}", highlight=False)


@app.command("dynamic-map")
@handle_errors
def dynamic_map_cmd(
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps from 'artic ep-map'."),
    out: Path = typer.Option(Path("data/dynamic.h5"), "--out", help="Dynamic map to write (HDF5)."),
    as_json: bool = typer.Option(False, "--json", help="Print Table IV as JSON."),
):
    """Derive the map of any jaw position from the typical one (rotation + translation); Table IV."""
    from ..control.dynamic import table_iv
    from ..stages.dynamic import build_dynamic_map

    from ..stages.dynamic import fresh_recipe

    fresh = fresh_recipe(maps, out)
    dm = build_dynamic_map(maps, out)
    rows = table_iv(dm)
    if as_json:
        out_console.print_json(json.dumps(rows))
        return
    table = Table(title=f"Table IV: derived ({dm.typical} carried by the fitted transform) vs simulated EP maps")
    for col in ("jaw", "position cm", "paper", "jaw rot. deg", "map rot. tip/dorsum deg", "tip error cm", "paper",
                "dorsum error cm", "paper", "leave-one-out tip/dorsum cm"):
        table.add_column(col, justify="left" if col == "jaw" else "right")
    f = lambda v, p=3: "" if v is None else f"{v:.{p}f}"  # noqa: E731
    for r in rows:
        table.add_row(r["jaw"], f"{r['position_cm']:+.3f}", f(r["paper_position_cm"]), f"{r['jaw_angle_deg']:+.2f}",
                      f"{r['theta_deg'][0]:+.2f} / {r['theta_deg'][1]:+.2f}", f(r["error_tip_cm"]),
                      f(r["paper_tip_cm"]), f(r["error_dorsum_cm"]), f(r["paper_dorsum_cm"]),
                      "" if r["loo_tip_cm"] is None else f"{r['loo_tip_cm']:.3f} / {r['loo_dorsum_cm']:.3f}")
    out_console.print(table)
    out_console.print(f"{out} is up to date (same EP maps and code)" if fresh else f"wrote {out}", highlight=False)


@app.command("solve-target")
@handle_errors
def solve_target_cmd(
    target: Optional[Path] = typer.Argument(None, help="Target file (YAML): jaw, crucial and indecisive features."),
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps from 'artic ep-map'."),
    dynamic: Path = typer.Option(Path("data/dynamic.h5"), "--dynamic", help="Dynamic map from 'artic dynamic-map'."),
    out: Optional[Path] = typer.Option(None, "--out", help="Result (YAML; CSV with --batch); default "
                                                           "data/solutions/<name>.yaml or .csv."),
    verify: bool = typer.Option(False, "--verify", help="Simulate the force set and report the error."),
    refine: bool = typer.Option(False, "--refine", help="Correct the force set by a few simulations until the "
                                                        "crucial feature is within its tolerance."),
    budget: int = typer.Option(8, "--budget", help="Most simulations --refine may spend."),
    batch: Optional[Path] = typer.Option(None, "--batch", help="Solve every row of this CSV instead."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers for --batch with --verify/--refine."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh for --verify / --refine and acoustic "
                                                                   "targets."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config for --verify / --refine and acoustic "
                                                                 "targets."),
    acoustic_maps: Path = typer.Option(Path("data/acoustic_maps.h5"), "--acoustic-maps",
                                       help="Formants of every EP from 'artic acoustic-map' (acoustic targets; "
                                            "computed from the maps' shapes when absent or for other lips)."),
):
    """Muscle forces that put the crucial feature (a place, or formants) on its target and approach the others
    (section V; formant targets go beyond the paper)."""
    from ..control.targets import batch_csv, load_target, read_batch, solve_batch
    from ..io.store import write_text_atomic
    from ..stages.solve import add_formants, load_context, simulator, solve_target

    if (target is None) == (batch is None):
        raise ArticError("give a target file or --batch CSV (one of them)")
    check_number("--budget", budget, ge=1)
    check_number("--jobs", jobs, ge=1)
    targets = read_batch(batch) if batch is not None else [load_target(target)]  # the user's file first
    acoustic = any(t.acoustic is not None for t in targets)
    spatial = any(t.acoustic is None for t in targets)  # acoustic targets use the mapped jaw positions only
    ctx = load_context(maps, dynamic if spatial else None, mesh if (verify or refine or acoustic) else None)
    if acoustic:
        add_formants(ctx, maps, mesh, config, acoustic_maps)
    sim = simulator(mesh, config, voiced=acoustic) if (verify or refine) else None
    if batch is not None:
        args = None if sim is None else (sim.cfg, sim.mesh, sim.wall, sim.mesh_sha256)
        res = _with_progress("targets", lambda update: solve_batch(ctx, targets, jobs, args, verify, refine, budget,
                                                                   update), plain=True)
        path = out or Path("data/solutions") / f"{batch.stem}.csv"
        write_text_atomic(path, batch_csv(res))
        bad = sum("unreachable" in r for r in res)
        out_console.print(f"wrote {path}: {len(res)} targets, {len(res) - bad} solved, {bad} unreachable",
                          highlight=False)
        return
    t = targets[0]
    doc, path, fresh = solve_target(t, ctx, out, sim, verify, refine, budget, config,
                                    "" if sim is None else sim.mesh_sha256)
    if fresh:
        out_console.print(f"{path} is up to date (same maps, target, options and code)", highlight=False)
        return
    if t.acoustic is not None:
        _print_acoustic_solution(t, doc, path)
        return
    ch = doc["chosen"]
    forces = ", ".join(f"{k} {v:g} N" for k, v in ch["forces_n"].items())
    out_console.print(f"{t.name}: {ch['family']} {ch['map']}: {forces}; predicted tip {ch['predicted_cm']['tip']}, "
                      f"dorsum {ch['predicted_cm']['dorsum']} cm; cost {ch['cost']:.3f} "
                      f"(best of {doc['candidates_considered']} candidates)", highlight=False)
    if "verified" in doc:
        out_console.print(f"verified by simulation: crucial error {doc['verified']['crucial_error_cm']:.3f} cm",
                          highlight=False)
    if "refined" in doc:
        r = doc["refined"]
        forces = ", ".join(f"{k} {v:g} N" for k, v in r["forces_n"].items())
        out_console.print(f"refined: {forces}; crucial error {r['crucial_error_cm']:.3f} cm after "
                          f"{r['simulations']} simulations" + ("" if r["converged"] else " (tolerance not reached)"),
                          highlight=False)
    out_console.print(f"wrote {path}", highlight=False)
    if "refined" in doc and not doc["refined"]["converged"]:
        err_console.print(f"target '{t.name}' not reached within {t.crucial.tolerance_cm:g} cm after "
                          f"{doc['refined']['simulations']} simulations (best {doc['refined']['crucial_error_cm']:.3f} "
                          f"cm, written to {path}); raise --budget or the tolerance", highlight=False)
        raise typer.Exit(3)


def _print_acoustic_solution(t, doc: dict, path: Path) -> None:
    fmt = lambda f: ", ".join(f"F{k + 1} {v:.0f}" for k, v in enumerate(f[:3]))  # noqa: E731
    ch = doc["chosen"]
    forces = ", ".join(f"{k} {v:g} N" for k, v in ch["forces_n"].items()) or "no tongue force"
    out_console.print(f"{t.name}: {ch['family']} {ch['map']}: {forces}; predicted {fmt(ch['predicted_formants_hz'])} "
                      f"Hz (target {fmt(t.acoustic.formants_hz)} Hz; best of {doc['candidates_considered']} "
                      "candidates)", highlight=False)
    for key, label in (("verified", "verified by simulation"), ("refined", "refined")):
        if key in doc:
            r = doc[key]
            head = ((", ".join(f"{k} {v:g} N" for k, v in r["forces_n"].items()) or "no tongue force") + "; ") \
                if "forces_n" in r else ""
            out_console.print(f"{label}: {head}{fmt(r['formants_hz'])} Hz, errors "
                              f"{', '.join(f'{e:+.1f} %' for e in r['errors_pct'])}"
                              + (f" after {r['simulations']} simulations" if key == "refined" else ""),
                              highlight=False)
    out_console.print(f"wrote {path}", highlight=False)
    last = doc.get("refined")
    if last is not None and not last["converged"]:
        tol = " / ".join(f"{100 * v:g}" for v in t.acoustic.tolerance)
        err_console.print(f"target '{t.name}': F1/F2 not within {tol} % after "
                          f"{last['simulations']} simulations (errors {', '.join(f'{e:+.1f} %' for e in last['errors_pct'])}, "
                          f"written to {path}); raise --budget or the tolerance", highlight=False)
        raise typer.Exit(3)


@app.command("export")
@handle_errors
def export_cmd(
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    sim: Optional[Path] = typer.Option(None, "--sim", help="A simulation from 'artic simulate' to export."),
    vtk: Optional[Path] = typer.Option(None, "--vtk", help="Folder for VTK (.vtu + .pvd) and XDMF files "
                                                           "(ParaView)."),
    csv_out: Optional[Path] = typer.Option(None, "--csv", help="CSV of the control points (time, tip, dorsum, "
                                                               "jaw x/y/z in cm); needs --sim."),
    every: int = typer.Option(1, "--every", help="Export every n-th recorded frame (VTK)."),
):
    """Write the mesh and simulations for ParaView (VTK/XDMF) and control points as CSV (EMA layout)."""
    from ..stages.export import export_csv, export_mesh_vtk, export_simulation_vtk

    if vtk is None and csv_out is None:
        raise ArticError("nothing to export; give --vtk FOLDER and/or --csv FILE")
    if csv_out is not None and sim is None:
        raise ArticError("--csv exports a simulation's control points; give --sim FILE.h5")
    check_number("--every", every, ge=1)
    written = []
    if vtk is not None:
        written += export_mesh_vtk(mesh, vtk)
        if sim is not None:
            written += export_simulation_vtk(sim, mesh, vtk, every)
    if csv_out is not None:
        written.append(export_csv(sim, csv_out))
    shown = ", ".join(str(p) for p in written[:4]) + (f" and {len(written) - 4} more" if len(written) > 4 else "")
    out_console.print(f"wrote {shown}", highlight=False)




@plot_app.command("ep-map")
@handle_errors
def plot_ep_map_cmd(
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps from 'artic ep-map'."),
    jaw: Optional[str] = typer.Option(None, "--jaw", help="Jaw position (default: the typical one, JO_0.5)."),
    pair: Optional[str] = typer.Option(None, "--pair", help="Two-muscle net to draw, e.g. SG+HG (default: the "
                                                            "first stored at that jaw position)."),
    out: Path = typer.Option(Path("reports/epmap.png"), "--out", help="Picture to write (PNG)."),
):
    """Fig. 8: EP vectors of the tip and dorsum, with one two-muscle contour net."""
    from ..plots.epmap import plot_ep_map
    from ..stages.epmap import load_ep_maps

    m = load_ep_maps(maps)
    path = plot_ep_map(m, jaw, pair, out)
    out_console.print(f"wrote {path}", highlight=False)


@plot_app.command("dynamic-map")
@handle_errors
def plot_dynamic_map_cmd(
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps."),
    dynamic: Path = typer.Option(Path("data/dynamic.h5"), "--dynamic", help="Dynamic map."),
    jaw: str = typer.Option("JO_2.5", "--jaw", help="Jaw position to compare (the paper's Fig. 9: JO 2.5 N)."),
    out: Path = typer.Option(Path("reports/fig9_dynamic_map.png"), "--out", help="Picture to write (PNG)."),
):
    """Fig. 9: a jaw position's EP vectors, simulated and derived from the typical map."""
    from ..plots.dynamic import plot_dynamic_map
    from ..stages.dynamic import load_dynamic_map
    from ..stages.epmap import load_ep_maps

    m = load_ep_maps(maps)
    dm = load_dynamic_map(dynamic, maps_path=maps)
    out_console.print(f"wrote {plot_dynamic_map(m, dm, jaw, out)}", highlight=False)


@plot_app.command("solution")
@handle_errors
def plot_solution_cmd(
    solution: Path = typer.Argument(..., help="Result of 'artic solve-target' (YAML)."),
    target: Path = typer.Option(..., "--target", help="The target file it solved."),
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps."),
    dynamic: Path = typer.Option(Path("data/dynamic.h5"), "--dynamic", help="Dynamic map."),
    out: Path = typer.Option(Path("reports/solution.png"), "--out", help="Picture to write (PNG)."),
):
    """Fig. 12: targets, the candidate force sets' predicted positions and the chosen one."""
    from ..config import read_yaml
    from ..control.targets import jaw_maps, load_target
    from ..plots.solution import plot_solution
    from ..stages.solve import load_context

    doc = read_yaml(solution, "solution file")
    if not isinstance(doc, dict) or not ("chosen" in doc or "unreachable" in doc):
        raise ArticError(f"{solution} is not a solve-target result; run 'artic solve-target' first")
    t = load_target(target)
    if t.acoustic is not None:  # a vowel: its formants and simulated area function, no maps needed
        from ..plots.solution import plot_acoustic_solution

        if "acoustic" not in doc:
            raise ArticError(f"{solution} answers a spatial target, {target} is an acoustic one; give the pair that "
                             "belong together")
        out_console.print(f"wrote {plot_acoustic_solution(doc, t, out)}", highlight=False)
        return
    ctx = load_context(maps, dynamic)
    jm, _, _, _ = jaw_maps(ctx, t)
    path = plot_solution(doc, t, jm, out)
    out_console.print(f"wrote {path}", highlight=False)


@app.command("report")
@handle_errors
def report_cmd(
    data: Path = typer.Option(Path("data"), "--data", help="Folder holding the pipeline's artefacts."),
    out: Path = typer.Option(Path("reports/paper.md"), "--out", help="Report to write (Markdown)."),
):
    """Write the report that sets our results beside the paper's."""
    from ..stages.report import write_report

    path = write_report(data, out)
    out_console.print(f"wrote {path}", highlight=False)


@app.command("acoustics")
@handle_errors
def acoustics_cmd(
    tube: Optional[Path] = typer.Option(None, "--tube", help="Tube (CSV): header length_cm,area_cm2, one row per "
                                                             "section from the glottis to the lips."),
    tracts: Optional[Path] = typer.Option(None, "--tracts", help="Vocal-tract file from 'artic vocal-tract': every "
                                                                 "frame (or --frame K)."),
    frame: Optional[int] = typer.Option(None, "--frame", help="With --tracts: one frame (default: all)."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'acoustics' section: air, walls, "
                                                                 "losses, branches)."),
    lossless: bool = typer.Option(False, "--lossless", help="The ideal hard-walled tube: no losses, an ideal "
                                                            "open end, no side branches."),
    velum_area: Optional[float] = typer.Option(None, "--velum-area", help="Velopharyngeal port opening, cm^2 "
                                                                          "(default: the tracts' or the config's, "
                                                                          "0 = closed)."),
    as_json: bool = typer.Option(False, "--json", help="Print formants_hz and bandwidths_hz as JSON (the last "
                                                       "frame's, with time_s, for tracts)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the transfer functions and formants (HDF5)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw the transfer function with the formants, or "
                                                             "for several frames the formant tracks (PNG)."),
):
    """Transfer function, radiated spectrum, formants F1-F5 and bandwidths of a tube or of vocal-tract frames."""
    from ..stages.acoustics import tract_acoustics, tube_acoustics

    if (tube is None) == (tracts is None):
        raise ArticError("give one of --tube FILE.csv or --tracts FILE.h5")
    if tube is not None and frame is not None:
        raise ArticError("--frame is for --tracts; a tube has one frame")
    if tube is not None:
        r = tube_acoustics(tube, config, lossless, velum_area, out)
        name = tube.name
    else:
        r = _with_progress("formants", lambda update: tract_acoustics(tracts, config, frame, lossless, velum_area,
                                                                      out, progress=update))
        name = tracts.name
    last = len(r.formants_hz) - 1
    fm = [None if not np.isfinite(v) else round(float(v), 2) for v in r.formants_hz[last]]
    bw = [None if not np.isfinite(v) else round(float(v), 2) for v in r.bandwidths_hz[last]]
    if plot is not None:
        from ..plots.acoustics import plot_tracks, plot_transfer

        if len(r.formants_hz) > 1:
            plot_tracks(r, plot, title=f"{name}: formant tracks")
        else:
            plot_transfer(r, 0, plot, title=f"{name}{' (lossless)' if lossless else ''}")
    if as_json:
        doc = {"formants_hz": fm, "bandwidths_hz": bw}
        if r.time_s is not None:
            doc["time_s"] = float(r.time_s[last])
        out_console.print_json(json.dumps(doc))
        return
    rows = [(f"F{k + 1}", "" if f is None else f"{f:.1f}", "" if b is None else f"{b:.1f}")
            for k, (f, b) in enumerate(zip(fm, bw))]
    when = "" if r.time_s is None else f" at t = {r.time_s[last]:.3f} s ({len(r.formants_hz)} frames)"
    _print_table(f"formants of {name}{when}", ("formant", "frequency Hz", "bandwidth Hz"), rows, left=("formant",))
    for p in (out, plot):
        if p is not None:
            out_console.print(f"wrote {p}", highlight=False)


@app.command("vocal-tract")
@handle_errors
def vocal_tract_cmd(
    sim: Optional[Path] = typer.Option(None, "--sim", help="Simulation (HDF5): the tract of every frame."),
    rest: bool = typer.Option(False, "--rest", help="The rest posture (the articulator settled under gravity)."),
    ep: Optional[str] = typer.Option(None, "--ep", help="One EP of the maps, JAW:MUSCLE=N[,MUSCLE=N] "
                                                        "(e.g. JO_0.5:SG=2.5)."),
    epmaps: Path = typer.Option(Path("data/epmaps.h5"), "--epmaps", help="EP maps (HDF5), for --ep."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh (HDF5) the shapes were made on."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'vocal_tract' section)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Tracts to write (HDF5; default data/tracts/NAME.h5)."),
    csv: Optional[Path] = typer.Option(None, "--csv", help="Also write one frame as a tube (CSV: length_cm,area_cm2)."),
    frame: Optional[int] = typer.Option(None, "--frame", help="The frame for --csv and --plot (default: the last)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw the midsagittal tract with its grid beside the "
                                                             "area function (PNG)."),
    animate: Optional[Path] = typer.Option(None, "--animate", help="Animate a simulation's tracts (GIF)."),
    lip_area: Optional[float] = typer.Option(None, "--lip-area", help="Lip aperture area, cm^2 (default: the "
                                                                      "config's; a schedule's tract entries follow)."),
    lip_length: Optional[float] = typer.Option(None, "--lip-length", help="Lip tube length, cm."),
    velum_port: Optional[float] = typer.Option(None, "--velum-port", help="Velopharyngeal port area, cm^2 (0 = closed)."),
    force: bool = typer.Option(False, "--force", help="Recompute even if the file is up to date."),
):
    """Area functions (glottis to lips) from simulated shapes: midline, grid, distances, areas."""
    from ..stages.vocal_tract import pick_frame, vocal_tract, write_csv

    if animate is not None and sim is None:
        raise ArticError("--animate needs a simulation (--sim FILE); a single shape has nothing to animate")
    r = vocal_tract(sim, rest, ep, epmaps, mesh, config, out, lip_area, lip_length, velum_port, force, frame)
    t = r.tracts
    k = pick_frame(t, frame)
    area, pos, reg = t.af.constriction()
    _print_table(f"vocal tract ({t.n_frames} frame{'s' if t.n_frames > 1 else ''})",
                 ("frame", "time s", "length cm", "min area cm^2", "at cm", "region"),
                 [(str(j), f"{t.time_s[j]:.3f}", f"{t.af.tract_length_cm[j]:.2f}", f"{area[j]:.3f}", f"{pos[j]:.2f}",
                   t.af.region_names[int(reg[j])]) for j in sorted({0, k, t.n_frames - 1})], left=("region",))
    written = [r.path]
    if csv is not None:
        written.append(write_csv(csv, t, k))
    if plot is not None:
        from ..plots.vocal_tract import plot_tract

        written.append(plot_tract(t, k, plot))
    if animate is not None:
        from ..plots.vocal_tract import animate_tracts

        written.append(animate_tracts(t, animate))
    for p in written:
        out_console.print(f"{'up to date' if p == r.path and r.up_to_date else 'wrote'} {p}", highlight=False)


@app.command("speak")
@handle_errors
def speak_cmd(
    utterance: Path = typer.Argument(..., help="Utterance file (YAML): segments (a target or forces, a duration), "
                                               "an F0 contour, a lip and velum course."),
    out: Optional[Path] = typer.Option(None, "--out", help="Sound to write (WAV); the TextGrid and NAME.h5 go "
                                                           "beside it (default data/utterances/NAME.wav)."),
    maps: Path = typer.Option(Path("data/epmaps.h5"), "--maps", help="EP maps the targets are solved on."),
    dynamic: Path = typer.Option(Path("data/dynamic.h5"), "--dynamic", help="Dynamic map, read only for a place "
                                 "target at a jaw position the maps hold no nets for."),
    acoustic_maps: Path = typer.Option(Path("data/acoustic_maps.h5"), "--acoustic-maps",
                                       help="Formants of every EP (vowel targets)."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh from 'artic build-mesh'."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'speech' section: ramps, glottis, "
                                                                 "lungs, noise)."),
    solutions: Optional[Path] = typer.Option(None, "--solutions", help="Where the targets' solutions are cached "
                                                                       "(default: a 'solutions' folder beside --out)."),
    accept_nearest: bool = typer.Option(False, "--accept-nearest", help="Speak the nearest reachable answer of an "
                                                                        "unreachable target instead of stopping."),
    budget: int = typer.Option(8, "--budget", help="Most simulations each target's refinement may spend."),
    jobs: int = typer.Option(1, "--jobs", help="Processes solving distinct targets at once."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Spectrogram with formant tracks, segments and the "
                                                             "tip/dorsum/jaw heights (PNG)."),
    animate: Optional[Path] = typer.Option(None, "--animate", help="The midsagittal view moving (GIF)."),
):
    """Speak a sequence of targets: each solved once, its forces ramped in at its segment's start and held, the
    whole simulated with contact, then the tract, formants and sound (WAV, TextGrid, HDF5)."""
    from ..stages import speak as speak_stage

    check_number("--budget", budget, ge=1)
    check_number("--jobs", jobs, ge=1)
    for opt, p, ext in (("--plot", plot, ".png"), ("--animate", animate, ".gif")):
        if p is not None and (p.suffix.lower() != ext or not p.parent.is_dir()):
            raise ArticError(f"{opt} {p}: give a {ext} file in an existing folder")
    say = lambda m: err_console.print(m, highlight=False)  # noqa: E731
    res = _with_progress("simulating", lambda update: speak_stage.speak(
        utterance, out, maps, mesh, acoustic_maps, config, solutions, accept_nearest, budget, update, say, jobs,
        dynamic))
    if res.up_to_date:
        out_console.print(f"{res.paths['wav']} is up to date (same utterance, solutions, mesh, config and code)",
                          highlight=False)
    else:
        s = res.spoken
        out_console.print(f"wrote {res.paths['wav']} ({len(s.audio.samples) / s.audio.sample_rate_hz:.2f} s), "
                          f"{res.paths['textgrid']}, {res.paths['h5']}", highlight=False)
        for lab, how in zip(s.plan.labels, s.plan.notes):
            out_console.print(f"  {lab}: {how}", highlight=False)
    if plot is not None or animate is not None:
        from ..stages.synthesize import read_wav

        rec = speak_stage.read(res.paths["h5"])
        if plot is not None:
            from ..plots.utterance import plot_utterance

            y, rate = read_wav(res.paths["wav"])
            out_console.print(f"wrote {plot_utterance(rec, y, rate, plot)}", highlight=False)
        if animate is not None:
            from ..plots.utterance import animate_utterance
            from ..stages.simulate import load_model

            model, _, wall = load_model(mesh, config)
            out_console.print(f"wrote {animate_utterance(rec, model, wall, animate)}", highlight=False)


@app.command("synthesize")
@handle_errors
def synthesize_cmd(
    out: Path = typer.Option(..., "--out", help="Sound to write (WAV, 16-bit PCM)."),
    tube: Optional[Path] = typer.Option(None, "--tube", help="Tube (CSV): header length_cm,area_cm2, glottis first."),
    tracts: Optional[Path] = typer.Option(None, "--tracts", help="Vocal-tract file: its frames, areas interpolated "
                                                                 "sample by sample."),
    solution: Optional[Path] = typer.Option(None, "--solution", help="A solve-target answer of an acoustic target: "
                                                                     "its simulated area function."),
    duration: Optional[float] = typer.Option(None, "--duration", help="How long, s (default: a tube or solution 1 s, "
                                                                      "tracts their frames' span)."),
    f0: float = typer.Option(110.0, "--f0", help="Fundamental frequency, Hz (50-500)."),
    f0_contour: Optional[Path] = typer.Option(None, "--f0-contour", help="F0 over time instead (CSV: "
                                                                          "time_s,f0_hz)."),
    amplitude_contour: Optional[Path] = typer.Option(None, "--amplitude-contour", help="The voice's gain over time "
                                                                                        "(CSV: time_s,amplitude)."),
    aspiration: float = typer.Option(0.0, "--aspiration", help="Breath noise, relative to the voice's RMS "
                                                               "(0: none)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw the sound's spectrogram (PNG)."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'acoustics.synthesis' section)."),
):
    """Voice a tube, a vocal-tract file or a solved vowel with the LF source through a reflection-type line;
    write a WAV file."""
    from ..stages.synthesize import synthesize_solution, synthesize_tracts, synthesize_tube

    if sum(v is not None for v in (tube, tracts, solution)) != 1:
        raise ArticError("give one of --tube FILE.csv, --tracts FILE.h5 or --solution FILE.yaml")
    if plot is not None and not plot.parent.is_dir():
        raise ArticError(f"--plot {plot}: the folder {plot.parent} does not exist; create it or give another path")
    if tube is not None:
        a = synthesize_tube(tube, out, 1.0 if duration is None else duration, f0, f0_contour, config,
                            amplitude_contour, aspiration)
    elif solution is not None:
        a = synthesize_solution(solution, out, 1.0 if duration is None else duration, f0, f0_contour, config,
                                amplitude_contour, aspiration)
    else:
        a = synthesize_tracts(tracts, out, f0, f0_contour, config, amplitude_contour, aspiration, duration)
    out_console.print(f"wrote {out}: {len(a.samples) / a.sample_rate_hz:.2f} s at {a.sample_rate_hz} Hz, 16-bit PCM",
                      highlight=False)
    if plot is not None:
        from ..plots.acoustics import plot_spectrogram

        out_console.print(f"wrote {plot_spectrogram(a.samples, a.sample_rate_hz, plot, title=out.name)}",
                          highlight=False)


def _plot_mesh(mesh: Path, out: Path, config: Path | None = None) -> Path:
    from ..config import load_config
    from ..geometry.tract import outline
    from ..plots.mesh import plot_mesh
    from ..stages.mesh import read

    cfg = load_config(config)
    m = read(mesh, cfg)
    tract = None
    if cfg.vocal_tract is not None:
        surface = m.mesh.nodes[m.mesh.node_sets["midsagittal_surface"], :2]
        tract = outline(cfg.vocal_tract, cfg.speaker.wall, surface, (np.eye(3), np.zeros(3))).drawn
    return plot_mesh(m.mesh, m.wall, m.speaker.landmarks_cm, out, tract=tract)


def _plot_simulation(sim: Path, model, wall, plot: Path | None, animate: Path | None) -> None:
    from ..stages.simulate import read

    s = read(sim, allow_invalid=True)
    traj = SimpleNamespace(x=s.positions_cm, time=s.time_s)
    if plot:
        from ..plots.simulation import plot_simulation

        plot_simulation(traj, model, wall, plot, title=f"{Path(sim).stem}: start and end shapes")
    if animate:
        from ..plots.animation import animate_simulation

        animate_simulation(traj, model, wall, animate)


def _plot_fig7(doc: dict, out: Path) -> Path:
    from ..plots.muscle_function import plot_fig7
    from ..stages.experiments import figure_paths

    if "figure" not in doc:
        raise ArticError(f"experiment '{doc.get('experiment')}' has no figure; only fig7 draws one")
    return plot_fig7(figure_paths(doc), out)


@plot_app.command("utterance")
@handle_errors
def plot_utterance_cmd(
    record: Path = typer.Argument(..., help="An utterance record (NAME.h5 from 'artic speak'); its WAV beside it."),
    out: Path = typer.Option(..., "--out", help="Picture to write (PNG)."),
):
    """Spectrogram of a spoken utterance with our formant tracks and its segments; tip, dorsum and jaw heights
    below on the same time axis."""
    from ..plots.utterance import plot_utterance
    from ..stages import speak as speak_stage
    from ..stages.synthesize import read_wav

    rec = speak_stage.read(record)
    y, rate = read_wav(Path(record).parent / str(rec.attrs.get("wav", Path(record).with_suffix(".wav").name)))
    out_console.print(f"wrote {plot_utterance(rec, y, rate, out)}", highlight=False)


@plot_app.command("mesh")
@handle_errors
def plot_mesh_cmd(
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="Mesh artefact from build-mesh."),
    out: Path = typer.Option(Path("reports/fig1_mesh.png"), "--out", help="Picture to write (PNG)."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config of the mesh (its vocal tract is drawn too)."),
):
    """Fig. 1: the mesh, the wall, the vocal tract's other parts and the muscles' landmarks."""
    out_console.print(f"wrote {_plot_mesh(mesh, out, config)}", highlight=False)


@plot_app.command("simulation")
@handle_errors
def plot_simulation_cmd(
    sim: Path = typer.Argument(..., help="A simulation from 'artic simulate' (HDF5)."),
    mesh: Path = typer.Option(Path("data/mesh.h5"), "--mesh", help="The mesh it was run on."),
    config: Optional[Path] = typer.Option(None, "--config", help="The config it was run with."),
    out: Optional[Path] = typer.Option(None, "--out", help="Start and end shapes (PNG)."),
    animate: Optional[Path] = typer.Option(None, "--animate", help="An animation (GIF)."),
):
    """Start and end shapes of a simulation (Fig. 4 style) and/or its animation."""
    from ..stages.simulate import load_model, read

    if out is None and animate is None:
        raise ArticError("nothing to draw; give --out PNG and/or --animate GIF")
    s = read(sim, allow_invalid=True)
    if not s.attrs.get("valid", True):
        err_console.print(f"[yellow]warning:[/] {sim} is marked invalid ({s.attrs.get('invalid_reason')}); "
                          "drawing it anyway", highlight=False)
    tongue_only = bool(s.attrs.get("tongue_only", False))
    model, _, wall = load_model(mesh, config, tongue_only=tongue_only)
    _plot_simulation(sim, model, wall, out, animate)
    out_console.print("wrote " + ", ".join(str(p) for p in (out, animate) if p), highlight=False)


@plot_app.command("experiment")
@handle_errors
def plot_experiment_cmd(
    table: Path = typer.Argument(..., help="An experiment table from 'artic experiment fig7 --out FILE'."),
    out: Path = typer.Option(Path("reports/fig7_trajectories.png"), "--out", help="Picture to write (PNG)."),
):
    """Fig. 7: the trajectories from four starting shapes (from the fig7 table)."""
    from ..stages.experiments import read

    out_console.print(f"wrote {_plot_fig7(read(table), out)}", highlight=False)


def main() -> None:  # pragma: no cover - console entry
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
