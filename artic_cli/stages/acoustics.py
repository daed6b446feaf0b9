"""Stage ``acoustics``: transfer function, radiated spectrum, formants and bandwidths of a tube or of every
frame of a vocal-tract file (section II.A's vocal tract as an area function)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..acoustics.formants import formants
from ..acoustics.model import air_of, frequencies, tract_of
from ..acoustics.transfer import radiated_pressure, transfer
from ..acoustics.tube import Tube, read_tube_csv
from ..config import Config, load_config
from ..errors import ArticError
from ..io.fingerprint import digest
from ..io.store import atomic_h5, open_artifact
from ..validation import check_number
from .base import Stage, up_to_date

STAGE = Stage(name="acoustics", module=__name__, sections=("acoustics",), kind="acoustics",
              hint="rerun 'artic acoustics'")


@dataclass
class Acoustics:
    """Frames x frequencies: the transfer function U_lips / U_glottis and the radiated pressure (dB), and
    frames x formants: their frequencies and -3 dB bandwidths (Hz; NaN where there are fewer peaks)."""

    frequency_hz: np.ndarray  # (F,)
    transfer_db: np.ndarray  # (T, F)
    pressure_db: np.ndarray  # (T, F)
    formants_hz: np.ndarray  # (T, K)
    bandwidths_hz: np.ndarray  # (T, K)
    time_s: np.ndarray | None = None  # (T,) for a time series
    min_area_cm2: np.ndarray | None = None  # (T,) each frame's smallest section (near 0: a closure)


def compute(tubes: list[Tube], cfg: Config, lossless: bool = False, velum_area_cm2=None,
            port_from_glottis_cm=None, progress=None, spectra: bool = True, bandwidths: bool = True) -> Acoustics:
    """Every tube's acoustics; ``velum_area_cm2`` and ``port_from_glottis_cm``: one value for all tubes or one
    per tube (None: the config's port area, and its distance from the lips for a plain tube).  ``spectra=False``:
    formants and bandwidths only (the stored transfer function and pressure spectrum are half the work; their
    arrays are then empty); ``bandwidths=False``: NaN bandwidths (a third of the formant search)."""
    ac = STAGE.view(cfg).acoustics
    air = air_of(ac, lossless)
    f = frequencies(ac)
    tf, pr, fm, bw = [], [], [], []
    per = lambda v, k: v[k] if isinstance(v, (list, tuple, np.ndarray)) else v  # noqa: E731
    for k, tube in enumerate(tubes):
        if progress is not None:
            progress(k, len(tubes))
        velum, port = per(velum_area_cm2, k), per(port_from_glottis_cm, k)
        tract = tract_of(tube, ac, None if velum is None else float(velum), lossless,
                         None if port is None else float(port))
        if spectra:
            h = transfer(tract, f, air)
            tf.append(20 * np.log10(np.maximum(np.abs(h), 1e-12)))
            pr.append(20 * np.log10(np.maximum(np.abs(radiated_pressure(h, f, air)), 1e-30) / 2e-4))
        fk, bk = formants(lambda x, t=tract: np.abs(transfer(t, x, air)), ac.max_frequency_hz,
                          ac.formant_search_step_hz, ac.formants, lossless=lossless, bandwidths=bandwidths)
        fm.append(fk)
        bw.append(bk)
    if progress is not None:
        progress(len(tubes), len(tubes))
    if not spectra:
        f = np.zeros(0)
        tf = pr = np.zeros((len(tubes), 0))
    return Acoustics(f, np.array(tf), np.array(pr), np.array(fm), np.array(bw),
                     min_area_cm2=np.array([float(np.min(t.area_cm2)) for t in tubes]))


def write(path: Path | str, result: Acoustics, prov=None, extra: dict | None = None) -> None:
    with atomic_h5(path, STAGE.kind, prov) as f:
        f.attrs.update(extra or {})
        f.attrs["layout"] = "frames x frequencies (transfer_db, pressure_db), frames x formants (formants_hz, bandwidths_hz)"
        for name, data, unit in (("frequency_hz", result.frequency_hz, "Hz"),
                                 ("transfer_db", result.transfer_db, "dB re 1 (U_lips / U_glottis)"),
                                 ("pressure_db", result.pressure_db, "dB re 20 uPa at 1 m per cm^3/s of glottal flow"),
                                 ("formants_hz", result.formants_hz, "Hz"), ("bandwidths_hz", result.bandwidths_hz, "Hz")):
            f.create_dataset(name, data=data).attrs["units"] = unit
        if result.time_s is not None:
            f.create_dataset("time_s", data=result.time_s).attrs["units"] = "s"
        if result.min_area_cm2 is not None:
            f.create_dataset("min_area_cm2", data=result.min_area_cm2).attrs["units"] = "cm^2"


def read(path: Path | str) -> Acoustics:
    with open_artifact(path, STAGE.kind, STAGE.hint) as f:
        try:
            return Acoustics(frequency_hz=f["frequency_hz"][()], transfer_db=f["transfer_db"][()],
                             pressure_db=f["pressure_db"][()], formants_hz=f["formants_hz"][()],
                             bandwidths_hz=f["bandwidths_hz"][()],
                             time_s=f["time_s"][()] if "time_s" in f else None,
                             min_area_cm2=f["min_area_cm2"][()] if "min_area_cm2" in f else None)
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {STAGE.hint}") from None


def tube_acoustics(tube: Path | str, config: Path | str | None = None, lossless: bool = False,
                   velum_area_cm2: float | None = None, out: Path | str | None = None) -> Acoustics:
    """The acoustics of a tube file; with ``out``, written there (left alone when it holds this recipe)."""
    check_number("--velum-area", velum_area_cm2, ge=0, le=10, unit="cm^2")
    cfg = load_config(config)
    t = read_tube_csv(tube)
    if out is not None:
        out = Path(out)
        if not out.parent.is_dir():
            raise ArticError(f"--out {out}: the folder {out.parent} does not exist; create it or give another path")
        prov = STAGE.provenance(cfg, inputs={"tube": digest({"l": t.length_cm, "a": t.area_cm2})},
                                params={"lossless": lossless, "velum_area_cm2": velum_area_cm2})
        if up_to_date(out, prov):
            return read(out)
    result = compute([t], cfg, lossless, velum_area_cm2)
    if out is not None:
        write(out, result, prov, {"source": str(tube), "lossless": lossless})
    return result


def port_positions(tracts) -> np.ndarray:
    """Per frame, where the nasal branch joins: the start of the velum region, cm from the glottis."""
    names = list(tracts.af.region_names)
    if "velum" not in names:
        raise ArticError("the vocal tract has no 'velum' region in its area law; name one 'velum' in the config")
    first = int(np.argmax(tracts.af.region == names.index("velum")))
    return tracts.af.length_cm[:, :first].sum(axis=1)


def tract_acoustics(tracts_path: Path | str, config: Path | str | None = None, frame: int | None = None,
                    lossless: bool = False, velum_area_cm2: float | None = None, out: Path | str | None = None,
                    progress=None) -> Acoustics:
    """The acoustics of every frame of a vocal-tract file (``frame``: one of them); the velopharyngeal port
    of each frame is the file's unless ``velum_area_cm2`` overrides it."""
    from . import vocal_tract as vt_stage

    check_number("--velum-area", velum_area_cm2, ge=0, le=10, unit="cm^2")
    cfg = load_config(config)
    t = vt_stage.read(tracts_path)
    frames = list(range(t.n_frames)) if frame is None else [vt_stage.pick_frame(t, frame)]
    if out is not None:
        out = Path(out)
        if not out.parent.is_dir():
            raise ArticError(f"--out {out}: the folder {out.parent} does not exist; create it or give another path")
    from ..io.store import stored_content_hash

    prov = STAGE.provenance(cfg, inputs={"tracts": str(stored_content_hash(tracts_path))},
                            params={"lossless": lossless, "velum_area_cm2": velum_area_cm2, "frames": frames})
    if out is not None and up_to_date(out, prov):
        return read(out)
    tubes = [Tube(t.af.length_cm[k], t.af.area_cm2[k]) for k in frames]
    velum = t.controls["velum_port_cm2"][frames] if velum_area_cm2 is None else velum_area_cm2
    result = compute(tubes, cfg, lossless, velum, port_positions(t)[frames], progress)
    result.time_s = t.time_s[frames]
    if out is not None:
        write(out, result, prov, {"source": str(tracts_path), "lossless": lossless, "frames": frames})
    return result
