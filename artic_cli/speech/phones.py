"""Phonemes made articulation: each ``{phoneme: X}`` segment of an utterance becomes the segments and tract
controls its inventory entry asks for (docs/inventory.md, "From a phoneme to a target").

* A vowel is a formant target at its jaw position with its lips.
* A consonant made by the tongue is a constriction target at its place (closure: 0 cm^2; a channel: its
  ``channel_cm2``) at its place's jaw position (the inventory's ``jaws``), its lips those of the vowel that
  follows (lip shape anticipates the vowel) unless it names its own.
* A bilabial or glottal consonant leaves the tongue to its neighbours (``hold``: the previous segment's
  forces); the lips close (a tract entry) or the glottis opens.
* A glide is a narrowing at its place; one ``like`` a vowel keeps that vowel's tip and dorsum as indecisive
  points.
* An affricate is a closure (at its ``closure_place`` if it names one) then a channel, a palatalized consonant
  its consonant then the palatal glide, a geminate the next consonant held a mora longer, the moraic nasal a
  closure at the next stop's, nasal's or affricate's place (else a nasalised vowel): each part a segment of its own, the later parts ``continues`` (one
  TextGrid interval per phoneme).
* A nasal opens the velum port ``nasal_margin_ms`` before it and closes it as long after it; a voiceless
  phoneme abducts the glottis (its ``glottis_cm2`` or the config's voiceless opening).
"""

from __future__ import annotations

from typing import Callable

from ..control.solver import LIP_SHAPES, parse_target
from ..errors import ArticError
from ..schedule import TractEntry
from .inventory import Inventory, Phoneme
from .utterance import Segment, Utterance

TONGUELESS = ("bilabial", "glottal")  # places the tongue does not make
TongueOf = Callable[[str], dict[str, list[float]]]  # a vowel's symbol -> {"tip": [x, y], "dorsum": [x, y]} (cm)


def _lips(p: Phoneme):
    """The inventory's lips as a target's ``lips`` (a name, a tube, or None for neutral / closed)."""
    return None if p.lips in ("neutral", "closed") else p.lips


def openness(jaw) -> float:
    """How open a jaw given by forces is (N: JO minus JC)."""
    f = jaw.forces_n or {}
    return float(f.get("JO", 0.0)) - float(f.get("JC", 0.0))


def vowel_jaw(p: Phoneme, beside: list[Phoneme], inv: Inventory):
    """A vowel's jaw: its own, or no more open than ``vowel_jaw_beside`` allows next to a consonant's place
    (the jaw raised for a vowel beside /t s/: Keating, Lindblom, Lubker & Gay 1994)."""
    jaw = p.jaw
    for c in beside:
        cap = inv.vowel_jaw_beside.get(c.place) if c is not None else None
        if cap is not None and jaw.forces_n is not None and openness(cap) < openness(jaw):
            jaw = cap
    return jaw


def vowel_target(sym: str, p: Phoneme, inv: Inventory, beside: list[Phoneme] = ()) -> dict:
    jaw = vowel_jaw(p, list(beside), inv)
    name = f"{sym}_vowel" if jaw == p.jaw else f"{sym}_vowel_jaw_{openness(jaw):g}".replace(".", "p").replace("-", "m")
    return {"name": name, "jaw": jaw.model_dump(exclude_none=True),
            "acoustic": {"formants_hz": list(p.formants_hz), "tolerance_pct": list(inv.realisation.vowel_tolerance_pct)},
            "tongue_highest": {"tongue": p.tongue_highest, "margin_cm": inv.realisation.tongue_margin_cm},
            **({"lips": _dump(_lips(p))} if _lips(p) is not None else {})}


def _dump(lips):
    return lips if isinstance(lips, str) else lips.model_dump()


def constriction_target(sym: str, p: Phoneme, inv: Inventory, area_cm2: float, lips, part: str = "") -> dict:
    """A constriction target at the phoneme's place (the tract's place the inventory maps it to)."""
    jaw = p.jaw if p.jaw is not None else inv.jaws.get(p.place)
    if jaw is None:
        raise ArticError(f"inventory: phonemes.{sym}: no jaw for place '{p.place}'; give it 'jaw' or add "
                         f"jaws.{p.place}")
    tol = inv.realisation.closure_tolerance_cm2 if area_cm2 == 0 else max(inv.realisation.channel_tolerance * area_cm2, 0.01)
    t = {"name": f"{sym}{part}_{p.place}_{area_cm2:g}".replace(".", "p"), "jaw": jaw.model_dump(exclude_none=True),
         "constriction": {"place": inv.places[p.place], "area_cm2": float(area_cm2), "tolerance_cm2": round(tol, 6)}}
    if lips is not None:
        t["lips"] = _dump(lips)
    return t


def _next_vowel(symbols: list[str], k: int, inv: Inventory) -> Phoneme | None:
    for s in symbols[k + 1:]:
        if s is not None and inv.phonemes[s].manner == "vowel":
            return inv.phonemes[s]
    return None


