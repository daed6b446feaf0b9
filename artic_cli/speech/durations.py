"""Mora-timed durations (docs/inventory.md, "Words"): each mora about ``timing.mora_ms`` at rate 1, its
segments stretching and shrinking to keep it (Port, Dalby & O'Dell 1987):

* a CV mora's consonant lasts its inventory duration, its vowel the rest of the mora (at least
  ``vowel_min_share`` of it); a fricative or affricate before its devoiced vowel about a mora
  (``devoiced_fricative_share``; Han 1994);
* a V, N or long-vowel mora lasts a mora; Q's closure makes the consonant after it ``geminate_ratio`` times
  a single one's (Han 1992);
* a vowel before Q or N lengthens by ``before_coda``, the coda shortened as much (Han 1994);
* the phrase's last mora lengthens by ``final_lengthening``; a pause lasts ``pause_ms``;
* everything divided by the rate.
"""

from __future__ import annotations

from .inventory import Inventory
from .romaji import Mora

FRICATIVE_LIKE = ("fricative", "affricate")


def mora_phones_ms(phrase: list[Mora], inv: Inventory, rate: float = 1.0) -> list[list[float]]:
    """Each mora's phones' durations (ms); a long vowel's second mora: [its length], added to the vowel before."""
    t = inv.timing
    mora = t.mora_ms / rate
    own = lambda sym: inv.phonemes[sym].duration_ms / rate  # noqa: E731
    out: list[list[float]] = []
    for k, m in enumerate(phrase):
        nxt = phrase[k + 1] if k + 1 < len(phrase) else None
        if m.phones == ["Q"]:
            c = next((x.phones[0] for x in phrase[k + 1:] if x.phones and x.phones != ["Q"]), None)
            out.append([(t.geminate_ratio - 1.0) * own(c) if c not in (None, "N") else mora])
        elif len(m.phones) == 2:
            c = own(m.phones[0])
            if m.devoiced and inv.phonemes[m.phones[0]].manner in FRICATIVE_LIKE:
                c = max(c, t.devoiced_fricative_share * mora)
            out.append([c, max(mora - c, t.vowel_min_share * mora)])
        else:
            out.append([mora])  # V, N, a long vowel's second mora
        if nxt is not None and nxt.phones in (["Q"], ["N"]) and m.vowel is not None:
            out[-1][-1] *= t.before_coda
    for k in range(1, len(phrase)):  # the coda gives back what the vowel before it gained (keeping half its own)
        if phrase[k].phones in (["Q"], ["N"]) and phrase[k - 1].vowel is not None:
            v = out[k - 1][-1]
            out[k][0] = max(out[k][0] - (v - v / t.before_coda), 0.5 * out[k][0])
    if phrase:
        out[-1][-1] *= t.final_lengthening
    return out


__all__ = ["mora_phones_ms"]
