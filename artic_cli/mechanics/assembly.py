"""Assembly into a fixed sparsity pattern and its factorisation.

Free degrees of freedom split into a *core* (the tongue's nodes, numbered
along a band) and an optional *border* (the few bone nodes of the jaw and
hyoid, which touch the whole tongue).  Every system matrix is then

    [ A   B ]      A: symmetric banded, half-bandwidth u (LAPACK upper storage)
    [ B^T C ]      B: dense n_core x n_border, C: dense n_border x n_border

Nodes carried rigidly by a bone have no dofs of their own: a map T takes the
free dofs to all node dofs, and the system matrix is T^T K T.  Each element
block knows, once and for all, where its entries land in one flat storage
(band | B | C), with T folded in: assembly is one sparse product.  The
factorisation is a block Cholesky (banded U of A, W = U^-T B, dense Cholesky
of the Schur complement C - W^T W); a solve is one banded forward and one
banded backward substitution plus small dense products.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dpbtrf, dpotrf, dpotrs, dtbtrs, dtrtrs
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..geometry.mirror import MIRROR


@dataclass(frozen=True)
class BandPattern:
    n_free: int  # core + border
    n_core: int
    u: int  # half bandwidth of the core (upper)
    dof_of: np.ndarray  # (3N,) position of each global dof (core first, then border), -1 if fixed or slaved
    free_dofs: np.ndarray  # (n_free,) global dof at each position
    reduce: sp.csr_matrix  # (3N, n_free) T: a change dq of the free dofs moves the nodes by T dq

    @property
    def n_border(self) -> int:
        return self.n_free - self.n_core

    @property
    def band_size(self) -> int:
        return (self.u + 1) * self.n_core

    @property
    def size(self) -> int:
        nb = self.n_border
        return self.band_size + self.n_core * nb + nb * nb

    @cached_property
    def reduce_t(self) -> sp.csr_matrix:
        """T^T: node forces (3N,) -> generalised forces on the free dofs."""
        return self.reduce.T.tocsr()

    def block_operator(self, nodes: np.ndarray) -> sp.csr_matrix:
        """(size, E * 3k * 3k) operator taking dense element blocks over ``nodes`` (E, k) to flat storage.

        It computes T^T K T for the element matrices K (slaved dofs spread onto their masters, fixed dofs
        dropped) and keeps the stored part: the band's upper triangle, B and C."""
        e, k = nodes.shape
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(e, 3 * k)
        width = int(np.diff(self.reduce.indptr).max(initial=1))
        cols, wts = _padded_rows(self.reduce, width)  # (3N, w)
        a = np.broadcast_to(dofs[:, :, None], (e, 3 * k, 3 * k)).ravel()
        b = np.broadcast_to(dofs[:, None, :], (e, 3 * k, 3 * k)).ravel()
        entry = np.arange(a.size)
        r = cols[a][:, :, None]
        c = cols[b][:, None, :]
        w = wts[a][:, :, None] * wts[b][:, None, :]
        flat = self._flat(np.broadcast_to(r, w.shape), np.broadcast_to(c, w.shape))
        keep = (w != 0.0) & (flat >= 0)
        ent = np.broadcast_to(entry[:, None, None], w.shape)[keep]
        return sp.csr_matrix((w[keep], (flat[keep], ent)), shape=(self.size, a.size))

    def diagonal_operator(self, nodes: np.ndarray) -> sp.csr_matrix:
        """Operator for 3x3 blocks on the diagonal at ``nodes`` (E,)."""
        return self.block_operator(nodes[:, None])

    def node_block_operator(self, pairs: np.ndarray, n_nodes: int) -> sp.csr_matrix:
        """(size, 9 (P + N)) operator taking node-level blocks to flat storage.

        The blocks (P + N, 3, 3) are the matrix's 3x3 block at (row i, column j) of each node pair
        (i < j) of ``pairs`` (P,2) (the block at (j, i) is its transpose), then each node's diagonal
        block.  Element matrices are summed into these blocks first, so that the folding of carried
        points and the choice of stored entries is paid once per node pair, not once per element."""
        p = len(pairs)
        pair_op = self.block_operator(pairs)  # (size, 36 P): dense 6x6 blocks over (i, j)
        a, b = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
        col = (9 * np.arange(p)[:, None] + (3 * a + b).ravel()).ravel()  # block entry (p, a, b)
        upper = (36 * np.arange(p)[:, None] + (6 * a + 3 + b).ravel()).ravel()  # element entry (a, 3 + b)
        lower = (36 * np.arange(p)[:, None] + (6 * (3 + b) + a).ravel()).ravel()  # its transpose (3 + b, a)
        pick = sp.csr_matrix((np.ones(2 * col.size), (np.r_[upper, lower], np.r_[col, col])), shape=(36 * p, 9 * p))
        return sp.hstack([pair_op @ pick, self.diagonal_operator(np.arange(n_nodes))], format="csr")

    def _flat(self, r: np.ndarray, c: np.ndarray) -> np.ndarray:
        """Flat storage index of matrix entry (r, c), -1 where it is not stored."""
        nc, nb = self.n_core, self.n_border
        band = (r < nc) & (c < nc) & (r <= c)
        off = (r < nc) & (c >= nc)
        corner = (r >= nc) & (c >= nc)
        flat = np.full(r.shape, -1, dtype=np.int64)
        flat = np.where(band, (self.u + r - c) * nc + c, flat)
        flat = np.where(off, self.band_size + r * nb + (c - nc), flat)
        return np.where(corner, self.band_size + nc * nb + (r - nc) * nb + (c - nc), flat)

    def unpack(self, flat: np.ndarray) -> "SystemMatrix":
        nc, nb = self.n_core, self.n_border
        band = flat[: self.band_size].reshape(self.u + 1, nc)
        b = flat[self.band_size: self.band_size + nc * nb].reshape(nc, nb)
        c = flat[self.band_size + nc * nb:].reshape(nb, nb)
        return SystemMatrix(band, b, c)