def _next_consonant(symbols: list[str], k: int, inv: Inventory) -> str | None:
    s = symbols[k + 1] if k + 1 < len(symbols) else None
    return s if s is not None and inv.phonemes[s].manner not in ("vowel", "geminate", "moraic_nasal") else None


def glide_target(sym: str, g: Phoneme, inv: Inventory, lips, tongue_of: TongueOf | None = None) -> dict:
    """A glide's narrowing at its place; one ``like`` a vowel keeps the tip and dorsum where that vowel has them
    as far as the narrowing lets it (indecisive points: [j] is /i/'s tongue narrowed, not any tongue that
    narrows the palate), when ``tongue_of`` tells where."""
    t = constriction_target(sym, g, inv, g.channel_cm2, lips)
    if g.like is not None and tongue_of is not None:
        t["indecisive"] = [{"point": k, "at_cm": [round(float(c), 4) for c in xy]}
                           for k, xy in tongue_of(g.like).items()]
    return t


def _parts(sym: str, p: Phoneme, inv: Inventory, lips, beside=(), tongue_of: TongueOf | None = None
           ) -> list[tuple[dict | None, float, bool]]:
    """(target or None (hold the tongue), share of the duration, whether it is a glide) of each part of a phoneme
    (``beside``: a vowel's neighbouring consonants)."""
    if p.manner == "vowel":
        return [(vowel_target(sym, p, inv, beside), 1.0, False)]
    if p.place is None:  # the moraic nasal as a nasalised vowel: the tongue of the segment before
        return [(None, 1.0, False)]
    if p.place in TONGUELESS:
        if p.palatalized:  # the tongue body takes the palatal glide's place during the lips' or glottis' gesture
            return [(glide_target(f"{sym}_y", _colouring(inv), inv, lips), 1.0, True)]
        return [(None, 1.0, False)]
    if p.manner == "approximant":
        return [(glide_target(sym, p, inv, lips, tongue_of), 1.0, True)]
    closure = p.manner in ("stop", "nasal", "tap", "affricate")
    shut = p.model_copy(update={"place": p.closure_place}) if p.closure_place is not None else p
    first = constriction_target(sym, shut, inv, 0.0 if closure else p.channel_cm2, lips)
    out = [(first, 1.0, False)]
    if p.manner == "affricate":
        share = inv.realisation.affricate_closure_share
        out = [(first, share, False),
               (constriction_target(sym, p, inv, p.channel_cm2, lips, "_release"), 1 - share, False)]
    if p.palatalized:
        share = inv.realisation.palatal_glide_share
        out = [(t, s * (1 - share), g) for t, s, g in out] + [
            (glide_target(f"{sym}_y", _colouring(inv), inv, lips), share, True)]
    return out


def _neighbour(symbols: list[str], k: int, step: int, inv: Inventory) -> Phoneme | None:
    """The consonant right before (``step`` -1) or after (+1) position ``k``, as it is made (N and Q stand in)."""
    j = k + step
    if not 0 <= j < len(symbols) or symbols[j] is None:
        return None
    p = inv.phonemes[symbols[j]]
    if symbols[j] in ("N", "Q"):
        try:
            p = _stand_in(symbols, j, inv)
        except ArticError:
            return None
    return None if p.manner == "vowel" else p


def _stand_in(symbols: list[str], k: int, inv: Inventory) -> Phoneme:
    """What the moraic nasal or the geminate at ``k`` is made as: N a nasal at the next consonant's place (m
    before p b m, n before t d n, velar before k g), a nasalised vowel (no place: the tongue held) before a
    vowel, glide, fricative or nothing; Q the next consonant itself."""
    nxt = _next_consonant(symbols, k, inv)
    if symbols[k] == "Q":
        if nxt is None:
            raise ArticError(f"segments[{k}]: the geminate Q needs a consonant after it (e.g. 'aQta')")
        return inv.phonemes[nxt]
    after = inv.phonemes[nxt] if nxt is not None else None
    if after is None or after.place == "glottal" or after.manner in ("fricative", "approximant"):
        # a nasalised vowel before a vowel, glide, fricative or pause: the tongue stays, the port opens
        return inv.phonemes["n"].model_copy(update={"place": None, "lips": "neutral"})
    n = inv.phonemes["m" if after.place == "bilabial" else "n"]
    return n if n.place == after.place else n.model_copy(update={"place": after.place, "lips": "neutral"})


