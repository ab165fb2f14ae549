"""Equivalence of principles: identically, on the branch (32), along states; where the
verdicts hold (the singular sets of the acceleration systems)."""

import random

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings

import jetnh.strategies as jst
from jetnh import JetSpace, System, compare
from jetnh.algebra import dag
from jetnh.mechanics.equivalence import agrees, defect_along, frobenius_T, singular_set
from jetnh.errors import PrincipleError
from jetnh.models import appell_hamel, rolling_disk
from jetnh.algebra.zero import vanishes


def test_disk_verdicts():
    s = rolling_disk()
    assert compare(s, "chetaev", "suslov").identical
    assert compare(s, "vakonomic", "holder").identical
    c = compare(s, "vakonomic", "suslov")
    assert not c.identical and c.on_branch_32 and c.branch_invariant   # Chaplygin


def _disk_with_spring():
    J = JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2, k = sp.symbols("R I1 I2 k")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2 - k * x**2 / 2
    return System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid],
                  dependent=[x, y])


def test_branch_32_is_not_invariant_when_dLtilde_dqalpha_is_not_zero():
    """A spring on the dependent x: the accelerations agree at states with lambda = -p,
    but d/dt(lambda_x + p_x) = dL~/dx = -k x there, so the vakonomic motion leaves the
    branch and the principles share no solution through it."""
    s = _disk_with_spring()
    c = compare(s, "vakonomic", "suslov")
    assert c.on_branch_32 and c.branch_invariant is False
    assert "leaves the branch" in str(c) and "no solutions" in str(c)
    # two routes to the rate on the branch: jetnh's flow, and dL~/dq^alpha by hand
    from jetnh.mechanics.equivalence import branch_32, branch_rates

    v = s.equations("vakonomic")
    sub = branch_32(s, v.multipliers, v.explicit)
    rates = branch_rates(s, v)
    hand = [sp.diff(s.L_tilde, q) for q in s.dependent]
    assert agrees(s, [r - h for r, h in zip(rates, hand)], derived=sub)
    assert not agrees(s, rates, derived=sub)


def full_matrix(s, lams):
    """The vakonomic acceleration system's matrix in (q'', lambda'), from L and f by
    sympy (not by jetnh's solve): [[H + lambda_a G^a, A^T], [A, 0]]."""
    qd = s.J.qd
    H = sp.hessian(s.L, qd)
    for f, lam in zip(s.constraints, lams):
        H += lam * sp.hessian(f, qd)
    A = sp.Matrix(s.constraints).jacobian(qd)
    return H.row_join(A.T).col_join(A.row_join(sp.zeros(s.k, s.k)))


def point(s, syms, rng, dps=50):
    """Random values (mpf) for ``syms``, dependent velocities from phi."""
    with mpmath.workdps(dps):
        pt = {x: mpmath.mpf(rng.uniform(0.3, 1.4)) for x in syms
              if x not in s.dependent_velocities}
        for v in s.dependent_velocities:
            pt[v] = dag.evaluate(s.phi[v], pt, dps=dps)
    return pt


def relative_det(M, pt, dps=50):
    """|det M| / prod of its row norms at ``pt`` (Hadamard: at most 1)."""
    with mpmath.workdps(dps):
        vals = dag.evaluate(list(M), pt, dps=dps)
        Mn = mpmath.matrix([vals[i * M.cols:(i + 1) * M.cols] for i in range(M.rows)])
        bound = mpmath.fprod(mpmath.norm(Mn[i, :]) for i in range(M.rows))
        return abs(mpmath.det(Mn)) / bound


