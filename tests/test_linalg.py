"""Symbolic solves that add no singularity: Cramer with shared minors (k <= 6), LU with
pivots chosen by value (larger k); checked against numeric solves at chosen points."""

import random

import mpmath
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from jetnh import JetSpace, System
from jetnh.algebra import dag, linalg
from jetnh.errors import JetnhError


def rotation(n, i, j, th):
    M = sp.eye(n)
    c, s = sp.cos(th), sp.sin(th)
    M[i, i] = M[j, j] = c
    M[i, j], M[j, i] = -s, s
    return M


def rotations(k, angles):
    """A product of plane rotations: det 1 everywhere, every entry zero somewhere."""
    planes = [(i, (i + 1) % k) for i in range(k)] + [(0, 2)]
    R = sp.eye(k)
    for (i, j), th in zip(planes, angles):
        R = R * rotation(k, i, j, th)
    return R


def old_pivots(M):
    """The pivots the form-based LU (shortest entry first) divided by."""
    A = M.copy().as_mutable()
    out = []
    for col in range(A.rows):
        best = min(range(col, A.rows), key=lambda r: linalg._pivot_cost(A[r, col]))
        A.row_swap(best, col)
        out.append(A[col, col])
        for r in range(col + 1, A.rows):
            fac = A[r, col] / A[col, col]
            for j in range(col, A.cols):
                A[r, j] = A[r, j] - fac * A[col, j]
    return out


def values(exprs, point, dps=40):
    with mpmath.workdps(dps):
        return [complex(v) for v in dag.evaluate(list(exprs), point, dps=dps)]


def rotation_system(k):
    names = " ".join(f"x{i}" for i in range(1, k + 1))
    J = JetSpace(names + " u w")
    u, w = J.q[k:]
    ud, wd = J.qd[k:]
    R = rotations(k, [u, w, u + w, u - w, 2 * u - w, w - u / 2][:k + 1])
    b = sp.Matrix([ud, wd, ud * sp.cos(w), wd * sp.sin(u) + 1, ud * wd, 1 + u * ud][:k])
    f = R * sp.Matrix(J.qd[:k]) - b
    L = sum(v**2 for v in J.qd) / 2 - sp.cos(u) * sp.sin(w)
    return System(J, L, list(f), list(J.q[:k])), R, b


@pytest.mark.parametrize("k", [4, 5])
def test_a_regular_split_of_rotations_is_solved_where_old_pivots_vanish(k):
    s, R, b = rotation_system(k)
    J = s.J
    u, w = J.q[k:]
    ud, wd = J.qd[k:]
    # the old LU divided by entries that vanish on u = w (k = 4) or elsewhere
    piv = old_pivots(R)
    zeros = []
    for p in piv[:2]:
        for th in (sp.Rational(7, 10), sp.Rational(3, 10)):
            sol = [z for z in sp.solve(p.xreplace({u: th}), w) if z.is_real]
            zeros += [{u: th, w: z} for z in sol[:1]]
    assert zeros, "the test needs points where the old pivots vanish"
    with linalg.divisors() as divs:
        phi = [s.phi[v] for v in s.dependent_velocities]
    assert len(divs) == 1                       # only det R
    acc = s.equations("chetaev").accelerations()
    qdd = [acc[a] for a in J.qdd]
    for pt in zeros + [{u: sp.Rational(1, 3), w: sp.Rational(5, 4)}]:
        point = {**pt, ud: sp.Rational(2, 5), wd: sp.Rational(-11, 10)}
        # the old pivot is zero here, the determinant is 1
        assert any(abs(values([p], point)[0]) < 1e-30 for p in piv) or pt[u] == sp.Rational(1, 3)
        assert abs(values(divs, point)[0] - 1) < 1e-30
        # phi = R^T b (R orthogonal), finite
        ref = (R.T * b).xreplace(point)
        got = values(phi, point)
        assert max(abs(g - complex(r.evalf(40))) for g, r in zip(got, ref)) < 1e-12
        # the accelerations against a numeric solve of [[H, -A^T], [A, 0]] there
        full = {**point, **{v: sp.Float(complex(g).real, 40) for v, g in
                            zip(s.dependent_velocities, got)}}
        exp = numeric_chetaev(s, full)
        got_a = values(qdd, full)
        assert max(abs(g - e) for g, e in zip(got_a, exp)) < 1e-12


