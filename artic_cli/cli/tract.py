"""``artic`` commands: the vocal tract and its sound: area functions, transfer functions and formants, synthesis."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..errors import ArticError
from ..stages import paths
from .app import app, handle_errors, out_console, print_table, with_progress


@app.command("vocal-tract")
@handle_errors
def vocal_tract_cmd(
    sim: Optional[Path] = typer.Option(None, "--sim", help="Simulation (HDF5): the tract of every frame."),
    rest: bool = typer.Option(False, "--rest", help="The rest posture (the articulator settled under gravity)."),
    ep: Optional[str] = typer.Option(None, "--ep", help="One EP of the maps, JAW:MUSCLE=N[,MUSCLE=N] "
                                                        "(e.g. JO_0.5:SG=2.5)."),
    epmaps: Path = typer.Option(paths.EPMAPS, "--epmaps", help="EP maps (HDF5), for --ep."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh (HDF5) the shapes were made on."),
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
    print_table(f"vocal tract ({t.n_frames} frame{'s' if t.n_frames > 1 else ''})",
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
        r = with_progress("formants", lambda update: tract_acoustics(tracts, config, frame, lossless, velum_area,
                                                                      out, progress=update))
        name = tracts.name
    if plot is not None:
        from ..plots.acoustics import plot_tracks, plot_transfer

        if len(r.formants_hz) > 1:
            plot_tracks(r, plot, title=f"{name}: formant tracks")
        else:
            plot_transfer(r, 0, plot, title=f"{name}{' (lossless)' if lossless else ''}")
    _print_formants(r, name, as_json)
    for p in (out, plot):
        if p is not None and not as_json:
            out_console.print(f"wrote {p}", highlight=False)


def _print_formants(r, name: str, as_json: bool) -> None:
    """The last frame's formants and bandwidths (Hz): a table, or JSON."""
    last = len(r.formants_hz) - 1
    fm = [None if not np.isfinite(v) else round(float(v), 2) for v in r.formants_hz[last]]
    bw = [None if not np.isfinite(v) else round(float(v), 2) for v in r.bandwidths_hz[last]]
    if as_json:
        doc = {"formants_hz": fm, "bandwidths_hz": bw}
        if r.time_s is not None:
            doc["time_s"] = float(r.time_s[last])
        out_console.print_json(json.dumps(doc))
        return
    rows = [(f"F{k + 1}", "" if f is None else f"{f:.1f}", "" if b is None else f"{b:.1f}")
            for k, (f, b) in enumerate(zip(fm, bw))]
    when = "" if r.time_s is None else f" at t = {r.time_s[last]:.3f} s ({len(r.formants_hz)} frames)"
    print_table(f"formants of {name}{when}", ("formant", "frequency Hz", "bandwidth Hz"), rows, left=("formant",))


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
