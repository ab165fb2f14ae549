"""Tests of jetnh.geometry.fields: vector fields, Lie bracket, total derivative field, prolongation.

Property tests draw small random expressions (polynomial and trigonometric in t, q, qd)
from the local strategies below and compare results numerically at fixed pseudo-random
points, or exactly with ``sympy.expand``; example tests check known prolongations
(Olver, Applications of Lie Groups to Differential Equations, Sec. 2.3).
"""

import functools
import random

import pytest
import sympy as sp
from hypothesis import given, strategies as st

import jetnh as jn
from jetnh.geometry.fields import (VectorField, commutator, prolong, total_derivative_field,
                          vertical_field)

try:                                    # the shared strategies, when present
    import jetnh.strategies as jst
except ImportError:                     # pragma: no cover
    jst = None


# ---------------------------------------------------------------------- strategies
def spaces(max_n=3, fields=True):
    """Jet spaces with 1..max_n coordinates, sometimes with a field ``lam``."""
    def build(n, with_field):
        J = jn.JetSpace([f"x{i}" for i in range(1, n + 1)])
        return J.with_fields(["lam"]) if with_field else J
    return st.builds(build, st.integers(1, max_n), st.booleans() if fields else st.just(False))


def variables(J, order=1, with_fields=True):
    """t and the jets of order <= order of the coordinates (and fields)."""
    bases = J.q + (J.fields if with_fields else ())
    return (J.t,) + tuple(J.jet(b, k) for b in bases for k in range(order + 1))


@functools.lru_cache(maxsize=None)
def expressions(vars_, max_leaves=5):
    """Small polynomial / trigonometric expressions in ``vars_`` (cached: building and
    validating a recursive strategy costs more than drawing from it)."""
    leaves = st.one_of(st.integers(-3, 3).map(sp.Integer), st.sampled_from(vars_))

    def extend(sub):
        return st.one_of(
            st.builds(sp.Add, sub, sub),
            st.builds(sp.Mul, sub, sub),
            sub.map(sp.sin), sub.map(sp.cos), sub.map(lambda e: e**2))
    return st.recursive(leaves, extend, max_leaves=max_leaves)


@st.composite
def fields_on(draw, J, order=1, max_components=3, expr_order=1):
    """A VectorField with a few components on t and jets of order <= ``order``."""
    keys = (J.t,) + tuple(J.jet(b, k) for b in J.q + J.fields for k in range(order + 1))
    chosen = draw(st.lists(st.sampled_from(keys), min_size=1, max_size=max_components,
                           unique=True))
    ex = expressions(variables(J, expr_order))
    return VectorField(J, {k: draw(ex) for k in chosen})


@st.composite
def space_and(draw, *makers, **space_kw):
    """(J, maker1(J), maker2(J), ...)."""
    J = draw(spaces(**space_kw))
    return (J,) + tuple(draw(m(J)) for m in makers)


@functools.lru_cache(maxsize=None)
def etas(J, order=0, with_fields=True, max_leaves=4):
    """Characteristics eta^s (a list over J.q) of jet order <= ``order``."""
    return st.lists(expressions(variables(J, order, with_fields), max_leaves),
                    min_size=J.n, max_size=J.n)


# ---------------------------------------------------------------------- numerics
def _value(sym, seed):
    return sp.Float(random.Random(f"{sym.name}/{seed}").uniform(-1.3, 1.3), 30)


def value(expr, seed=1):
    """``expr`` at a pseudo-random point (30 digits; same point for same symbol and seed)."""
    expr = sp.sympify(expr)
    return complex(expr.xreplace({s: _value(s, seed) for s in expr.free_symbols}).evalf())


def assert_same(a, b, seeds=(1,)):
    """a == b at pseudo-random points, to a relative tolerance."""
    for seed in seeds:
        va, vb = value(a, seed), value(b, seed)
        assert abs(va - vb) <= 1e-9 * (1 + abs(va) + abs(vb)), (a, b, va, vb)


def assert_same_fields(X, Y):
    for s in set(X.components) | set(Y.components):
        assert_same(X[s], Y[s])


# ---------------------------------------------------------------------- examples
J2 = jn.JetSpace("x y")
x, y = J2.q
xt, yt = J2.qd
xtt, ytt = J2.qdd
t = J2.t


def test_rotation_prolongation():
    R = VectorField(J2, {x: -y, y: x})
    assert prolong(J2, {x: -y, y: x}, order=1) == VectorField(
        J2, {x: -y, y: x, xt: -yt, yt: xt})
    assert R.prolong(2).components == {x: -y, y: x, xt: -yt, yt: xt, xtt: -ytt, ytt: xtt}
    assert R.prolong(0) == R
    assert commutator(J2, R.prolong(1)) == (0, 0)


