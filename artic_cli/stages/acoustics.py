"""Stage ``acoustics``: transfer function, radiated spectrum, formants and bandwidths of a tube or of every
frame of a vocal-tract file (section II.A's vocal tract as an area function)."""

from __future__ import annotations

from pathlib import Path


from ..acoustics.analysis import Acoustics, analyse
from ..acoustics.tube import Tube, read_tube_csv
from ..config import Config, load_config
from ..errors import ArticError
from ..io.fingerprint import digest
from ..io.store import atomic_h5, open_artifact
from ..validation import check_number
from .base import Stage, up_to_date

STAGE = Stage(name="acoustics", module=__name__, sections=("acoustics",), kind="acoustics",
              hint="rerun 'artic acoustics'")


def compute(tubes: list[Tube], cfg: Config, lossless: bool = False, velum_area_cm2=None,
            port_from_glottis_cm=None, progress=None, spectra: bool = True, bandwidths: bool = True) -> Acoustics:
    """:func:`artic_cli.acoustics.analysis.analyse` with the stage's config section."""
    return analyse(tubes, STAGE.view(cfg).acoustics, lossless, velum_area_cm2, port_from_glottis_cm, progress,
                   spectra, bandwidths)


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


def tract_acoustics(tracts_path: Path | str, config: Path | str | None = None, frame: int | None = None,
                    lossless: bool = False, velum_area_cm2: float | None = None, out: Path | str | None = None,
                    progress=None) -> Acoustics:
    """The acoustics of every frame of a vocal-tract file (``frame``: one of them); the velopharyngeal port
    of each frame is the file's unless ``velum_area_cm2`` overrides it."""
    from . import vocal_tract as vt_stage
    from ..tract.areas import port_positions

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
