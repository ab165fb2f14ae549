"""Symbolic linear algebra without simplify and without spurious singularities.

Small systems (k <= 3) are solved by the adjugate over the determinant, so that the only
denominator is the determinant itself: a solve introduces no singularity the matrix does
not have.  Larger systems use LU with pivots chosen for being constants, then for being
short, which keeps unit-diagonal (explicit-form) blocks free of divisions.
"""

from __future__ import annotations

import random

import numpy as np
import sympy as sp
from sympy.matrices.utilities import dotprodsimp

from . import dag

_ADJUGATE_MAX = 3


def _pivot_cost(e) -> tuple[int, int]:
    if e == 0:
        return (2, 0)
    if e.is_number:
        return (0, 0)
    return (1, dag.size(e, cap=200))   # count_ops walks the tree: exponential when nested


def solve(M: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
    """The solution X of M X = rhs for square M (rhs may have several columns)."""
    k = M.rows
    if k == 0:
        return sp.zeros(0, rhs.cols)
    if k == 1:
        return rhs / M[0, 0]
    # sympy's matrix products otherwise run cancel() on every entry (dotprodsimp): that is
    # a simplification on the hot path, minutes long on an N-trailer's reduced mass matrix
    with dotprodsimp(False):
        if k <= _ADJUGATE_MAX:
            det = M.det(method="berkowitz")
            return matmul(M.adjugate(method="berkowitz"), rhs) / det
        return _lu_solve(M, rhs)


def matmul(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """A B with each entry one Add of its non-zero products (sympy's product adds term by
    term, re-flattening the partial sums, and cancels unless dotprodsimp is off)."""
    return sp.Matrix(A.rows, B.cols, lambda i, j: sp.Add(*[
        A[i, m] * B[m, j] for m in range(A.cols) if A[i, m] != 0 and B[m, j] != 0]))


def embed(Phi: sp.Matrix, ind, dep) -> sp.Matrix:
    """P with the identity on the rows ``ind`` and ``Phi`` on the rows ``dep``: for
    Phi = -A_dep^-1 A_ind its columns span ker A (q = P u, u the ``ind`` components)."""
    P = sp.zeros(len(ind) + len(dep), len(ind))
    for m, i in enumerate(ind):
        P[i, m] = 1
    for a, i in enumerate(dep):
        P[i, :] = Phi[a, :]
    return P


def inverse(M: sp.Matrix) -> sp.Matrix:
    """M^-1 by ``solve`` (adjugate / det for small M)."""
    return solve(M, sp.eye(M.rows))


def _lu_solve(M: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
    """Gaussian elimination with pivots chosen by ``_pivot_cost`` (row pivoting)."""
    A = M.copy().as_mutable()
    B = rhs.copy().as_mutable()
    k = A.rows
    for col in range(k):
        best = min(range(col, k), key=lambda r: _pivot_cost(A[r, col]))
        if A[best, col] == 0:
            raise ZeroDivisionError("singular matrix")
        if best != col:
            A.row_swap(best, col)
            B.row_swap(best, col)
        piv = A[col, col]
        for r in range(col + 1, k):
            if A[r, col] != 0:
                fac = A[r, col] / piv
                for R, j0 in ((A, col), (B, 0)):        # zero entries stay untouched
                    for j in range(j0, R.cols):
                        if R[col, j] != 0:
                            R[r, j] = R[r, j] - fac * R[col, j]
    X = sp.zeros(k, B.cols)
    for r in range(k - 1, -1, -1):
        acc = B[r, :] - matmul(A[r, r + 1:], X[r + 1:, :])
        X[r, :] = acc / A[r, r]
    return X


def _numeric_samples(matrices, points: int, seed: int, complete=None, symbols=()):
    """The matrices evaluated at up to ``points`` random points (values in [0.31, 1.37]),
    skipping points where an entry is not a finite real number.  ``complete(values)``
    may overwrite some of the values (e.g. put the point on a manifold); ``symbols`` are
    drawn too (those ``complete`` needs)."""
    syms = sorted(set(symbols).union(*(M.free_symbols for M in matrices)), key=lambda s: s.name)
    rng = random.Random(seed)
    for _ in range(points):
        vals = {s: sp.Float(rng.uniform(0.31, 1.37)) for s in syms}
        try:
            if complete is not None:
                vals = complete(vals)
            values = iter(dag.evaluate([e for M in matrices for e in M], vals, dps=17))
            arrs = [np.array([float(next(values)) for _ in range(len(M))]).reshape(M.shape)
                    for M in matrices]
        except (TypeError, ValueError, ZeroDivisionError, np.linalg.LinAlgError):
            continue
        if all(np.all(np.isfinite(a)) for a in arrs):
            yield arrs


def _rank(arr, tol) -> int:
    if arr.size == 0:
        return 0
    s = np.linalg.svd(arr, compute_uv=False)
    return int(np.sum(s > tol * max(1.0, s[0])))


def numeric_rank(M: sp.Matrix, points: int = 3, seed: int = 0, tol: float = 1e-9) -> int:
    """The generic rank of a symbolic matrix: the largest rank at a few random points.

    Matrices of abstract (undefined) functions cannot be evaluated; their rank is
    decided symbolically, with zero meaning zero after ``expand``.
    """
    ranks = [_rank(a, tol) for (a,) in _numeric_samples([M], points, seed)]
    if not ranks:            # abstract functions: no numbers to draw, decide symbolically
        return M.rank(iszerofunc=lambda e: sp.expand(e) == 0, simplify=False)
    return max(ranks)


def reduced_rank(H: sp.Matrix, A: sp.Matrix, ind, dep, points: int = 3, seed: int = 0,
                 tol: float = 1e-9, complete=None, symbols=()) -> int:
    """The generic rank of P^T H P, P = [I; -A_dep^-1 A_ind] spanning ker A (rows of
    the ``ind`` and ``dep`` coordinates): numerically from H and A, never from P
    (``complete`` and ``symbols`` as in ``_numeric_samples``)."""
    ind, dep = list(ind), list(dep)
    ranks = []
    for Hn, An in _numeric_samples([H, A], points, seed, complete, symbols):
        P = np.zeros((H.rows, len(ind)))
        P[ind, range(len(ind))] = 1.0
        if dep:
            try:
                P[dep, :] = -np.linalg.solve(An[:, dep], An[:, ind])
            except np.linalg.LinAlgError:
                continue
        ranks.append(_rank(P.T @ Hn @ P, tol))
    if ranks:
        return max(ranks)
    with dotprodsimp(False):  # abstract functions: decide symbolically (small systems)
        P = embed(-solve(A[:, dep], A[:, ind]) if dep else sp.zeros(0, len(ind)), ind, dep)
        return numeric_rank(P.T * H * P, points, seed, tol)
