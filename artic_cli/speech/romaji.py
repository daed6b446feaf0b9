"""Typed Japanese -> words of morae of the inventory's symbols.

A text is Hepburn romaji (the common kunrei spellings si ti tu hu zi sya tya zya too), hiragana or katakana;
spaces part words, ``,`` is a pause; a long vowel is doubled (``oo``), ``ou`` or a macron (``ō``); ``n'``
parts a moraic nasal from a vowel or y after it (``hon'ya``); an apostrophe after any other mora marks the
accent (``ha'shi``: the pitch falls after ``ha``).  ``N`` (not starting a word) and ``Q`` may be written as
the moraic nasal and the geminate themselves.  Every error names the character and its position (1-based, in
the text as typed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import ArticError
from .kana import is_kana, kana_romaji

VOWELS = ("a", "i", "u", "e", "o")
MACRONS = {"ā": "aa", "ī": "ii", "ū": "uu", "ē": "ee", "ō": "oo", "â": "aa", "î": "ii", "û": "uu", "ê": "ee",
           "ô": "oo"}
# onsets, longest first; kunrei spellings read as their Hepburn ones
ONSETS = ("ch", "sh", "ts", "ky", "gy", "ny", "hy", "my", "ry", "py", "by", "sy", "ty", "zy", "jy", "dy", "cy",
          "k", "g", "s", "z", "t", "d", "n", "h", "b", "p", "m", "y", "r", "w", "f", "j")
KUNREI_ONSET = {"sy": "sh", "ty": "ch", "cy": "ch", "zy": "j", "jy": "j", "dy": "j"}
ALLOPHONE = {("s", "i"): "sh", ("t", "i"): "ch", ("t", "u"): "ts", ("h", "u"): "f", ("z", "i"): "j",
             ("d", "i"): "j", ("d", "u"): "z"}  # kunrei si ti tu hu zi (and di du) as spoken
LONG = {("a", "a"), ("i", "i"), ("u", "u"), ("e", "e"), ("o", "o"), ("o", "u")}  # a vowel lengthening the one before


@dataclass
class Mora:
    label: str  # in Hepburn romaji: 'ka', 'N', 'Q', 'o' (a long vowel's second mora)
    phones: list[str]  # the inventory's symbols; [] for a long vowel's second mora (the vowel lasts on)
    devoiced: bool = False  # its vowel voiceless (set by :func:`artic_cli.speech.frontend.devoice`)

    @property
    def vowel(self) -> str | None:
        return self.phones[-1] if self.phones and self.phones[-1] in VOWELS else None


@dataclass
class Word:
    text: str
    morae: list[Mora] = field(default_factory=list)
    accent: int | None = None  # the mora (1-based) the pitch falls after; None: unaccented


Char = tuple[str, int]  # a character of the normalised text and its position in the typed one (1-based)


def normalise(text: str) -> list[Char]:
    """The text as lower-case Hepburn letters, marks and separators, each with where it was typed: kana read
    (:func:`artic_cli.speech.kana.kana_romaji`), macrons doubled, ``N`` kept as the moraic nasal where it does
    not start a word, ``Q`` as the geminate."""
    out: list[Char] = []
    k = 0
    while k < len(text):
        ch = text[k]
        if is_kana(ch):
            j = k
            while j < len(text) and is_kana(text[j]):
                j += 1
            for n, r in enumerate(kana_romaji(list(text[k:j]))):
                if r is None:
                    raise ArticError(f"--text: '{text[k + n]}' at position {k + n + 1} is not a kana this front end "
                                     "reads (give romaji for it)")
                out += [(c, k + n + 1) for c in r]
            k = j
            continue
        starts_word = not out or out[-1][0] in " ,"
        if ch in MACRONS:
            out += [(c, k + 1) for c in MACRONS[ch]]
        elif ch == "N" and not starts_word:
            out.append(("N", k + 1))
        elif ch == "Q":
            out.append(("Q", k + 1))
        elif ch.isspace():
            out.append((" ", k + 1))
        else:
            out.append((ch.lower() if ch.isascii() else ch, k + 1))
        k += 1
    return out


LETTERS = set("".join(ONSETS) + "".join(VOWELS) + "NQ'")


def _unknown(ch: Char) -> ArticError:
    return ArticError(f"--text: '{ch[0]}' at position {ch[1]} is not romaji, kana or a mark (give Hepburn romaji "
                      "such as 'konnichiwa', kana, ' after an accented mora, ',' for a pause)")


def _misplaced(ch: Char, why: str) -> ArticError:
    return ArticError(f"--text: '{ch[0]}' at position {ch[1]} {why}")


def syllabify(chars: list[Char], text: str) -> Word:
    """One word's characters as its morae and accent."""
    w = Word(text)
    k, n = 0, len(chars)
    at = lambda j: chars[j][0] if j < n else ""  # noqa: E731
    while k < n:
        c, nxt = at(k), at(k + 1)
        if c == "'":
            if not w.morae:
                raise _misplaced(chars[k], "is an accent mark on no mora (put it after the accented mora: ha'shi)")
            if w.accent is not None:
                raise _misplaced(chars[k], f"is a second accent mark in '{text}' (a word has one accented mora)")
            w.accent = len(w.morae)
            k += 1
        elif c in ("N", "Q"):
            w.morae.append(Mora(c, [c]))
            k += 1
        elif c in VOWELS:
            prev = w.morae[-1].vowel if w.morae else None
            if prev is not None and (prev, c) in LONG:
                w.morae.append(Mora(c, []))
            else:
                w.morae.append(Mora(c, [c]))
            k += 1
        elif c == "n" and nxt not in VOWELS and nxt != "y":
            w.morae.append(Mora("N", ["N"]))
            k += 2 if nxt == "'" else 1  # n' parts the nasal from what follows
        elif c == "m" and nxt in ("p", "b", "m"):
            w.morae.append(Mora("N", ["N"]))  # Hepburn's m for the moraic nasal before a labial (tempura)
            k += 1
        elif c.isalpha() and c.isascii() and c not in VOWELS and (nxt == c or (c in "tc" and at(k + 1) + at(k + 2) == "ch")):
            w.morae.append(Mora("Q", ["Q"]))  # a doubled consonant (kitte, gakkou; matcha, maccha)
            k += 1
        else:
            onset = next((o for o in ONSETS if "".join(at(k + j) for j in range(len(o))) == o), None)
            if onset is None:
                raise _unknown(chars[k])
            typed = len(onset)
            v = at(k + typed)
            if v not in VOWELS:
                if v and v not in LETTERS:
                    raise _unknown(chars[k + typed])
                raise _misplaced(chars[k], f"starts '{onset}' with no vowel after it (a consonant needs one: "
                                 f"'{onset}a', or double it for a geminate)")
            onset = ALLOPHONE.get((KUNREI_ONSET.get(onset, onset), v), KUNREI_ONSET.get(onset, onset))
            if onset == "w" and v != "a":
                w.morae.append(Mora(v, [v]))  # wo (the particle), wi, we: their vowel
            else:
                w.morae.append(Mora(onset + v, [onset, v]))
            k += typed + 1
    return w


def words(text: str) -> list[Word | None]:
    """The text's words in order, None for each pause (``,``)."""
    chars = normalise(text)
    out: list[Word | None] = []
    run: list[Char] = []

    def flush():
        if run:
            out.append(syllabify(run, text[run[0][1] - 1:run[-1][1]]))
            run.clear()
    for ch in chars:
        if ch[0] == " ":
            flush()
        elif ch[0] in ",、，":
            flush()
            out.append(None)
        else:
            run.append(ch)
    flush()
    return out


__all__ = ["Mora", "Word", "normalise", "syllabify", "words", "VOWELS"]
