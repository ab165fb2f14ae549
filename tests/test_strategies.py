"""The promises of jetnh.strategies: shapes, jet orders, definedness, regularity, solvability."""

from __future__ import annotations

import pytest
import sympy as sp
from hypothesis import given, strategies as st
from hypothesis.errors import InvalidArgument

import jetnh.strategies as jst
import jetnh as jn
import jetnh.mechanics.principles
from jetnh import JetSpace


def _values(exprs, rnd, spread=3.0):
    syms = set()
    for e in exprs:
        syms |= sp.sympify(e).free_symbols
    return {s: sp.Float(rnd.uniform(-spread, spread), 30) for s in sorted(syms, key=str)}


def _finite_real(expr, point):
    v = sp.sympify(expr).xreplace(point).evalf(30)
    return v.is_number and v.is_finite and v.is_real is not False and abs(sp.im(v)) < 1e-20


def test_public_names():
    assert set(jst.__all__) == {"jet_spaces", "jet_expressions", "polynomials", "lagrangians",
                                "affine_constraints", "nonlinear_constraints",
                                "constrained_systems", "forces", "systems", "principles",
                                "scenes"}
    for name in jst.__all__:
        assert getattr(jst, name).__doc__


@given(jst.systems(max_n=3, forced=True), jst.principles())
def test_systems_and_principles_are_values(system, principle):
    assert isinstance(system, jn.System) and system.forces and system.k >= 1
    assert principle in jn.mechanics.principles.REGISTRY
    assert principle.multiplier_symbols(system) == (
        () if principle.name == "chetaev" else tuple(
            sp.Symbol(f"lambda_{q.name}") for q in system.dependent))


@given(jst.jet_spaces(2, 5))
def test_jet_spaces(J):
    assert isinstance(J, JetSpace)
    assert 2 <= J.n <= 5
    assert [s.name for s in J.q] == [f"q{i}" for i in range(1, J.n + 1)]
    assert J.fields == ()


@given(st.data(), st.randoms(use_true_random=False))
def test_jet_expressions_are_small_defined_and_of_bounded_order(data, rnd):
    J = data.draw(jst.jet_spaces(1, 3)).with_fields("lam")
    order = data.draw(st.integers(0, 3))
    with_time = data.draw(st.booleans())
    of = data.draw(st.sampled_from([None, J.fields, J.q[:1] + J.fields]))
    e = data.draw(jst.jet_expressions(J, order=order, with_time=with_time, of=of))
    bases = J.q if of is None else of
    allowed = {J.jet(b, k) for b in bases for k in range(order + 1)} | ({J.t} if with_time else set())
    assert e.free_symbols <= allowed
    assert J.order(e, of=bases) <= order
    assert sp.count_ops(e) < 200
    for _ in range(3):
        assert _finite_real(e, _values([e], rnd))


@given(st.data())
def test_polynomials(data):
    J = data.draw(jst.jet_spaces(1, 3))
    deg = data.draw(st.integers(1, 3))
    p = data.draw(jst.polynomials(J, order=2, max_degree=deg, max_terms=4))
    variables = (J.t,) + J.q + J.qd + J.qdd
    poly = sp.Poly(p, *variables)
    assert poly.total_degree() <= deg
    assert len(poly.terms()) <= 5


@given(st.data(), st.randoms(use_true_random=False))
def test_lagrangians_are_regular(data, rnd):
    J = data.draw(jst.jet_spaces(1, 4))
    gyro = data.draw(st.sampled_from([None, True, False]))
    with_time = data.draw(st.booleans())
    L = data.draw(jst.lagrangians(J, with_time=with_time, gyroscopic=gyro))
    assert J.order(L) == 1
    if not with_time:
        assert J.t not in L.free_symbols
    H = sp.hessian(L, J.qd)
    for i in range(J.n):
        for j in range(J.n):
            assert (H[i, j] == 0) == (i != j)                 # diagonal
            assert J.order(H[i, j]) <= 0                       # depends on (t, q) only
    p = _values([H], rnd)
    assert all(H[i, i].xreplace(p) > 0 for i in range(J.n))   # positive definite
    flipped = L.xreplace({v: -v for v in J.qd})
    if gyro is False:
        assert sp.expand(flipped - L) == 0                      # even in the velocities
    if gyro is True:
        assert sp.expand(flipped - L) != 0


def _check_explicit(J, constraints, dependent):
    assert len(constraints) == len(dependent)
    assert 1 <= len(dependent) < J.n
    assert len(set(dependent)) == len(dependent) and set(dependent) <= set(J.q)
    dep_v = [J.qd[J.q.index(a)] for a in dependent]
    indep_v = [v for v in J.qd if v not in dep_v]
    for f, a_v in zip(constraints, dep_v):
        assert J.order(f) <= 1
        # f = qd^a - phi(t, q, qd^mu): the Jacobian in dependent velocities is the identity
        for b_v in dep_v:
            assert sp.diff(f, b_v) == (1 if b_v == a_v else 0)
        phi = a_v - f
        assert not (set(dep_v) & phi.free_symbols)
    return indep_v


@given(st.data())
def test_affine_constraints(data):
    J = data.draw(jst.jet_spaces(2, 5))
    m = data.draw(st.one_of(st.none(), st.integers(1, J.n - 1)))
    constraints, dependent = data.draw(jst.affine_constraints(J, m=m))
    if m is not None:
        assert len(dependent) == m
    indep_v = _check_explicit(J, constraints, dependent)
    for f in constraints:
        for u in indep_v:
            assert J.order(sp.diff(f, u)) <= 0                 # affine in velocities


