"""``artic`` commands: speech: utterances spoken from targets in time."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import ArticError
from ..stages import paths
from ..validation import check_number
from .app import app, err_console, handle_errors, out_console, with_progress


@app.command("speak")
@handle_errors
def speak_cmd(
    utterance: Optional[Path] = typer.Argument(None, help="Utterance file (YAML): segments (a phoneme, a target "
                                                          "or forces, a duration), an F0 contour, a lip and velum "
                                                          "course.  Or give --text."),
    text: Optional[str] = typer.Option(None, "--text", help="Japanese to speak: Hepburn or kunrei romaji, or kana "
                                       "(e.g. 'konnichiwa', \"ha'shi\": the pitch falls after 'ha'; ',' a pause); "
                                       "mora-timed, devoiced, its pitch from the accents."),
    rate: float = typer.Option(1.0, "--rate", help="Speaking rate with --text (0.5-2; 2: morae half as long)."),
    f0_range: Optional[str] = typer.Option(None, "--f0-range", help="LOW,HIGH Hz of the --text pitch (default "
                                           "the inventory's, 95,135)."),
    inventory: Optional[Path] = typer.Option(None, "--inventory", help="Phoneme inventory (default "
                                                                       "configs/phonemes/japanese.yaml)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Sound to write (WAV); the TextGrid and NAME.h5 go "
                                                           "beside it (default data/utterances/NAME.wav)."),
    maps: Path = typer.Option(paths.EPMAPS, "--maps", help="EP maps the targets are solved on."),
    dynamic: Path = typer.Option(paths.DYNAMIC, "--dynamic", help="Dynamic map, read only for a place "
                                 "target at a jaw position the maps hold no nets for."),
    acoustic_maps: Path = typer.Option(paths.ACOUSTIC_MAPS, "--acoustic-maps",
                                       help="Formants of every EP (vowel targets)."),
    mesh: Path = typer.Option(paths.MESH, "--mesh", help="Mesh from 'artic build-mesh'."),
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
    page: Optional[Path] = typer.Option(None, "--html", help="A page to look at and listen to (HTML): the sound, "
                                        "the spectrogram with tiers and movement, the animation (drawn beside it)."),
):
    """Speak a sequence of targets: each solved once, its forces ramped in at its segment's start and held, the
    whole simulated with contact, then the tract, formants and sound (WAV, TextGrid, HDF5)."""
    from ..stages import speak as speak_stage

    check_number("--budget", budget, ge=1)
    check_number("--jobs", jobs, ge=1)
    if (utterance is None) == (text is None):
        raise ArticError("give an utterance file or --text ROMAJI, one of them (e.g. artic speak --text aga)")
    if text is not None:
        from ..speech.inventory import DEFAULT, load_inventory
        from ..speech.text import utterance_of_text

        utterance = utterance_of_text(text, load_inventory(inventory or DEFAULT), rate=rate,
                                      f0_range_hz=_f0_range(f0_range))
    elif rate != 1.0 or f0_range is not None:
        raise ArticError("--rate and --f0-range shape --text; an utterance file gives its durations and f0_hz")
    if page is not None:  # the page's pictures are drawn beside it
        plot, animate = plot or page.with_suffix(".png"), animate or page.with_suffix(".gif")
    for opt, p, ext in (("--plot", plot, ".png"), ("--animate", animate, ".gif"), ("--html", page, ".html")):
        if p is not None and (p.suffix.lower() != ext or not p.parent.is_dir()):
            raise ArticError(f"{opt} {p}: give a {ext} file in an existing folder")
    say = lambda m: err_console.print(m, highlight=False)  # noqa: E731
    res = with_progress("simulating", lambda update: speak_stage.speak(
        utterance, out, maps, mesh, acoustic_maps, config, solutions, accept_nearest, budget, update, say, jobs,
        dynamic, inventory))
    _report(res)
    if plot is not None or animate is not None:
        _draw(res.paths, plot, animate, mesh, config)
    if page is not None:
        _page(res.paths, page, plot, animate)


def _f0_range(value: str | None) -> tuple[float, float] | None:
    if value is None:
        return None
    try:
        lo, hi = (float(v) for v in value.split(","))
    except ValueError:
        raise ArticError(f"--f0-range {value}: give LOW,HIGH in Hz, e.g. --f0-range 90,140") from None
    if not 50 <= lo < hi <= 500:  # NaN fails too
        raise ArticError(f"--f0-range {value}: give LOW,HIGH in Hz with 50 <= LOW < HIGH <= 500")
    return lo, hi


def _page(files: dict, page: Path, plot: Path, animate: Path) -> None:
    import os

    from ..io.store import write_text_atomic
    from ..report.html import utterance_page
    from ..stages import speak as speak_stage

    rec = speak_stage.read(files["h5"])
    rel = lambda p: os.path.relpath(p, page.parent)  # noqa: E731
    rows = [(lab, f"{s:.3f}", f"{1e3 * d:.0f}", how) for lab, s, d, how in zip(rec.labels, rec.starts_s,
                                                                              rec.durations_s, rec.how)]
    text = utterance_page(str(rec.attrs.get("name", page.stem)), rel(files["wav"]), rel(plot), rel(animate), rows,
                          rel(files["textgrid"]))
    out_console.print(f"wrote {write_text_atomic(page, text)}", highlight=False)


def _report(res) -> None:
    if res.up_to_date:
        out_console.print(f"{res.paths['wav']} is up to date (same utterance, solutions, mesh, config and code)",
                          highlight=False)
        return
    s = res.spoken
    out_console.print(f"wrote {res.paths['wav']} ({len(s.audio.samples) / s.audio.sample_rate_hz:.2f} s), "
                      f"{res.paths['textgrid']}, {res.paths['h5']}", highlight=False)
    for lab, how in zip(s.plan.labels, s.plan.notes):
        out_console.print(f"  {lab}: {how}", highlight=False)


def _draw(files: dict, plot: Path | None, animate: Path | None, mesh: Path, config: Path | None) -> None:
    from ..io.wav import read_wav
    from ..stages import speak as speak_stage

    rec = speak_stage.read(files["h5"])
    if plot is not None:
        from ..plots.utterance import plot_utterance

        y, rate = read_wav(files["wav"])
        out_console.print(f"wrote {plot_utterance(rec, y, rate, plot)}", highlight=False)
    if animate is not None:
        from ..plots.utterance import animate_utterance
        from ..stages.simulate import load_model

        model, _, wall = load_model(mesh, config)
        out_console.print(f"wrote {animate_utterance(rec, model, wall, animate)}", highlight=False)
