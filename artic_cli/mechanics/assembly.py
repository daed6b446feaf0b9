"""Assembly into a fixed banded pattern and its Cholesky factorisation.

Free degrees of freedom are numbered along a reverse Cuthill-McKee order of
the node graph, so every system matrix (mass, damping, tangent stiffness,
volume tangent) is symmetric banded with half-bandwidth ``u``.  Each element
block knows, once and for all, where its entries land in LAPACK's upper band
storage ``ab[u + r - c, c]``; assembly is then one ``np.bincount``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.linalg import cho_solve_banded, cholesky_banded
from scipy.sparse.csgraph import reverse_cuthill_mckee


@dataclass(frozen=True)
class BandPattern:
    n_free: int
    u: int  # half bandwidth (upper)
    dof_of: np.ndarray  # (3N,) position of each global dof in the band order, -1 if fixed
    free_dofs: np.ndarray  # (n_free,) global dof at each band position

    @property
    def size(self) -> int:
        return (self.u + 1) * self.n_free

    def block_index(self, nodes: np.ndarray) -> np.ndarray:
        """Flat band indices of the dense blocks over ``nodes`` (E, k): (E, 3k, 3k).

        Entries that are fixed or below the diagonal map to ``self.size`` (a
        discard bin)."""
        e, k = nodes.shape
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(e, 3 * k)
        pos = self.dof_of[dofs]
        r = pos[:, :, None]
        c = pos[:, None, :]
        ok = (r >= 0) & (c >= 0) & (r <= c)
        flat = (self.u + r - c) * self.n_free + c
        return np.where(ok, flat, self.size)

    def assemble(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum ``values`` (same shape as ``index``) into band storage (u+1, n_free)."""
        acc = np.bincount(index.ravel(), weights=values.ravel(), minlength=self.size + 1)
        return acc[: self.size].reshape(self.u + 1, self.n_free)


def _half_bandwidth(order: np.ndarray, pairs: np.ndarray, free_mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    dof_order = (3 * order[:, None] + np.arange(3)).ravel()
    free_dofs = dof_order[free_mask[dof_order]]
    dof_of = np.full(free_mask.size, -1, dtype=np.int64)
    dof_of[free_dofs] = np.arange(len(free_dofs))
    pos = dof_of[(3 * pairs[:, :, None] + np.arange(3)).reshape(len(pairs), 6)].astype(float)
    pos[pos < 0] = np.nan
    both = ~np.isnan(pos).all(axis=1)
    span = np.nanmax(pos[both], axis=1) - np.nanmin(pos[both], axis=1) if both.any() else np.zeros(1)
    return max(int(span.max()), 2), dof_of, free_dofs


def band_pattern(n_nodes: int, pairs: np.ndarray, fixed: np.ndarray) -> BandPattern:
    """Pattern for a node graph with edges ``pairs`` and fixed dof mask (N,3).

    The node order is the given numbering or its reverse Cuthill-McKee
    permutation, whichever gives the narrower band."""
    adj = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n_nodes, n_nodes))
    adj = (adj + adj.T + sp.eye(n_nodes)).tocsr()
    free_mask = ~np.asarray(fixed, dtype=bool).ravel()
    candidates = [np.arange(n_nodes), reverse_cuthill_mckee(adj, symmetric_mode=True)]
    u, dof_of, free_dofs = min((_half_bandwidth(o, pairs, free_mask) for o in candidates), key=lambda r: r[0])
    return BandPattern(n_free=len(free_dofs), u=u, dof_of=dof_of, free_dofs=free_dofs)


@dataclass
class BandFactor:
    """Cholesky factor of a banded SPD matrix with the coefficients it was built for."""

    cb: np.ndarray
    key: tuple

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return cho_solve_banded((self.cb, False), rhs, check_finite=False)


def factorize(ab: np.ndarray, key: tuple) -> BandFactor:
    return BandFactor(cb=cholesky_banded(ab, lower=False, check_finite=False), key=key)


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
