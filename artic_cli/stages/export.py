"""Export for other tools: VTK / XDMF for ParaView (through meshio), CSV for EMA-style analysis.

* ``mesh.vtu``: the tongue's 120 hexahedra (VTK_HEXAHEDRON, the same corner order) and ``wall.vtu``: the
  vocal-tract wall triangles with their part (palate, pharynx, mandible) as cell data.
* A simulation: one ``.vtu`` per recorded frame (tongue hexahedra plus the jaw and hyoid links as lines,
  node velocity as point data) indexed by a ``.pvd`` collection with the times, and the same motion as
  one XDMF time series of the tongue (the first frame's mesh with a ``displacement`` field per step;
  use Warp By Vector).
* CSV: time and the control points, one row per frame, columns ``time_s, tip_x_cm, tip_y_cm, tip_z_cm,
  dorsum_..., jaw_...`` as EMA trajectories are usually laid out.
All lengths in cm, times in s.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..errors import ArticError
from ..io.store import atomic_path, load_mesh, write_text_atomic
from .simulate import read as read_simulation

SIM_HINT = "rerun 'artic simulate' to produce it"


def _meshio():
    try:
        import meshio
    except ImportError:  # pragma: no cover - a dependency
        raise ArticError("export needs meshio; pip install meshio") from None
    return meshio


def _write(path: Path, mesh) -> None:
    with atomic_path(path, path.suffix) as tmp:
        mesh.write(tmp, file_format="vtu")


def export_mesh_vtk(mesh_path: Path | str, out_dir: Path | str) -> list[Path]:
    meshio = _meshio()
    m = load_mesh(mesh_path)
    mesh, wall = m.mesh, m.wall
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tongue = meshio.Mesh(mesh.nodes, [("hexahedron", mesh.bricks)],
                         cell_data={"brick": [np.arange(len(mesh.bricks))]})
    wall_mesh = meshio.Mesh(wall.vertices, [("triangle", wall.triangles)], cell_data={"part": [wall.part]})
    paths = [out / "mesh.vtu", out / "wall.vtu"]
    _write(paths[0], tongue)
    _write(paths[1], wall_mesh)
    return paths


def _read_sim(sim_path: Path | str):
    s = read_simulation(sim_path, allow_invalid=True)
    return s.time_s, s.positions_cm, s.velocities_cm_s, s.control_points


def export_simulation_vtk(sim_path: Path | str, mesh_path: Path | str, out_dir: Path | str,
                          every: int = 1) -> list[Path]:
    """Frames as VTU + a PVD index, and an XDMF time series of displacements."""
    meshio = _meshio()
    m = load_mesh(mesh_path)
    mesh = m.mesh
    t, x, v, _ = _read_sim(sim_path)
    nt = len(mesh.nodes)
    if x.shape[1] < nt:
        raise ArticError(f"{sim_path} does not match the mesh {mesh_path} ({x.shape[1]} nodes); give its mesh")
    cells = [("hexahedron", mesh.bricks)]
    if x.shape[1] > nt:  # the articulator: jaw and hyoid as lines between their nodes
        from ..geometry.anatomy import LINK_KINDS, build_body

        body = build_body(SimpleNamespace(speaker=m.speaker), mesh)
        bones = body.links[np.isin(body.link_kind, [LINK_KINDS.index(k) for k in ("mandible", "hyoid")])]
        cells.append(("line", bones))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stem = Path(sim_path).stem
    frames = list(range(0, len(t), max(1, every)))
    paths, entries = [], []
    for k in frames:
        p = out / f"{stem}_{k:04d}.vtu"
        _write(p, meshio.Mesh(x[k], cells, point_data={"velocity_cm_s": v[k]}))
        paths.append(p)
        entries.append(f'    <DataSet timestep="{t[k]:.6g}" part="0" file="{p.name}"/>')
    pvd = out / f"{stem}.pvd"
    write_text_atomic(pvd, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
                      + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    xdmf = out / f"{stem}.xdmf"
    h5 = xdmf.with_suffix(".h5")
    # meshio's XDMF writer puts its heavy-data file in the working directory, named after the .xdmf stem:
    # write in the output folder under a temporary stem, then rename both (the .xdmf names the .h5)
    tmp_stem = f".{stem}.partial"
    with contextlib.chdir(out):
        try:
            with meshio.xdmf.TimeSeriesWriter(f"{tmp_stem}.xdmf") as w:
                w.write_points_cells(x[0, :nt], cells[:1])  # the tongue (meshio's XDMF writer: one cell type)
                for k in frames:
                    w.write_data(float(t[k]), point_data={"displacement": x[k, :nt] - x[0, :nt],
                                                          "velocity_cm_s": v[k, :nt]})
            text = Path(f"{tmp_stem}.xdmf").read_text().replace(f"{tmp_stem}.h5", h5.name)
            os.replace(f"{tmp_stem}.h5", h5.name)
            write_text_atomic(xdmf.name, text)
        finally:
            for leftover in (f"{tmp_stem}.xdmf", f"{tmp_stem}.h5"):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(leftover)
    return [pvd, xdmf, h5, *paths]


def export_csv(sim_path: Path | str, out: Path | str) -> Path:
    t, _, _, cps = _read_sim(sim_path)
    names = [k for k in ("tip", "dorsum", "jaw") if k in cps]
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["time_s"] + [f"{n}_{a}_cm" for n in names for a in "xyz"])
    for k in range(len(t)):
        w.writerow([f"{t[k]:.6f}"] + [f"{cps[n][k, a]:.6f}" for n in names for a in range(3)])
    return write_text_atomic(out, buf.getvalue())
