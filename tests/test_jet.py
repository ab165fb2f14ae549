"""Tests of jetnh.geometry.jet: the jet space, the total derivative D, the Euler operator, conversions.

Identities are checked on random expressions from jetnh.strategies, numerically at random
points with 40-digit arithmetic (fast, and exact enough to see any real discrepancy),
and on hand-computed examples exactly.
"""

from __future__ import annotations

import random

import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st
from sympy.calculus.euler import euler_equations
from sympy.physics.vector import dynamicsymbols

import jetnh as jn
import jetnh.strategies as jst
from jetnh import JetnhError, JetSpace, JetSpaceError

PREC = 40          # digits used for numeric evaluation
TOL = 1e-20        # relative tolerance at that precision

randoms = st.randoms(use_true_random=False)

# sympy's own routes (euler_equations, diff of dynamicsymbols) are slow: the tests that
# use them as references run 2/5 of the profile's examples (10 in "ci", 120 in "dev").
fewer = settings(max_examples=max(5, settings.default.max_examples * 2 // 5))


# ------------------------------------------------------------------ numeric helpers
def _point(exprs, rnd: random.Random) -> dict:
    """Random values in [-1.5, 1.5] for every free symbol of ``exprs``."""
    syms = set()
    for e in exprs:
        syms |= sp.sympify(e).free_symbols
    return {s: sp.Float(rnd.uniform(-1.5, 1.5), PREC) for s in sorted(syms, key=str)}


def _num(expr, point):
    v = sp.sympify(expr).xreplace(point).evalf(PREC)
    assert v.is_number, f"leftover symbols in {v}"
    assert v.is_finite, f"{expr} is not finite at {point}"
    return v


def assert_num_equal(a, b, rnd: random.Random, points: int = 2):
    """a == b at ``points`` random points, to relative tolerance TOL."""
    for _ in range(points):
        p = _point([a, b], rnd)
        va, vb = _num(a, p), _num(b, p)
        assert abs(va - vb) <= TOL * (1 + abs(va) + abs(vb)), (
            f"\n  {a}\n  != {b}\n  at {p}: {va} vs {vb}")


def assert_num_zero(a, rnd: random.Random, points: int = 2):
    assert_num_equal(a, sp.S.Zero, rnd, points)


def _exprs(J, **kw):
    return jst.jet_expressions(J, **kw)


def test_numeric_helper_sees_differences():
    J = JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    rnd = random.Random(0)
    assert_num_equal(sp.sin(x) ** 2 + sp.cos(x) ** 2, 1, rnd)
    with pytest.raises(AssertionError):
        assert_num_equal(sp.sin(x) * xd, sp.sin(x) * xd * (1 + sp.Rational(1, 10**15)), rnd)
    with pytest.raises(AssertionError):
        assert_num_zero(x * xd + sp.Rational(1, 10**12) * x, rnd)


# ------------------------------------------------------------------ construction, names
def test_coordinates_and_jet_names():
    J = JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    assert J.t == sp.Symbol("t")
    assert [s.name for s in J.q] == ["x", "y", "phi", "psi"]
    assert [s.name for s in J.qd] == ["x_t", "y_t", "phi_t", "psi_t"]
    assert [s.name for s in J.qdd] == ["x_tt", "y_tt", "phi_tt", "psi_tt"]
    assert all(type(s) is sp.Symbol and s.assumptions0 == {"commutative": True}
               for s in J.q + J.qd + J.qdd)
    assert J.n == 4
    assert J.jet(x, 0) is x or J.jet(x, 0) == x
    assert J.jet("phi", 3) == sp.Symbol("phi_ttt")
    assert J.jet(psi, 7).name == "psi_" + "t" * 7
    assert J.jets(1) == J.qd and J.jets(2) == J.qdd and J.jets(0) == J.q
    assert J.jets(2, of=[y, psi]) == (sp.Symbol("y_tt"), sp.Symbol("psi_tt"))


@pytest.mark.parametrize("spec", ["x y", "x, y", " x ,y ", ["x", "y"],
                                  [sp.Symbol("x"), "y"], ("x", sp.Symbol("y"))])
def test_name_specs_give_equal_values(spec):
    J = JetSpace(spec)
    assert J == JetSpace("x y") and hash(J) == hash(JetSpace("x y"))
    assert J.q == sp.symbols("x y")
    assert J != JetSpace("y x") and J != JetSpace("x y", t="s")
    assert J != JetSpace("x y").with_fields("lam")


def test_split():
    J = JetSpace("x q_1").with_fields("lam")
    x, q1 = J.q
    (lam,) = J.fields
    assert J.split(x) == (x, 0)
    assert J.split(sp.Symbol("x_ttt")) == (x, 3)
    assert J.split(sp.Symbol("q_1_tt")) == (q1, 2)
    assert J.split(sp.Symbol("lam_t")) == (lam, 1)
    assert J.split(J.t) is None
    assert J.split(sp.Symbol("z_t")) is None
    assert J.split(sp.Symbol("m")) is None
    assert J.split(sp.Symbol("x_tx")) is None


def test_order_examples():
    J = JetSpace("x y")
    (x, y), (xd, yd), (xdd, ydd) = J.q, J.qd, J.qdd
    assert J.order(J.t) == -1
    assert J.order(sp.Integer(5)) == -1
    assert J.order(5) == -1
    assert J.order(sp.Symbol("k") * J.t) == -1
    assert J.order(x) == 0
    assert J.order(x * yd + J.t) == 1
    assert J.order(xdd * y + J.t) == 2
    assert J.order(xdd * y, of=[y]) == 0
    assert J.order(xdd * y, of=[x]) == 2
    assert J.order(sp.sin(J.jet(x, 5)) + ydd) == 5


@given(st.data())
def test_order_of_generated_expressions(data):
    J = data.draw(jst.jet_spaces(1, 3))
    k = data.draw(st.integers(0, 2))
    e = data.draw(_exprs(J, order=k, max_depth=2))
    assert J.order(e) <= k
    top = J.order(e)
    De = J.D(e)
    assert J.order(De) <= top + 1
    if top >= 0:
        # D(e) contains q^s_(top+1) exactly for the bases on whose top jet e depends
        for b in J.q:
            assert (J.jet(b, top + 1) in De.free_symbols) == (sp.diff(e, J.jet(b, top)) != 0)
        assert J.order(De) == top + 1


# ------------------------------------------------------------------ the total derivative
def test_D_examples():
    J = JetSpace("x y")
    (x, y), (xd, yd), (xdd, ydd) = J.q, J.qd, J.qdd
    t = J.t
    assert J.D(x) == xd
    assert J.D(xd) == xdd
    assert J.D(J.jet(y, 4)) == J.jet(y, 5)
    assert J.D(t) == 1
    assert J.D(sp.Integer(7)) == 0
    assert J.D(3) == 0
    assert J.D(sp.Symbol("k")) == 0                       # a parameter is constant
    assert sp.expand(J.D(x * y) - (xd * y + x * yd)) == 0
    assert sp.expand(J.D(t**2 * sp.sin(x)) - (2 * t * sp.sin(x) + t**2 * sp.cos(x) * xd)) == 0
    assert sp.expand(J.D(xd**2 / 2 + sp.cos(x)) - (xd * xdd - sp.sin(x) * xd)) == 0


@given(st.data(), randoms)
def test_D_is_linear(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    a = data.draw(_exprs(J, order=1, max_depth=2))
    b = data.draw(_exprs(J, order=1, max_depth=2))
    c = data.draw(st.integers(-5, 5)) / sp.Integer(data.draw(st.integers(1, 4)))
    k = sp.Symbol("k")                                   # a parameter scales too
    assert_num_equal(J.D(c * a + k * b), c * J.D(a) + k * J.D(b), rnd)


@given(st.data(), randoms)
def test_D_obeys_leibniz_and_chain_rule(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    a = data.draw(_exprs(J, order=1, max_depth=2))
    b = data.draw(_exprs(J, order=2, max_depth=1))
    Da, Db = J.D(a), J.D(b)
    assert_num_equal(J.D(a * b), Da * b + a * Db, rnd)
    assert_num_equal(J.D(sp.sin(a)), sp.cos(a) * Da, rnd)
    assert_num_equal(J.D(sp.exp(b)), sp.exp(b) * Db, rnd, points=1)


@fewer
@given(st.data(), randoms)
def test_D_agrees_with_time_derivative_of_dynamicsymbols(data, rnd):
    """D is d/dt along curves: compare with sympy's diff of x(t), x'(t), ..."""
    J = data.draw(jst.jet_spaces(1, 3))
    e = data.draw(_exprs(J, order=data.draw(st.integers(0, 2)), max_depth=2))
    k = data.draw(st.integers(1, 2))
    via_sympy = J.from_dynamic(sp.diff(J.to_dynamic(e), dynamicsymbols._t, k))
    assert_num_equal(J.Dk(e, k), via_sympy, rnd)


# ------------------------------------------------------------------ Dk
def test_Dk_examples():
    J = JetSpace("x")
    (x,) = J.q
    t = J.t
    assert J.Dk(x, 0) == x
    for k in range(6):
        assert J.Dk(x, k) == J.jet(x, k)
    assert J.Dk(t**3, 3) == 6
    assert J.Dk(t**3, 4) == 0
    assert J.Dk(sp.exp(t), 5) == sp.exp(t)
    assert sp.expand(J.Dk(x**2, 2) - (2 * J.qd[0] ** 2 + 2 * x * J.qdd[0])) == 0


@given(st.data(), randoms)
def test_Dk_is_repeated_D_and_general_leibniz(data, rnd):
    J = data.draw(jst.jet_spaces(1, 2))
    a = data.draw(_exprs(J, order=1, max_depth=1))
    b = data.draw(_exprs(J, order=1, max_depth=1))
    i, j = data.draw(st.integers(0, 1)), data.draw(st.integers(0, 1))
    assert J.Dk(a, 0) == a
    assert J.Dk(a, i + j) == J.Dk(J.Dk(a, i), j)
    assert_num_equal(J.Dk(a, 2), J.D(J.D(a)), rnd, points=1)
    # D^2(ab) = D^2 a b + 2 Da Db + a D^2 b
    assert_num_equal(J.Dk(a * b, 2),
                     J.Dk(a, 2) * b + 2 * J.D(a) * J.D(b) + a * J.Dk(b, 2), rnd)


# ------------------------------------------------------------------ the Euler operator
def test_euler_examples():
    J = JetSpace("x y")
    (x, y), (xd, yd), (xdd, ydd) = J.q, J.qd, J.qdd
    m, k = sp.symbols("m k", positive=True)
    # harmonic oscillator: paper's sign [L]_s = dL/dq - d/dt dL/dqdot
    assert J.euler(m * xd**2 / 2 - k * x**2 / 2) == (-k * x - m * xdd, 0)
    assert sp.expand(J.euler(xd**2 / 2 + sp.cos(x))[0] - (-sp.sin(x) - xdd)) == 0
    # second-order Lagrangian x_tt**2/2 gives + x_tttt
    assert J.euler(xdd**2 / 2) == (J.jet(x, 4), 0)
    # a time-dependent, coupled one
    e = J.euler(J.t * xd * y)
    assert sp.expand(e[0] - (-(y + J.t * yd))) == 0
    assert e[1] == J.t * xd
    # wrt: only the asked-for bases
    assert J.euler(xd * y, wrt=[y]) == (xd,)
    assert J.euler(sp.Integer(3)) == (0, 0)


@given(st.data(), randoms)
def test_total_derivatives_are_null_lagrangians(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    k = data.draw(st.integers(0, 2))
    G = data.draw(_exprs(J, order=k, max_depth=2 if k < 2 else 1))
    for E in J.euler(J.D(G)):
        assert_num_zero(E, rnd, points=1)


@given(st.data(), randoms)
def test_euler_is_linear(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    a = data.draw(_exprs(J, order=1, max_depth=2))
    b = data.draw(_exprs(J, order=2, max_depth=1))
    for ea, eb, eab in zip(J.euler(a), J.euler(b), J.euler(3 * a - b / 2)):
        assert_num_equal(eab, 3 * ea - eb / 2, rnd, points=1)


def _sympy_euler(J, L):
    """[L]_s from sympy.calculus.euler.euler_equations, one function at a time.

    euler_equations silently drops equations that sympy decides are trivially true or
    false (``Eq(0, 0)``, ``Eq(1, 0)``), so each function gets a marker term
    ``eps*f'**2/2`` (contributing ``-eps*f''``) and eps is set to 0 afterwards.
    """
    Ld = J.to_dynamic(L)
    t = dynamicsymbols._t
    eps = sp.Dummy("eps")
    out = []
    for s in J.q:
        f = dynamicsymbols(s.name)
        (eq,) = euler_equations(Ld + eps * f.diff(t) ** 2 / 2, [f], t)
        out.append(J.from_dynamic((eq.lhs - eq.rhs).xreplace({eps: 0})))
    return out


@fewer
@given(st.data(), randoms)
def test_euler_agrees_with_sympy_on_random_lagrangians(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    L = data.draw(jst.lagrangians(J, max_depth=1))
    for mine, ref in zip(J.euler(L), _sympy_euler(J, L)):
        assert_num_equal(mine, ref, rnd, points=1)


@fewer
@given(st.data(), randoms)
def test_euler_agrees_with_sympy_on_higher_order_expressions(data, rnd):
    J = data.draw(jst.jet_spaces(1, 2))
    k = data.draw(st.integers(1, 2))
    L = data.draw(_exprs(J, order=k, max_depth=3 - k))
    for mine, ref in zip(J.euler(L), _sympy_euler(J, L)):
        assert_num_equal(mine, ref, rnd, points=1)


@given(st.data(), randoms)
def test_euler_of_regular_lagrangian_is_second_order_with_minus_hessian(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3))
    L = data.draw(jst.lagrangians(J))
    E = J.euler(L)
    assert all(J.order(e) <= 2 for e in E)
    for s, e in enumerate(E):
        for r in range(J.n):
            assert_num_equal(sp.diff(e, J.qdd[r]), -sp.diff(L, J.qd[s], J.qd[r]), rnd, points=1)


# ------------------------------------------------------------------ fields
def test_with_fields():
    J = JetSpace("x y")
    K = J.with_fields("lam mu")
    lam, mu = K.fields
    assert J.fields == () and K.q == J.q and K.qd == J.qd and K.t == J.t
    assert [f.name for f in K.fields] == ["lam", "mu"]
    assert K.D(lam) == sp.Symbol("lam_t")
    assert K.jet(mu, 2) == sp.Symbol("mu_tt")
    assert J.D(lam) == 0                                    # unknown to J: a constant
    assert K.order(sp.Symbol("lam_tt")) == -1              # order counts coordinates ...
    assert K.order(sp.Symbol("lam_tt"), of=K.fields) == 2  # ... unless asked for fields
    assert K.with_fields("nu").fields == (lam, mu, sp.Symbol("nu"))
    x = J.q[0]
    assert K.euler(lam * (J.qd[0] - x), wrt=K.fields) == (J.qd[0] - x, 0)
    assert K.euler(lam * J.qd[0]) == (-sp.Symbol("lam_t"), 0)


@given(st.data(), randoms)
def test_D_acts_on_fields(data, rnd):
    J = data.draw(jst.jet_spaces(1, 2)).with_fields("lam1 lam2")
    bases = J.q + J.fields
    a = data.draw(_exprs(J, order=1, max_depth=2, of=bases))
    b = data.draw(_exprs(J, order=1, max_depth=1, of=bases))
    assert_num_equal(J.D(a * b), J.D(a) * b + a * J.D(b), rnd, points=1)
    for lam in J.fields:
        assert sp.diff(J.D(a), J.jet(lam, 2)) == sp.diff(a, J.jet(lam, 1))
    for E in J.euler(J.D(b), wrt=bases):
        assert_num_zero(E, rnd, points=1)


# ------------------------------------------------------------------ dynamicsymbols
def test_to_dynamic_and_from_dynamic_examples():
    J = JetSpace("x y")
    (x, y), (xd, yd), (xdd, ydd) = J.q, J.qd, J.qdd
    t = dynamicsymbols._t
    X, Y = dynamicsymbols("x y")
    e = J.t * x * yd + xdd
    d = J.to_dynamic(e)
    assert d == t * X * Y.diff(t) + X.diff(t, 2)
    assert J.from_dynamic(d) == e
    assert J.from_dynamic(X.diff(t, 3)) == J.jet(x, 3)
    K = JetSpace("x y", t="tau")
    assert K.to_dynamic(K.t * K.qd[0]) == t * X.diff(t)
    assert K.from_dynamic(t * X.diff(t)) == K.t * K.qd[0]


@given(st.data())
def test_dynamic_round_trip(data):
    J = data.draw(jst.jet_spaces(1, 4))
    if data.draw(st.booleans()):
        J = J.with_fields("lam")
    bases = J.q + J.fields
    e = data.draw(_exprs(J, order=data.draw(st.integers(0, 3)), of=bases))
    d = J.to_dynamic(e)
    assert not (d.free_symbols - {dynamicsymbols._t}), d   # no jet symbols left
    assert J.from_dynamic(d) == e
    assert J.check(e) == e


# ------------------------------------------------------------------ latex
def test_latex_dots():
    J = JetSpace("x phi")
    (x, phi), (xd, phid), (xdd, phidd) = J.q, J.qd, J.qdd
    assert J.latex(xd) == r"\dot{x}"
    assert J.latex(phidd) == r"\ddot{\phi}"
    assert J.latex(J.jet(x, 5)) == r"x^{(5)}"
    s = J.latex(xd**2 + x)
    assert r"\dot{x}^{2}" in s and "x_" not in s


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("spec", [
    [1, 2],                    # not names
    ["x", 2.5],
    [sp.Symbol("x") + 1],
    "x x",                     # duplicate
    ["x", sp.Symbol("x")],
    "x t",                     # clashes with the time symbol
    "x x_t",                   # jet suffix
    "x_t",
    "phi_tt",
    "",                        # empty
    [],
    "1x",                      # not a name
    "x__y",
    "_x",
    "x-y",
])
def test_bad_coordinates_raise(spec):
    with pytest.raises(JetSpaceError):
        JetSpace(spec)


def test_bad_fields_and_time_raise():
    J = JetSpace("x y")
    for fields in ("x", "lam lam", "lam_t", [3]):
        with pytest.raises(JetSpaceError):
            J.with_fields(fields)
    with pytest.raises(JetSpaceError):
        JetSpace("x", t="x")
    with pytest.raises(JetSpaceError):
        JetSpace("x", t="2t")


def test_errors_are_jetnh_and_value_errors():
    with pytest.raises(JetnhError):
        JetSpace("x x")
    with pytest.raises(ValueError):
        JetSpace("x x")
    assert issubclass(jn.JetSpaceError, jn.JetnhError)


def test_jet_of_unknown_base_raises():
    J = JetSpace("x y")
    for base in ("z", sp.Symbol("z"), "x_t", J.qd[0], "t", J.t):
        with pytest.raises(JetSpaceError):
            J.jet(base, 1)
    with pytest.raises(JetSpaceError):
        J.jets(1, of=[sp.Symbol("z")])
    with pytest.raises(JetSpaceError):
        J.jet(J.q[0], -1)


@pytest.mark.parametrize("make", [
    lambda J: sp.Symbol("x", real=True),
    lambda J: sp.Symbol("x", real=True) * J.q[1] + J.qd[0],
    lambda J: sp.Symbol("y_t", positive=True),
    lambda J: sp.sin(sp.Symbol("x_tt", real=True)),
    lambda J: dynamicsymbols("x"),
    lambda J: dynamicsymbols("x").diff(dynamicsymbols._t) + J.q[0],
    lambda J: "x + y",
    lambda J: "x",
    lambda J: None,
    lambda J: object(),
    lambda J: [J.q[0]],
    lambda J: sp.IndexedBase("m")[1] * J.qd[0],          # not a Symbol: no parameter
    lambda J: sp.MatrixSymbol("M", 2, 2)[0, 1] * J.q[0],
])
def test_check_refuses(make):
    J = JetSpace("x y")
    with pytest.raises(JetSpaceError):
        J.check(make(J))


def test_check_accepts():
    J = JetSpace("x y")
    x, y = J.q
    k = sp.Symbol("k", positive=True)            # parameters may carry assumptions
    for e in (x, J.qd[1] * k, sp.Integer(2), sp.Rational(1, 3) * J.t, sp.sin(J.qdd[0])):
        assert J.check(e) == e
    assert J.check(3) == 3 and isinstance(J.check(3), sp.Basic)
    assert J.check(1.5) == sp.Float(1.5)


def test_explicit_functions_are_allowed_and_differentiated():
    """Undefined functions not named like a coordinate (a forcing u(t), a generic
    f(x, x_t)) are explicit functions: check accepts them and D uses the chain rule."""
    J = JetSpace("x y")
    (x, y), (xd, yd), (xdd, ydd) = J.q, J.qd, J.qdd
    u, f = sp.Function("u"), sp.Function("f")
    e = u(J.t) * x
    assert J.check(e) == e
    assert J.D(e) == sp.Derivative(u(J.t), J.t) * x + u(J.t) * xd
    g = f(x, xd)
    assert J.check(g) == g
    assert J.D(g) == sp.diff(g, x) * xd + sp.diff(g, xd) * xdd
    assert J.order(g) == 1
    for bad in (sp.Function("x")(J.t), sp.Function("y")(x)):   # named like a coordinate
        with pytest.raises(JetSpaceError):
            J.check(bad)


def test_clashing_symbols_raise_in_D_order_and_euler():
    J = JetSpace("x y")
    xr = sp.Symbol("x", real=True)
    for op in (J.D, J.order, J.euler, J.check):
        with pytest.raises(JetSpaceError):
            op(xr * J.qd[0])


def test_from_dynamic_refuses_unknown_functions():
    J = JetSpace("x y")
    with pytest.raises(JetSpaceError):
        J.from_dynamic(dynamicsymbols("z"))
    with pytest.raises(JetSpaceError):
        J.from_dynamic(dynamicsymbols("z").diff(dynamicsymbols._t))


# ------------------------------------------------------------------ time-symbol clashes, strings
@pytest.mark.parametrize("given_t", [False, True])
def test_time_symbol_with_assumptions_is_refused(given_t):
    """A Symbol('t', real=True) would silently be a constant for D."""
    tr = sp.Symbol("t", real=True)
    J = JetSpace("x", t=tr) if given_t else JetSpace("x")
    (x,) = J.q
    assert J.t == sp.Symbol("t")
    for op in (J.check, J.D, J.order, J.euler):
        with pytest.raises(JetSpaceError):
            op(tr * x)


def test_time_name_with_jet_suffix_is_refused():
    for t in ("s_t", "x_tt"):
        with pytest.raises(JetSpaceError):
            JetSpace("s x", t=t)


def test_calculus_refuses_strings():
    """sympify would execute a string: every operation refuses them."""
    J = JetSpace("x y")
    for op in (J.D, lambda e: J.Dk(e, 2), J.order, J.euler, J.to_dynamic, J.from_dynamic,
               J.latex):
        with pytest.raises(JetSpaceError):
            op("x*y_t")


def test_dynamic_round_trip_with_coordinate_named_t():
    K = JetSpace("t", t="tau")
    e = K.q[0] * K.t
    assert K.from_dynamic(K.to_dynamic(e)) == e


def test_total_derivative_and_euler_on_the_n_trailer_agree_with_sympy_diff():
    """On nested expressions (the 3-trailer's phi and embedded Lagrangian L~), J.D and
    J.euler, computed on the shared graph (dag.diff), agree with the same operators
    built from sympy.diff on the trees, at a random point to 35 digits."""
    from jetnh.algebra import dag
    from jetnh.models import n_trailer

    s = n_trailer(N=3)
    J, Lt = s.J, s.L_tilde
    ind = s.independent

    def D_tree(e):
        terms = [sp.diff(e, J.t)]
        for x in e.free_symbols:
            if J.split(x):
                base, k = J.split(x)
                terms.append(sp.diff(e, x) * J.jet(base, k + 1))
        return sp.Add(*terms)

    mine = [J.D(p) for p in s.phi.values()] + list(J.euler(Lt, wrt=ind))
    ref = [D_tree(p) for p in s.phi.values()]
    ref += [sp.diff(Lt, q) - D_tree(sp.diff(Lt, J.jet(q, 1))) for q in ind]
    rng = random.Random(3)
    syms = dag.free_symbols(mine + ref)
    point = {x: sp.Rational(rng.randrange(300, 1300), 1000) for x in syms}
    for a, b in zip(dag.evaluate(mine, point, dps=45), dag.evaluate(ref, point, dps=45)):
        assert abs(a - b) <= 1e-35 * max(1, abs(b))
