"""Linear ansatz problems solved by sampling, with coefficients polynomial in the parameters.

A problem has n unknown constants c_j and linear conditions sum_j c_j C_j(p) = 0 that
must hold at every point p = (t, q, velocities, multipliers, parameters); the answer is
the null space.  Conserved quantities (``integrals.py``) and Noether and Lie symmetries
(``symmetries.py``) are such problems.  The route:

1. At one random rational value theta0 of the parameters the unknowns whose ansatz
   functions are dependent at random points (on the constraint manifold: multiples of a
   constraint) are dropped, keeping the earlier ones (``independent_columns``); the
   conditions are imposed at twice as many random points as unknowns kept and reduced
   (50 digits, fixed-point integers):
   the generic dimension r of the solution space and the unknowns it uses (its support S).
   Combinations whose ansatz function vanishes identically (dependent ansatz functions)
   are not counted.
2. With parameters, the constants become polynomials in the parameter atoms theta (the
   parameters, and functions of parameters alone such as sin(alpha)) of degree
   d = 0, 1, ...: unknowns S x monomials(theta, d), points drawn with random parameters,
   null vectors read back as rationals.  An integral whose coefficients are rational
   functions of the parameters is, times its common denominator, polynomial, so this finds
   it at the degree of that polynomial.  The solutions are reduced over the field of
   rational functions of theta (no parameter multiples, lowest degree first, the rank
   taken from the ansatz functions' values at a second random theta), and d grows until
   the rank reaches r (a JetnhWarning says so when the budget stops it first).

Every solution is then proved exactly by its caller (``integrals._check``).
"""

from __future__ import annotations

import itertools
import random
import warnings
from fractions import Fraction

import mpmath
import numpy as np
import sympy as sp

from . import dag
from ..errors import ArgumentError, JetnhError, JetnhWarning

BUDGET = 400            # unknowns of one linear solve (after independent_columns)
RAW_BUDGET = 1600       # unknowns of an ansatz as written (checked before it is built)
DPS = 50                # digits of the numeric route
MAX_PARAMETER_DEGREE = 3
_TOL = mpmath.mpf(10) ** -30
# an entry of a condition row below this is the rounding of an exact cancellation (the
# rows are evaluated at 60 digits from terms of order one at the sampled points)
_ZERO = mpmath.mpf(10) ** -45


def exponents(n, d):
    """Exponent tuples of the monomials of degree d in n variables (graded lex order)."""
    return sorted((tuple(c.count(i) for i in range(n))
                   for c in itertools.combinations_with_replacement(range(n), d)), reverse=True)


def monomial(U, e):
    return sp.Mul(*[u**k for u, k in zip(U, e)])


def parameter_atoms(exprs, parameters) -> tuple:
    """The generic quantities the parameters enter through: each parameter that occurs
    polynomially, and each non-polynomial function of parameters alone (sin(alpha),
    sqrt(k)); constants are sought as polynomials in these."""
    params = set(parameters)
    atoms, plain = set(), set()
    for e in dag.nodes(list(exprs)):
        if e.free_symbols and e.free_symbols <= params and (
                isinstance(e, sp.Function) or (e.is_Pow and not e.exp.is_Integer)):
            atoms.add(e)
    for e in exprs:
        rest = e.xreplace({a: sp.Dummy() for a in atoms})
        plain |= rest.free_symbols & params
    return tuple(sorted(plain, key=str)) + tuple(sorted(atoms, key=str))