@given(st.data())
def test_nonlinear_constraints(data):
    J = data.draw(jst.jet_spaces(2, 5))
    k = data.draw(st.integers(1, J.n - 1))
    dep = data.draw(st.permutations(J.q))[:k]
    if data.draw(st.booleans()):
        dep = [s.name for s in dep]                            # names work too
    constraints, dependent = data.draw(jst.nonlinear_constraints(J, dependent=dep))
    assert [s.name for s in dependent] == [str(d) for d in dep]
    indep_v = _check_explicit(J, constraints, dependent)
    for f in constraints:
        assert any(sp.diff(f, u, v) != 0 for u in indep_v for v in indep_v)


@given(jst.constrained_systems(2, 4))
def test_constrained_systems(system):
    J, L, constraints, dependent = system
    assert 2 <= J.n <= 4
    assert J.order(L) == 1
    _check_explicit(J, constraints, dependent)


@given(jst.constrained_systems(3, 3, affine=True))
def test_constrained_systems_affine_flag(system):
    J, L, constraints, dependent = system
    assert J.n == 3
    indep_v = _check_explicit(J, constraints, dependent)
    assert all(sp.diff(f, u, v) == 0 for f in constraints for u in indep_v for v in indep_v)


@pytest.mark.parametrize("make", [
    lambda: jst.jet_spaces(0, 3),
    lambda: jst.jet_spaces(4, 3),
    lambda: jst.jet_expressions(JetSpace("x"), order=-1),
    lambda: jst.jet_expressions(JetSpace("x"), of=(), with_time=False),
    lambda: jst.affine_constraints(JetSpace("x")),
    lambda: jst.affine_constraints(JetSpace("x y"), m=2),
    lambda: jst.affine_constraints(JetSpace("x y"), dependent=["z"]),
    lambda: jst.affine_constraints(JetSpace("x y z"), dependent=["x", "x"]),
    lambda: jst.nonlinear_constraints(JetSpace("x y z"), m=1, dependent=["x", "y"]),
    lambda: jst.nonlinear_constraints(JetSpace("x y"), dependent=["x", "y"]),
    lambda: jst.constrained_systems(min_n=1),
    lambda: jst.constrained_systems(mass="dense"),
    lambda: jst.nonlinear_constraints(JetSpace("x y z"), m=2, implicit=True),
])
def test_bad_arguments_raise_invalid_argument(make):
    with pytest.raises(InvalidArgument):
        make()



# ---------------------------------------------------------------------- broader systems
@given(st.data(), st.randoms(use_true_random=False))
def test_full_mass_matrices_are_positive_definite_and_not_diagonal(data, rnd):
    J = data.draw(jst.jet_spaces(2, 4))
    L = data.draw(jst.lagrangians(J, mass="full", gyroscopic=False))
    H = sp.hessian(L, J.qd)
    assert all(J.order(e) <= 0 for e in H)                     # depends on (t, q) only
    for _ in range(2):
        Hn = H.xreplace(_values([H], rnd)).evalf(30)
        assert all(Hn[:i, :i].det() > 0 for i in range(1, J.n + 1))   # Sylvester


def test_full_mass_matrices_are_drawn_off_the_diagonal():
    seen = set()

    @given(jst.jet_spaces(2, 3).flatmap(lambda J: jst.lagrangians(J, mass="full").map(
        lambda L: (J, L))))
    def draw(case):
        J, L = case
        H = sp.hessian(L, J.qd)
        seen.add(any(H[i, j] != 0 for i in range(J.n) for j in range(J.n) if i != j))
        seen.add(("q", bool(H.free_symbols & set(J.q))))
    draw()
    assert True in seen and ("q", True) in seen


@given(st.data(), st.randoms(use_true_random=False))
def test_implicit_affine_constraints_have_an_invertible_full_dependent_block(data, rnd):
    J = data.draw(jst.jet_spaces(3, 5))
    constraints, dependent = data.draw(jst.affine_constraints(J, implicit=True))
    dep_v = [J.qd[J.q.index(a)] for a in dependent]
    A = sp.Matrix([[sp.diff(f, v) for v in dep_v] for f in constraints])
    assert all(J.order(e) <= 0 and J.t not in e.free_symbols for e in A)
    for f in constraints:                                      # affine in the velocities
        assert all(J.order(sp.diff(f, v)) <= 0 for v in J.qd)
    det = A.det()
    for _ in range(2):
        assert abs(det.xreplace(_values([det], rnd)).evalf(30)) >= 1 - 1e-20


@given(st.data(), st.randoms(use_true_random=False))
def test_implicit_nonlinear_constraints_are_nonlinear_in_the_dependent_velocity(data, rnd):
    import jetnh as jn

    J = data.draw(jst.jet_spaces(2, 4))
    constraints, dependent = data.draw(jst.nonlinear_constraints(J, implicit=True))
    system = jn.System(J, J.qd[0] ** 2 / 2, constraints, dependent=dependent)
    v = J.jet(dependent[0], 1)
    assert sp.diff(constraints[0], v, v) != 0
    for f, a in zip(constraints, dependent):
        v = J.jet(a, 1)
        phi = system.phi[v]
        point = _values([phi, f], rnd, spread=1.0)
        point[v] = phi.xreplace(point).evalf(30)
        assert abs(f.xreplace(point).evalf(30)) < 1e-20        # phi solves f = 0


@given(jst.constrained_systems(2, 5, affine=None, implicit=None, mass=None))
def test_constrained_systems_with_every_option(system):
    J, L, constraints, dependent = system
    assert 2 <= J.n <= 5 and len(constraints) == len(dependent)
    assert J.order(L) == 1 and all(J.order(f) <= 1 for f in constraints)
