"""Tests of jetnh.geometry.forms: Cartan calculus identities on random forms, known values, contact
forms, and galgebra's exterior algebra as an independent cross-check."""

import pytest
import sympy as sp
from hypothesis import given, strategies as st

from jetnh import JetSpace, JetSpaceError
from jetnh.algebra.zero import expr_is_zero
from jetnh.geometry.forms import (Form, basis, contact_forms, coordinate_key, d, differential,
                                  interior, lie_derivative, pullback, wedge)

J = JetSpace("x y")
t = J.t
x, y = J.q
xt, yt = J.qd
xtt, ytt = J.qdd
a = sp.Symbol("a")                      # a parameter: constant for d
POOL = (t, x, y, xt, yt)                # the coordinates of J^1 M, canonical order
ATOMS = (t, x, y, xt, yt, a, sp.sin(x), sp.exp(y), sp.cos(t * yt))


# ----------------------------------------------------------------- strategies
@st.composite
def coefficients(draw, atoms=ATOMS):
    terms = []
    for _ in range(draw(st.integers(1, 2))):
        c = draw(st.integers(-3, 3).filter(bool))
        fs = draw(st.lists(st.sampled_from(atoms), max_size=2))
        terms.append(c * sp.Mul(*fs))
    return sp.Add(*terms)


@st.composite
def forms(draw, p=None, pool=POOL, space=J, atoms=ATOMS, max_terms=3):
    if p is None:
        p = draw(st.integers(0, 3))
    terms = {}
    for _ in range(draw(st.integers(0, max_terms))):
        key = tuple(draw(st.permutations(pool))[:p])      # any order: tests canonicalising
        terms[key] = terms.get(key, 0) + draw(coefficients(atoms))
    return Form(space, p, terms)


@st.composite
def vector_fields(draw, pool=POOL):
    keys = draw(st.lists(st.sampled_from(pool), min_size=1, max_size=3, unique=True))
    return {k: draw(coefficients()) for k in keys}


def componentwise_lie(X, w):
    """L_X of a 0- or 1-form from the coordinate formulas (independent of Cartan)."""
    if w.degree == 0:
        f = w[()]
        return Form.function(J, sum(X.get(s, 0) * sp.diff(f, s) for s in POOL))
    out = {}
    for j in POOL:
        c = sum(X.get(i, 0) * sp.diff(w[(j,)], i) for i in POOL)
        c += sum(w[(i,)] * sp.diff(X.get(i, 0), j) for i in POOL)
        out[(j,)] = c
    return Form(J, 1, out)


def bracket(X, Y):
    return {k: sum(X.get(i, 0) * sp.diff(Y.get(k, 0), i) - Y.get(i, 0) * sp.diff(X.get(k, 0), i)
                   for i in POOL) for k in POOL}


# ----------------------------------------------------------------- Cartan calculus
@given(forms())
def test_d_squared_is_zero(w):
    assert d(d(w)).is_zero()


@given(forms(), forms())
def test_d_is_a_graded_derivation(u, v):
    lhs = d(u ^ v)
    rhs = (d(u) ^ v) + (-1) ** u.degree * (u ^ d(v))
    assert lhs == rhs


@given(forms(max_terms=2), forms(max_terms=2), forms(max_terms=2))
def test_wedge_is_associative(u, v, w):
    assert ((u ^ v) ^ w) == (u ^ (v ^ w))
    assert wedge(u, v, w) == (u ^ (v ^ w))


@given(forms(), forms())
def test_wedge_is_graded_commutative(u, v):
    assert (u ^ v) == (-1) ** (u.degree * v.degree) * (v ^ u)


@given(forms(p=1))
def test_one_form_wedge_itself_vanishes(u):
    assert (u ^ u).is_zero()


@given(vector_fields(), forms(), forms())
def test_interior_is_an_antiderivation(X, u, v):
    lhs = interior(X, u ^ v)
    rhs = (interior(X, u) ^ v) + (-1) ** u.degree * (u ^ interior(X, v))
    assert lhs.degree == rhs.degree == u.degree + v.degree - 1
    assert lhs == rhs


@given(vector_fields(), forms())
def test_interior_twice_is_zero(X, w):
    assert interior(X, interior(X, w)).is_zero()


@given(vector_fields(), st.one_of(forms(p=0), forms(p=1)))
def test_cartan_formula_against_componentwise_lie_derivative(X, w):
    assert lie_derivative(X, w) == componentwise_lie(X, w)


@given(vector_fields(), vector_fields(), forms(p=2, max_terms=2))
def test_lie_interior_commutator_is_interior_of_bracket(X, Y, w):
    lhs = lie_derivative(X, interior(Y, w)) - interior(Y, lie_derivative(X, w))
    assert lhs == interior(bracket(X, Y), w)


class _HasComponents:
    def __init__(self, comps):
        self.components = comps


