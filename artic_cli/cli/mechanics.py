"""``artic`` commands: the mechanics: the mesh, simulations, the cuboid check, the paper's experiments, muscle function."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import List, Optional

import typer
from rich.table import Table

from ..errors import ArticError
from ..stages import paths
from ..validation import DEFAULT_MAX_FORCE_N, check_number
from .app import app, exit_on_interrupt, handle_errors, out_console, print_table, validate_app, with_progress
from .plot import plot_fig7_file, plot_mesh_file, plot_simulation_file


@app.command("build-mesh")
@handle_errors
def build_mesh_cmd(
    config: Optional[Path] = typer.Option(None, "--config", help="Speaker config (YAML); default configs/default.yaml."),
    out: Path = typer.Option(paths.MESH, "--out", help="Mesh artefact to write (HDF5)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw the midsagittal view (PNG), like Fig. 1."),
):
    """Build the tongue mesh (bricks + cylinders) and the vocal-tract wall."""
    from ..stages.mesh import build_mesh

    s = build_mesh(config, out)
    if plot:
        plot_mesh_file(out, plot, config)
    rel = abs(s.cylinder_volume_cm3 - s.volume_cm3) / s.volume_cm3
    verb = f"{s.path} is up to date (same speaker geometry and code)" if s.up_to_date else f"wrote {s.path}"
    out_console.print(f"{verb}: {s.nodes} nodes, {s.bricks} bricks, {s.cylinders} cylinders, "
                      f"tongue volume {s.volume_cm3:.3f} cm^3 (cylinders {s.cylinder_volume_cm3:.3f} cm^3, "
                      f"rel. diff {rel:.1e}), wall {s.wall_triangles} triangles"
                      + (f"; figure {plot}" if plot else ""), highlight=False)


@app.command("simulate")
@handle_errors
def simulate_cmd(
    schedule: Optional[Path] = typer.Option(None, "--schedule", help="Load schedule (YAML): node sets, forces in N, "
                                            "onset/duration in ms."),
    solution: Optional[Path] = typer.Option(None, "--solution", help="Replay a solve-target answer as it was "
                                            "verified (instead of --schedule) and report its crucial error."),
    hold_jaw: Optional[bool] = typer.Option(None, "--hold-jaw/--free-jaw", help="With --solution: the mandible "
                                            "held as the maps hold it, or free (default: as the answer records)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time in s (default: the schedule's duration_ms)."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step in s (default: the config's dt_ms)."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
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

    if (schedule is None) == (solution is None):
        raise ArticError("give --schedule FILE or --solution FILE (one of them)")
    if solution is not None:
        return _replay(solution, mesh, config, out, hold_jaw)

    args = (schedule, duration, dt, mesh, config, out, volume_constraint)
    r = with_progress("simulating", lambda update: simulate(*args, update, tongue_only=tongue_only, contact=contact))
    if plot or animate:
        plot_simulation_file(r.path, r.model, r.wall, plot, animate)
    if r.up_to_date:
        out_console.print(f"{r.path} is up to date (same mesh, config sections, schedule, options and code); "
                          f"max |volume change| {100 * r.max_volume_change:.3f} %", highlight=False)
        refuse_unphysical(r)
        return
    t = r.trajectory
    sim_time = t.time[-1] - t.time[0]
    out_console.print(
        f"wrote {r.path}: {t.stats['steps']} steps of {t.stats['dt'] * 1e3:g} ms, wall {t.stats['wall_time_s']:.3f} s "
        f"({t.stats['wall_time_s'] / sim_time:.3f} s per simulated s), max |volume change| "
        f"{100 * r.max_volume_change:.3f} % (constraint {'on' if r.model.volume_constraint else 'off'}), "
        f"inverted bricks {int(t.inverted.max())}" + (f"; figure {plot}" if plot else "")
        + (f"; animation {animate}" if animate else ""), highlight=False)
    refuse_unphysical(r)


def _replay(solution: Path, mesh: Path, config: Optional[Path], out: Optional[Path], hold_jaw: Optional[bool]):
    from ..stages.solve_runs import replay_solution

    r = with_progress("simulating", lambda update: replay_solution(solution, mesh, config, out, hold_jaw, update))
    c = r.conditions
    where = "; ".join(f"{n} ({x:.4f}, {y:.4f})" for n, (x, y) in r.reached_cm.items())
    how = f"jaw {c['jaw']}, {c['duration_ms']:g} ms from {c['start']}"
    out_console.print(f"{solution} replayed ({how}): {where} cm" + (f"; written to {r.path}" if r.path else ""),
                      highlight=False)
    if r.crucial_error_cm is not None:
        out_console.print(f"crucial error {r.crucial_error_cm:.4f} cm", highlight=False)


def refuse_unphysical(r) -> None:
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
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
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
        plot_fig7_file(doc, plot)
    rows = [SimpleNamespace(**r) for r in doc["rows"]]
    if as_json:
        out_console.print_json(json.dumps(doc["rows"]))
        return
    print_table(f"experiment {name}: ours beside Dang & Honda (2004)", ("quantity", "ours", "paper", "unit", "note"),
                 [(r.name, "n/a" if r.ours is None else f"{r.ours:.3g}", "" if r.paper is None else f"{r.paper:g}",
                   r.unit, r.note) for r in rows], left=("quantity", "note"))


@app.command("muscle-function")
@handle_errors
def muscle_function_cmd(
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config (its 'muscle_function' section sets the "
                                                                 "grid; thin start_levels_n for a quick run)."),
    out: Path = typer.Option(paths.MUSCLE_FUNCTION, "--out", help="Starts and end points (HDF5)."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers."),
    cache: Optional[Path] = typer.Option(None, "--cache", help="Where finished starts are kept for resuming."),
    plot_dir: Optional[Path] = typer.Option(None, "--plot-dir", help="Also draw Figs. 5 and 6 into this folder."),
):
    """Section IV.A.1: each muscle at 4 N for 150 ms from scattered starts (Figs. 5 and 6)."""
    from ..experiments.muscle_function import convergence
    from ..stages.muscle_function import build_muscle_function

    with exit_on_interrupt(f"interrupted; {out} was not touched, finished starts are cached and a rerun resumes"):
        mf, wall, cached, distinct, fresh = with_progress(
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
