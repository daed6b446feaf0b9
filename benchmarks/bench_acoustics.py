"""Acoustics speed: one transfer function (1024 frequencies, 44 sections) and formant tracks of 200 frames;
VocalTractLab's transfer function side by side where it is installed.  Goals (issue 14): 5 ms and 1 s."""

from __future__ import annotations


import numpy as np

from artic_cli.acoustics.formants import formants
from artic_cli.acoustics.model import air_of, tract_of
from artic_cli.acoustics.transfer import transfer
from artic_cli.acoustics.tube import Tube
from artic_cli.config import load_config
from timing import median_time  # benchmarks/timing.py



def main() -> None:
    ac = load_config().acoustics
    air = air_of(ac)
    rng = np.random.default_rng(14)
    tubes = [Tube(np.full(44, 17.5 / 44), np.clip(3 + 2 * np.sin(np.linspace(0, 3, 44) + p), 0.3, None))
             for p in rng.uniform(0, 6, 200)]
    f = np.linspace(ac.max_frequency_hz / 1024, ac.max_frequency_hz, 1024)
    tract = tract_of(tubes[0], ac)
    one = median_time(lambda: transfer(tract, f, air))
    print(f"one transfer function, 1024 frequencies, 44 sections + piriform fossa: {one * 1e3:.2f} ms "
          f"(goal <= 5 ms: {'met' if one <= 0.005 else 'NOT met'})")

    def tracks():
        for t in tubes:
            tr = tract_of(t, ac)
            formants(lambda x, tr=tr: np.abs(transfer(tr, x, air)), ac.max_frequency_hz, ac.formant_search_step_hz)

    tr_time = median_time(tracks, n=3)
    print(f"formant tracks (F1-F5 with bandwidths), 200 frames: {tr_time:.2f} s "
          f"(goal <= 1 s: {'met' if tr_time <= 1.0 else 'NOT met'})")
    from artic_cli.stages.synthesize import compute_frames

    cfg = load_config()
    lengths = np.stack([t.length_cm for t in tubes])
    areas = np.stack([t.area_cm2 for t in tubes])
    times = np.linspace(0.0, 1.0, 200)
    compute_frames(lengths[:2], areas[:2], times[:2], cfg, 0.05)  # compile (or load) the line
    syn = median_time(lambda: compute_frames(lengths, areas, times, cfg, 1.0), n=3)
    print(f"1 s of audio (44.1 kHz) from 200 frames: {syn:.2f} s (goal <= 1 s: {'met' if syn <= 1.0 else 'NOT met'})")
    speech_synthesis(cfg, lengths, areas, times)
    try:
        import vocaltractlab_cython as vtl
    except ImportError:
        print("VocalTractLab not installed (pip install vocaltractlab-cython): no side-by-side figure")
        return
    shape = vtl.get_shape("a", "tract")
    theirs = median_time(lambda: vtl.tract_state_to_transfer_function(shape, n_spectrum_samples=2048))
    print(f"VocalTractLab, one transfer function (its default, 2048-point spectrum): {theirs * 1e3:.2f} ms; "
          f"ours / theirs = {one / theirs:.2f}")


def speech_synthesis(cfg, lengths, areas, times) -> None:
    """The speaking synthesis with every source (issue 44): the air in time, aspiration, bursts, the voice
    bar, and the nasal branch with the port shut and open the whole second.  Goal: at most 0.1 s per second
    of audio on one core."""
    from artic_cli import units
    from artic_cli.acoustics.sources import Larynx, synthesize_speech

    def larynx(port_cm2: float, frames: int = len(times)) -> Larynx:
        return Larynx(glottis_cm2=np.full(frames, 0.05), port_cm2=np.full(frames, port_cm2),
                      port_at_cm=8.5, lung_pressure=units.kpa_to_cgs(0.8), voicing=np.ones(frames),
                      noise=cfg.speech.noise, voiced_cm2=0.05)

    synthesize_speech(lengths[:2], areas[:2], times[:2], cfg.acoustics, 0.05, larynx(0.5, 2))  # compile or load
    for port in (0.0, 0.5):
        took = median_time(lambda: synthesize_speech(lengths, areas, times, cfg.acoustics, 1.0, larynx(port)), n=3)
        print(f"1 s of speech with every source, the port {'open 0.5 cm^2' if port else 'shut'}: {took:.3f} s "
              f"(goal <= 0.1 s per s of audio: {'met' if took <= 0.1 else 'NOT met'})")


if __name__ == "__main__":
    main()
