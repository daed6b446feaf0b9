"""The report's speech sections: vowels from formant targets and utterances from targets in time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..speech.measures import EMA_PEAK_CM_S, too_fast
from .rows import Row, verdict


def vowel_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """The five vowels: target, simulated formants (refined, else the nearest force set's), forces, sound."""
    import os

    from ..config import read_yaml

    out_dir = Path("reports") if out_dir is None else out_dir
    rows: list[Row] = []
    lines = ["Each vowel is a formant target (male Japanese averages) solved on the EP maps with `--refine`: "
             "F1 within 10 % and F2 within 7 %.  An unreachable vowel shows its nearest force set, simulated.", ""]
    pictures: list[str] = []
    for path in sorted((data / "vowels").glob("*.yaml")):
        doc = read_yaml(path, "vowel solution")
        res = doc.get("refined") or doc.get("verified") or {}
        goal = doc.get("acoustic", {}).get("formants_hz", [np.nan, np.nan])
        f = res.get("formants_hz", [np.nan, np.nan])
        err = res.get("errors_pct", [np.nan, np.nan])
        forces = res.get("forces_n") or (doc.get("chosen") or doc.get("nearest") or {}).get("forces_n", {})
        wav = path.with_suffix(".wav")
        sound = f"[{wav.name}]({os.path.relpath(wav, out_dir)})" if wav.is_file() else ""
        lips = doc.get("lips", {})
        pictures.append(f"![/{doc['target']}/: formants and area function](vowel_{path.stem}.png)")
        lines.append(f"* /{doc['target']}/: target F1 / F2 {goal[0]:.0f} / {goal[1]:.0f} Hz, ours {f[0]:.0f} / "
                     f"{f[1]:.0f} Hz ({err[0]:+.1f} %, {err[1]:+.1f} %); forces "
                     f"{', '.join(f'{k} {v:g} N' for k, v in forces.items()) or 'none'}; lips "
                     f"{lips.get('area_cm2', np.nan):g} cm^2, {lips.get('length_cm', np.nan):g} cm" +
                     (f"; listen: {sound}" if sound else ""))
        ok = bool(res.get("within_tolerance")) and "unreachable" not in doc
        how = "unreachable by the maps: nearest force set simulated" if "unreachable" in doc else (
            "refined by simulation" if "refined" in doc else "verified by simulation")
        rows.append(Row(f"/{doc['target']}/: F1 / F2", f"{goal[0]:.0f} / {goal[1]:.0f} Hz",
                        f"{f[0]:.0f} / {f[1]:.0f} Hz ({err[0]:+.1f} %, {err[1]:+.1f} %; {how})",
                        verdict(ok, "F1 within 10 %, F2 within 7 %")))
    return rows, lines + [""] + pictures + [""]


MAX_VOLUME, MAX_BEYOND_CM = 0.003, 0.01  # the goals: volume within 0.3 %, tissue within 0.01 cm of the wall


def broken_limits(m: dict, rec) -> list[str]:
    """What a spoken record breaks of the mechanical goals (``m``: its measures): each too-fast articulator,
    the volume change, inverted bricks, the tissue beyond the wall; [] when it keeps them all."""
    sp = m["peak_speed_cm_s"]
    out = [f"{k} {sp.get(k, np.nan):.0f} cm/s" for k in too_fast(sp)]
    inv, beyond = int(rec.attrs.get("inverted_bricks_max", 0)), float(rec.attrs.get("max_beyond_wall_cm", np.nan))
    if not m["max_volume_change"] <= MAX_VOLUME:
        out.append(f"volume {100 * m['max_volume_change']:.2f} %")
    if inv:
        out.append(f"{inv} inverted")
    if not beyond <= MAX_BEYOND_CM:
        out.append(f"{beyond:.3f} cm beyond the wall")
    return out


def utterance_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    """Each spoken utterance: its segments (how their forces were found, F1 / F2), closures, noise, speeds, the
    sound and its TextGrid; rows for the measures speech needs."""
    import os

    from ..io.wav import read_wav
    from ..speech.measures import measures
    from ..stages import speak as speak_stage

    out_dir = Path("reports") if out_dir is None else out_dir
    rows: list[Row] = []
    records = [(path, speak_stage.read(path)) for path in sorted((data / "utterances").glob("*.h5"))]
    first = records[0][1] if records else None
    ramp = f"{first.ramp_ms:g} ms" if first else "the configured ramp"
    rise, fall = first.activation_ms if first else (0.0, 0.0)
    lag = (f", the muscles following them through first-order activation dynamics ({rise:g} ms rising, {fall:g} ms "
           "falling; the paper's forces follow at once)") if rise > 0 or fall > 0 else ""
    lines = ["Each utterance is a list of targets with durations (`configs/utterances/`), spoken by `artic speak "
             f"--accept-nearest`: every target solved once, its forces ramped in over {ramp} and held (the paper's "
             "static forces) or opened with a pulse (`pulse_step`, beyond the paper), switched on at the segment's "
             "start or a lead before it (each line names its course and lead, a segment its own lead and a stop "
             f"its press on the solved forces){lag}, the whole simulated with contact, then "
             "tract, formants and sound (LF voice, off in voiceless segments; turbulence noise at the narrowest "
             "place).  Formants are our transfer function's, medians over each segment's middle half.", ""]
    pictures: list[str] = []
    for path, rec in records:
        wav = path.with_suffix(".wav")
        y, rate = read_wav(wav)
        m = measures(rec, y, rate)
        name = str(rec.attrs.get("name", path.stem))
        own = [(f", {lead:g} ms ahead" if lead != rec.lead_ms else "") + (f", pressed x{f:g}" if f != 1.0 else "")
               for lead, f in zip(rec.leads_ms, rec.press)]
        segs = "; ".join(f"{s['label']} ({h}{o}) F1 / F2 {s['f1_hz']:.0f} / {s['f2_hz']:.0f} Hz"
                         for s, h, o in zip(m["segments"], rec.how, own))
        clos = ", ".join(f"{c['duration_ms']:.0f} ms at {c['start_s']:.2f} s" for c in m["closures"]) or "none"
        sp = m["peak_speed_cm_s"]
        tg = path.with_suffix(".TextGrid")
        lines.append(f"* /{name}/ ({rec.force_course} forces, {rec.lead_ms:g} ms ahead): {segs}; closures: {clos}; "
                     f"narrowest {m['min_constriction_cm2']:.2f} cm^2; peak "
                     f"speeds tip / dorsum / jaw {sp.get('tip', np.nan):.1f} / {sp.get('dorsum', np.nan):.1f} / "
                     f"{sp.get('jaw', np.nan):.1f} cm/s; listen: [{wav.name}]({os.path.relpath(wav, out_dir)}), "
                     f"[{tg.name}]({os.path.relpath(tg, out_dir)})")
        pictures.append(f"![/{name}/: spectrogram, formant tracks, tip / dorsum / jaw heights]"
                        f"(utterance_{path.stem}.png)")
        rows += _goal_rows(name, m, rec, y, rate)
        if name.startswith("aia"):
            def ms(v: float) -> str:
                return f"{v:.0f}" if np.isfinite(v) else "not in the segment"

            t90 = "; ".join(f"{s['label']} " + " / ".join(ms(s.get(f'{c}_t90_ms', np.nan)) for c in
                                                           ("tip", "dorsum", "jaw")) for s in m["segments"])
            lines.append(f"  * {m['force_course']} forces: time to cover 90 % of the way to each segment's EP "
                         f"(tip / dorsum / jaw, ms): {t90}; commanded force impulse {m['force_impulse_n_s']:.2f} "
                         f"N s, peak total {m['peak_total_force_n']:.1f} N")
    table, summary = landmark_table(records)
    made, made_rows = articulator_table(records)
    heard, heard_rows = vowel_class_table(records)
    rows += summary + made_rows + heard_rows
    return rows, lines + [""] + table + [""] + made + [""] + heard + [""] + pictures + [""]


def spoken_phones(records, manners: dict[str, str]):
    """(path, record, phone intervals) of each record with a TextGrid that holds a consonant of the inventory."""
    from ..speech.judge import devoiced_marked
    from ..speech.textgrid import read_phones

    for path, rec in records:
        tg = path.with_suffix(".TextGrid")
        if not tg.is_file():
            continue
        iv = devoiced_marked(read_phones(tg), rec.starts_s, rec.voiced, manners)
        if any(manners.get(lab) not in (None, "vowel") for _, _, lab in iv):
            yield path, rec, iv


def vowel_class_table(records) -> tuple[list[str], list[Row]]:
    """The vowels beside the consonants spoken through the inventory: each one's F1 / F2 (the formant tracks,
    over its middle half) and the nearest of the five male Japanese means in Bark (speech/vowel_class.py, held to
    Praat in the tests); one row for how many sound as intended."""
    from ..speech.inventory import load_inventory
    from ..speech.vowel_class import heard_text, heard_vowels

    inv = load_inventory()
    means = {v: tuple(p.formants_hz[:2]) for v, p in inv.phonemes.items() if p.manner == "vowel"}
    manners = {k: p.manner for k, p in inv.phonemes.items()}
    out = ["The vowels beside the consonants, heard as the nearest of the five male Japanese means (Bark; F1 / F2 "
           "from the formant tracks over each vowel's middle half):", ""]
    ok = total = 0
    for path, rec, iv in spoken_phones(records, manners):
        found = heard_vowels(iv, rec.time_s, rec.formants_hz, means)
        ok, total = ok + sum(h["ok"] for h in found), total + len(found)
        wrong = [f"/{h['label']}/ at {h['start_s']:.2f} s {heard_text(h)}"
                 for h in found if not h["ok"]]
        if wrong:
            out.append(f"* /{rec.attrs.get('name', path.stem)}/: " + "; ".join(wrong))
    if not total:
        return [], []
    if ok == total:
        out.append("* every one as intended")
    row = Row("Vowels beside the consonants (issue 45): heard as intended", "the nearest male Japanese mean "
              "(Bark) is the vowel's own (goal)", f"{ok} of {total}", verdict(ok == total, "every vowel as intended"))
    return out, [row]


def articulator_table(records) -> tuple[list[str], list[Row]]:
    """Each /t d n s z r k g/ between vowels: the dorsum's distance from where the vowels hold it and the
    tip's rise at its narrowest frame (speech/articulation.py), and whether the articulator its entry names
    made it; one row for how many did."""
    from ..speech.articulation import LIMIT_CM, articulators
    from ..speech.inventory import load_inventory

    manners = {k: p.manner for k, p in load_inventory().phonemes.items()}
    out = [f"Which articulator made each consonant (at its narrowest frame, against the vowels beside it; the tip's "
           f"consonants keep the dorsum within {LIMIT_CM} cm, the dorsum's keep the tip from rising more):", ""]
    done = total = 0
    for path, rec, iv in spoken_phones(records, manners):
        for m in articulators(rec, iv, manners):
            done, total = done + m["ok"], total + 1
            out.append(f"* /{rec.attrs.get('name', path.stem)}/ {m['symbol']} (the {m['by']}'s) at {m['at_s']:.3f} s: "
                       f"dorsum {m['dorsum_cm']:.2f} cm from the vowels', tip {m['tip_rise_cm']:+.2f} cm; "
                       + ("made so" if m["ok"] else "not made so"))
    if not total:
        return [], []
    row = Row("Articulators (issue 45: the tip's consonants keep the dorsum, the dorsum's the tip)",
              f"each within {LIMIT_CM} cm of the vowels' (goal)", f"{done} of {total}",
              verdict(done == total, "every consonant made by its articulator"))
    return out, [row]


LANDMARK_COLUMNS = ("closure_ms", "closure_db", "closure_voiced", "voiced_share", "level_db", "low_ratio_db",
                    "band_3_8k_db", "centroid_hz", "dip_db", "f2_hz")


def landmark_table(records) -> tuple[list[str], list[Row]]:
    """Every consonant of the utterances spoken through the inventory: its landmarks against the vowels beside
    it (speech/landmarks.py; closure ms and dB, voicing in the closure and overall, level, murmur's low ratio,
    3-8 kHz band, centroid, dip, F2) and the checks of its manner; one row for how many pass."""
    from ..io.wav import read_wav
    from ..speech.inventory import load_inventory
    from ..speech.landmarks import consonants

    manners = {k: p.manner for k, p in load_inventory().phonemes.items()}
    out = ["Each consonant's acoustic landmarks (dB against the vowels beside it; voicing as a share of frames; "
           "`speech/landmarks.py`, held to Praat in the tests) and the checks of its manner (failed ones named):", ""]
    names = {"closure_ms": "closure {} ms", "closure_db": "at {} dB", "closure_voiced": "closure voiced {}",
             "voiced_share": "voiced {}", "level_db": "level {} dB", "low_ratio_db": "low ratio {} dB",
             "band_3_8k_db": "3-8 kHz {} dB", "centroid_hz": "centroid {} Hz", "dip_db": "dip {} dB",
             "f2_hz": "F2 {} Hz"}
    passed = total = 0
    centroids: dict[str, list[float]] = {"s": [], "sh": []}
    for path, rec, iv in spoken_phones(records, manners):
        y, rate = read_wav(path.with_suffix(".wav"))
        for m in consonants(y, rate, iv, manners, (rec.time_s, rec.formants_hz)):
            if m["symbol"] in centroids and np.isfinite(m.get("centroid_hz", np.nan)):
                centroids[m["symbol"]].append(float(m["centroid_hz"]))
            ok = all(m["checks"].values())
            passed, total = passed + ok, total + 1
            cells = []
            for c in LANDMARK_COLUMNS:
                v = m.get(c)
                if v is not None and np.isfinite(v):
                    cells.append(names[c].format(f"{100 * v:.0f} %" if c in ("closure_voiced", "voiced_share")
                                                 else f"{v:.0f}"))
            failed = [k for k, v in m["checks"].items() if not v]
            out.append(f"* /{rec.attrs.get('name', path.stem)}/ {m['symbol']} ({m['duration_ms']:.0f} ms): "
                       + ", ".join(cells) + "; " + ("passes" if ok else "fails " + "; ".join(failed)))
    if not total:
        return [], []
    row = Row("Consonant landmarks (issue 45's checks, every consonant spoken)", "every consonant passes its manner's "
              "checks (goal)", f"{passed} of {total} pass", verdict(passed == total, "every consonant's landmarks"))
    return out, [row] + centroid_rows(centroids)


def centroid_rows(centroids: dict[str, list[float]]) -> list[Row]:
    """Whether every /sh/'s 1-10 kHz centroid (Hz) lies below every /s/'s: the place heard in the noise ([ɕ]'s
    longer front cavity rings lower); no row without both."""
    if not (centroids.get("s") and centroids.get("sh")):
        return []
    said = lambda v: ", ".join(f"{x:.0f}" for x in v)  # noqa: E731
    return [Row("Centroids of /sh/ below /s/'s (issue 45)", "every /sh/'s 1-10 kHz centroid below every /s/'s (goal)",
                f"/sh/ {said(centroids['sh'])} Hz; /s/ {said(centroids['s'])} Hz",
                verdict(max(centroids["sh"]) < min(centroids["s"]), "the place in the noise"))]


def _goal_rows(name: str, m: dict, rec, y: np.ndarray, rate: int) -> list[Row]:
    """The goals one utterance is judged by: F2's course (/aia/), a stop's closure and burst, frication, peak
    speeds against EMA, and the tissue staying physical."""
    from ..acoustics.measures import band_level_db

    rows: list[Row] = []
    sp = m["peak_speed_cm_s"]
    vowels = [s for s in m["segments"] if s["label"] not in ("k", "t", "s", "p")]
    vowel_db = float(np.mean([s["level_db"] for s in vowels])) if vowels else np.nan
    if name == "aia":
        f2 = [s["f2_hz"] for s in m["segments"]]
        rise, fall = f2[1] - f2[0], f2[1] - f2[2]
        rows.append(Row("/aia/: F2 rise /a/ -> /i/, fall /i/ -> /a/", ">= 600 Hz each (goal)",
                        f"{rise:+.0f} / {fall:+.0f} Hz", verdict(rise >= 600 and fall >= 600, ">= 600 Hz")))
    if name in ("aka", "ata", "apa"):
        c = max(m["closures"], key=lambda c: c["duration_ms"]) if m["closures"] else None
        ours = "no closure"
        if c is not None:
            burst = band_level_db(y, rate, c["end_s"], c["end_s"] + 0.015, 3000.0)
            ours = (f"{c['duration_ms']:.0f} ms, {c['level_db'] - vowel_db:+.0f} dB against the vowels; the "
                    f"release's first 15 ms above 3 kHz {burst - vowel_db:+.0f} dB against the vowels' level")
        ok = c is not None and 40 <= c["duration_ms"] <= 120 and c["level_db"] - vowel_db <= -30
        rows.append(Row(f"/{name}/: closure", "40-120 ms, >= 30 dB below the vowels (goal)", ours,
                        verdict(ok, "a stop")))
    if name == "asa":
        s_ = [s for s in m["segments"] if s["label"] == "s"]
        vowel_hf = float(np.mean([s["level_above_3khz_db"] for s in vowels]))
        hf = s_[0]["level_above_3khz_db"] - vowel_hf if s_ else np.nan
        rows.append(Row("/asa/: level above 3 kHz, /s/ against the vowels", ">= +20 dB (goal)", f"{hf:+.1f} dB",
                        verdict(bool(hf >= 20), "frication")))
    fast = {k: sp.get(k, np.nan) for k in EMA_PEAK_CM_S}
    ok = not too_fast(sp)
    rows.append(Row(f"/{name}/: peak speeds tip / dorsum / jaw", "<= 40 / 32 / 12 cm/s (EMA, Table II) +50 %",
                    " / ".join(f"{fast[k]:.1f}" for k in EMA_PEAK_CM_S) + " cm/s",
                    verdict(ok, "each at most 50 % above the EMA peak")))
    inv, beyond = int(rec.attrs.get("inverted_bricks_max", 0)), float(rec.attrs.get("max_beyond_wall_cm", np.nan))
    rows.append(Row(f"/{name}/: volume change, inverted bricks, beyond the wall", "<= 0.3 %, none, <= 0.01 cm "
                    "(goal)", f"{100 * m['max_volume_change']:.3f} %, {inv}, {beyond:.4f} cm",
                    verdict(m["max_volume_change"] <= MAX_VOLUME and inv == 0 and beyond <= MAX_BEYOND_CM,
                             "the tissue stays physical")))
    return rows