def realise(u: Utterance, inv: Inventory, default_lips: tuple[float, float], tongue_of: TongueOf | None = None
            ) -> Utterance:
    """The utterance with every ``phoneme`` segment made into target and hold segments and tract entries
    (``default_lips``: the config's lip tube, area cm^2 and length cm, for neutral lips; ``tongue_of``: where a
    vowel puts the tip and dorsum, for the glides like it)."""
    if not any(s.phoneme is not None for s in u.segments):
        return u
    symbols = [s.phoneme for s in u.segments]
    for k, s in enumerate(symbols):
        if s is not None and s not in inv.phonemes:
            raise ArticError(f"segments[{k}].phoneme: '{s}' is not in the inventory; symbols: "
                             f"{' '.join(inv.phonemes)}")
    segments, tract, t = [], list(u.tract), 0.0
    nasal_runs = []
    for k, seg in enumerate(u.segments):
        if seg.phoneme is None:
            segments.append(seg)
            t += seg.duration_ms
            continue
        sym = seg.phoneme
        p = _stand_in(symbols, k, inv) if sym in ("N", "Q") else inv.phonemes[sym]
        nv = _next_vowel(symbols, k, inv)
        lips = _lips(p) if p.lips != "neutral" else (_lips(nv) if nv is not None else None)
        voiced = (p.voiced if sym != "N" else True) and not seg.devoiced
        glottis = p.glottis_cm2
        closing = voiced and p.manner in ("stop", "affricate", "tap") and p.velum_port_cm2 == 0 and sym not in ("N", "Q")
        expand = inv.realisation.voiced_stop_expansion_cm3_s if closing else None
        beside = [_neighbour(symbols, k, d, inv) for d in (-1, 1)] if p.manner == "vowel" else []
        for n, (target, share, glide) in enumerate(_parts(sym, p, inv, lips, beside, tongue_of)):
            common = dict(duration_ms=seg.duration_ms * share, voiced=voiced, glottis_cm2=glottis,
                          label=sym if n == 0 else None, continues=n > 0, cavity_expansion_cm3_s=expand)
            if glide:  # a glide undershoots in a short interval: the timing does not press it
                common["press"] = 1.0
            segments.append(Segment(target=target, **common) if target is not None else Segment(hold=True, **common))
        if p.lips == "closed" or (p.place == "bilabial" and p.manner == "fricative"):
            area = 0.0 if p.lips == "closed" else p.channel_cm2
            tract.append(TractEntry(at_ms=max(t - inv.realisation.lip_closing_ms, 0.0), ramp_ms=inv.realisation.lip_closing_ms,
                                    lip_area_cm2=area))
            # ... and stay so at its start, whatever lips a tongue target of its own (/py/'s glide) brings
            tract.append(TractEntry(at_ms=t, ramp_ms=0.0, lip_area_cm2=area))
            after = _lips(nv) if nv is not None else None
            tube = _tube(after, default_lips)
            if t + seg.duration_ms < u.duration_ms:
                tract.append(TractEntry(at_ms=t + seg.duration_ms, ramp_ms=inv.realisation.lip_opening_ms,
                                        lip_area_cm2=tube[0], lip_length_cm=tube[1]))
        if p.velum_port_cm2 > 0:
            nasal_runs.append((t, t + seg.duration_ms, p.velum_port_cm2))
        t += seg.duration_ms
    tract += _port_entries(nasal_runs, inv.realisation.nasal_margin_ms, u.duration_ms)
    return u.model_copy(update={"segments": segments, "tract": tract})


def vowel_tongues(inv: Inventory, solve, max_force_n: float) -> TongueOf:
    """Where each vowel's solved target puts the tip and dorsum (cm; the refinement's simulated points, else the
    maps' prediction), each vowel solved once by ``solve`` (targets -> answers with their documents)."""
    known: dict[str, dict[str, list[float]]] = {}

    def tongue_of(v: str) -> dict[str, list[float]]:
        if v not in known:
            t = parse_target(vowel_target(v, inv.phonemes[v], inv), f"inventory: phonemes.{v}", max_force_n)
            doc = solve([t])[0].doc or {}
            points = (doc.get("refined") or {}).get("reached_cm") or (doc.get("chosen") or {}).get("predicted_cm") or {}
            known[v] = {k: [float(c) for c in xy] for k, xy in points.items() if k in ("tip", "dorsum")}
        return known[v]
    return tongue_of


def _colouring(inv: Inventory) -> Phoneme:
    """A palatalized consonant's glide: /y/'s place at the wider ``palatal_glide_cm2``, no vowel's tongue (a
    secondary articulation in a short part)."""
    return inv.phonemes["y"].model_copy(update={"channel_cm2": inv.realisation.palatal_glide_cm2, "like": None})


def _tube(lips, default_lips: tuple[float, float]) -> tuple[float, float]:
    shape = LIP_SHAPES.get(lips) if isinstance(lips, str) else lips
    return default_lips if shape is None else (float(shape.area_cm2), float(shape.length_cm))


def _port_entries(runs: list[tuple[float, float, float]], margin_ms: float, total_ms: float) -> list[TractEntry]:
    """The port opening ``margin_ms`` before each nasal run (adjacent nasals joined) and closing over as long
    after it: open at the nasal's start, shut ``margin_ms`` after its end."""
    joined: list[list[float]] = []
    for a, b, area in runs:
        if joined and abs(joined[-1][1] - a) < 1e-9:
            joined[-1][1], joined[-1][2] = b, max(joined[-1][2], area)
        else:
            joined.append([a, b, area])
    out = []
    for a, b, area in joined:
        start = max(a - margin_ms, 0.0)
        out.append(TractEntry(at_ms=start, ramp_ms=a - start, velum_port_cm2=area))
        if b < total_ms:
            out.append(TractEntry(at_ms=b, ramp_ms=margin_ms, velum_port_cm2=0.0))
    return out


__all__ = ["TongueOf", "constriction_target", "glide_target", "realise", "vowel_target"]