def numeric_chetaev(s, point):
    """q'' of H q'' - A^T mu = r, A q'' = -v ([L] + mu A = 0 and D f = 0) by mpmath."""
    J = s.J
    q, qd = J.q, J.qd
    L = s.L
    H = sp.hessian(L, qd)
    r = sp.Matrix([sp.diff(L, q[i]) - sum(sp.diff(L, qd[i], q[j]) * qd[j] for j in range(J.n))
                   - sp.diff(L, qd[i], J.t) for i in range(J.n)])
    f = sp.Matrix(s.constraints)
    A = f.jacobian(qd)
    v = f.jacobian(q) * sp.Matrix(qd) + sp.diff(f, J.t)
    k, n = s.k, J.n
    M = H.row_join(-A.T).col_join(A.row_join(sp.zeros(k, k)))
    rhs = r.col_join(-v)
    with mpmath.workdps(40):
        Mn = mpmath.matrix([[mpmath.mpf(complex(x).real) for x in values(M.row(i), point)]
                            for i in range(n + k)])
        bn = mpmath.matrix([mpmath.mpf(complex(x).real) for x in values(rhs, point)])
        sol = mpmath.lu_solve(Mn, bn)
        return [complex(sol[i]) for i in range(n)]


def test_lu_pivots_by_value_for_large_systems():
    """k = 7 (LU): the form-based choice divided by x (zero at x = 0) and by
    sin^2 + cos^2 - 1 (zero everywhere); the value-based one by neither."""
    x, y = sp.symbols("x y")
    k = 7
    M = sp.eye(k) * (3 + sp.cos(y))
    M[0, 0] = x
    M[1, 0] = 2 + sp.sin(x) * sp.cos(y)
    M[0, 1] = sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1 + 1
    M[2, 0] = sp.Rational(1, 3) * (sp.sin(y) ** 2 + sp.cos(y) ** 2 - 1)
    M[3, 2], M[2, 3] = y, -y
    for i in range(1, k):
        M[i, i - 1] = M[i, i - 1] or sp.cos(x * i)
    rhs = sp.Matrix([sp.sin(i * x + y) for i in range(k)])
    piv = old_pivots(M)
    assert piv[0] == x
    with linalg.divisors() as divs:
        X = linalg.solve(M, rhs)
    assert all(d != x for d in divs)
    for pt in ({x: 0, y: sp.Rational(1, 2)}, {x: sp.Rational(9, 10), y: sp.Rational(1, 7)}):
        got = values(X, pt)
        with mpmath.workdps(40):
            Mn = mpmath.matrix([[complex(v).real for v in values(M.row(i), pt)] for i in range(k)])
            ref = mpmath.lu_solve(Mn, mpmath.matrix([complex(v).real for v in values(rhs, pt)]))
        assert max(abs(g - complex(ref[i])) for i, g in enumerate(got)) < 1e-12


def test_lu_never_divides_by_an_entry_that_is_zero_in_value():
    x, y = sp.symbols("x y")
    k = 7
    zero = sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1           # short, nonzero in form, 0 in value
    M = sp.eye(k) + sp.Matrix(k, k, lambda i, j: sp.cos(i * x + j * y) / 5 if i != j else 0)
    M[0, 0] = zero
    X = linalg.solve(M, sp.ones(k, 1))
    got = values(X, {x: sp.Rational(1, 2), y: sp.Rational(1, 3)})
    assert all(abs(g) < 1e3 for g in got)


@settings(max_examples=10, deadline=None)
@given(st.integers(4, 8), st.integers(0, 10**6))
def test_solves_match_numeric_solves(k, seed):
    """Random dense trigonometric matrices, k = 4..8 (Cramer and LU), at random points."""
    rng = random.Random(seed)
    x, y = sp.symbols("x y")
    M = sp.Matrix(k, k, lambda i, j: rng.randint(-3, 3) + rng.choice(
        [sp.sin, sp.cos])(rng.randint(1, 3) * x - rng.randint(0, 2) * y))
    rhs = sp.Matrix(k, 2, lambda i, j: rng.randint(-2, 2) * x + sp.cos(j * y))
    X = linalg.solve(M, rhs)
    pt = {x: sp.Rational(rng.randint(1, 99), 37), y: sp.Rational(rng.randint(1, 99), 41)}
    with mpmath.workdps(40):
        Mn = mpmath.matrix([[complex(v).real for v in values(M.row(i), pt)] for i in range(k)])
        if abs(mpmath.det(Mn)) < mpmath.mpf(10) ** -10:
            return
        got = values(X, pt)
        for j in range(2):
            ref = mpmath.lu_solve(Mn, mpmath.matrix([complex(v).real
                                                     for v in values(rhs.col(j), pt)]))
            scale = 1 + max(abs(complex(ref[i])) for i in range(k))
            assert max(abs(got[i * 2 + j] - complex(ref[i])) for i in range(k)) < 1e-12 * scale