def _padded_rows(t: sp.csr_matrix, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Each row's column indices and values, padded to ``width`` with (0, 0.0)."""
    n = t.shape[0]
    counts = np.diff(t.indptr)
    cols = np.zeros((n, width), dtype=np.int64)
    vals = np.zeros((n, width))
    slot = np.arange(t.nnz) - np.repeat(t.indptr[:-1], counts)
    row = np.repeat(np.arange(n), counts)
    cols[row, slot] = t.indices
    vals[row, slot] = t.data
    return cols, vals


@dataclass
class SystemMatrix:
    band: np.ndarray
    b: np.ndarray
    c: np.ndarray


def _half_bandwidth(order: np.ndarray, pairs: np.ndarray, core_free: np.ndarray):
    dof_order = (3 * order[:, None] + np.arange(3)).ravel()
    free = dof_order[core_free[dof_order]]
    dof_of = np.full(core_free.size, -1, dtype=np.int64)
    dof_of[free] = np.arange(len(free))
    pos = dof_of[(3 * pairs[:, :, None] + np.arange(3)).reshape(len(pairs), 6)].astype(float)
    pos[pos < 0] = np.nan
    both = (~np.isnan(pos)).sum(axis=1) >= 2
    span = np.nanmax(pos[both], axis=1) - np.nanmin(pos[both], axis=1) if both.any() else np.zeros(1)
    return max(int(span.max()), 2), dof_of, free


def band_pattern(n_nodes: int, pairs: np.ndarray, fixed: np.ndarray, n_core: int | None = None,
                 slaves: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                 mirror: tuple[np.ndarray, np.ndarray] | None = None) -> BandPattern:
    """Pattern for a node graph with edges ``pairs`` and fixed dof mask (N,3).

    Nodes ``0 .. n_core-1`` form the banded core, in their given order or in
    reverse Cuthill-McKee order, whichever band is narrower; the other free
    nodes form the dense border.  ``slaves`` = (nodes (S,), masters (S,m),
    weights (S,m)): each slaved node moves as the weighted sum of its masters
    (border nodes) and has no degrees of freedom of its own.  ``mirror`` =
    (nodes (H,), images (H,)): each of ``nodes`` is the mirror image of its
    image in the plane z = 0, (x, y, z) = (x', y', -z'), and has no degrees of
    freedom either (one half of a left-right symmetric body is solved)."""
    n_core = n_nodes if n_core is None else n_core
    fixed = np.asarray(fixed, dtype=bool)
    slaved = np.zeros(n_nodes, dtype=bool)
    if slaves is not None:
        slaved[slaves[0]] = True
    image = np.arange(n_nodes)  # the node whose dofs move each node (itself, or its mirror image)
    if mirror is not None:
        halves, images = (np.asarray(a, dtype=np.int64) for a in mirror)
        if slaved[halves].any() or slaved[images].any() or np.isin(images, halves).any():
            raise ValueError("a mirrored node is carried, or its image is mirrored itself")
        if (fixed[halves] != fixed[images]).any():
            raise ValueError("a mirrored node and its image are held differently")
        image[halves] = images
        slaved[halves] = True
    core = np.zeros(n_nodes, dtype=bool)
    core[:n_core] = ~slaved[:n_core]
    pairs = image[pairs] if len(pairs) else pairs
    core_pairs = pairs[core[pairs].all(axis=1)] if len(pairs) else pairs
    adj = sp.coo_matrix((np.ones(len(core_pairs)), (core_pairs[:, 0], core_pairs[:, 1])), shape=(n_core, n_core))
    adj = (adj + adj.T + sp.eye(n_core)).tocsr()
    core_free = np.zeros(3 * n_nodes, dtype=bool)
    core_free[: 3 * n_core] = (~fixed[:n_core] & core[:n_core, None]).ravel()
    candidates = [np.arange(n_core), reverse_cuthill_mckee(adj, symmetric_mode=True)]
    u, dof_of, free = min((_half_bandwidth(o, core_pairs, core_free) for o in candidates), key=lambda r: r[0])
    n_core_free = len(free)
    border_mask = ~fixed[n_core:] & ~slaved[n_core:, None]
    border = np.flatnonzero(border_mask.ravel()) + 3 * n_core
    dof_of[border] = n_core_free + np.arange(len(border))
    n_free = n_core_free + len(border)
    own = np.flatnonzero(dof_of >= 0)
    reduce = sp.csr_matrix((np.ones(len(own)), (own, dof_of[own])), shape=(3 * n_nodes, n_free))
    if mirror is not None:  # a mirrored node's row: its image's, with z reversed
        dofs = (3 * images[:, None] + np.arange(3)).ravel()
        flip = sp.csr_matrix((np.tile(MIRROR, len(halves)), (np.arange(len(dofs)), dofs)), shape=(len(dofs), 3 * n_nodes))
        reduce = reduce + _onto_rows((3 * halves[:, None] + np.arange(3)).ravel(), flip @ reduce, 3 * n_nodes)
    if slaves is not None:
        nodes, masters, weights = (np.asarray(a) for a in slaves)
        for d in range(3):
            if (dof_of[3 * image[masters] + d] < 0).any():
                raise ValueError("a slaved node's master is fixed or slaved itself")
        cols = 3 * masters[:, None, :] + np.arange(3)[None, :, None]  # (S,3,m): dof d of each master
        w = np.broadcast_to(weights[:, None, :], cols.shape)
        spread = sp.csr_matrix((w.ravel(), (np.repeat(np.arange(3 * len(nodes)), masters.shape[1]), cols.ravel())),
                               shape=(3 * len(nodes), 3 * n_nodes))
        reduce = reduce + _onto_rows((3 * nodes[:, None] + np.arange(3)).ravel(), spread @ reduce, 3 * n_nodes)
    reduce = reduce.tocsr()
    reduce.eliminate_zeros()
    return BandPattern(n_free=n_free, n_core=n_core_free, u=u, dof_of=dof_of,
                       free_dofs=np.concatenate([free, border]), reduce=reduce)


def _onto_rows(rows: np.ndarray, block: sp.spmatrix, n_dofs: int) -> sp.csr_matrix:
    """(n_dofs, block's columns): ``block``'s k-th row placed at row ``rows[k]``, zero elsewhere."""
    place = sp.csr_matrix((np.ones(len(rows)), (rows, np.arange(len(rows)))), shape=(n_dofs, len(rows)))
    return place @ block


def _check(info: int, what: str) -> None:
    if info > 0:
        raise np.linalg.LinAlgError(f"{what}: matrix not positive definite")
    if info < 0:
        raise ValueError(f"{what}: illegal argument {-info}")


@dataclass
class BandFactor:
    """Block Cholesky factor L of a bordered banded SPD matrix, with the key it was built for.

        [ A   B ]   [ U^T  0  ] [ U  W    ]
        [ B^T C ] = [ W^T  Ls ] [ 0  Ls^T ],   W = U^-T B,  Ls Ls^T = C - W^T W

    (A = U^T U banded).  ``forward`` applies L^-1 and ``backward`` L^-T, each one
    banded triangular solve plus small dense work; LAPACK is called directly
    (these systems are small, and the SciPy wrappers' checks cost more than the
    solves)."""

    cb: np.ndarray
    key: tuple
    w: np.ndarray | None = None  # U^-T B (n_core, n_border)
    ls: np.ndarray | None = None  # lower Cholesky factor of the Schur complement

    def forward(self, rhs: np.ndarray) -> np.ndarray:
        nc = self.cb.shape[1]
        y1, info = dtbtrs(self.cb, rhs[:nc], uplo="U", trans="T")
        _check(info, "banded solve")
        if self.ls is None:
            return y1
        y2, info = dtrtrs(self.ls, rhs[nc:] - self.w.T @ y1, lower=1)
        return np.concatenate([y1, y2])

    def backward(self, y: np.ndarray) -> np.ndarray:
        nc = self.cb.shape[1]
        if self.ls is None:
            x1, info = dtbtrs(self.cb, y, uplo="U", trans="N")
            return x1
        x2, info = dtrtrs(self.ls, y[nc:], lower=1, trans=1)
        x1, info = dtbtrs(self.cb, y[:nc] - self.w @ x2, uplo="U", trans="N")
        return np.concatenate([x1, x2])

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self.backward(self.forward(rhs))


@dataclass(frozen=True)
class LowRankFactor:
    """Solves with A + G diag(k) G^T by the Woodbury identity, from a factor L of A.

    With Z = L^-1 G:  (A + G K G^T)^-1 = L^-T (I - Z (K^-1 + Z^T Z)^-1 Z^T) L^-1."""

    base: BandFactor
    terms_key: tuple  # what the rank-one terms were built for
    z: np.ndarray | None = None  # L^-1 G (n_free, r)
    s: np.ndarray | None = None  # Cholesky (upper) of diag(1/k) + Z^T Z

    @property
    def key(self) -> tuple:
        return self.base.key

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        y = self.base.forward(rhs)
        if self.z is not None:
            c, _ = dpotrs(self.s, self.z.T @ y)
            y = y - self.z @ c
        return self.base.backward(y)


def add_low_rank(base: BandFactor, g: np.ndarray, k: np.ndarray, terms_key: tuple = ()) -> LowRankFactor:
    """Factor of A + G diag(k) G^T (k > 0) for rank-one terms that do not fit the band."""
    if g.shape[1] == 0:
        return LowRankFactor(base=base, terms_key=terms_key)
    z = base.forward(np.ascontiguousarray(g))
    s, info = dpotrf(np.diag(1.0 / k) + z.T @ z)
    _check(info, "low-rank update")
    return LowRankFactor(base=base, terms_key=terms_key, z=z, s=s)


def factorize(mat: SystemMatrix, key: tuple) -> BandFactor:
    cb, info = dpbtrf(mat.band)
    _check(info, "banded Cholesky")
    if mat.c.size == 0:
        return BandFactor(cb=cb, key=key)
    w = np.zeros_like(mat.b)
    # U^T is lower triangular, so column c of W is zero above the first core row that B couples to c:
    # solve from there on (border dofs with no link to the core have W = 0)
    nz = mat.b != 0.0
    first = np.where(nz.any(axis=0), nz.argmax(axis=0), mat.b.shape[0])
    for k in np.unique(first[first < mat.b.shape[0]]):
        cols = np.flatnonzero(first == k)
        w[k:, cols], info = dtbtrs(cb[:, k:], mat.b[k:, cols], uplo="U", trans="T")
        _check(info, "banded solve")
    ls, info = dpotrf(mat.c - w.T @ w, lower=1)
    _check(info, "Schur complement")
    return BandFactor(cb=cb, key=key, w=w, ls=ls)


@dataclass(frozen=True)
class NodeAssembly:
    """Where element blocks land: the node pairs (i < j) joined by any element, each element's pair,
    and the operator from node-level blocks (P + N, 3, 3) to the pattern's flat storage."""

    pairs: np.ndarray  # (P,2)
    cyl_pair: np.ndarray  # (C,) pair of each cylinder or link
    brick_pair: np.ndarray  # (B,8,8) pair of each two corners of a brick, -1 on the diagonal
    seg_pair: np.ndarray  # (S,) pair of each fibre segment
    operator: sp.csr_matrix  # (size, 9 (P + N))

    @property
    def n_pairs(self) -> int:
        return len(self.pairs)

    def add_pairs(self, out: np.ndarray, i: np.ndarray, j: np.ndarray, pair: np.ndarray, k: np.ndarray) -> None:
        """Add two-node elements' 3x3 blocks ``k`` (E, 3, 3) to node-level blocks ``out`` (P + N, 3, 3): k on
        both diagonals, -k on their pair (numpy; the terms' compiled loops compute the same)."""
        if len(k) == 0:
            return
        p = self.n_pairs
        np.add.at(out, p + i, k)
        np.add.at(out, p + j, k)
        np.add.at(out, pair, -k)

    def add_bricks(self, out: np.ndarray, bricks: np.ndarray, grad: np.ndarray, w: np.ndarray) -> None:
        """Add w g_a g_b^T for every two corners of every brick (``grad`` (B, 8, 3)) to ``out``."""
        if not len(grad):
            return
        gg = w[:, None, None, None, None] * grad[:, :, None, :, None] * grad[:, None, :, None, :]  # (B,8,8,3,3)
        na, nb = bricks[:, :, None], bricks[:, None, :]
        upper = np.broadcast_to(na < nb, gg.shape[:3])
        diag = np.broadcast_to(np.eye(8, dtype=bool), gg.shape[:3])
        np.add.at(out, self.brick_pair[upper], gg[upper])
        np.add.at(out, self.n_pairs + np.broadcast_to(na, gg.shape[:3])[diag], gg[diag])


@dataclass(frozen=True)
class Layout:
    """The solver's fixed view of a model, made once when it is built: the band pattern of the reduced
    unknowns, where element blocks land in it, the consistent mass in its flat storage, and the scatter of
    the cylinders' force vectors onto the nodes."""

    pattern: BandPattern
    assembly: NodeAssembly
    mass_flat: np.ndarray  # M in flat storage (BandPattern.unpack)
    scatter: sp.csr_matrix  # (N, C): node force = scatter @ (T n)


def node_assembly(pattern: "BandPattern", n_nodes: int, cyl_edges: np.ndarray, bricks: np.ndarray,
                  seg_edges: np.ndarray) -> NodeAssembly:
    """Node pairs and the operator for two-node elements (cylinders, links: ``cyl_edges`` (C,2); fibre
    segments: ``seg_edges`` (S,2)) and bricks (B,8)."""
    corner_a = np.broadcast_to(bricks[:, :, None], (len(bricks), 8, 8))
    corner_b = np.broadcast_to(bricks[:, None, :], (len(bricks), 8, 8))
    pairs = node_pairs(np.vstack([cyl_edges, seg_edges, np.column_stack([corner_a.ravel(), corner_b.ravel()])]))
    return NodeAssembly(pairs=pairs, cyl_pair=pair_index(pairs, cyl_edges[:, 0], cyl_edges[:, 1]),
                        brick_pair=pair_index(pairs, corner_a.ravel(), corner_b.ravel()).reshape(corner_a.shape),
                        seg_pair=pair_index(pairs, seg_edges[:, 0], seg_edges[:, 1]),
                        operator=pattern.node_block_operator(pairs, n_nodes))


def node_pairs(edges: np.ndarray) -> np.ndarray:
    """(P,2) the distinct node pairs (i < j) among ``edges`` (E,2)."""
    e = np.sort(np.asarray(edges, dtype=np.int64), axis=1)
    return np.unique(e[e[:, 0] != e[:, 1]], axis=0)


def pair_index(pairs: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row of ``pairs`` holding each (a, b) in either order; -1 where a == b.  Every other pair must exist."""
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    scale = int(pairs.max(initial=0)) + 1
    keys = pairs[:, 0] * scale + pairs[:, 1]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    q = lo * scale + hi
    idx = np.searchsorted(keys, q)
    same = a == b
    found = (idx < len(keys)) & (keys[np.minimum(idx, len(keys) - 1)] == q)
    if not (found | same).all():
        raise ValueError("an element joins two nodes that are not a listed pair")
    return np.where(same, -1, idx)


def sparse_blocks(nodes: np.ndarray, blocks: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Global (3N, 3N) sparse matrix from dense blocks (E, 3k, 3k) over ``nodes`` (E, k)."""
    e, k = nodes.shape
    dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(e, 3 * k)
    rows = np.broadcast_to(dofs[:, :, None], blocks.shape).ravel()
    cols = np.broadcast_to(dofs[:, None, :], blocks.shape).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(3 * n_nodes, 3 * n_nodes))


def pair_blocks(k3: np.ndarray) -> np.ndarray:
    """(C,3,3) two-node element blocks -> (C,6,6) [[k, -k], [-k, k]]."""
    top = np.concatenate([k3, -k3], axis=2)
    return np.concatenate([top, -top], axis=1)
