"""The report's words section: each word of ``configs/words/`` spoken from text, every phone interval judged
(:mod:`artic_cli.speech.judge`), its durations, sound, TextGrid and spectrogram."""

from __future__ import annotations

import os
from pathlib import Path

from .rows import Row, verdict
from .speech import broken_limits

PHONES_GOAL, VOWELS_GOAL = 0.9, 0.9  # issue 46: shares of phone intervals passing, of vowels heard right


def word_section(data: Path, out_dir: Path | None = None) -> tuple[list[Row], list[str]]:
    from ..io.wav import read_wav
    from ..speech.inventory import load_inventory
    from ..speech.judge import devoiced_marked, phone_results
    from ..speech.measures import measures
    from ..speech.textgrid import read_phones
    from ..stages import speak as speak_stage

    out_dir = Path("reports") if out_dir is None else out_dir
    paths = sorted((data / "words").glob("*.h5"))
    if not paths:
        return [], []
    inv = load_inventory()
    manners = {k: p.manner for k, p in inv.phonemes.items()}
    lines = ["Each word is typed as text (`configs/words/`) and spoken by `artic speak` with nothing set per word: "
             "the front end makes its morae, devoiced vowels, N and Q, mora-timed durations and Tokyo pitch "
             "(`speech/text.py`), the planner times its gestures from the model's movement (`speech/timing.py`).  "
             "Every phone interval is judged: a consonant by its manner's landmark checks, a vowel by the nearest "
             "male Japanese mean (Bark), a devoiced vowel (u̥) by being voiced in under half of it.", ""]
    phones = passed = vowels = heard = 0
    limits: list[str] = []
    for path in paths:
        rec = speak_stage.read(path)
        wav, tg = path.with_suffix(".wav"), path.with_suffix(".TextGrid")
        y, rate = read_wav(wav)
        iv = devoiced_marked(read_phones(tg), rec.starts_s, rec.voiced, manners)
        res = phone_results(y, rate, iv, rec.time_s, rec.formants_hz, inv)
        v = [r for r in res if r["kind"] == "vowel"]
        phones, passed = phones + len(res), passed + sum(r["ok"] for r in res)
        vowels, heard = vowels + len(v), heard + sum(r["ok"] for r in v)
        morae = _tier_labels(tg, "morae")
        failing = "; ".join(f"{r['label']} at {r['start_s']:.2f} s: {', '.join(r['failed'])}" for r in res
                            if not r["ok"]) or "none"
        name = str(rec.attrs.get("name", path.stem))
        pic = out_dir / f"word_{path.stem}.png"
        links = f"[wav]({os.path.relpath(wav, out_dir)}), [TextGrid]({os.path.relpath(tg, out_dir)})" + (
            f", [spectrogram]({pic.name})" if pic.is_file() else "")
        durations = " ".join(f"{r['label']} {1e3 * (r['end_s'] - r['start_s']):.0f}" for r in res)
        lines.append(f"* **{name}** ({' '.join(morae)}; {1e3 * float(rec.attrs.get('duration_s', 0.0)):.0f} ms): "
                     f"phones passing {sum(r['ok'] for r in res)} of {len(res)}, vowels heard "
                     f"{sum(r['ok'] for r in v)} of {len(v)}; failing: {failing}; durations (ms): {durations}; {links}")
        broken = broken_limits(measures(rec, y, rate), rec)
        if broken:
            limits.append(f"{name} ({', '.join(broken)})")
    rows = [Row("Words from text: phone intervals passing their checks (issue 46)",
                f">= {100 * PHONES_GOAL:.0f} % (goal)", f"{passed} of {phones} ({100 * passed / max(phones, 1):.0f} %)",
                verdict(passed >= PHONES_GOAL * phones, f">= {100 * PHONES_GOAL:.0f} % of the phones")),
            Row("Words from text: vowels heard as intended", f">= {100 * VOWELS_GOAL:.0f} % (goal)",
                f"{heard} of {vowels} ({100 * heard / max(vowels, 1):.0f} %)",
                verdict(heard >= VOWELS_GOAL * vowels, f">= {100 * VOWELS_GOAL:.0f} % of the vowels")),
            Row("Words from text: peak speeds, volume, inversion, wall", "EMA + 50 %, <= 0.3 %, none, <= 0.01 cm "
                "(goal)", "broken in " + "; ".join(limits) if limits else "every word",
                verdict(not limits, "every word physical"))]
    return rows, lines + [""]


def _tier_labels(tg: Path, name: str) -> list[str]:
    from praatio import textgrid

    t = textgrid.openTextgrid(str(tg), includeEmptyIntervals=False)
    return [e.label for e in t.getTier(name).entries] if name in t.tierNames else []


__all__ = ["word_section"]