@given(vector_fields(), forms(p=2))
def test_interior_accepts_objects_with_components(X, w):
    assert interior(_HasComponents(X), w) == interior(X, w)


# ----------------------------------------------------------------- pullback
@st.composite
def maps(draw):
    keys = draw(st.lists(st.sampled_from(POOL), min_size=1, max_size=3, unique=True))
    return {k: draw(coefficients(atoms=(t, x, y, xt, yt, a, sp.sin(y)))) for k in keys}


@given(forms(), maps())
def test_pullback_commutes_with_d(w, phi):
    assert pullback(d(w), phi) == d(pullback(w, phi))


@given(forms(max_terms=2), forms(max_terms=2), maps())
def test_pullback_preserves_wedge(u, v, phi):
    assert pullback(u ^ v, phi) == (pullback(u, phi) ^ pullback(v, phi))


def test_pullback_identity_and_known_value():
    w = x * differential(J, y) + differential(J, t)
    assert pullback(w, {}) == w
    # polar-like map x -> y*cos(t): d(y cos t) = cos t dy - y sin t dt
    got = pullback(differential(J, x), {x: y * sp.cos(t)})
    assert got == sp.cos(t) * differential(J, y) - y * sp.sin(t) * differential(J, t)


# ----------------------------------------------------------------- contact forms
@st.composite
def curves(draw):
    return draw(coefficients(atoms=(t, sp.sin(t), sp.exp(t), a)))


@given(curves(), curves())
def test_contact_forms_vanish_along_prolonged_curves(cx, cy):
    J3 = J
    prolong = {}
    for base, c in ((x, cx), (y, cy)):
        for k in range(3):
            prolong[J3.jet(base, k)] = sp.diff(c, t, k)
    for theta in contact_forms(J3, order=2):
        assert pullback(theta, prolong).is_zero()


@given(curves())
def test_contact_form_detects_non_prolonged_curves(cx):
    # x_t mapped to c' + 1: not the prolongation, theta^x pulls back to -dt
    theta_x = contact_forms(J)[0]
    got = pullback(theta_x, {x: cx, xt: sp.diff(cx, t) + 1})
    assert got == -differential(J, t)


def test_contact_forms_known_values_and_total_derivative():
    th = contact_forms(J, order=2)
    assert len(th) == 4
    assert th[0] == differential(J, x) - xt * differential(J, t)
    assert th[3] == differential(J, yt) - ytt * differential(J, t)
    D = {t: 1, x: xt, y: yt, xt: xtt, yt: ytt}          # the total derivative field
    for theta in th:
        assert interior(D, theta).is_zero()
    with pytest.raises(ValueError):
        contact_forms(J, order=0)


# ----------------------------------------------------------------- known values
def test_canonical_order_and_signs():
    assert [coordinate_key(J, s) for s in (t, x, y, xt, yt, xtt)] == sorted(
        coordinate_key(J, s) for s in (t, x, y, xt, yt, xtt))
    dt, dx, dxt = differential(J, t), differential(J, x), differential(J, xt)
    w = dx ^ dt
    assert w.terms == {(t, x): -1}
    assert w[(x, t)] == 1 and w[(t, x)] == -1
    assert (dx ^ dx).is_zero() and len(dx ^ dx) == 0
    assert (dxt ^ dx ^ dt).terms == {(t, x, xt): -1}
    assert Form(J, 2, {(x, x): 5}).is_zero()
    assert Form(J, 2, {(y, x): 1, (x, y): 1}).is_zero()


def test_known_exterior_derivatives():
    dt, dx, dy, dxt = (differential(J, s) for s in (t, x, y, xt))
    f = x ** 2 * xt + a * t
    assert d(Form.function(J, f)) == 2 * x * xt * dx + x ** 2 * dxt + a * dt
    # d(x_t dx) = dx_t ^ dx = -dx ^ dx_t
    assert d(xt * dx).terms == {(x, xt): -1}
    # d(y dx - x dy) = -2 dx ^ dy
    assert d(y * dx - x * dy) == -2 * (dx ^ dy)
    # contact form: d theta^x = -dx_t ^ dt = dt ^ dx_t
    assert d(contact_forms(J)[0]) == (dt ^ dxt)
    # undefined functions are differentiated by the chain rule
    g = sp.Function("g")(t, x)
    assert d(Form.function(J, g)) == sp.diff(g, t) * dt + sp.diff(g, x) * dx


def test_known_interior_products():
    dt, dx, dy = (differential(J, s) for s in (t, x, y))
    assert interior({x: 1}, dt ^ dx) == -dt
    assert interior({t: 1}, dt ^ dx) == dx
    assert interior({x: y, y: -x}, dx ^ dy) == y * dy + x * dx
    z = interior({x: 1}, Form.function(J, x))
    assert z.degree == -1 and z.is_zero()
    with pytest.raises(TypeError):
        interior(3, dx)