def test_appell_hamel_agrees_off_the_singular_branch():
    s = appell_hamel()
    c = compare(s, "vakonomic", "suslov")
    assert c.identical and c.on_branch_32 is None
    lam = s.equations("vakonomic").multipliers[0]
    m, a, b = sp.symbols("m a b")
    xd, yd, _ = s.J.qd
    branch = [f for f in c.singular if lam in f.free_symbols]
    assert len(branch) == 1 and c.singular[0] == branch[0]
    # the branch, solved from the factor: lambda_z = a m |v| / b
    (sol,) = sp.solve(branch[0], lam)
    assert vanishes(sol - a * m * sp.sqrt(xd**2 + yd**2) / b)
    # the other factors: the constraint's kink, the mass, the parameter a (b/a)
    assert set(c.singular) - {branch[0]} == {xd**2 + yd**2, m, a}
    # the full system (built from L and f by sympy) is singular on the branch, with the
    # kernel q'' = (-ydot, xdot, 0), lambda' = 0: the motion is not unique there
    M = full_matrix(s, [lam])
    on = {lam: a * m * sp.sqrt(xd**2 + yd**2) / b}
    assert vanishes(M.det(method="berkowitz").xreplace(on), s)
    assert all(vanishes(e, s) for e in M.xreplace(on) * sp.Matrix([-yd, xd, 0, 0]))
    rng = random.Random(1)
    syms = dag.free_symbols(list(M)) | {lam}
    for _ in range(5):
        assert relative_det(M, point(s, syms, rng)) > 1e-6
    # the verdict says where it holds, within budget
    text = str(c)
    assert "off the singular set" in text and "lambda_z" in text and len(text) < 600
    assert len(repr(c)) < 600
    assert "lambda_z" not in str(compare(s, "chetaev", "suslov"))


def test_a_comparison_text_stays_within_budget():
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2 * (2 + sp.sin(x * y))
    # a long nested constraint: its singular factors are long; the text stays short
    f = zd - sp.sqrt(1 + sum(sp.cos(k * x) * xd**2 + sp.sin(k * y) * yd**2 for k in range(1, 9)))
    c = compare(System(J, L, [f], [z]), "vakonomic", "suslov")
    assert c.singular and len(str(c)) < 1200 and len(repr(c)) < 1200


def test_an_empty_singular_set_reads_as_empty():
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    c = compare(System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], [z]), "chetaev", "suslov")
    assert not c.singular and repr(c).endswith("singular=<0>)")
    assert "singular set" not in str(c)


@settings(max_examples=6)
@given(jst.systems(max_n=3, affine=False))
def test_the_singular_set_is_where_the_vakonomic_system_is_singular(s):
    """Two routes: the factors with multipliers jetnh reports (from its block solve) and
    the determinant of the full system [[H + lambda G, A^T], [A, 0]] (sympy, from L and f):
    on every root lambda_1 of a factor the determinant vanishes, and on every root of the
    determinant some factor vanishes (the other values random)."""
    lams = s.equations("vakonomic").multipliers
    sing = singular_set(s, "vakonomic")
    M = full_matrix(s, lams)
    lam = lams[0]
    branch = [f for f in sing if lam in f.free_symbols]
    syms = sorted(dag.free_symbols(list(M) + sing + list(s.phi.values())) | set(lams),
                  key=lambda x: x.name)
    rng = random.Random(0)
    with mpmath.workdps(50):
        pt = point(s, syms, rng)

        def det_at(v):
            return relative_det(M, {**pt, lam: v})

        # det M is a polynomial in lambda_1 of degree <= n: its coefficients, then roots
        xs = [mpmath.mpf(i) / 3 for i in range(s.J.n + 1)]
        vals = [mpmath.det(mpmath.matrix([[e for e in row] for row in _rows(M, {**pt, lam: v})]))
                for v in xs]
        coeffs = mpmath.lu_solve(mpmath.matrix([[v**j for j in range(s.J.n, -1, -1)] for v in xs]),
                                 mpmath.matrix(vals))
        coeffs = list(coeffs)
        scale = max(abs(c) for c in coeffs)
        while coeffs and abs(coeffs[0]) < mpmath.mpf(10)**-30 * scale:
            coeffs.pop(0)
        roots = mpmath.polyroots(coeffs, maxsteps=200, extraprec=100) if len(coeffs) > 1 else []
        assert bool(roots) == bool(branch)
        for r in roots:
            worst = min(_relative(f, {**pt, lam: r}) for f in branch)
            assert worst < 1e-20
        for f in branch:
            poly = sp.Poly(f, lam)
            cs = [dag.evaluate(c, pt, dps=50) for c in poly.all_coeffs()]
            for r in (mpmath.polyroots(cs, maxsteps=200, extraprec=100) if len(cs) > 1 else []):
                assert det_at(r) < 1e-20
            # off the factor (lambda_1 random) the system is regular
            assert det_at(mpmath.mpf(rng.uniform(2, 3))) > 1e-30


