"""``artic`` commands: the target solver: a target (a place or formants) in, muscle forces out."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..stages import paths
from .app import app, err_console, handle_errors, out_console, with_progress


@app.command("solve-target")
@handle_errors
def solve_target_cmd(
    target: Optional[Path] = typer.Argument(None, help="Target file (YAML): jaw, crucial and indecisive features."),
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps from 'artic ep-map'."),
    dynamic: Path = typer.Option(paths.DYNAMIC, "--dynamic", help="Dynamic map from 'artic dynamic-map'."),
    out: Optional[Path] = typer.Option(None, "--out", help="Result (YAML; CSV with --batch); default "
                                                           f"{paths.SOLUTIONS}/<name>.yaml or .csv."),
    verify: bool = typer.Option(False, "--verify", help="Simulate the force set and report the error."),
    refine: bool = typer.Option(False, "--refine", help="Correct the force set by a few simulations until the "
                                                        "crucial feature is within its tolerance."),
    budget: int = typer.Option(8, "--budget", help="Most simulations --refine may spend."),
    batch: Optional[Path] = typer.Option(None, "--batch", help="Solve every row of this CSV instead."),
    jobs: int = typer.Option(2, "--jobs", help="Parallel workers for --batch with --verify/--refine."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh for --verify / --refine and acoustic "
                                                                   "targets."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config for --verify / --refine and acoustic "
                                                                 "targets."),
    hold_jaw: bool = typer.Option(False, "--hold-jaw", help="Check the answer with the mandible held at the jaw "
                                  "position's rest, as the maps were made (default: the jaw free, as 'artic "
                                  "simulate' and 'artic speak' run the forces)."),
    acoustic_maps: Path = typer.Option(paths.ACOUSTIC_MAPS, "--acoustic-maps",
                                       help="Formants of every EP from 'artic acoustic-map' (acoustic targets; "
                                            "computed from the maps' shapes when absent or for other lips)."),
):
    """Muscle forces that put the crucial feature (a place, or formants) on its target and approach the others
    (section V; formant targets go beyond the paper)."""
    from ..stages.solve_runs import solve_files

    r = with_progress("targets", lambda update: solve_files(target, batch, maps, dynamic, mesh, config, acoustic_maps,
                                                            out, verify, refine, budget, jobs, update,
                                                            hold_jaw or None), plain=True)
    if r.rows is not None:
        bad = sum("unreachable" in row for row in r.rows)
        out_console.print(f"wrote {r.path}: {len(r.rows)} targets, {len(r.rows) - bad} solved, {bad} unreachable",
                          highlight=False)
    elif r.up_to_date:
        out_console.print(f"{r.path} is up to date (same maps, target, options and code)", highlight=False)
    elif r.target.acoustic is not None:
        _print_acoustic_solution(r.target, r.doc, r.path)
    elif r.target.constriction is not None:
        _print_constriction_solution(r.target, r.doc, r.path)
    else:
        _print_place_solution(r.target, r.doc, r.path)


def _print_place_solution(t, doc: dict, path: Path) -> None:
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


def _print_constriction_solution(t, doc: dict, path: Path) -> None:
    g = t.constriction
    ch = doc["chosen"]
    forces = lambda d: ", ".join(f"{k} {v:g} N" for k, v in d.items()) or "no tongue force"  # noqa: E731
    out_console.print(f"{t.name}: {ch['family']} {ch['map']}: {forces(ch['forces_n'])}; predicted {g.place} area "
                      f"{ch['place_area_cm2']:.3f} cm^2 (target {g.area_cm2:g} +- {g.tolerance_cm2:g}; best of "
                      f"{doc['candidates_considered']} candidates)", highlight=False)
    for key, label in (("verified", "verified by simulation"), ("refined", "refined")):
        if key in doc:
            r = doc[key]
            out_console.print(f"{label}: {forces(r['forces_n'])}; {g.place} area {r['place_area_cm2']:.3f} cm^2"
                              + (f" (forces x {r['scale']:g}) after {r['simulations']} simulations"
                                 if key == "refined" else ""), highlight=False)
    out_console.print(f"wrote {path}", highlight=False)
    last = doc.get("refined")
    if last is not None and not last["converged"]:
        err_console.print(f"target '{t.name}': the {g.place} area {last['place_area_cm2']:.3f} cm^2 misses "
                          f"{g.area_cm2:g} +- {g.tolerance_cm2:g} cm^2 after {last['simulations']} simulations "
                          f"(written to {path}); raise --budget or choose another jaw position", highlight=False)
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
