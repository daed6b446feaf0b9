"""Hiragana and katakana as Hepburn romaji: each kana its mora, a small ya/yu/yo joined to the kana before it
(きゃ kya, しゃ sha), the small tsu the geminate ``Q``, ん the moraic nasal ``N``, the long mark ー the vowel
before it again; katakana read as the hiragana it shares a sound with."""

from __future__ import annotations

ROWS = {  # a row's consonant -> its kana for a, i, u, e, o ("" where the row has none)
    "": "あいうえお", "k": "かきくけこ", "g": "がぎぐげご", "s": "さしすせそ", "z": "ざじずぜぞ",
    "t": "たちつてと", "d": "だぢづでど", "n": "なにぬねの", "h": "はひふへほ", "b": "ばびぶべぼ",
    "p": "ぱぴぷぺぽ", "m": "まみむめも", "y": "や\0ゆ\0よ", "r": "らりるれろ", "w": "わゐ\0ゑを"}
IRREGULAR = {"si": "shi", "zi": "ji", "ti": "chi", "tu": "tsu", "di": "ji", "du": "zu", "hu": "fu", "wi": "i",
             "we": "e", "wo": "o"}
SMALL_Y = {"ゃ": "a", "ゅ": "u", "ょ": "o"}
SMALL_VOWEL = {"ぁ": "a", "ぃ": "i", "ぅ": "u", "ぇ": "e", "ぉ": "o"}  # only after ふ: fa fi fe fo
PALATAL = {"shi": "sh", "chi": "ch", "ji": "j"}  # an i-row kana whose consonant a small ya/yu/yo keeps


def _table() -> dict[str, str]:
    out = {}
    for c, row in ROWS.items():
        for v, k in zip("aiueo", row):
            if k != "\0":
                out[k] = IRREGULAR.get(c + v, c + v)
    out.update({"ん": "N", "っ": "Q", "ゔ": "bu"})
    return out


KANA = _table()


def is_kana(ch: str) -> bool:
    return "\u3041" <= ch <= "\u309f" or "\u30a0" <= ch <= "\u30ff"


def hiragana(ch: str) -> str:
    """A katakana as the hiragana of the same sound (others unchanged)."""
    return chr(ord(ch) - 0x60) if "\u30a1" <= ch <= "\u30f6" else ch


def kana_romaji(kana: list[str]) -> list[str | None]:
    """Romaji for a run of kana, one string per kana (``""`` for a small kana joined to the one before it, None
    for one that is not read here)."""
    out: list[str | None] = []
    for ch in map(hiragana, kana):
        prev = out[-1] if out else None
        last = next((r for r in reversed(out) if r), None)  # the sound a long mark lengthens
        if ch in SMALL_Y and prev and prev.endswith("i") and prev != "i":
            base = PALATAL.get(prev, prev[:-1] + "y")
            out[-1] = base + SMALL_Y[ch]
            out.append("")
        elif ch in SMALL_VOWEL and prev == "fu":
            out[-1] = "f" + SMALL_VOWEL[ch]
            out.append("")
        elif ch == "ー" and last and last[-1] in "aiueo":
            out.append(last[-1])
        else:
            out.append(KANA.get(ch))
    return out


__all__ = ["KANA", "is_kana", "kana_romaji"]
