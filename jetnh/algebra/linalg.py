"""Symbolic linear algebra without simplify and without spurious singularities.

Small systems (k <= 3) are solved by the adjugate over the determinant, and systems up
to k = 6 by Cramer's rule with shared minors, so that the only denominator is the
determinant itself: a solve introduces no singularity the matrix does not have (a split
whose every entry vanishes somewhere, det = 1, is solved everywhere).  Larger systems
use LU with pivots chosen by their values at random points (the matrix is eliminated
numerically alongside): never an entry that is zero in value; constants first (which
keeps unit-diagonal, explicit-form blocks free of divisions), then the largest, the
shortest among near ties.  A pivot may still vanish on a lower-dimensional set where the
matrix is regular (their product is the determinant); ``divisors`` collects them.
"""

from __future__ import annotations

import contextlib
import contextvars
import random

import mpmath
import numpy as np
import sympy as sp
from sympy.matrices.utilities import dotprodsimp

from . import dag
from ..errors import ArgumentError, JetnhError

_ADJUGATE_MAX = 3
_CRAMER_MAX = 6           # larger systems: LU with pivots chosen by value


def _pivot_cost(e) -> tuple[int, int]:
    if e == 0:
        return (2, 0)
    if e.is_number:
        return (0, 0)
    return (1, dag.size(e, cap=200))   # count_ops walks the tree: exponential when nested


_DIVISORS: contextvars.ContextVar = contextvars.ContextVar("jetnh_divisors", default=None)


@contextlib.contextmanager
def divisors():
    """Collect, in a list, what every ``solve`` inside the block divides by: the
    determinant (k <= 3) or the LU pivots (whose product is the determinant, up to sign).
    Where one vanishes the solve is singular, whether or not its numerators vanish too."""
    out: list = []
    token = _DIVISORS.set(out)
    try:
        yield out
    finally:
        _DIVISORS.reset(token)


def _divides(d):
    out = _DIVISORS.get()
    if out is not None and not d.is_number:
        out.append(d)


