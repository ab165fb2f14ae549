"""Symbolic linear algebra without simplify and without spurious singularities.

Small systems (k <= 3) are solved by the adjugate over the determinant, so that the only
denominator is the determinant itself: a solve introduces no singularity the matrix does
not have.  Larger systems use LU with pivots chosen for being constants, then for being
short, which keeps unit-diagonal (explicit-form) blocks free of divisions.
"""

from __future__ import annotations

import random

import sympy as sp
from sympy.matrices.utilities import dotprodsimp

_ADJUGATE_MAX = 3


def _pivot_cost(e) -> tuple[int, int]:
    if e == 0:
        return (2, 0)
    if e.is_number:
        return (0, 0)
    return (1, sp.count_ops(e, visual=False))


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
            return (M.adjugate(method="berkowitz") * rhs) / det
        return _lu_solve(M, rhs)


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
                A[r, :] = A[r, :] - fac * A[col, :]
                B[r, :] = B[r, :] - fac * B[col, :]
    X = sp.zeros(k, B.cols)
    for r in range(k - 1, -1, -1):
        acc = B[r, :] - A[r, r + 1:] * X[r + 1:, :]
        X[r, :] = acc / A[r, r]
    return X


def numeric_rank(M: sp.Matrix, points: int = 3, seed: int = 0, tol: float = 1e-9) -> int:
    """The generic rank of a symbolic matrix: the largest rank at a few random points.

    Matrices of abstract (undefined) functions cannot be evaluated; their rank is
    decided symbolically, with zero meaning zero after ``expand``.
    """
    import numpy as np

    syms = sorted(M.free_symbols, key=lambda s: s.name)
    rng = random.Random(seed)
    best = 0
    evaluated = False
    for _ in range(points):
        vals = {s: sp.Float(rng.uniform(0.31, 1.37)) for s in syms}
        try:
            arr = np.array(M.xreplace(vals).evalf(), dtype=float)
        except (TypeError, ValueError):
            continue
        if not np.all(np.isfinite(arr)):
            continue
        if arr.size == 0:
            return 0
        evaluated = True
        s = np.linalg.svd(arr, compute_uv=False)
        best = max(best, int(np.sum(s > tol * max(1.0, s[0]))))
    if not evaluated:        # abstract functions: no numbers to draw, decide symbolically
        return M.rank(iszerofunc=lambda e: sp.expand(e) == 0, simplify=False)
    return best