def test_completing_puts_the_pivot_points_on_a_manifold():
    """An entry v - x^2 is zero on the manifold v = x^2 only: with ``completing`` the
    value-based choice sees it as zero there and never divides by it."""
    x, v = sp.symbols("x v")
    k = 7
    M = sp.eye(k) * 2 + sp.Matrix(k, k, lambda i, j: sp.sin(i * x + j) / 9 if i != j else 0)
    M[0, 0] = 10 * (v - x**2)
    M[1, 0] = 1 + x * v
    with linalg.divisors() as free:
        linalg.solve(M, sp.ones(k, 1))

    def on(values):
        values = dict(values)
        values[v] = values[x] ** 2
        return values
    with linalg.completing(on), linalg.divisors() as bound:
        X = linalg.solve(M, sp.ones(k, 1))
    assert free[0] == M[0, 0]                   # off the manifold it looks largest
    assert all(d != M[0, 0] for d in bound)
    got = values(X, {x: sp.Rational(1, 2), v: sp.Rational(1, 4)})
    assert all(abs(g) < 1e3 for g in got)


@pytest.mark.parametrize("k", [12, 24])
def test_lu_keeps_a_triangular_block_sparse(k):
    """A lower-triangular block with a full first column (the N-trailer's split): the
    sparsest acceptable row is the pivot (Markowitz), so the solve has no fill-in -- its
    size grows like k^2, not k^3 -- and divides by the diagonal alone (the factors of
    det M), never by an entry of the first column (a singularity M does not have)."""
    xs = sp.symbols(f"x0:{k}")
    M = sp.zeros(k, k)
    for i in range(k):
        M[i, 0] = sp.cos(xs[i])
        for j in range(1, i + 1):
            M[i, j] = 2 + sp.sin(xs[i]) if i == j else xs[i] * xs[j] / 3
    rhs = sp.Matrix([sp.sin(x) + 1 for x in xs])
    with linalg.divisors() as divs:
        X = linalg.solve(M, rhs)
    assert divs == [M[i, i] for i in range(k)]
    assert dag.size(list(X)) < 4 * k * k
    pt = {x: sp.Rational(3 + i % 5, 7) for i, x in enumerate(xs)}
    Mn = mpmath.matrix([[complex(v).real for v in values(M.row(i), pt)] for i in range(k)])
    ref = mpmath.lu_solve(Mn, mpmath.matrix([complex(v).real for v in values(rhs, pt)]))
    got = values(X, pt)
    assert max(abs(got[i] - complex(ref[i])) for i in range(k)) < 1e-12 * (
        1 + max(abs(complex(ref[i])) for i in range(k)))


def test_mp_rank_decides_in_double_only_what_double_can_see():
    """A full rank far from singular is decided in double precision (``_clearly_full``);
    a smallest singular value below double's reach (1e-20 of the largest) is left to the
    high-precision SVD, which finds it above its tolerance (full) -- and an exact rank
    deficiency stays deficient.  Same answers as ``mpmath.svd_r`` alone."""
    with mpmath.workdps(80):
        Q = mpmath.matrix([[1, 2, 0], [0, 1, 3], [2, 0, 1]])
        dependent = mpmath.matrix([[1, 2, 3], [2, 4, 6], [0, 1, 1]])
        # rows that differ by 1e-20 (no scaling of rows or columns separates them)
        hidden = mpmath.matrix([[1, 1, 0], [1, 1 + mpmath.mpf("1e-20"), 0], [0, 1, 1]])
        assert linalg._clearly_full(linalg._equilibrate(Q))
        assert not linalg._clearly_full(linalg._equilibrate(hidden))
        assert linalg.mp_rank(Q) == 3
        assert linalg.mp_rank(hidden) == 3
        assert linalg.mp_rank(dependent) == 2
        s = mpmath.svd_r(linalg._equilibrate(hidden), compute_uv=False)
        assert min(abs(x) for x in s) > linalg._RANK_TOL * max(abs(x) for x in s)


