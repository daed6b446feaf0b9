"""The report's vocal-tract section: the rest tract, simulated tracts, their acoustics and sound (section II.A)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .rows import Row, verdict


def tract_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """The rest tract and the tracts of the articulator's simulations."""
    from ..stages import vocal_tract as vt

    out_dir = Path("reports") if out_dir is None else out_dir
    rest = vt.read(data / "tracts" / "rest.h5")
    area, pos, reg = rest.af.constriction()
    length = float(rest.af.tract_length_cm[0])
    grid_area = rest.af.area_cm2[0, :rest.grid.n_lines]
    n_lip = len(rest.af.region) - rest.grid.n_lines
    rows = [Row("rest tract length, glottis to lips", "adult male, about 17 cm (16.5-18)",
                f"{length:.2f} cm ({rest.grid.n_lines} grid sections + {n_lip} lip sections)",
                verdict(16.5 <= length <= 18.0, "16.5-18 cm")),
            Row("rest tract: smallest area (grid)", "open vowel [e]: no constriction",
                f"{grid_area.min():.2f} cm^2 at {pos[0]:.1f} cm ({rest.af.region_names[int(reg[0])]})",
                verdict(grid_area.min() >= 0.15, "at least 0.15 cm^2"))]
    if rest.band_area_cm2 is not None:
        ratio = rest.band_area_cm2[0] / np.where(grid_area > 0, grid_area, np.nan)
        by_region = ", ".join(f"{name} {np.nanmedian(ratio[rest.grid.region == i]):.2f}"
                              for i, name in enumerate(rest.af.region_names[:-1]) if (rest.grid.region == i).any())
        med = float(np.nanmedian(ratio))
        rows.append(Row("rest tract: 3-D band area / power law", "the paper: midsagittal distances and laws",
                        f"median {med:.2f} ({by_region})", verdict(0.5 <= med <= 2.0, "median within a factor 2")))
    lines = ["![The rest tract: midsagittal view, grid and area function](tract_rest.png)", ""]
    acoustics = data / "acoustics" / "rest.h5"
    if acoustics.is_file():
        from ..stages.acoustics import read as read_acoustics

        fm = read_acoustics(acoustics).formants_hz[0]
        for k, (target, name) in enumerate(((500.0, "F1"), (1947.0, "F2"))):
            err = fm[k] / target - 1
            rows.append(Row(f"rest tract [e] (default lips): {name}",
                            f"male Japanese /e/ {target:.0f} Hz (Jo's averages)", f"{fm[k]:.0f} Hz ({100 * err:+.0f} %)",
                            verdict(abs(err) <= 0.15, "within 15 %, the speaker's check")))
        lines += ["![The rest tract's transfer function and formants](acoustics_rest.png)",
                  "![The rest tract voiced for 1 s (F0 115 Hz)](spectrogram_rest.png)", ""]
    amaps = data / "acoustic_maps.h5"
    if amaps.is_file():
        from ..speech.vowels import JAPANESE_VOWELS
        from ..stages.acoustic_map import read as read_amaps

        am = read_amaps(amaps)
        pts = np.concatenate([am.points(j)[:, :2] for j in am.jaws])

        def within(points: np.ndarray) -> list[str]:
            return [v for v, (f1, f2) in JAPANESE_VOWELS.items()
                    if np.any((np.abs(points[:, 0] / f1 - 1) <= 0.1) & (np.abs(points[:, 1] / f2 - 1) <= 0.1))]

        reached = within(pts)
        # the lips are a control: the maps also hold every EP's formants with the config's mapped lip tubes
        lipped = {key: within(f[:, :2]) for key, f in am.points_with_lips().items()}
        every = [v for v in JAPANESE_VOWELS if v in reached or any(v in r for r in lipped.values())]
        with_lips = "".join(f"; with lips {a:g} cm^2 x {b:g} cm: {' '.join(r) or 'none'}"
                            for (a, b), r in lipped.items())
        rows.append(Row("EP maps in the F1-F2 plane (every jaw position; the lips a control)",
                        "male Japanese a i u e o",
                        f"{len(pts)} EPs: F1 {np.nanmin(pts[:, 0]):.0f}-{np.nanmax(pts[:, 0]):.0f} Hz, F2 "
                        f"{np.nanmin(pts[:, 1]):.0f}-{np.nanmax(pts[:, 1]):.0f} Hz; vowels within 10 %, default lips: "
                        f"{' '.join(reached) or 'none'}{with_lips}",
                        verdict(len(every) == 5, "all five within 10 % with some lip tube of the maps")))
        lines += ["![The EP maps' vowel space](vowel_space.png)", ""]
    wav = data / "audio" / "rest.wav"
    if wav.is_file():
        import os

        lines += [f"Listen: [the rest tract, 1 s]({os.path.relpath(wav, out_dir)})", ""]
    for path in sorted((data / "tracts").glob("*.h5")):
        if path.stem == "rest":
            continue
        t = vt.read(path)
        a, p, r = t.af.constriction()
        k = int(np.argmin(a))
        sane = bool(np.isfinite(t.af.area_cm2).all() and (t.af.area_cm2 >= 0).all())
        rows.append(Row(f"{path.stem}: the narrowest frame of {t.n_frames}", "areas finite, >= 0, one per frame",
                        f"{a[k]:.3f} cm^2 at {p[k]:.1f} cm ({t.af.region_names[int(r[k])]}), "
                        f"t = {t.time_s[k] * 1e3:.0f} ms", verdict(sane, "finite and >= 0")))
        lines.append(f"![{path.stem}: the last frame's tract](tract_{path.stem}.png)")
        if (data / "acoustics" / f"{path.stem}.h5").is_file():
            lines.append(f"![{path.stem}: formant tracks](acoustics_{path.stem}.png)")
    return rows, lines + [""]