def test_arithmetic_equality_and_immutability():
    dx, dy = differential(J, x), differential(J, y)
    w = x * dx + dy
    assert w - w == 0
    assert 2 * w == w + w == w * 2
    assert (w / 2) * 2 == w
    assert w != dx
    assert Form.function(J, x) + 1 == Form.function(J, x + 1)
    assert (Form.function(J, y) * dx) == y * dx
    assert hash(w) == hash(dy + x * dx)
    assert {w: 1}[dy + x * dx] == 1
    with pytest.raises(AttributeError):
        w.degree = 3
    with pytest.raises(ValueError):
        w + (dx ^ dy)
    with pytest.raises(TypeError):
        dx * dy
    with pytest.raises(JetSpaceError):
        differential(J, a)
    with pytest.raises(JetSpaceError):
        w + differential(JetSpace("u"), sp.Symbol("u"))
    assert str(x * dx + dy) == "(x)*dx + dy"
    assert "dot{x}" in (xt * dx).latex()


def test_fields_and_higher_jets_are_coordinates():
    Jf = J.with_fields("lam")
    lam = Jf.fields[0]
    lam_t = Jf.jet(lam, 1)
    w = d(Form.function(Jf, lam * xt + a))
    assert w == xt * differential(Jf, lam) + lam * differential(Jf, xt)
    assert coordinate_key(Jf, lam) < coordinate_key(Jf, xt) < coordinate_key(Jf, lam_t)


def test_zero_tests_expand_rational_numeric():
    dx = differential(J, x)
    trig = (sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1) * dx
    assert not trig.is_zero()
    assert trig.is_zero_numeric()
    assert trig.map(sp.simplify).is_zero()
    assert ((1 / (x + 1) - x / (x * x + x)) * dx).is_zero()          # common denominator
    assert not (x * dx).is_zero_numeric()


def test_basis_sorts_with_the_sign_of_the_permutation():
    assert basis(J, (y, x)) == (-1, (x, y))
    assert basis(J, (xt, t, y)) == (1, (t, y, xt))
    assert basis(J, (x, y, x)) is None
    w = wedge(differential(J, y), differential(J, x))
    sign, key = basis(J, (y, x))
    assert w.terms[key] == sign


# ----------------------------------------------------------------- galgebra cross-check
galgebra_ga = pytest.importorskip("galgebra.ga")


def _ga_for(space):
    pool = (space.t,) + space.q + space.qd
    names = " ".join("e_" + s.name.replace("_", "") for s in pool)
    g, *basis = galgebra_ga.Ga.build(names, g=[1] * len(pool), coords=pool)
    return g, basis, pool


GA = {n: (JetSpace(["x", "y"][:n]),) + _ga_for(JetSpace(["x", "y"][:n])) for n in (1, 2)}


def to_ga(w, g, basis, pool):
    mv = g.mv(sp.S.Zero, "scalar")      # galgebra 0.6: a Python int 0 gives a broken Mv
    for key, c in w.terms.items():
        blade = g.mv(sp.S.One, "scalar")
        for s in key:
            blade = blade ^ basis[pool.index(s)]
        mv = mv + c * blade
    return mv


def ga_coefs(mv, g, p):
    try:
        return [sp.expand(c) for c in mv.get_coefs(p)]
    except TypeError:                    # galgebra: the zero multivector has no coefficients
        return [0] * len(g.indexes[p])


def assert_matches_ga(w, mv, g, pool):
    got = ga_coefs(mv, g, w.degree)
    for idx, c in zip(g.indexes[w.degree], got):
        key = tuple(pool[i] for i in idx)
        assert expr_is_zero(w[key] - c), (key, w[key], c)


@st.composite
def ga_case(draw):
    n = draw(st.sampled_from((1, 2)))
    space, g, basis, pool = GA[n]
    atoms = pool + (a, sp.sin(pool[1]))
    return n, draw(forms(p=1, pool=pool, space=space, atoms=atoms)), \
        draw(forms(p=1, pool=pool, space=space, atoms=atoms)), \
        draw(forms(p=draw(st.integers(1, 2)), pool=pool, space=space, atoms=atoms))


@given(ga_case())
def test_wedge_matches_galgebra_outer_product(case):
    n, u, v, w = case
    _, g, basis, pool = GA[n]
    U, V, W = (to_ga(f, g, basis, pool) for f in (u, v, w))
    assert_matches_ga(u ^ v, U ^ V, g, pool)
    if u.degree + v.degree + w.degree <= len(pool):
        assert_matches_ga(u ^ v ^ w, U ^ V ^ W, g, pool)


@given(ga_case())
def test_d_matches_galgebra_grad_outer(case):
    # Euclidean metric, Cartesian coordinates: grad ^ A is the exterior derivative of A
    n, u, _, w = case
    _, g, basis, pool = GA[n]
    for f in (u, w):
        assert_matches_ga(d(f), g.grad ^ to_ga(f, g, basis, pool), g, pool)
