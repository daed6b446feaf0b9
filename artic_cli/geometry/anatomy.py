"""The whole articulator body: tongue mesh, jaw, hyoid, skull points and muscle routing.

Node numbering: the 231 tongue nodes first (banded), then the bone nodes
(mandible and hyoid, the "border" of the linear system), then the skull
points muscles pull from (fixed).  All of it is geometry and topology; the
forces live in :mod:`artic_cli.mechanics`.

Mandible (paper Fig. 2f): four nodes a side (condyle, coronoid, gonion,
symphysis) joined by five stiff links, two triangles (condyle-coronoid-gonion,
coronoid-gonion-symphysis) sharing the shearing link coronoid-gonion; the two
sides are tied by cross links so that the jaw is rigid in 3D.  Carried by
the mandible (each a fixed affine combination of four mandible nodes, so it
moves rigidly with them and has no degrees of freedom of its own): the lower
incisor point (the jaw control point), the geniohyoid origin, the mylohyoid
line, the digastric fossae and the tongue's innermost concentric line (the
genioglossus tendon at the genial tubercles).  Hyoid: body (two nodes) and two greater horns, braced.  The
tongue floor line rests on the hyoid and mandible through soft links.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config import Config, Muscles
from ..errors import ArticError
from .mesh import Mesh, tongue_node_index, tongue_mesh

LINK_KINDS = ("mandible", "hyoid", "floor", "strap", "sling")  # sling: the floor hung from the mylohyoid lines
TONGUE_MUSCLES = ("GGa", "GGm", "GGp", "HG", "SG", "SL", "IL", "T", "V", "GH", "MH")
JAW_MUSCLES = ("temporalis_anterior", "temporalis_posterior", "masseter", "medial_pterygoid",
               "lateral_pterygoid_upper", "lateral_pterygoid_lower", "anterior_digastric", "posterior_digastric")


def check_muscle_names(names, valid, key: str, what: str = "muscle") -> None:
    """One ArticError naming the first of ``names`` not in ``valid``, the config key it sits under, and the
    valid names."""
    for name in names:
        if name not in valid:
            raise ArticError(f"config: {key} names unknown {what} '{name}'; valid: {', '.join(valid)}")


@dataclass(frozen=True)
class Body:
    mesh: Mesh  # the tongue (nodes 0 .. n_tongue-1)
    nodes: np.ndarray  # (N,3) every node, cm
    names: dict[str, int]  # named points (bilateral ones end in _l / _r)
    links: np.ndarray  # (L,2) passive links
    link_kind: np.ndarray  # (L,) index into LINK_KINDS
    fibres: dict[str, list[np.ndarray]]  # muscle -> fibres (node chains, origin first)
    fibre_weight: dict[str, np.ndarray]  # muscle -> share of the muscle's force per fibre
    fixed: np.ndarray  # skull points (all dofs fixed)
    mandible: np.ndarray  # nodes moving with the mandible (incl. carried points)
    carried: np.ndarray  # points fixed to the mandible (incisor, muscle origins, the tongue's GG origin line)
    carrier: np.ndarray  # (4,) mandible nodes whose rigid motion carries them
    hyoid: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_tongue(self) -> int:
        return len(self.mesh.nodes)


class _Builder:
    def __init__(self, mesh: Mesh):
        self.points = [p for p in mesh.nodes]
        self.names: dict[str, int] = {}

    def add(self, name: str, xyz) -> int:
        self.points.append(np.asarray(xyz, dtype=float))
        self.names[name] = len(self.points) - 1
        return self.names[name]

    def bilateral(self, name: str, xyz) -> tuple[int, int]:
        x, y, z = xyz
        return self.add(f"{name}_l", (x, y, abs(z))), self.add(f"{name}_r", (x, y, -abs(z)))


def _landmark(cfg: Config, key: str):
    try:
        return cfg.speaker.landmarks_cm[key]
    except KeyError:
        raise ArticError(f"config: speaker.landmarks_cm lacks '{key}'; add it (x, y, z in cm)") from None


def _straight_route(nodes: np.ndarray, lines: list[list[int]], start_level: int) -> list[int]:
    """A fibre from ``lines[-1][start_level]`` to the tip (``lines[0][-1]``, the first radial line's surface
    node) through, on each radial line in between, the node nearest the straight segment joining them."""
    a, b = nodes[lines[-1][start_level]], nodes[lines[0][-1]]
    d = (b - a) / np.linalg.norm(b - a)
    off = lambda i: float(np.linalg.norm(np.cross(nodes[i] - a, d)))  # noqa: E731
    return [lines[-1][start_level], *(min(line, key=off) for line in lines[-2:0:-1]), lines[0][-1]]


def build_body(cfg: Config, mesh: Mesh | None = None, *, digastric_through_sling: bool = False,
               digastric_sling: str = "fixed",
               verticalis_sections: int = 4, verticalis_to_level: int = 3, il_midsagittal: bool = False,
               il_route=None, gg_tendon: str = "all",
               floor_on_mylohyoid: bool = False, sg_routes=None) -> Body:
    """The articulator's nodes, links and muscle routes, in named steps: the mandible and the points it
    carries, the hyoid, the tongue's floor, the skull's fixed points and straps, then the muscles' fibres.

    ``digastric_through_sling``: the anterior digastric's fibre goes on from the sling to the mastoid (a segment
    that adds its length to the fibre's); ``digastric_sling``: ``"fixed"``, the sling a skull point at the hyoid
    body's rest end, or ``"hyoid"``, the hyoid body's own end node; ``verticalis_sections``: the verticalis spans
    this many radial sections from the tip, from the surface down to concentric level ``verticalis_to_level``;
    ``il_midsagittal``: IL has a fibre in the midsagittal plane as well; ``il_route``: IL's path
    (``muscles.inferior_longitudinalis``; None: that key's default); ``gg_tendon``: the mandible carries the
    tongue's GG tendon line in ``"all"`` three planes or the ``"midsagittal"`` one;
    ``floor_on_mylohyoid``: the floor nodes are also linked to their two nearest mylohyoid points;
    ``sg_routes``: SG's fibres per side (``muscles.styloglossus`` items; None: that key's default)."""
    mesh = mesh if mesh is not None else tongue_mesh(cfg.speaker.tongue)
    sg_routes = Muscles().styloglossus if sg_routes is None else sg_routes
    il_route = Muscles().inferior_longitudinalis if il_route is None else il_route
    _check_routes(mesh, il_route, sg_routes, verticalis_sections, verticalis_to_level)
    b = _Builder(mesh)
    lm = lambda key: _landmark(cfg, key)  # noqa: E731
    links = _Links()
    jaw = _mandible(b, lm, links)
    anchor = mesh.node_sets["anchor"]
    if gg_tendon == "midsagittal":  # the genial tubercle is in the midline; the lateral tendon nodes are tissue
        anchor = np.intersect1d(anchor, mesh.node_sets["midsagittal"])
    hy = _hyoid(b, lm, links)
    _floor(b, mesh, links, hy, jaw, floor_on_mylohyoid)
    skull = _skull(b, lm, links, hy, digastric_sling)
    fib: dict[str, list[np.ndarray]] = {m: [] for m in TONGUE_MUSCLES + JAW_MUSCLES}
    _tongue_fibres(fib, mesh, hy, skull, sg_routes, il_route, il_midsagittal, verticalis_sections,
                   verticalis_to_level)
    _jaw_and_floor_fibres(fib, mesh, jaw, hy, skull, digastric_through_sling)
    nodes = np.array(b.points)
    weights = _fibre_weights(nodes, fib)
    carried = [jaw["incisor"], jaw["gh_origin"], *jaw["mylohyoid_front"], *jaw["mylohyoid_back"],
               *jaw["mylohyoid_mid"], *jaw["digastric_fossa"]]
    mandible = np.array(sorted({*[i for p in BONE_PARTS for i in jaw[p]], *carried}))
    frame = [jaw["symphysis"][0], jaw["symphysis"][1], jaw["coronoid"][0], jaw["gonion"][1]]
    sets = dict(mesh.node_sets)
    sets["jaw"] = np.array([jaw["incisor"]])
    sets["mandible"] = mandible
    sets["hyoid"] = hy["all"]
    return Body(mesh=mesh, nodes=nodes, names=b.names, links=np.array(links.pairs, dtype=np.int64),
                link_kind=np.array(links.kinds), fibres=fib, fibre_weight=weights, fixed=np.array(skull["fixed"]),
                mandible=mandible, carried=np.array([*carried, *anchor], dtype=np.int64),
                carrier=np.array(frame, dtype=np.int64), hyoid=hy["all"], node_sets=sets)


BONE_PARTS = ("condyle", "coronoid", "gonion", "symphysis")  # the mandible's frame nodes, a pair each


class _Links:
    """The passive links in the order they are made, with their kinds (an index of LINK_KINDS)."""

    def __init__(self):
        self.pairs: list[tuple[int, int]] = []
        self.kinds: list[int] = []

    def __call__(self, a: int, c: int, kind: str) -> None:
        self.pairs.append((a, c))
        self.kinds.append(LINK_KINDS.index(kind))


def _check_routes(mesh: Mesh, il_route, sg_routes, verticalis_sections: int, verticalis_to_level: int) -> None:
    """One-line errors for muscle routes that leave the tongue's grid."""
    nr, nc, _ = mesh.grid
    (il_k, _), il_level = il_route.start, il_route.level
    if il_k > nr - 1 or il_level > nc - 2:
        raise ArticError(f"config: muscles.inferior_longitudinalis leaves the tongue (start radial {il_k}, level "
                         f"{il_level}); radials run 1-{nr - 1} and levels 0-{nc - 2}")
    for i, route in enumerate(sg_routes):
        for name, (k, j) in (("entry", route.entry), ("radials", (route.radials[0], route.level)),
                             ("radials", (route.radials[1], route.level))):
            if k > nr - 1 or j > nc - 1:
                raise ArticError(f"config: muscles.styloglossus[{i}].{name} leaves the tongue (radial {k}, level {j}); "
                                 f"radials run 0-{nr - 1} and levels 0-{nc - 1}")
    if not 1 <= verticalis_sections <= nr - 1:
        raise ArticError(f"config: muscles.verticalis_sections is {verticalis_sections}; give 1 to {nr - 1} "
                         "(the tongue's radial sections)")
    if not 0 <= verticalis_to_level <= nc - 2:
        raise ArticError(f"config: muscles.verticalis_to_level is {verticalis_to_level}; give 0 to {nc - 2} "
                         "(0: the GG tendon; the fibre needs two levels)")