@settings(max_examples=15, deadline=None)
@given(st.integers(1, 9), st.integers(1, 3), st.integers(0, 2**32 - 1), st.booleans())
def test_mp_solve_agrees_with_mpmath(k, m, seed, triangular):
    """linalg.mp_solve (elimination skipping zeros) against mpmath's inverse, dense and
    lower triangular (a chain's A_dep), with a zero on the diagonal's first entry."""
    rng = random.Random(seed)
    with mpmath.workdps(50):
        A = mpmath.matrix([[mpmath.mpf(rng.uniform(-1, 1)) if (j <= i or not triangular)
                            else 0 for j in range(k)] for i in range(k)])
        if k > 1 and not triangular:
            A[0, 0] = 0
        B = mpmath.matrix([[mpmath.mpf(rng.uniform(-1, 1)) for _ in range(m)]
                           for _ in range(k)])
        try:
            ref = mpmath.inverse(A) * B
        except ZeroDivisionError:
            return
        X = linalg.mp_solve(A, B)
        assert (X.rows, X.cols) == (k, m)
        assert mpmath.mnorm(X - ref, 1) <= mpmath.mpf(10) ** -35 * (1 + mpmath.mnorm(ref, 1))


def test_values_beyond_every_precision_are_not_taken_for_zeros():
    """sin(1e100 x) has no correct digit at 50 or 80 digits: its two evaluations disagree
    without the higher one shrinking, so it is not cancellation noise (once set to zero,
    which gave the wrong rank); with no other point to use, a JetnhError says so."""
    x = sp.Symbol("x")
    with pytest.raises(JetnhError, match="cannot decide their generic rank"):
        linalg.numeric_rank(sp.Matrix([[sp.sin(10**100 * x)]]))
    assert linalg.numeric_rank(sp.Matrix([[sp.sin(x) - sp.sin(x) * (1 + 10**-60) + 1]])) == 1


def test_nested_exponentials_are_refused_at_once_not_computed():
    """exp(exp(exp(exp(exp(x))))) at x = 5 has a logarithm beyond 10**dps: mpmath would
    run for hours (or raise MemoryError) computing it; evaluate raises OverflowError, so
    rank sampling skips the point."""
    x = sp.Symbol("x")
    e = x
    for _ in range(5):
        e = sp.exp(e)
    with pytest.raises(OverflowError):
        dag.evaluate(e, {x: 5}, dps=50)
    with pytest.raises(OverflowError):
        dag.evaluate(sp.Integer(2) ** (10**100 * x), {x: 1}, dps=50)
    assert linalg.numeric_rank(sp.Matrix([[e, 0], [0, x]])) == 2


def test_a_tiny_model_with_nested_exponentials_derives_or_says_why_not():
    """L = exp(exp(exp(exp(phi_t)))) + ... on a rolling constraint: its reduced Hessian has
    rank 2.  With a fifth exp (values of size e**(5e78)) the rank cannot be decided at 80
    digits: a JetnhError says so at once (was a bare MemoryError, then a false 'singular:
    rank 1 < 2' from entries set to zero as noise)."""
    import jetnh as jn
    J = jn.JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xt, yt, pt, st = J.qd
    f = pt
    for levels in (4, 5):
        f = sp.exp(f) if levels == 5 else sp.exp(sp.exp(sp.exp(sp.exp(pt))))
        S = jn.System(J, f + xt**2 + yt**2 + st**2,
                      [xt - sp.cos(psi) * pt, yt - sp.sin(psi) * pt], dependent=[x, y])
        if levels == 4:
            acc = S.equations("chetaev").accelerations()
            assert set(acc) >= {J.qdd[2], J.qdd[3]}
        else:
            with pytest.raises(JetnhError, match="cannot decide their generic rank"):
                S.equations("chetaev").accelerations()


def test_matrix_arithmetic_is_sympys():
    """``add``, ``sub``, ``neg``, ``scaled`` and ``matmul`` give sympy's matrices entry
    for entry (the same children in the same order), zero entries and cancelling ones
    included."""
    x, y, z = sp.symbols("x y z")
    A = sp.Matrix([[x + y, 0, 2 * x], [sp.sin(z), -x * y, 1], [0, x, y - 1]])
    B = sp.Matrix([[x - y, 3, -2 * x], [0, x * y, sp.Rational(1, 2)], [z + 1, 0, y]])
    with sp.matrices.utilities.dotprodsimp(False):
        pairs = [(linalg.add(A, B), A + B), (linalg.sub(A, B), A - B), (linalg.neg(A), -A),
                 (linalg.scaled(A, 1 / (x + z)), A / (x + z)), (linalg.matmul(A, B), A * B)]
    for got, want in pairs:
        assert got.shape == want.shape
        for g, w in zip(got, want):
            assert type(g) is type(w) and g == w and g.args == w.args