class Problem:
    """What the solver needs: ``n`` unknowns, ``rows(rng, count, fixed, columns)`` condition
    rows at random points (parameters from ``fixed`` when given; only the unknowns
    ``columns`` when given), each returned with its point, and
    ``values(point)``, the n ansatz functions' values there (to recognise solutions that
    vanish identically, and to rank solutions over the parameters)."""

    n = 0
    parameters: tuple = ()
    atoms: tuple = ()

    def rows(self, rng, count, fixed=None, columns=None):   # pragma: no cover - interface
        raise NotImplementedError

    def values(self, point):                           # pragma: no cover - interface
        raise NotImplementedError

    def float_values(self, points):
        """The ansatz functions' values at ``points`` as a float array [points, n]
        (subclasses evaluate all points at once)."""
        return np.array([[float(x) for x in self.values(p)] for p in points],
                        dtype=float).reshape(-1, self.n)

    def raw_points(self, rng, count, fixed=None):
        """``count`` random points, not checked for regularity (``float_values`` is)."""
        return self.points(rng, count, fixed)

    def points(self, rng, count, fixed=None):
        """``count`` distinct random points (those of as many condition rows)."""
        out, seen = [], set()
        while len(out) < count:
            for _, p in self.rows(rng, count - len(out), fixed, columns=[]):
                if id(p) not in seen:
                    seen.add(id(p))
                    out.append(p)
        return out


def random_parameters(params, rng, wide=False) -> dict:
    """Positive random rationals: in [1/2, 2], or of larger height (``wide``)."""
    if wide:
        return {s: sp.Rational(rng.randint(40, 400), rng.randint(37, 211)) for s in params}
    return {s: sp.Rational(rng.randint(4, 16), 8) for s in params}


def solve(problem: Problem, what: str, max_degree: int = MAX_PARAMETER_DEGREE) -> list:
    """The solutions: lists of n coefficients (sympy, polynomial in the atoms; rational
    when there are no parameters), a basis over the rational functions of the parameters."""
    n = problem.n
    rng = random.Random(20240614)
    theta0 = random_parameters(problem.parameters, rng, wide=True)
    keep = independent_columns(problem, rng, theta0)
    m = len(keep)
    if m > BUDGET:
        raise budget_error(m, f"{what}: independent ansatz functions on the constraint "
                              f"manifold, of {n} written")
    rows0 = [r for r, _ in problem.rows(rng, 2 * m + 4, theta0, columns=keep)]
    A, piv = _rref(rows0, m)
    null = []
    for v in _null_vectors(A, piv, m):
        full = [mpmath.mpf(0)] * n
        for j, x in zip(keep, v):
            full[j] = x
        null.append(full)
    if not null:
        return []
    # the functions of the null vectors at random points (theta0): their rank is r
    pts = problem.points(rng, len(null) + 4, theta0)
    F = [problem.values(p) for p in pts]
    with mpmath.workdps(DPS):
        # with the constant function first: solutions that are constants do not count
        r = _rank([[mpmath.mpf(1)] + [_combine(f, v) for v in null] for f in F]) - 1
    if r == 0:
        return []
    support = sorted({j for v in null for j in range(n) if abs(v[j]) > _TOL})
    atoms = problem.atoms
    if not atoms:
        return _reduce(problem, [_read(v) for v in null], support, (), [()], r)[0]
    found, d = [], 0
    for d in range(max_degree + 1):
        monos = [e for k in range(d + 1) for e in exponents(len(atoms), k)]
        cols = [(j, e) for j in support for e in monos]
        if len(cols) > BUDGET:
            break
        rows = []
        where = {j: i for i, j in enumerate(support)}
        for row, p in problem.rows(rng, 2 * len(cols) + 4, columns=support):
            th = _atom_values(atoms, p)
            with mpmath.workdps(DPS + 10):
                tv = {e: power_product(th, e) for e in monos}
                rows.append([to_mpf(row[where[j]]) * tv[e] for j, e in cols])
        A, piv = _rref(rows, len(cols))
        vecs = [_read(v) for v in _null_vectors(A, piv, len(cols))]
        found, rank = _reduce(problem, vecs, support, atoms, cols, r, monos)
        if rank == r:
            return found
    warnings.warn(
        f"{what}: {r - len(found)} of the {r} solutions at generic parameter values have "
        f"coefficients that are not polynomial of degree <= {d} in the parameters "
        f"{[str(a) for a in atoms]} within the budget of {BUDGET} unknowns; pass "
        "coefficients that carry those parameter factors", JetnhWarning, stacklevel=3)
    return found