def test_scaling_and_time_translation():
    S = prolong(J2, [x, y], order=2)
    assert S.components == {x: x, y: y, xt: xt, yt: yt, xtt: xtt, ytt: ytt}
    T = prolong(J2, [0, 0], xi=1, order=3)
    assert T.components == {t: 1}
    Ts = prolong(J2, [0, 0], xi=t, order=2)          # t d_t -> -k q_(k) d_q_(k)
    assert Ts.components == {t: t, xt: -xt, yt: -yt, xtt: -2 * xtt, ytt: -2 * ytt}


def test_galilean_boost_and_projective_field():
    B = prolong(J2, {x: t}, order=2)
    assert B.components == {x: t, xt: 1}
    P = prolong(J2, {x: t * x, y: t * y}, xi=t**2, order=2)    # Olver's projective field
    assert sp.expand(P[xt] - (x - t * xt)) == 0
    assert sp.expand(P[xtt] - (-3 * t * xtt)) == 0
    assert sp.expand(P[ytt] - (-3 * t * ytt)) == 0


def test_total_derivative_field_components():
    D2 = total_derivative_field(J2, 2)
    assert D2.components == {t: 1, x: xt, y: yt, xt: xtt, yt: ytt}
    assert total_derivative_field(J2, 0).components == {t: 1}
    assert total_derivative_field(J2, 1, bases=[y]).components == {t: 1, y: yt}
    Jl = J2.with_fields(["lam"])
    lam = Jl.fields[0]
    assert total_derivative_field(Jl, 1)[lam] == Jl.jet(lam, 1)


def test_vertical_field_and_commutator_examples():
    V = vertical_field(J2, {x: y}, {x: 0})
    assert V.components == {x: y}
    assert commutator(J2, V) == (yt, 0)
    W = vertical_field(J2, [t * x, 0])
    assert W.components == {x: t * x, xt: x + t * xt}
    assert commutator(J2, W) == (0, 0)
    c = (x * yt, sp.sin(t))
    assert commutator(J2, vertical_field(J2, [y, x], defect=c)) == c
    assert commutator(J2, VectorField(J2, {xt: xtt, x: xt}), k=1) == (J2.jet(x, 3), 0)
    assert commutator(J2, VectorField(J2, {xt: yt, xtt: y}), k=1) == (ytt - y, 0)


def test_bracket_examples():
    X = VectorField(J2, {x: 1})
    Y = VectorField(J2, {y: x})
    assert X.bracket(Y) == VectorField(J2, {y: 1})
    R = VectorField(J2, {x: -y, y: x})
    S = VectorField(J2, {x: x, y: y})
    assert R.bracket(S).is_zero                      # rotations commute with scaling
    D = total_derivative_field(J2, 2)
    assert D.bracket(R.prolong(2)).truncate(1).is_zero


def test_value_semantics_and_printing():
    X = VectorField(J2, {x: (x + 1)**2, y: 0, t: 0})
    assert set(X.components) == {x}
    with pytest.raises(TypeError):
        X.components[y] = 1
    assert X[y] == 0 and X.is_vertical and X.order == 0
    Y = VectorField(J2, {x: x**2 + 2 * x + 1})
    assert X == Y and hash(X) == hash(Y) and len({X, Y}) == 1
    assert X != VectorField(J2, {x: x**2})
    assert X != VectorField(jn.JetSpace("x y z"), {x: x**2 + 2 * x + 1})
    assert X.expand().components == {x: x**2 + 2 * x + 1}
    assert sum([X, Y]) == 2 * X == X * 2 == X + X
    assert (X - Y).expand().components == {} and (X - Y).is_zero
    assert str(VectorField(J2, {})) == "0" == VectorField(J2, {}).latex()
    assert (x * X)(y) == 0 and (X / 2)(x) == X[x] / 2
    assert "VectorField(" in repr(X) and "d/dx" in str(X)
    V = VectorField(J2, {t: 1, xt: yt})
    assert not V.is_vertical and V.order == 1
    assert r"\dot{y}" in V.latex() and r"\partial t" in V.latex()
    assert V.subs(yt, 2)[xt] == 2 and V.xreplace({yt: y})[xt] == y
    assert V.truncate(0).components == {t: 1}


