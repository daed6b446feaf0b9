"""High-vowel devoicing (Tokyo Japanese): /i u/ lose their voice between two voiceless consonants (kita,
kutsu) and at a phrase's end after one (desu), keeping their tongue, lips and mora (japanese.md, "Devoicing").
Not twice in a row (the second of kikitai keeps its voice), not a long vowel, not the accented mora (its fall
would go unheard)."""

from __future__ import annotations

from .inventory import Inventory
from .romaji import Mora

HIGH = ("i", "u")


def _voiceless(sym: str, inv: Inventory) -> bool:
    p = inv.phonemes[sym]
    return p.manner not in ("vowel", "moraic_nasal", "geminate") and not p.voiced


def _starts_voiceless(morae: list[Mora], k: int, inv: Inventory) -> bool:
    """Whether the mora at ``k`` begins with a voiceless consonant (a geminate: the one it doubles)."""
    while k < len(morae) and morae[k].phones == ["Q"]:
        k += 1
    return k < len(morae) and bool(morae[k].phones) and _voiceless(morae[k].phones[0], inv)


def devoice(morae: list[Mora], accented: set[int], inv: Inventory) -> None:
    """Mark the devoiced morae of one phrase (``morae`` in order, across its words; ``accented``: the indices of
    accented morae), in place."""
    for k, m in enumerate(morae):
        if m.vowel not in HIGH or len(m.phones) != 2 or not _voiceless(m.phones[0], inv) or k in accented:
            continue
        if k > 0 and morae[k - 1].devoiced:
            continue
        after = morae[k + 1] if k + 1 < len(morae) else None
        if after is not None and not after.phones:
            continue  # a long vowel
        m.devoiced = after is None or _starts_voiceless(morae, k + 1, inv)


__all__ = ["devoice"]