def _mandible(b: _Builder, lm, link: _Links) -> dict:
    """The mandible: 4 nodes a side, linked into one rigid bone, and the points it carries (no links: they
    move with the frame, see mechanics.model.Carried)."""
    jaw = {part: b.bilateral(part, lm(part)) for part in BONE_PARTS}
    jaw["incisor"] = b.add("lower_incisor", lm("lower_incisor"))
    jaw["gh_origin"] = b.add("gh_origin", lm("gh_origin"))
    jaw["mylohyoid_front"] = b.bilateral("mylohyoid_front", lm("mylohyoid_line_front"))
    jaw["mylohyoid_back"] = b.bilateral("mylohyoid_back", lm("mylohyoid_line_back"))
    mf, mb = np.asarray(lm("mylohyoid_line_front")), np.asarray(lm("mylohyoid_line_back"))
    jaw["mylohyoid_mid"] = b.bilateral("mylohyoid_mid", tuple(0.5 * (mf + mb)))
    jaw["digastric_fossa"] = b.bilateral("digastric_fossa", lm("digastric_fossa"))
    for s in (0, 1):
        c, r, g, y = (jaw[p][s] for p in BONE_PARTS)
        for a, d in ((c, r), (c, g), (r, g), (r, y), (g, y)):  # two triangles + shearing link
            link(a, d, "mandible")
    left, right = {p: jaw[p][0] for p in BONE_PARTS}, {p: jaw[p][1] for p in BONE_PARTS}
    for p in BONE_PARTS:  # cross links: the two halves form one rigid bone
        link(left[p], right[p], "mandible")
    for p, q in (("symphysis", "gonion"), ("symphysis", "condyle"), ("coronoid", "condyle"), ("gonion", "coronoid")):
        link(left[p], right[q], "mandible")
        link(right[p], left[q], "mandible")
    return jaw