def test_errors():
    with pytest.raises(jn.JetSpaceError, match="keyed by 'x'"):
        VectorField(J2, {"x": 1})
    with pytest.raises(jn.JetSpaceError, match="not a coordinate"):
        VectorField(J2, {sp.Symbol("z"): 1})
    with pytest.raises(jn.JetSpaceError, match="keyed by"):
        VectorField(J2, {x + y: 1})
    with pytest.raises(jn.JetSpaceError, match="clashes"):
        VectorField(J2, {sp.Symbol("x", real=True): 1})
    with pytest.raises(jn.JetSpaceError, match="string"):
        VectorField(J2, {x: "y"})
    with pytest.raises(jn.JetSpaceError, match="scalar"):
        VectorField(J2, {x: sp.Matrix([1, 2])})
    with pytest.raises(jn.JetSpaceError, match="mapping"):
        VectorField(J2, [(x, 1)])
    with pytest.raises(jn.JetSpaceError):
        VectorField("x y", {x: 1})
    X3 = VectorField(jn.JetSpace("x y z"), {x: 1})
    X2 = VectorField(J2, {x: 1})
    with pytest.raises(jn.JetSpaceError, match="different jet spaces"):
        X2.bracket(X3)
    with pytest.raises(jn.JetSpaceError, match="different jet spaces"):
        X2 + X3
    with pytest.raises(TypeError):
        X2 * X2
    with pytest.raises(jn.JetSpaceError, match="not on"):
        commutator(J2, X3)
    with pytest.raises(jn.JetSpaceError, match="jets such as"):
        prolong(J2, {xt: 1})
    with pytest.raises(jn.JetSpaceError, match="expected 2"):
        prolong(J2, [1, 2, 3])
    with pytest.raises(jn.JetSpaceError, match="order"):
        prolong(J2, [1, 2], order=-1)
    with pytest.raises(jn.JetSpaceError, match="order"):
        total_derivative_field(J2, 1.5)
    with pytest.raises(jn.JetSpaceError, match="not both"):
        vertical_field(J2, [x, y], [0, 0], defect=[0, 0])
    with pytest.raises(jn.JetSpaceError, match="no jet components"):
        VectorField(J2, {xt: 1}).prolong(1)
    with pytest.raises(jn.JetSpaceError, match="string"):
        X2("x")


# ---------------------------------------------------------------------- properties
@given(space_and(fields_on, fields_on))
def test_bracket_antisymmetric(case):
    J, X, Y = case
    assert X.bracket(Y) == -Y.bracket(X)
    assert X.bracket(X).is_zero


@given(space_and(fields_on, fields_on, fields_on, max_n=2))
def test_jacobi_identity(case):
    J, X, Y, Z = case
    total = X.bracket(Y.bracket(Z)) + Y.bracket(Z.bracket(X)) + Z.bracket(X.bracket(Y))
    for c in total.components.values():
        assert_same(c, 0)


@given(space_and(fields_on, fields_on, lambda J: expressions(variables(J, 1))))
def test_bracket_is_commutator_of_derivations(case):
    J, X, Y, f = case
    assert_same(X.bracket(Y)(f), X(Y(f)) - Y(X(f)))


@given(space_and(fields_on, fields_on, lambda J: expressions(variables(J, 1)),
                 lambda J: expressions(variables(J, 1))))
def test_module_and_leibniz_rules(case):
    J, X, Y, f, g = case
    assert sp.expand(X(f * g) - X(f) * g - f * X(g)) == 0
    assert sp.expand((X + g * Y)(f) - X(f) - g * Y(f)) == 0
    assert_same_fields((g * Y).bracket(X), g * Y.bracket(X) - X(g) * Y)


@given(space_and(lambda J: st.integers(1, 3), lambda J: expressions(variables(J, 2))))
def test_total_derivative_field_agrees_with_D(case):
    J, extra, f = case
    D = total_derivative_field(J, 2 + extra)
    assert sp.expand(D(f) - J.D(f)) == 0
    assert D.bracket(total_derivative_field(J, 3 + extra)).truncate(extra).is_zero


@given(space_and(etas, etas, lambda J: st.integers(1, 2)))
def test_prolongation_of_bracket_evolutionary_point_case(case):
    """pr[v_Q, v_R] = [pr v_Q, pr v_R] exactly at every order when Q, R have order 0."""
    J, Q, R, k = case
    X0, Y0 = VectorField(J, dict(zip(J.q, Q))), VectorField(J, dict(zip(J.q, R)))
    B0 = X0.bracket(Y0)
    lhs = prolong(J, {s: B0[s] for s in J.q}, order=k)
    rhs = prolong(J, Q, order=k).bracket(prolong(J, R, order=k))
    assert_same_fields(lhs, rhs)


@given(space_and(lambda J: etas(J, 1, max_leaves=3), lambda J: etas(J, 1, max_leaves=3),
                 lambda J: expressions(variables(J, 1), 3), max_n=2))
def test_prolongation_of_bracket_generalized(case):
    """Generalized Q, R of order 1: the characteristic of the bracket is
    pr v_Q(R) - pr v_R(Q); its prolongation agrees with [pr v_Q, pr v_R] on order-1 f."""
    J, Q, R, f = case
    PQ, PR = prolong(J, Q, order=2), prolong(J, R, order=2)
    S = [PQ(r) - PR(q) for q, r in zip(Q, R)]
    assert_same(prolong(J, S, order=1)(f), PQ.bracket(PR)(f))