def independent_columns(problem, rng, theta) -> list:
    """The unknowns whose ansatz functions are linearly independent at random points
    (parameters ``theta``), each kept when it is not a combination of those before it:
    a basis of the ansatz modulo the functions that vanish where the points lie (the
    constraint manifold), so the solve neither meets trivial solutions nor loses any.
    Float64 with a relative threshold of 1e-9 on the orthogonalized column (exact
    dependencies leave 1e-15)."""
    n = problem.n
    with np.errstate(all="ignore"):
        F = problem.float_values(problem.raw_points(rng, 2 * n + 20, theta))
    F = F[np.all(np.isfinite(F), axis=1)][:n + 10]       # regular points only
    norms = np.linalg.norm(F, axis=0)
    keep, Q = [], np.zeros((F.shape[0], 0))
    for j in range(n):
        if not np.isfinite(norms[j]) or norms[j] == 0:
            continue
        v = F[:, j] / norms[j]
        for _ in range(2):                              # Gram-Schmidt, twice
            v = v - Q @ (Q.T @ v)
        size = np.linalg.norm(v)
        if size > 1e-9:
            keep.append(j)
            Q = np.column_stack([Q, v / size])
    return keep


def to_mpf(x):
    """A value as an mpf (exact rationals converted at the working precision)."""
    if isinstance(x, sp.Rational):
        return mpmath.mpf(int(x.p)) / int(x.q)
    if isinstance(x, (Fraction, int)):
        x = Fraction(x)
        return mpmath.mpf(x.numerator) / x.denominator
    return mpmath.mpf(x)


def _atom_values(atoms, point):
    with mpmath.workdps(DPS + 10):
        return [to_mpf(point[a]) if a in point else dag.evaluate(a, point, dps=DPS + 10)
                for a in atoms]


def power_product(u, e):
    """prod u_k^e_k of numbers (mpmath or exact), skipping the zero exponents."""
    r = 1
    for x, k in zip(u, e):
        if k:
            r = r * x**k
    return r


# ---------------------------------------------------------------------- reduction
def _reduce(problem, vecs, support, atoms, cols, r, monos=None):
    """A basis over the rational functions of the atoms, lowest parameter degree first:
    each vector is kept when its ansatz function at random points (one random value of
    the atoms) is independent of those kept.  Returns (solutions, rank)."""
    n = problem.n
    rng = random.Random(99)
    theta1 = random_parameters(problem.parameters, rng, wide=True)
    pts = problem.points(rng, len(support) + 4, theta1)
    F = [problem.values(p) for p in pts]
    th = _atom_values(atoms, pts[0]) if atoms else []
    deg = {e: sum(e) for e in (monos or [()])}

    def coeffs(v):          # per unknown: its coefficient value at theta1
        c = [mpmath.mpf(0)] * n
        for (j, e), x in zip(cols if atoms else [(j, ()) for j in range(n)], v):
            if x:
                c[j] += to_mpf(x) * (power_product(th, e) if atoms else 1)
        return c

    if atoms:
        levels = sorted({max((deg[e] for (j, e), x in zip(cols, v) if x), default=0)
                         for v in vecs})
        ordered = []
        for k in levels:                        # V_k: the solutions of degree <= k
            high = [i for i, (j, e) in enumerate(cols) if deg[e] > k]
            M = sp.Matrix([[v[i] for v in vecs] for i in high]) if high else \
                sp.zeros(0, len(vecs))
            basis = M.nullspace() if high else [sp.eye(len(vecs))[:, i] for i in range(len(vecs))]
            for b in basis:
                ordered.append([sum(b[i] * vecs[i][c] for i in range(len(vecs)))
                                for c in range(len(cols))])
    else:
        ordered = vecs
    kept, rows = [], []
    _extends(rows, [Fraction(1)] * len(F))      # constants are not solutions
    for v in ordered:
        with mpmath.workdps(DPS + 10):
            c = coeffs(v)
            w = [_frac(_combine(f, c)) for f in F]
        if _extends(rows, w):
            kept.append(v)
            if len(kept) == r:
                break
    out = []
    for v in kept:
        c = [sp.S.Zero] * n
        for (j, e), x in zip(cols if atoms else [(j, ()) for j in range(n)], v):
            if x:
                c[j] += x * (monomial(atoms, e) if atoms else 1)
        out.append(c)
    return out, len(kept)