def _hyoid(b: _Builder, lm, link: _Links) -> dict:
    """The hyoid: its body's ends and its horns' tips, braced."""
    body_l, body_r = b.bilateral("hyoid_body", lm("hyoid_body_end"))
    horn_l, horn_r = b.bilateral("hyoid_horn", lm("hyoid_horn_tip"))
    for a, d in ((body_l, body_r), (body_l, horn_l), (body_r, horn_r), (body_l, horn_r), (body_r, horn_l),
                 (horn_l, horn_r)):
        link(a, d, "hyoid")
    return {"body": (body_l, body_r), "horn": (horn_l, horn_r), "all": np.array([body_l, body_r, horn_l, horn_r])}


def _floor(b: _Builder, mesh: Mesh, link: _Links, hy: dict, jaw: dict, on_mylohyoid: bool) -> None:
    """The tongue's floor (its last radial line) on the hyoid and, optionally, the mylohyoid lines: soft links
    to the two nearest points of each."""
    nr, nc, planes = mesh.grid
    sling = np.array([*jaw["mylohyoid_front"], *jaw["mylohyoid_mid"], *jaw["mylohyoid_back"]])
    points = np.array(b.points)

    def nearest_two(targets, node):
        return targets[np.argsort(np.linalg.norm(points[targets] - points[node], axis=1))[:2]]

    for p in range(planes):
        for j in range(2, nc):
            node = int(tongue_node_index(nr - 1, j, p, nc - 1))
            for h in nearest_two(hy["all"], node):
                link(node, int(h), "floor")
            if on_mylohyoid:
                for h in nearest_two(sling, node):
                    link(node, int(h), "sling")