def _rows(M, pt):
    vals = dag.evaluate(list(M), pt, dps=50)
    return [vals[i * M.cols:(i + 1) * M.cols] for i in range(M.rows)]


def _relative(f, pt):
    """|f| relative to its terms' sizes at ``pt``."""
    terms = list(sp.Add.make_args(f))
    vals = dag.evaluate([f, *terms], pt, dps=50)
    return abs(vals[0]) / max([mpmath.mpf(1)] + [abs(v) for v in vals[1:]])


def test_agreement_is_decided_on_the_graph_at_two_precisions():
    s = rolling_disk()
    x, y, phi, psi = s.J.q
    # a difference of 1e-25 survives (30-digit arithmetic alone would call it noise)
    assert not agrees(s, sp.sin(psi)**2 + sp.cos(psi)**2 - 1 + sp.Rational(1, 10**25))
    assert agrees(s, sp.sin(psi)**2 + sp.cos(psi)**2 - 1)
    # nested expressions (trees of 3^60 nodes) are never flattened: (e + 1)^2 / (e + 2)
    # and e + 1 / (e + 2) are the same map, iterated 60 times
    e1 = e2 = e3 = psi
    for _ in range(60):
        e1 = (e1 + 1) * (e1 + 1) / (e1 + 2)
        e2 = e2 + 1 / (e2 + 2)
        e3 = e3 + 1 / (e3 + 2 + sp.Rational(1, 10**6))
    assert agrees(s, e1 - e2)
    assert not agrees(s, e1 - e3)


def test_suslov_differs_from_chetaev_when_p_T_is_nonzero():
    J = JetSpace("x y z")
    x, y, z = J.q
    s = System(J, sum(v**2 for v in J.qd) / 2, [J.qd[2] - y * J.qd[0]], [z])
    assert not compare(s, "chetaev", "suslov").identical
    pT = s.on_constraints(s.p_dependent[0]) * s.T()[0, 0]
    assert not vanishes(pT, s)


@settings(max_examples=8)
@given(jst.systems(max_n=3, affine=True))
def test_integrable_iff_T_vanishes(s):
    T_zero = all(vanishes(e, s) for e in s.T()) and all(vanishes(e, s) for e in frobenius_T(s))
    assert T_zero == s.is_integrable()


def test_defect_along_states():
    s = rolling_disk()
    rng = np.random.default_rng(0)
    n = 7
    d = {q.name: rng.uniform(0, 1, n) for q in s.J.q}
    d.update(phi_t=rng.uniform(0, 1, n), psi_t=rng.uniform(0, 1, n), R=np.ones(n),
             I1=np.full(n, 0.5), I2=np.full(n, 0.25))
    assert defect_along(s, "chetaev", "suslov", d) < 1e-12
    d["lambda_x"] = -d["phi_t"] * np.cos(d["psi"])       # lambda = -p: the branch (32)
    d["lambda_y"] = -d["phi_t"] * np.sin(d["psi"])
    assert defect_along(s, "chetaev", "vakonomic", d) < 1e-12
    d["lambda_x"] = d["lambda_x"] + 0.3
    assert defect_along(s, "chetaev", "vakonomic", d) > 1e-3