def _combine(f, c):
    """sum_j f_j c_j, or 0 when it is below 1e-30 of the sum of |f_j c_j| (an exact
    cancellation, e.g. sin^2 + cos^2 - 1, seen at finite precision)."""
    terms = [to_mpf(f[j]) * c[j] for j in range(len(c)) if c[j]]
    v = mpmath.fsum(terms)
    return v if abs(v) > _TOL * mpmath.fsum(abs(x) for x in terms) else mpmath.mpf(0)


def _frac(x):
    return Fraction(mpmath.nstr(x, DPS))


def _extends(rows, w):
    """Gaussian elimination of w against the echelon ``rows`` (Fractions); appends and
    returns True when w is independent (numerically: above 1e-30 relative)."""
    w = list(w)
    scale = max((abs(x) for x in w), default=0)
    for piv, row in rows:
        if w[piv]:
            f = w[piv] / row[piv]
            w = [a - f * b for a, b in zip(w, row)]
    k = max(range(len(w)), key=lambda i: abs(w[i]), default=None)
    if k is None or not scale or abs(w[k]) <= Fraction(1, 10**30) * scale:
        return False
    rows.append((k, w))
    return True


# ---------------------------------------------------------------------- linear algebra
def _rref(rows, n):
    """Reduced row echelon form of the rows (50 digits; scaled partial pivoting) in fixed
    point: integers times 2^-256.  Returns (rows, pivot columns)."""
    P = 256
    tol = int(_TOL * 2**P)
    with mpmath.workdps(DPS):
        A = []
        for r in rows:
            r = [to_mpf(v) for v in r]
            r = [v if abs(v) > _ZERO else 0 for v in r]     # cancellation noise
            s = max((abs(v) for v in r), default=0)
            if s:
                A.append([int(mpmath.nint(v / s * 2**P)) for v in r])
    piv, i = [], 0
    for j in range(n):
        k = max(range(i, len(A)), key=lambda k: abs(A[k][j]), default=None)
        if k is None or abs(A[k][j]) < tol:
            continue
        A[i], A[k] = A[k], A[i]
        p = A[i][j]
        A[i] = [0] * j + [(v << P) // p for v in A[i][j:]]
        row = A[i][j:]
        for k2 in range(len(A)):
            f = A[k2][j]
            if k2 != i and f:
                A[k2][j:] = [a - ((f * b) >> P) for a, b in zip(A[k2][j:], row)]
        piv.append(j)
        i += 1
    return A, piv


def _null_vectors(A, piv, n):
    """The null basis of the RREF (mpf entries), one vector per free column."""
    P = 256
    pset = set(piv)
    out = []
    with mpmath.workdps(DPS):
        for f in (j for j in range(n) if j not in pset):
            vec = [mpmath.mpf(0)] * n
            vec[f] = mpmath.mpf(1)
            for r, j in enumerate(piv):
                vec[j] = -mpmath.mpf(A[r][f]) / 2**P
            out.append(vec)
    return out


def _rank(M):
    """The numeric rank (50 digits) of a small matrix of mpf values."""
    if not M or not M[0]:
        return 0
    A, piv = _rref(M, len(M[0]))
    return len(piv)


def _read(vec):
    return [_rational(x) if x else sp.S.Zero for x in vec]


def _rational(x):
    with mpmath.workdps(DPS):
        fr = Fraction(mpmath.nstr(x, DPS)).limit_denominator(10**12)
        if abs(x - mpmath.mpf(fr.numerator) / fr.denominator) > _TOL * max(1, abs(x)):
            raise JetnhError(
                f"a solution has the coefficient {mpmath.nstr(x, 20)}, not a rational "
                "number: jetnh finds solutions with rational coefficients only; pass "
                "coefficients that absorb the irrational factor")
    return sp.Rational(fr.numerator, fr.denominator)


def budget_error(count, detail, budget=BUDGET):
    return ArgumentError(
        f"the ansatz has {count} unknowns ({detail}), over the budget of {budget}; lower "
        "degree or pass fewer coefficients (e.g. coefficients=[1])")
