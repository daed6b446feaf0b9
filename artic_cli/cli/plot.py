"""``artic`` commands: pictures of every artefact."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Optional

import numpy as np
import typer

from ..errors import ArticError
from ..stages import paths
from .app import err_console, handle_errors, out_console, plot_app


def plot_mesh_file(mesh: Path, out: Path, config: Path | None = None) -> Path:
    from ..config import load_config
    from ..tract.outline import outline
    from ..plots.mesh import plot_mesh
    from ..stages.mesh import read

    cfg = load_config(config)
    m = read(mesh, cfg)
    tract = None
    if cfg.vocal_tract is not None:
        surface = m.mesh.nodes[m.mesh.node_sets["midsagittal_surface"], :2]
        tract = outline(cfg.vocal_tract, cfg.speaker.wall, surface, (np.eye(3), np.zeros(3))).drawn
    return plot_mesh(m.mesh, m.wall, m.speaker.landmarks_cm, out, tract=tract)


def plot_simulation_file(sim: Path, model, wall, plot: Path | None, animate: Path | None) -> None:
    from ..stages.simulate import read

    s = read(sim, allow_invalid=True)
    traj = SimpleNamespace(x=s.positions_cm, time=s.time_s)
    if plot:
        from ..plots.simulation import plot_simulation

        plot_simulation(traj, model, wall, plot, title=f"{Path(sim).stem}: start and end shapes")
    if animate:
        from ..plots.animation import animate_simulation

        animate_simulation(traj, model, wall, animate)


def plot_fig7_file(doc: dict, out: Path) -> Path:
    from ..plots.muscle_function import plot_fig7
    from ..stages.experiments import figure_paths

    if "figure" not in doc:
        raise ArticError(f"experiment '{doc.get('experiment')}' has no figure; only fig7 draws one")
    return plot_fig7(figure_paths(doc), out)


@plot_app.command("muscle-function")
@handle_errors
def plot_muscle_function_cmd(
    study: Path = typer.Argument(paths.MUSCLE_FUNCTION, help="Result of 'artic muscle-function'."),
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
    from ..io.wav import read_wav

    samples, rate = read_wav(wav)
    out_console.print(f"wrote {plot_spectrogram(samples, rate, out, title=wav.name)}", highlight=False)


@plot_app.command("acoustic-map")
@handle_errors
def plot_acoustic_map_cmd(
    result: Path = typer.Argument(paths.ACOUSTIC_MAPS, help="Result of 'artic acoustic-map'."),
    out: Path = typer.Option(..., "--out", help="The vowel space (PNG)."),
):
    """Every EP in the F1-F2 plane, jaw position by jaw position, with the Japanese vowels."""
    from ..plots.acoustic_map import plot_vowel_space
    from ..speech.vowels import JAPANESE_VOWELS
    from ..stages.acoustic_map import read

    out_console.print(f"wrote {plot_vowel_space(read(result), out, JAPANESE_VOWELS)}", highlight=False)


@plot_app.command("ep-map")
@handle_errors
def plot_ep_map_cmd(
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps from 'artic ep-map'."),
    jaw: Optional[str] = typer.Option(None, "--jaw", help="Jaw position (default: the typical one, JO_0.5)."),
    pair: Optional[str] = typer.Option(None, "--pair", help="Two-muscle net to draw, e.g. SG+HG (default: the "
                                                            "first stored at that jaw position)."),
    out: Path = typer.Option(paths.FIG8, "--out", help="Picture to write (PNG)."),
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
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps."),
    dynamic: Path = typer.Option(paths.DYNAMIC, "--dynamic", help="Dynamic map."),
    jaw: str = typer.Option("JO_2.5", "--jaw", help="Jaw position to compare (the paper's Fig. 9: JO 2.5 N)."),
    out: Path = typer.Option(paths.FIG9, "--out", help="Picture to write (PNG)."),
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
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps."),
    dynamic: Path = typer.Option(paths.DYNAMIC, "--dynamic", help="Dynamic map."),
    out: Path = typer.Option(paths.FIG12, "--out", help="Picture to write (PNG)."),
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
    from ..io.wav import read_wav

    rec = speak_stage.read(record)
    y, rate = read_wav(Path(record).parent / str(rec.attrs.get("wav", Path(record).with_suffix(".wav").name)))
    out_console.print(f"wrote {plot_utterance(rec, y, rate, out)}", highlight=False)


@plot_app.command("mesh")
@handle_errors
def plot_mesh_cmd(
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh artefact from build-mesh."),
    out: Path = typer.Option(paths.FIG1, "--out", help="Picture to write (PNG)."),
    config: Optional[Path] = typer.Option(None, "--config", help="Config of the mesh (its vocal tract is drawn too)."),
):
    """Fig. 1: the mesh, the wall, the vocal tract's other parts and the muscles' landmarks."""
    out_console.print(f"wrote {plot_mesh_file(mesh, out, config)}", highlight=False)


@plot_app.command("simulation")
@handle_errors
def plot_simulation_cmd(
    sim: Path = typer.Argument(..., help="A simulation from 'artic simulate' (HDF5)."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="The mesh it was run on."),
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
    plot_simulation_file(sim, model, wall, out, animate)
    out_console.print("wrote " + ", ".join(str(p) for p in (out, animate) if p), highlight=False)


@plot_app.command("experiment")
@handle_errors
def plot_experiment_cmd(
    table: Path = typer.Argument(..., help="An experiment table from 'artic experiment fig7 --out FILE'."),
    out: Path = typer.Option(paths.FIG7, "--out", help="Picture to write (PNG)."),
):
    """Fig. 7: the trajectories from four starting shapes (from the fig7 table)."""
    from ..stages.experiments import read

    out_console.print(f"wrote {plot_fig7_file(read(table), out)}", highlight=False)
