"""``artic`` commands: the maps: EP maps, dynamic maps and acoustic maps."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import numpy as np
import typer
from rich.table import Table

from ..stages import paths
from ..validation import check_number
from .app import app, exit_on_interrupt, handle_errors, out_console, print_table, with_progress


@app.command("ep-map")
@handle_errors
def ep_map_cmd(
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config the mesh was built from (its 'epmap' "
                                                                 "section says what to compute)."),
    out: Path = typer.Option(paths.EPMAPS, "--out", help="EP maps to write (HDF5)."),
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
        r = with_progress("equilibria", lambda update: build_ep_maps(mesh, config, out, jobs, backend, scheduler, fast,
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
    print_table(f"Contribution factors (Table III), jaw position '{c['jaw']}'",
                 ("muscle", "tip", "paper tip", "dorsum", "paper dorsum", "tip amplitude cm", "dorsum amplitude cm"),
                 rows, left=("muscle",))


@app.command("acoustic-map")
@handle_errors
def acoustic_map_cmd(
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps from 'artic ep-map' (with shapes)."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="The mesh the maps were built on."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config ('vocal_tract' and 'acoustics')."),
    out: Path = typer.Option(paths.ACOUSTIC_MAPS, "--out", help="Formants and area functions (HDF5)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="The vowel space: every EP in the F1-F2 plane (PNG)."),
    force: bool = typer.Option(False, "--force", help="Recompute even if the file is up to date."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers (net by net)."),
):
    """Every EP's area function and formants F1-F4 (with the config's lips and its mapped lip tubes): the EP
    maps made acoustic."""
    from ..speech.vowels import JAPANESE_VOWELS
    from ..stages.acoustic_map import acoustic_map

    check_number("--jobs", jobs, ge=1)
    r = with_progress("nets", lambda update: acoustic_map(maps, mesh, config, out, update, force, jobs))
    rows = []
    for jname in r.maps.jaws:
        p = r.maps.points(jname)
        rows.append((jname, str(len(p)), f"{np.nanmin(p[:, 0]):.0f}-{np.nanmax(p[:, 0]):.0f}",
                     f"{np.nanmin(p[:, 1]):.0f}-{np.nanmax(p[:, 1]):.0f}"))
    print_table("the EP maps' formants", ("jaw", "EPs", "F1 Hz", "F2 Hz"), rows, left=("jaw",))
    if plot is not None:
        from ..plots.acoustic_map import plot_vowel_space

        out_console.print(f"wrote {plot_vowel_space(r.maps, plot, JAPANESE_VOWELS)}", highlight=False)
    out_console.print(f"{'up to date' if r.up_to_date else 'wrote'} {r.path}", highlight=False)


@app.command("dynamic-map")
@handle_errors
def dynamic_map_cmd(
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps from 'artic ep-map'."),
    out: Path = typer.Option(paths.DYNAMIC, "--out", help="Dynamic map to write (HDF5)."),
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