@given(space_and(lambda J: etas(J, 0, max_leaves=3), lambda J: etas(J, 0, max_leaves=3),
                 lambda J: expressions(variables(J, 0), 3), lambda J: expressions(variables(J, 0), 3),
                 lambda J: st.integers(1, 2), max_n=2, fields=False))
def test_prolongation_of_bracket_point_fields(case):
    """Point fields xi d_t + eta d_q (Olver Sec. 2.3): pr[v, w] = [pr v, pr w]."""
    J, e1, e2, xi1, xi2, k = case
    v = VectorField(J, {J.t: xi1, **dict(zip(J.q, e1))})
    w = VectorField(J, {J.t: xi2, **dict(zip(J.q, e2))})
    assert_same_fields(v.bracket(w).prolong(k), v.prolong(k).bracket(w.prolong(k)))


@given(space_and(lambda J: etas(J, 1, max_leaves=3), lambda J: expressions(variables(J, 1), 3),
                 lambda J: st.integers(1, 2)))
def test_prolongation_recursion_and_splitting(case):
    """eta_(k+1) = D eta_(k) - q_(k+1) D xi, and pr v = pr v_Q + xi D (Olver Sec. 5.1)."""
    J, eta, xi, k = case
    P = prolong(J, eta, xi=xi, order=k)
    for b in J.q + J.fields:
        for j in range(k):
            assert sp.expand(P[J.jet(b, j + 1)] - J.D(P[J.jet(b, j)])
                             + J.jet(b, j + 1) * J.D(xi)) == 0
    Qs = [e - xi * J.jet(s, 1) for e, s in zip(eta, J.q)]
    Qf = [-xi * J.jet(lam, 1) for lam in J.fields]
    assert P == prolong(J, Qs + Qf, order=k) + xi * total_derivative_field(J, k + 1)


@given(space_and(lambda J: etas(J, 1, max_leaves=3), lambda J: st.integers(1, 3)))
def test_commutator_vanishes_for_prolonged_evolutionary_fields(case):
    J, eta, k = case
    P = prolong(J, eta, order=k)
    for j in range(k):
        assert all(c == 0 for c in commutator(J, P, k=j, bases=J.q + J.fields))
    assert all(c == 0 for c in commutator(J, vertical_field(J, eta)))


@given(space_and(lambda J: etas(J, 1, max_leaves=3), lambda J: etas(J, 1, max_leaves=3),
                 lambda J: etas(J, 1, max_leaves=3)))
def test_commutator_is_the_prescribed_defect(case):
    J, eta, zeta, c = case
    V = vertical_field(J, eta, zeta)
    assert V.is_vertical and V.order <= 1
    for got, e, z in zip(commutator(J, V), eta, zeta):
        assert sp.expand(got - (J.D(e) - z)) == 0
    W = vertical_field(J, eta, defect=c)
    for got, want in zip(commutator(J, W), c):
        assert sp.expand(got - want) == 0
    for e, cc, v in zip(eta, c, J.qd):
        assert sp.expand(W[v] - J.D(e) + cc) == 0


@st.composite
def order_and_function(draw, J):
    """(k, f): a prolongation order k in 1..2 and f of jet order < k."""
    k = draw(st.integers(1, 2))
    return k, draw(expressions(variables(J, min(k - 1, 1))))


@given(space_and(lambda J: etas(J, 1, max_leaves=3), order_and_function))
def test_prolonged_evolutionary_field_commutes_with_D(case):
    """[D, pr v_Q] f = 0 for f of order < k (Q of order 1, pr to order k)."""
    J, eta, (k, f) = case
    P = prolong(J, eta, order=k)
    D = total_derivative_field(J, k + 2)
    assert_same(D.bracket(P)(f), 0)
    assert_same(D(P(f)), P(J.D(f)))


@pytest.mark.skipif(not hasattr(jst, "jet_expressions"), reason="jetnh.strategies not available")
@given(st.data())
def test_with_shared_strategies(data):
    """D field and prolongation on the shared jetnh.strategies expressions (exp, sqrt, ...)."""
    J = data.draw(jst.jet_spaces(1, 3))
    f = data.draw(jst.jet_expressions(J, order=1, max_depth=1))
    eta = data.draw(st.lists(jst.jet_expressions(J, order=1, max_depth=1),
                             min_size=J.n, max_size=J.n))
    assert_same(total_derivative_field(J, 2)(f), J.D(f))
    P = prolong(J, eta, order=2)
    assert_same(J.D(P(f)), P(J.D(f)))
    assert all(c == 0 for c in commutator(J, P))