SKULL_POINTS = (("styloid", "styloid_tip"), ("mastoid", "mastoid_notch"),
                ("temporalis_anterior_origin", "temporalis_anterior_origin"),
                ("temporalis_posterior_origin", "temporalis_posterior_origin"), ("masseter_origin", "masseter_origin"),
                ("medial_pterygoid_origin", "medial_pterygoid_origin"),
                ("lateral_pterygoid_upper_origin", "lateral_pterygoid_upper_origin"),
                ("lateral_pterygoid_lower_origin", "lateral_pterygoid_lower_origin"))


def _skull(b: _Builder, lm, link: _Links, hy: dict, digastric_sling: str) -> dict:
    """The skull's fixed points (a pair each: the muscles' origins, the digastric's sling, sternum and thyroid)
    and the strap links from sternum and thyroid to the hyoid."""
    out: dict = {"fixed": []}

    def skull(name, key):
        ids = b.bilateral(name, lm(key))
        out["fixed"].extend(ids)
        return ids

    for name, key in SKULL_POINTS:
        out[name] = skull(name, key)
    if digastric_sling == "hyoid":  # the fibrous loop on the hyoid body: the digastric's tension lifts the hyoid
        out["digastric_sling"] = hy["body"]
    else:  # the digastric tendon's fixed pulley (paper III.A)
        out["digastric_sling"] = skull("digastric_sling", "hyoid_body_end")
    sternum, thyroid = skull("sternum", "sternum"), skull("thyroid", "thyroid")
    for s in (0, 1):
        link(sternum[s], hy["body"][s], "strap")
        link(thyroid[s], hy["horn"][s], "strap")
    return out


def _chain(pts) -> np.ndarray:
    return np.array(pts, dtype=np.int64)