def _matrix_lu(M, rhs):
    """The LU solve written with sympy's matrix operations (as it was): the reference
    ``_lu_solve``'s expressions must equal, node for node."""
    A, B, k = M.copy().as_mutable(), rhs.copy().as_mutable(), M.rows
    pending = [[[] for _ in range(B.cols)] for _ in range(k)]
    Ns = [[[N[i, j] for j in range(k)] for i in range(k)] for N in linalg._pivot_values(A)]
    with mpmath.workdps(linalg._PIVOT_DPS):
        scales = [max(abs(x) for row in N for x in row) for N in Ns]
        for col in range(k):
            best = linalg._choose(A.tolist(), Ns, col, scales)
            if best != col:
                A.row_swap(best, col)
                B.row_swap(best, col)
                pending[best], pending[col] = pending[col], pending[best]
                for N in Ns:
                    N[best], N[col] = N[col], N[best]
            for j, terms in enumerate(pending[col]):
                if terms:
                    B[col, j] = sp.Add(B[col, j], *terms)
            for r in range(col + 1, k):
                if A[r, col] != 0:
                    fac = A[r, col] / A[col, col]
                    for j in range(col, k):
                        if A[col, j] != 0:
                            A[r, j] = A[r, j] - fac * A[col, j]
                    for j in range(B.cols):
                        if B[col, j] != 0:
                            pending[r][j].append(-(fac * B[col, j]))
                for N in Ns:
                    top, row = N[col], N[r]
                    if top[col] != 0 and row[col] != 0:
                        nf = row[col] / top[col]
                        for j in range(col, k):
                            if top[j] != 0:
                                row[j] -= nf * top[j]
    X = sp.zeros(k, B.cols)
    for r in range(k - 1, -1, -1):
        X[r, :] = (B[r, :] - A[r, r + 1:] * X[r + 1:, :]) / A[r, r]
    return X


@settings(max_examples=8, deadline=None)
@given(st.integers(7, 9), st.integers(0, 10**6), st.booleans())
def test_lu_builds_the_expressions_sympys_matrices_build(k, seed, sparse):
    """``_lu_solve`` (lists of rows, sums and products by ``dag.build``) makes the
    expressions of the same elimination written with sympy's matrix operations, node
    for node: dense and triangular-ish random trigonometric matrices."""
    rng = random.Random(seed)
    x, y = sp.symbols("x y")

    def entry(i, j):
        if sparse and j > i + 1:
            return sp.S.Zero
        return rng.randint(-2, 2) + rng.choice([sp.sin, sp.cos])(rng.randint(1, 3) * x - y)
    M = sp.Matrix(k, k, entry)
    rhs = sp.Matrix(k, 2, lambda i, j: rng.randint(-2, 2) * x + sp.cos(j * y))
    with sp.matrices.utilities.dotprodsimp(False):
        want = _matrix_lu(M, rhs)
    got = linalg._lu_solve(M, rhs)
    for g, w in zip(got, want):
        assert type(g) is type(w) and g == w and g.args == w.args


def test_float_zero_entries_are_sympy_zeros():
    """A Float 0.0 (not == 0 in sympy) is no pivot and adds as sympy's matrices add it:
    a singular matrix of Float zeros is refused, not solved into NaN; 0.0 + 2 is 2.0."""
    zero = sp.Float(0.0)
    with pytest.raises(ZeroDivisionError):
        linalg._lu_solve(sp.Matrix([[zero, 1], [zero, 2]]), sp.Matrix([1, 2]))
    x = sp.Symbol("x")
    M = sp.Matrix([[zero, 1], [1, x]])
    assert linalg._lu_solve(M, sp.Matrix([1, 2])) == sp.Matrix([2 - x, 1])
    for op, ref in ((linalg.add, sp.Matrix.__add__), (linalg.sub, sp.Matrix.__sub__)):
        got = op(sp.Matrix([[zero, x]]), sp.Matrix([[2, zero]]))
        want = ref(sp.Matrix([[zero, x]]), sp.Matrix([[2, zero]]))
        assert got == want and [type(e) for e in got] == [type(e) for e in want]
