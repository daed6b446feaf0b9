"""``artic`` commands: exports and the report."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import ArticError
from ..stages import paths
from ..validation import check_number
from .app import app, handle_errors, out_console


@app.command("export")
@handle_errors
def export_cmd(
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
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


@app.command("report")
@handle_errors
def report_cmd(
    data: Path = typer.Option(paths.DATA, "--data", help="Folder holding the pipeline's artefacts."),
    out: Path = typer.Option(paths.REPORT, "--out", help="Report to write (Markdown)."),
):
    """Write the report that sets our results beside the paper's."""
    from ..stages.report import write_report

    path = write_report(data, out)
    out_console.print(f"wrote {path}", highlight=False)