def _tongue_fibres(fib: dict, mesh: Mesh, hy: dict, skull: dict, sg_routes, il_route, il_midsagittal: bool,
                   verticalis_sections: int, verticalis_to_level: int) -> None:
    """The tongue's muscles: GG in three parts along the midsagittal radial lines, HG and SG from the hyoid and
    the styloid, IL along the lower side, SL under the dorsum, T across, V down from the dorsum."""
    nr, nc, planes = mesh.grid
    t = lambda k, j, p: int(tongue_node_index(k, j, p, nc - 1))  # noqa: E731
    mid, sides = planes // 2, (planes - 1, 0)  # the left (+z) plane first, as bilateral() returns left, right
    radial = lambda k, p: _chain([t(k, j, p) for j in range(nc)])  # noqa: E731
    last = nr - 1
    for part, ks in (("GGa", range(0, 4)), ("GGm", range(4, 7)), ("GGp", range(7, last + 1))):
        fib[part] += [radial(k, mid) for k in ks]  # the front radial lines, the first one under the tip
    for s, p in enumerate(sides):
        for h in (hy["body"][s], hy["horn"][s]):
            for j in (3, 5):
                fib["HG"].append(_chain([h] + [t(k, j, p) for k in range(last, 6, -1)]))
        for route in sg_routes:
            (ke, je), (k0, k1) = route.entry, route.radials
            fib["SG"].append(_chain([skull["styloid"][s], t(ke, je, p)]
                                    + [t(k, route.level, p) for k in range(k0, k1 - 1, -1)]))
    (il_k, il_j), il_level = il_route.start, il_route.level
    # lower side, root to tip, in the parasagittal planes (between GG and HG) and optionally the midsagittal one
    for p in (*sides, mid) if il_midsagittal else sides:
        if il_route.path == "straight":
            fib["IL"].append(_chain(_straight_route(mesh.nodes, [[t(k, j, p) for j in range(nc)]
                                                                 for k in range(il_k + 1)], il_j)))
        else:
            fib["IL"].append(_chain([t(il_k, j, p) for j in range(il_j, il_level)] + [t(k, il_level, p) for k in range(
                il_k, 0, -1)] + [t(0, j, p) for j in range(il_level + 1, nc)]))
    down = lambda k, p: _chain([t(k, j, p) for j in range(nc - 1, verticalis_to_level - 1, -1)])  # noqa: E731
    for p in range(planes):
        fib["SL"].append(_chain([t(k, nc - 2, p) for k in range(8, 0, -1)] + [t(0, nc - 1, p)]))
        if p != mid:
            fib["V"] += [down(k, p) for k in range(verticalis_sections)]
    for k in range(2, 8):
        for j in (nc - 3, nc - 2):
            fib["T"].append(_chain([t(k, j, 0), t(k, j, mid), t(k, j, planes - 1)]))
    fib["V"] += [down(k, mid) for k in range(verticalis_sections)]  # front part of the tongue, dorsum into the blade


def _jaw_and_floor_fibres(fib: dict, mesh: Mesh, jaw: dict, hy: dict, skull: dict, through_sling: bool) -> None:
    """The floor of the mouth (MH, GH), the jaw's muscles and the digastric, a fibre a side each."""
    nr, nc, planes = mesh.grid
    t = lambda k, j, p: int(tongue_node_index(k, j, p, nc - 1))  # noqa: E731
    mid, last = planes // 2, nr - 1
    for s in (0, 1):
        body = hy["body"][s]
        fib["MH"] += [_chain([jaw["mylohyoid_front"][s], t(last, 1, mid)]),
                      _chain([jaw["mylohyoid_mid"][s], t(last, 3, mid)]),
                      _chain([jaw["mylohyoid_back"][s], t(last, 5, mid)]), _chain([jaw["mylohyoid_back"][s], body])]
        fib["GH"].append(_chain([jaw["gh_origin"], body]))
        for muscle, origin, insertion in (("temporalis_anterior", "temporalis_anterior_origin", "coronoid"),
                                          ("temporalis_posterior", "temporalis_posterior_origin", "coronoid"),
                                          ("masseter", "masseter_origin", "gonion"),
                                          ("medial_pterygoid", "medial_pterygoid_origin", "gonion"),
                                          ("lateral_pterygoid_upper", "lateral_pterygoid_upper_origin", "condyle"),
                                          ("lateral_pterygoid_lower", "lateral_pterygoid_lower_origin", "condyle")):
            fib[muscle].append(_chain([skull[origin][s], jaw[insertion][s]]))
        beyond = [skull["mastoid"][s]] if through_sling else []  # the segment on to the mastoid
        fib["anterior_digastric"].append(_chain([jaw["digastric_fossa"][s], skull["digastric_sling"][s], *beyond]))
        fib["posterior_digastric"].append(_chain([skull["mastoid"][s], body]))


def _fibre_weights(nodes: np.ndarray, fib: dict) -> dict:
    """Each muscle's force shared equally by its fibres; a fibre of zero length is an error."""
    weights = {}
    for m, fs in fib.items():
        lengths = np.array([np.linalg.norm(np.diff(nodes[f], axis=0), axis=1).sum() for f in fs])
        weights[m] = np.full(len(fs), 1.0 / len(fs))
        if not np.all(lengths > 0):
            raise ArticError(f"muscle {m} has a fibre of zero length; check the landmarks")
    return weights