def test_defect_along_a_nested_system_agrees_with_mpmath():
    """n_trailer (nested accelerations): the largest defect over states, evaluated on the
    graph with numpy, is the largest of the defects evaluated one state at a time with
    mpmath (dag.evaluate, 30 digits)."""
    from jetnh.algebra import dag
    from jetnh.models import n_trailer

    s = n_trailer(N=3)
    rng = np.random.default_rng(1)
    n = 5
    lams = s.equations("vakonomic").multipliers
    free = [x for x in s.J.q + s.independent_velocities + s.parameters + lams]
    d = {x.name: rng.uniform(0.3, 1.2, n) for x in free}
    got = defect_along(s, "chetaev", "vakonomic", d)
    a1 = s.equations("chetaev").accelerations()
    a2 = s.equations("vakonomic").accelerations()
    defects = dag.xreplace([a1[q] - a2[q] for q in s.J.qdd], s.phi)
    ref = max(abs(float(v)) for i in range(n)
              for v in dag.evaluate(defects, {x: d[x.name][i] for x in free}))
    assert ref > 1e-3 and abs(got - ref) <= 1e-9 * ref


def test_large_polynomial_factors_are_kept_whole():
    """A singular factor too large to factor safely (sympy's multivariate factoring can
    take minutes, depending on its random evaluation points) is kept as one factor; small
    ones are factored."""
    from jetnh.algebra import singular

    xs = sp.symbols("a0:8")
    big = sum((k + 1) * xs[k % 8] ** (k % 5) * xs[(3 * k) % 8] ** 2 for k in range(30)) + 1
    assert not singular._factorable(sp.expand(big))
    assert singular._split(sp.expand(big)) == [sp.expand(big)]
    small = sp.expand((xs[0] + xs[1]) * (xs[2] - 3))
    assert set(singular._split(small)) == {xs[0] + xs[1], xs[2] - 3}


def test_compare_takes_aliases_and_reports_canonical_names():
    s = rolling_disk()
    by_alias = compare(s, "nonholonomic", "hoelder")
    by_name = compare(s, "chetaev", "holder")
    assert by_alias.principles == by_name.principles == ("chetaev", "holder")
    assert by_alias.identical == by_name.identical
    assert [sp.srepr(by_alias.defects[q]) for q in s.J.qdd] == \
        [sp.srepr(by_name.defects[q]) for q in s.J.qdd]


def test_compare_refuses_one_principle_twice():
    with pytest.raises(PrincipleError, match="both chetaev"):
        compare(rolling_disk(), "chetaev", "Lagrange-d'Alembert")


def test_singular_factors_are_drawn_out_and_declared_signs_kept():
    """Closed forms: a sum that is a monomial after sin^2 = 1 - cos^2 is that monomial's
    factors; a sum too large to factor has its terms' common factors drawn out; a
    parameter declared positive is never in the set."""
    from jetnh.algebra.singular import singular_set

    m, r, q2, x, a, b, c, d = sp.symbols("m r q2 x a b c d")
    M = sp.Symbol("M", positive=True)
    e = (45 * m**3 * r**6 * sp.sin(q2)**2 / 16 + 75 * m**3 * r**6 * sp.cos(q2)**2 / 32
         - 45 * m**3 * r**6 / 16)                     # = -15/32 m^3 r^6 cos(q2)^2
    assert singular_set([1 / e]) == [m, r, sp.cos(q2)]
    big = sp.expand(m**3 * r**6 * (sp.sin(a) + sp.cos(b) + sp.sin(c) + sp.cos(d) + x))
    assert singular_set([1 / big]) == [m, r, x + sp.sin(a) + sp.sin(c) + sp.cos(b) + sp.cos(d)]
    assert singular_set([1 / (m * x)]) == [m, x] and singular_set([1 / (M * x)]) == [x]
    assert singular_set([sp.sqrt(M - x**2) / M]) == [M - x**2]