def solve(M: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
    """The solution X of M X = rhs for square M (rhs may have several columns)."""
    k = M.rows
    if k == 0:
        return sp.zeros(0, rhs.cols)
    if k == 1:
        _divides(M[0, 0])
        return rhs / M[0, 0]
    # sympy's matrix products otherwise run cancel() on every entry (dotprodsimp): that is
    # a simplification on the hot path, minutes long on an N-trailer's reduced mass matrix
    with dotprodsimp(False):
        if k <= _ADJUGATE_MAX:
            det = M.det(method="berkowitz")
            _divides(det)
            return matmul(M.adjugate(method="berkowitz"), rhs) / det
        if k <= _CRAMER_MAX:
            return _cramer_solve(M, rhs)
        return _lu_solve(M, rhs)


def _cramer_solve(M: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
    """Cramer's rule with every minor built once (Laplace expansion along the top row,
    memoised by columns: about 2^k (k/2 + 1) minors per right-hand column), so that the
    only denominator is det M: fraction-free, no pivot."""
    k = M.rows
    memo: dict = {}

    def entry(src, r):
        return M[r, src] if isinstance(src, int) else rhs[r, src[1]]

    def minor(cols):             # the rows below k - len(cols), these columns in order
        if not cols:
            return sp.S.One
        if cols in memo:
            return memo[cols]
        r = k - len(cols)
        terms = []
        for i, src in enumerate(cols):
            e = entry(src, r)
            if e == 0:
                continue
            m = minor(cols[:i] + cols[i + 1:])
            if m != 0:
                terms.append((e if i % 2 == 0 else -e) * m)
        memo[cols] = out = sp.Add(*terms)
        return out

    det = minor(tuple(range(k)))
    if det == 0:
        raise ZeroDivisionError("singular matrix")
    _divides(det)
    X = sp.zeros(k, rhs.cols)
    for c in range(rhs.cols):
        for j in range(k):
            num = minor(tuple(range(j)) + (("rhs", c),) + tuple(range(j + 1, k)))
            if num != 0:
                X[j, c] = num / det
    return X


def matmul(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """A B with each entry one Add of its non-zero products (sympy's product adds term by
    term, re-flattening the partial sums, and cancels unless dotprodsimp is off); sums
    and products built by ``dag.build``."""
    return sp.Matrix(A.rows, B.cols, lambda i, j: dag.build(sp.Add, [
        dag.mul(A[i, m], B[m, j]) for m in range(A.cols) if A[i, m] != 0 and B[m, j] != 0]))


def add(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """A + B, entry by entry as sympy's matrix sum (a zero entry adds nothing), the sums
    built by ``dag.build``."""
    return _entrywise(A, B, _sum2)


def sub(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """A - B as sympy's A + (-B) (B's entries times -1), built as ``add``."""
    return _entrywise(A, neg(B), _sum2)


def neg(A: sp.Matrix) -> sp.Matrix:
    """-A as sympy's (each entry times -1)."""
    return scaled(A, sp.S.NegativeOne)


def scaled(A: sp.Matrix, c) -> sp.Matrix:
    """A c as sympy's (each non-zero entry times c), the products built by ``dag.mul``."""
    return sp.Matrix(A.rows, A.cols, lambda i, j: dag.mul(A[i, j], c) if A[i, j] != 0
                     else A[i, j])


def _entrywise(A, B, op) -> sp.Matrix:
    if A.shape != B.shape:
        raise sp.ShapeError(f"Matrix size mismatch: {A.shape} + {B.shape}.")
    return sp.Matrix(A.rows, A.cols, lambda i, j: (
        op(A[i, j], B[i, j]) if A[i, j] != 0 and B[i, j] != 0 else A[i, j] if B[i, j] == 0
        else B[i, j]))


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


_PIVOT_SEED = 20080557  # the random points of pivoting (fixed: the same solve each run)
_PIVOT_DPS = 30          # digits of the numeric elimination that chooses pivots
_PIVOT_POINTS = 3        # random points at which pivots are compared
_PIVOT_ZERO = 1e-15      # |value| below this times the matrix's largest counts as zero
_PIVOT_TIE = 0.25        # scores within this factor of the best are near ties
_PIVOT_SPARSE = 0.01     # ... within this factor, the sparsest row is preferred
_PIVOT_CONSTANT = 1e-3   # a nonzero constant with this score at least is preferred
_COMPLETE: contextvars.ContextVar = contextvars.ContextVar("jetnh_complete", default=None)


@contextlib.contextmanager
def completing(complete):
    """Inside the block, the random points at which ``solve`` chooses pivots are passed
    through ``complete(values)`` (mpmath numbers, within ``mpmath.workdps``), e.g. to put
    them on the constraint manifold."""
    token = _COMPLETE.set(complete)
    try:
        yield
    finally:
        _COMPLETE.reset(token)


def _pivot_values(M: sp.Matrix) -> list:
    """M's entries at up to ``_PIVOT_POINTS`` random points (mpmath matrices, complex
    where the entries are); points outside their domain are skipped, and none is drawn
    once one lacks a symbol's value (``completing`` may need symbols M does not have:
    every point draws the same ones)."""
    syms = sorted(dag.free_symbols(list(M)), key=lambda s: s.name)
    rng = random.Random(_PIVOT_SEED)
    complete = _COMPLETE.get()
    out = []
    for _ in range(_POINT_TRIES * _PIVOT_POINTS):
        if len(out) >= _PIVOT_POINTS:
            break
        with mpmath.workdps(_PIVOT_DPS):
            pt = {s: mpmath.mpf(rng.randrange(31 * _DEN // 100, 137 * _DEN // 100)) / _DEN
                  for s in syms}
            try:
                if complete is not None:
                    pt = complete(pt)
                vals = dag.evaluate(list(M), pt, dps=_PIVOT_DPS)
            except ArgumentError:    # a symbol without a value: so at every point
                break
            except (TypeError, ValueError, ZeroDivisionError, ArithmeticError, Inexact):
                continue
            if all(mpmath.isfinite(v) for v in vals):
                out.append(mpmath.matrix([vals[i * M.cols:(i + 1) * M.cols]
                                          for i in range(M.rows)]))
    return out


def _choose(A, Ns, col, scales):
    """The pivot row for column ``col`` of ``A`` (a list of rows), by value at the random
    points (``Ns``, eliminated alongside): each candidate's smallest size relative to the
    column's largest over the points.  Among the candidates not far smaller than the best
    (``_PIVOT_SPARSE``), the row with the fewest nonzero entries left (Markowitz: the
    least fill-in, so a sparse, e.g. triangular, block keeps a solve of size O(k^2), not
    O(k^3)); then a nonzero constant, then near ties by the cheapest form.  Entries zero
    at a point are never chosen while another is not; without values, by form alone."""
    k = len(A)
    rows = [r for r in range(col, k) if A[r][col] != 0]
    if not Ns or not rows:
        return min(range(col, k), key=lambda r: _pivot_cost(A[r][col]))
    score = {r: mpmath.inf for r in rows}
    for N, scale in zip(Ns, scales):
        top = max(abs(N[r][col]) for r in rows)
        for r in rows:
            v = abs(N[r][col])
            score[r] = min(score[r], v / top if v > _PIVOT_ZERO * scale else 0)
    best = max(score.values())
    if best == 0:                            # zero at a point: fall back to the form
        return min(rows, key=lambda r: _pivot_cost(A[r][col]))
    fill = {r: sum(1 for e in A[r][col + 1:] if e != 0) for r in rows}
    least = min(fill[r] for r in rows if score[r] >= _PIVOT_SPARSE * best)
    rows = [r for r in rows if fill[r] == least and score[r] >= _PIVOT_SPARSE * best]
    consts = [r for r in rows if A[r][col].is_number and score[r] >= _PIVOT_CONSTANT]
    if consts:
        return max(consts, key=lambda r: score[r])
    best = max(score[r] for r in rows)
    near = [r for r in rows if score[r] >= _PIVOT_TIE * best]
    return min(near, key=lambda r: (_pivot_cost(A[r][col]), -score[r]))


def _lu_solve(M: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
    """Gaussian elimination with row pivots chosen by value (``_choose``): the matrix is
    evaluated at random points (``completing`` puts them on a manifold) and eliminated
    numerically alongside, so that a pivot is never an entry that vanishes identically
    (or one that is merely short), and constants are kept as pivots where they serve.
    The entries are held as lists of rows (a sympy matrix's indexing cost as much as the
    arithmetic); each is the expression sympy's matrix operations make."""
    k, m = M.rows, rhs.cols
    A = [[_zero_exact(M[i, j]) for j in range(k)] for i in range(k)]
    B = [[_zero_exact(rhs[i, j]) for j in range(m)] for i in range(k)]
    # the terms subtracted from B's entries, added up once when the row is the pivot's
    # (subtracting them one by one re-flattens every partial sum: cubic in k)
    pending = [[[] for _ in range(m)] for _ in range(k)]
    # the values as lists of rows (mpmath's matrix indexing was most of the elimination)
    Ns = [[[N[i, j] for j in range(k)] for i in range(k)] for N in _pivot_values(M)]
    with mpmath.workdps(_PIVOT_DPS):
        scales = [max(abs(x) for row in N for x in row) for N in Ns]
        for col in range(k):
            best = _choose(A, Ns, col, scales)
            if A[best][col] == 0:
                raise ZeroDivisionError("singular matrix")
            if best != col:
                for rows in (A, B, pending, *Ns):
                    rows[best], rows[col] = rows[col], rows[best]
            top, tb = A[col], B[col]
            for j, terms in enumerate(pending[col]):
                if terms:
                    tb[j] = dag.build(sp.Add, [tb[j], *terms])
            piv = top[col]
            _divides(piv)
            for r in range(col + 1, k):
                row = A[r]
                if row[col] != 0:
                    fac = dag.div(row[col], piv)
                    for j in range(col, k):                 # zero entries stay untouched
                        if top[j] != 0:
                            row[j] = dag.sub(row[j], dag.mul(fac, top[j]))
                    for j in range(m):
                        if tb[j] != 0:
                            pending[r][j].append(-dag.mul(fac, tb[j]))
                for N in Ns:         # zero multipliers and entries change nothing: skipped
                    ntop, nrow = N[col], N[r]
                    if ntop[col] and nrow[col]:       # mpmath numbers: nonzero
                        nf = nrow[col] / ntop[col]
                        for j in range(col, k):
                            if ntop[j]:
                                nrow[j] -= nf * ntop[j]
    X = [None] * k
    for r in range(k - 1, -1, -1):          # B[r] - A[r, r+1:] X[r+1:], then / A[r, r]
        inv = sp.S.One / A[r][r]            # as sympy's matrices: times 1/A[r, r]
        X[r] = [_times(_minus(B[r][c], dag.build(sp.Add, [
            dag.mul(A[r][j], X[j][c]) for j in range(r + 1, k)
            if A[r][j] != 0 and X[j][c] != 0])), inv) for c in range(m)]
    return sp.Matrix(X) if k else sp.zeros(0, m)


def _zero_exact(e):
    """``e``, a numeric zero (a Float 0.0, which sympy does not count as == 0) as sympy's
    zero: a matrix's row swaps make it so, and the pivot test asks for it."""
    return sp.S.Zero if e.is_Number and e.is_zero else e


def _sum2(a, b):
    """``a + b`` of two entries as sympy's matrix sum makes it: two numbers by the
    operator (``Add(0.0, 2)`` is 2, ``0.0 + 2`` is 2.0), else ``dag.build``."""
    return a + b if a.is_Number and b.is_Number else dag.build(sp.Add, [a, b])


def _minus(a, b):
    """Entry of sympy's matrix a - b (a + (-1) b, zero entries added to nothing)."""
    if b == 0:
        return a
    b = dag.mul(b, sp.S.NegativeOne)
    return b if a == 0 else _sum2(a, b)


def _times(a, c):
    """Entry of sympy's matrix a c (a zero entry stays zero)."""
    return a if a == 0 else dag.mul(a, c)


# ------------------------------------------------------------------ generic rank
# The rank of a symbolic matrix is decided at random points, independently of scale, as
# the rank of the matrix as written (binary floats are exact numbers, not rounded copies).
# Where the entries are rational functions of the point (polynomial Lagrangians and
# constraints) the point is rational and the rank exact.  Otherwise each point is
# evaluated at two precisions: an entry whose two values disagree is rounding noise of an
# exact zero (sin^2 + cos^2 - 1, a reduced matrix that vanishes on the constraints) and is
# set to zero; every other entry is then known to about 40 digits.  Rows and columns are
# equilibrated (scaled by powers of two, which keeps the rank and the digits) and
# singular values below _RANK_TOL times the largest count as zero.  So diag(1, 1e-20) or
# constraints 1e-12 f^1, f^2 have full rank, while f and 1e10 f, or (x' + y')^2, do not.
_DPS = (50, 80)          # the two working precisions (decimal digits)
_NOISE = 1e-12           # relative disagreement between them that marks an entry as noise
_SHRUNK = 1e-3           # ... which is a zero's noise if it shrank at least this much
_RANK_TOL = 1e-30        # singular values below this times the largest are zero
_POINT_TRIES = 4         # attempts per wanted point (a point may leave the domain)
EXACT_MAX = 4000        # distinct subexpressions up to which exact evaluation is tried
_DEN = 100 * 2**16       # denominator of the rational points


class Inexact(ValueError):
    """An exact evaluation met an irrational value (use the numeric one)."""


def exact_values(exprs, values: dict) -> list:
    """The values of ``exprs`` at the rational point ``values`` as sympy Rationals (floats
    read as the exact binary numbers they are), or Inexact."""
    rule = dict(values)
    rule.update({f: sp.Rational(f) for f in dag.atoms(list(exprs), sp.Float)})
    out = dag.xreplace(list(exprs), rule)
    if any(v in (sp.zoo, sp.nan, sp.oo, -sp.oo) for v in out):
        raise ZeroDivisionError("not finite at this point")
    if not all(isinstance(v, sp.Rational) for v in out):
        raise Inexact("not rational at a rational point")
    return out


def real_value(v):
    """``v`` as a finite mpf, or None (complex beyond noise, infinite, nan)."""
    if isinstance(v, mpmath.mpc):
        if abs(v.imag) > mpmath.mpf(10) ** (-(mpmath.mp.dps // 2)) * max(1, abs(v.real)):
            return None
        v = v.real
    v = mpmath.mpf(v)
    return v if mpmath.isfinite(v) else None


class _Unresolved(ArithmeticError):
    """An entry that neither precision resolves: not confirmed, and not shrinking as a
    zero's rounding noise does with more digits."""


def _denoise(lo, hi):
    """``hi`` with the entries that ``lo`` (the same at lower precision) does not confirm
    set to zero: cancellation noise, which shrinks with the precision.  An unconfirmed
    entry that does not shrink (a value beyond both precisions, e.g. exp(exp(exp(50))))
    is ``_Unresolved``."""
    out = hi.copy()
    for i in range(hi.rows):
        for j in range(hi.cols):
            if abs(lo[i, j] - hi[i, j]) > _NOISE * abs(hi[i, j]):
                if abs(hi[i, j]) > _SHRUNK * abs(lo[i, j]):
                    raise _Unresolved(f"entry ({i}, {j}) is not resolved at {_DPS} digits")
                out[i, j] = 0
    return out


#: what an evaluation at a sample point may raise where the point is no good; of them,
#: the values too large to hold (mpmath's exp(exp(exp(exp(exp(1))))) raises MemoryError at
#: once, before anything is allocated)
_OVERFLOW = (OverflowError, MemoryError)
_NOT_A_NUMBER = (TypeError, ValueError, ZeroDivisionError, ArithmeticError)


def _generic_samples(exprs, build, points: int, seed: int, complete=None, symbols=()):
    """For up to ``points`` random points (values in [0.31, 1.37]): ``build(values)`` of
    the values of ``exprs`` there -- exact (Rationals; ``build`` then returns a sympy
    Matrix) when they are rational, else an mpmath matrix built at both precisions and
    denoised.  A point where an entry is not a finite real number, or where ``build`` or
    ``complete`` fails (``_NOT_A_NUMBER``), is skipped; a JetnhError where no point gave numbers and
    some overflowed or were not resolved (``_denoise``).  ``complete(values)``
    may overwrite values (e.g. put the point on a manifold): it gets Rationals (and
    raises ``Inexact`` when it cannot stay exact) or mpmath numbers, within
    ``mpmath.workdps`` of the precision.  ``symbols`` are drawn too."""
    exprs = list(exprs)
    syms = sorted(set(symbols) | dag.free_symbols(exprs), key=lambda s: s.name)
    rng = random.Random(seed)
    try_exact = dag.size(exprs, cap=EXACT_MAX + 1) <= EXACT_MAX
    got = unresolved = 0
    for _ in range(_POINT_TRIES * points):
        if got >= points:
            return
        base = {s: sp.Rational(rng.randrange(31 * _DEN // 100, 137 * _DEN // 100), _DEN)
                for s in syms}
        if try_exact:
            try:
                vals = complete(dict(base)) if complete is not None else base
                M = build(exact_values(exprs, vals))
            except Inexact:
                try_exact = False           # irrational entries: numeric from now on
            except _OVERFLOW:
                unresolved += 1
                continue
            except _NOT_A_NUMBER:
                continue
            else:
                got += 1
                yield M
                continue
        mats = []
        try:
            for dps in _DPS:
                with mpmath.workdps(dps):
                    mp_base = {s: mpmath.mpf(v.p) / v.q for s, v in base.items()}
                    vals = complete(mp_base) if complete is not None else mp_base
                    values = [real_value(v) for v in dag.evaluate(exprs, vals, dps=dps)]
                    if any(v is None for v in values):
                        raise ValueError("not a finite real number")
                    mats.append(build(values))
            with mpmath.workdps(_DPS[-1]):
                M = _denoise(*mats)
        except _OVERFLOW + (_Unresolved,):
            unresolved += 1
            continue
        except _NOT_A_NUMBER:
            continue
        got += 1
        yield M
    if got == 0 and unresolved:
        raise JetnhError(
            f"at {unresolved} of the {_POINT_TRIES * points} random points tried (values "
            f"in [0.31, 1.37]) the expressions overflow or are not resolved at {_DPS[-1]} "
            "digits, and no point gave numbers, so jetnh cannot decide their generic rank; "
            "rescale the model (e.g. fewer nested exp)")


def _equilibrate(M):
    """D1 M D2 with every non-zero row and column of largest entry in [1/2, 1) (powers
    of two: no digit is lost, the rank is kept)."""
    M = M.copy()
    for _ in range(2):
        for i in range(M.rows):
            m = max((abs(M[i, j]) for j in range(M.cols)), default=0)
            if m:
                e = mpmath.frexp(m)[1]
                for j in range(M.cols):
                    M[i, j] = mpmath.ldexp(M[i, j], -e)
        for j in range(M.cols):
            m = max((abs(M[i, j]) for i in range(M.rows)), default=0)
            if m:
                e = mpmath.frexp(m)[1]
                for i in range(M.rows):
                    M[i, j] = mpmath.ldexp(M[i, j], -e)
    return M


def mp_rank(M) -> int:
    """The rank of a sympy Matrix of Rationals (exact), or of an mpmath matrix known to
    about 40 digits, after equilibration."""
    if M.rows == 0 or M.cols == 0:
        return 0
    if isinstance(M, sp.MatrixBase):
        return M.rank()
    with mpmath.workdps(_DPS[-1]):
        M = _equilibrate(M)
        if all(M[i, j] == 0 for i in range(M.rows) for j in range(M.cols)):
            return 0
        if _clearly_full(M):
            return min(M.rows, M.cols)
        s = mpmath.svd_r(M, compute_uv=False)
        top = max(abs(x) for x in s)
        return sum(1 for x in s if abs(x) > _RANK_TOL * top)


_FULL_MARGIN = 1e-8      # float singular values above this times the largest: full rank


def _clearly_full(M) -> bool:
    """Whether the equilibrated mpmath matrix ``M`` (entries at most 1, one of at least
    1/2 in every non-zero column) has full rank by far, decided in double precision: its
    singular values differ from those of its rounding by at most about
    sqrt(rows cols) 2^-53 plus LAPACK's backward error (< 1e-12 here), so a smallest
    one above ``_FULL_MARGIN`` times the largest is far above ``_RANK_TOL`` in high
    precision too, and ``svd_r``'s cost (cubic in mpmath arithmetic) is spared.  Any
    doubt (a small singular value, an entry beyond double range): False."""
    rows, cols = M.rows, M.cols
    if rows * cols > 10**6:
        return False
    F = np.array([[float(M[i, j]) for j in range(cols)] for i in range(rows)])
    if not np.all(np.isfinite(F)):
        return False
    s = np.linalg.svd(F, compute_uv=False)
    return len(s) == min(rows, cols) and s[0] > 0 and s[-1] > _FULL_MARGIN * s[0]


def _ranks(samples, full: int) -> list[int]:
    """The ranks of the sampled matrices, up to the first of rank ``full`` (the largest
    possible: the generic rank is decided, the other points are not drawn)."""
    out = []
    for M in samples:
        out.append(mp_rank(M))
        if out[-1] >= full:
            break
    return out


def _reshape(rows: int, cols: int):
    """values -> a rows x cols matrix: sympy for Rationals, else mpmath."""
    def build(values):
        if values and isinstance(values[0], sp.Basic):
            return sp.Matrix(rows, cols, values)
        return mpmath.matrix([values[i * cols:(i + 1) * cols] for i in range(rows)])
    return build


def numeric_rank(M: sp.Matrix, points: int = 3, seed: int = 0) -> int:
    """The generic rank of a symbolic matrix: the largest rank at a few random points,
    decided in high precision, independently of the scale of rows and columns (see the
    comment above ``_DPS``).

    Matrices of abstract (undefined) functions cannot be evaluated; their rank is
    decided symbolically, with zero meaning zero after ``expand``.
    """
    if M.rows == 0 or M.cols == 0:
        return 0
    ranks = _ranks(_generic_samples(list(M), _reshape(M.rows, M.cols), points, seed),
                   min(M.rows, M.cols))
    if not ranks:            # abstract functions: no numbers to draw, decide symbolically
        return M.rank(iszerofunc=lambda e: sp.expand(e) == 0, simplify=False)
    return max(ranks)


def mp_solve(A, B):
    """A^-1 B for mpmath matrices (A square and regular) by Gaussian elimination with
    partial pivoting on lists, skipping zero multipliers and entries: a banded or
    triangular A (a chain's A_dep) costs O(k w^2), not mpmath's dense O(k^3) inverse."""
    k, m = A.rows, B.cols
    rows = [[A[i, j] for j in range(k)] + [B[i, c] for c in range(m)] for i in range(k)]
    for col in range(k):
        best = max(range(col, k), key=lambda r: abs(rows[r][col]))
        if rows[best][col] == 0:
            raise ZeroDivisionError("singular matrix")
        rows[col], rows[best] = rows[best], rows[col]
        top = rows[col]
        live = [j for j in range(col + 1, k + m) if top[j] != 0]
        for r in range(col + 1, k):
            row = rows[r]
            if row[col] != 0:
                f = row[col] / top[col]
                for j in live:
                    row[j] -= f * top[j]
    X = mpmath.matrix(k, m)
    for i in range(k - 1, -1, -1):
        row = rows[i]
        for c in range(m):
            acc = row[k + c]
            for j in range(i + 1, k):
                if row[j] != 0:
                    acc -= row[j] * X[j, c]
            X[i, c] = acc / row[i]
    return X


def reduced_rank(H: sp.Matrix, A: sp.Matrix, ind, dep, points: int = 3, seed: int = 0,
                 complete=None, symbols=()) -> int:
    """The generic rank of P^T H P, P = [I; -A_dep^-1 A_ind] spanning ker A (rows of
    the ``ind`` and ``dep`` coordinates): in high precision from H and A, never from the
    symbolic P (``complete`` and ``symbols`` as in ``_generic_samples``)."""
    ind, dep = list(ind), list(dep)
    n, m = H.rows, len(ind)
    if m == 0:
        return 0
    h, a = _reshape(n, n), _reshape(A.rows, A.cols)

    def build(values):
        exact = bool(values) and isinstance(values[0], sp.Basic)
        Hn = h(values[:n * n])
        P = (sp.zeros if exact else mpmath.zeros)(n, m)
        for c, i in enumerate(ind):
            P[i, c] = 1
        if dep:
            An = a(values[n * n:])
            Ad = (sp.Matrix if exact else mpmath.matrix)(
                [[An[r, j] for j in dep] for r in range(An.rows)])
            Ai = (sp.Matrix if exact else mpmath.matrix)(
                [[An[r, j] for j in ind] for r in range(An.rows)])
            if mp_rank(Ad) < len(dep):
                raise ZeroDivisionError("singular A_dep at this point")
            X = -(Ad.inv() * Ai) if exact else -mp_solve(Ad, Ai)
            for r, i in enumerate(dep):
                for c in range(m):
                    P[i, c] = X[r, c]
        return P.T * Hn * P

    ranks = _ranks(_generic_samples(list(H) + list(A), build, points, seed, complete,
                                    symbols), m)
    if ranks:
        return max(ranks)
    with dotprodsimp(False):  # abstract functions: decide symbolically (small systems)
        P = embed(-solve(A[:, dep], A[:, ind]) if dep else sp.zeros(0, len(ind)), ind, dep)
        return numeric_rank(P.T * H * P, points, seed)
