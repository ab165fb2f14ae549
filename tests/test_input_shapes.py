"""Every entry point of the symbolic core either gives the right answer or a JetnhError
that names the problem and the fix: one test per class of input, hypothesis where the
class is a family (scales of mass matrices and constraint Jacobians)."""

import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import example, given
from hypothesis import strategies as st
from sympy.physics.mechanics import dynamicsymbols

import jetnh as jn
from jetnh.algebra import linalg
from jetnh.mechanics.system import System
from jetnh.errors import (ConstraintError, JetnhError, JetnhWarning, JetSpaceError,
                          LagrangianError, PrincipleError)
from jetnh.algebra.zero import vanishes

J = jn.JetSpace("x y z")
x, y, z = J.q
xd, yd, zd = J.qd
T = (xd**2 + yd**2 + zd**2) / 2
F = xd - y * zd                       # a nonholonomic constraint (Heisenberg-like)
m, a = sp.symbols("m a")


def _same_accelerations(s1, s2, principle="chetaev"):
    a1 = s1.equations(principle).accelerations()
    a2 = s2.equations(principle).accelerations()
    assert set(a1) == set(a2)
    return all(vanishes(a1[k] - a2[k], s1) for k in a1)


# ------------------------------------------------------------------ 1. shapes of input
def test_eq_constraints_are_lhs_minus_rhs():
    """Eq(lhs, rhs) means lhs - rhs = 0, in a list or alone (it was kept as an Eq,
    misclassified, and crashed in symengine when the accelerations were asked)."""
    ref = System(J, T, [F])
    for cons in ([sp.Eq(xd, y * zd)], sp.Eq(xd, y * zd), (sp.Eq(xd - y * zd, 0),)):
        s = System(J, T, cons)
        assert s.constraints == (F,)
        assert s.phi == ref.phi
        assert _same_accelerations(s, ref, "vakonomic")


def test_bare_expression_and_column_matrix_are_lists():
    """A single constraint needs no list (it was a raw TypeError); a column or row
    Matrix is read as its entries."""
    assert System(J, T, F).constraints == (F,)
    assert System(J, T, F, dependent=x).dependent == (x,)
    G = zd - x * yd
    assert System(J, T, sp.Matrix([F, G])).constraints == (F, G)
    assert System(J, T, sp.Matrix([[F, G]])).constraints == (F, G)
    assert System(J, T, None).k == 0


@pytest.mark.parametrize("cons, error, words", [
    (["x_t - y*z_t"], JetSpaceError, "string"),
    ("x_t - y*z_t", JetSpaceError, "string"),
    ([None], ConstraintError, "None"),
    ([True], ConstraintError, "boolean"),
    ([sp.Eq(xd, xd)], ConstraintError, "boolean"),          # sympy made it True
    ([xd < y], ConstraintError, "relation"),
    ([sp.Ge(xd, y)], ConstraintError, "inequalities"),
    ([sp.Ne(xd, y)], ConstraintError, "Ne"),
    (sp.Matrix([[F, 0], [0, F]]), ConstraintError, "2x2 Matrix"),
    ([[F]], ConstraintError, "flat list"),
    ({F}, ConstraintError, "give a list"),
    ([object()], ConstraintError, "not a sympy expression"),
    (3.5, ConstraintError, "neither"),
    ([0], ConstraintError, "identically zero"),
    ([a], ConstraintError, "condition on the parameters"),
    ([xd + sp.I * y], ConstraintError, "imaginary"),
    ([xd + sp.oo * y], ConstraintError, "infinity"),
])
def test_constraints_in_wrong_shapes_are_named(cons, error, words):
    with pytest.raises(error, match=words):
        System(J, T, cons)


@pytest.mark.parametrize("L, error, words", [
    (sp.Eq(T, 0), LagrangianError, "equation"),
    (xd < 1, LagrangianError, "relation"),
    (sp.Matrix([T]), LagrangianError, "Matrix"),
    ([T], LagrangianError, "list"),
    (None, LagrangianError, "None"),
    ("x_t**2", JetSpaceError, "string"),
    (T + sp.nan, LagrangianError, "nan"),
    (T + sp.I * x, LagrangianError, "imaginary"),
])
def test_lagrangian_in_wrong_shapes_is_named(L, error, words):
    with pytest.raises(error, match=words):
        System(J, L)


def test_dependent_in_every_shape():
    """A Symbol or a name alone, or names in one string; a multi-letter name alone was
    split into letters."""
    J2 = jn.JetSpace("x phi")
    f = J2.qd[1] - J2.q[0] * J2.qd[0]
    for dep in ("phi", J2.q[1], ["phi"], "phi,", (J2.q[1],)):
        assert System(J2, J2.qd[0]**2 + J2.qd[1]**2, [f], dependent=dep).dependent == (J2.q[1],)
    s = System(J, T, [F, zd - x * yd], dependent="x z")
    assert s.dependent == (x, z)


@pytest.mark.parametrize("dep, words", [
    (["w"], "not a coordinate"),
    ([xd], "jet of x: give the coordinate"),
    ([1], "of type int"),
    ([x + y], "of type Add"),
    ({x}, "ordered"),
    ([x, x], "repeat"),
    (3, "coordinates"),
])
def test_bad_dependent_is_named(dep, words):
    with pytest.raises(ConstraintError, match=words):
        System(J, T, [F], dependent=dep)


@pytest.mark.parametrize("defaults, words", [
    ([1.0], "mapping"),
    ({m: "2"}, "real number"),
    ({m: a}, "must be a number"),
    ({m: 1j}, "real"),
    ({m: float("nan")}, "finite"),
    ({m: True}, "real number"),
    ({3: 1.0}, "Symbol or its name"),
    ({m: 1.0, "m": 2.0}, "two defaults"),
    ({"mass": 1.0}, "not a parameter"),
])
def test_bad_defaults_are_named(defaults, words):
    with pytest.raises(ConstraintError, match=words):
        System(J, m * T, [F], defaults=defaults)


def test_good_defaults_are_floats():
    s = System(J, m * T, [F], defaults={"m": sp.Rational(3, 2)})
    assert s.defaults == {m: 1.5} and type(s.defaults[m]) is float
    assert System(J, m * T, defaults={m: np.float32(2)}).defaults == {m: 2.0}


def test_branch_is_checked_when_given():
    """Out of range was an IndexError (or silently ignored with one root); now a
    ConstraintError naming the number of solutions, at construction."""
    f = xd**2 - (1 + y**2) * zd**2                      # x' = +-sqrt(1 + y^2) z'
    with pytest.raises(ConstraintError, match="2 solutions"):
        System(J, T, [f], dependent=[x], branch=2)
    with pytest.raises(ConstraintError, match="counts from 0"):
        System(J, T, [f], dependent=[x], branch=-1)
    for bad in ("1", 1.0, True):
        with pytest.raises(ConstraintError, match="integer"):
            System(J, T, [f], dependent=[x], branch=bad)
    s0, s1 = (System(J, T, [f], dependent=[x], branch=b) for b in (0, 1))
    assert sp.simplify(s0.phi[xd] + s1.phi[xd]) == 0
    with pytest.raises(ConstraintError, match="1 solution"):
        System(J, T, [F], branch=1)
    with pytest.warns(JetnhWarning, match="ignored"):
        System(J, T, [F], branch=0)


# ------------------------------------------------------------------ 2. jet look-alikes
@pytest.mark.parametrize("name", ["xdot", "x_dot", "dx", "x_d", "xp", "xt", "dxdt"])
def test_velocity_lookalike_names_warn(name):
    """A hand-made 'xdot' is a constant parameter, not the velocity: say so."""
    v = sp.Symbol(name)
    with pytest.warns(JetnhWarning, match=rf"'{name}'.*constant parameter.*J\.qd\[0\]"):
        s = System(J, T + v * x, [F])
    assert v in s.parameters


def test_jets_of_unknown_bases_and_velocity_named_functions_warn():
    with pytest.warns(JetnhWarning, match="'u_t' is named like a jet of 'u'"):
        System(J, T + sp.Symbol("u_t") * x)
    with pytest.warns(JetnhWarning, match=r"xdot\(t\) is an explicit function, not the velocity"):
        System(J, T + sp.Function("xdot")(J.t) * x)


def test_own_jet_symbols_and_ordinary_parameters_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        System(J, m * T - a * x, [F])
        System(J, T + sp.Symbol("x_t") * x, [F])         # the same Symbol as J.qd[0]


def test_jet_names_with_other_assumptions_are_refused():
    with pytest.raises(JetSpaceError, match="clashes with the jet coordinate"):
        System(J, T + sp.Symbol("x_t", real=True))
    with pytest.raises(JetSpaceError, match="time symbol"):
        System(J, T + sp.Symbol("t", positive=True) * x)


def test_dynamicsymbols_are_converted():
    """x(t) and x(t).diff(t) of sympy.physics.mechanics (or Function('x')(t)) are the
    coordinate and its velocity (they were refused)."""
    X, Y, Z = dynamicsymbols("x y z")
    t = dynamicsymbols._t
    Ld = (X.diff(t)**2 + Y.diff(t)**2 + Z.diff(t)**2) / 2 - m * X
    s = System(J, Ld, [sp.Eq(X.diff(t), Y * Z.diff(t))])
    ref = System(J, T - m * x, [F])
    assert s.L == ref.L and s.constraints == ref.constraints
    assert System(J, sp.Function("x")(J.t).diff(J.t)**2 / 2).L == xd**2 / 2


def test_explicit_functions_of_time_stay():
    """A forcing u(t) is an explicit function (not a coordinate): kept, and derived."""
    u = sp.Function("u")(J.t)
    acc = System(J, T + u * x).equations("chetaev").accelerations()
    assert acc[J.qdd[0]] == u


@pytest.mark.parametrize("name", ["lambda_x", "lambda_z_t", "nu_y", "eta_x"])
def test_parameters_named_like_multipliers_are_refused(name):
    """lambda_x in L was silently the multiplier of x in the vakonomic equations."""
    with pytest.raises(JetSpaceError, match="rename the parameter"):
        System(J, T + sp.Symbol(name) * xd, [F])


@pytest.mark.parametrize("name", ["lambda_x", "nu_y", "eta_x"])
def test_coordinates_named_like_multipliers_are_refused(name):
    """A coordinate lambda_x beside x was refused later, as a jet space given
    'lambda_x' twice, by the vakonomic equations' extended space."""
    K = jn.JetSpace(f"x y {name}")
    x_, y_, w = K.q
    L = (K.qd[0]**2 + K.qd[1]**2 + K.qd[2]**2) / 2
    with pytest.raises(JetSpaceError, match=f"the coordinate '{name}'.*rename the coordinate"):
        System(K, L, [K.qd[0] - w * K.qd[1]], dependent=[x_])


def test_non_symbol_parameters_and_unevaluated_derivatives_are_refused():
    with pytest.raises(JetSpaceError, match=r"not a Symbol.*Symbol\('m_1'\)"):
        System(J, sp.IndexedBase("m")[1] * T)
    with pytest.raises(LagrangianError, match=r"unevaluated derivative.*J\.D"):
        System(J, T + sp.Derivative(x * xd, J.t))
    with pytest.raises(LagrangianError, match="integral"):
        System(J, T + sp.Integral(x, J.t))


# ------------------------------------------------------------------ 3. scale-aware rank
_SCALES = st.integers(-12, 12).map(lambda e: sp.Float(10.0**e))
_EXACT_SCALES = st.integers(-12, 12).map(lambda e: sp.Integer(10)**e)
_ROWS = st.lists(st.integers(-3, 3), min_size=3, max_size=3)


def _quadratic(scales, rows):
    return sum((s * sum(c * v for c, v in zip(r, J.qd)))**2 for s, r in zip(scales, rows)) / 2


@given(st.lists(_SCALES, min_size=3, max_size=3))
@example([sp.Float(1.0), sp.Float(1e-10), sp.Float(1.0)])
@example([sp.Float(1e12), sp.Float(1e-12), sp.Float(1.0)])
def test_diagonal_mass_matrices_of_any_scale_are_regular(scales):
    """L = sum s_i qdot_i^2 / 2 - q_i: regular at every scale; q''_i = -1/s_i (the old
    test, rank at relative tolerance 1e-9, refused s = (1, 1e-10, 1))."""
    L = sum(s * v**2 for s, v in zip(scales, J.qd)) / 2 - x - y - z
    s = System(J, L)
    assert s.is_regular()
    acc = s.equations("chetaev").accelerations()
    for q2, sc in zip(J.qdd, scales):
        assert abs(float(acc[q2]) * float(sc) + 1) < 1e-12


@given(st.lists(_EXACT_SCALES, min_size=3, max_size=3),
       st.lists(_ROWS, min_size=3, max_size=3))
@example([sp.Integer(1), sp.Integer(10)**8, sp.Integer(1)], [[0, 0, 1], [0, 1, 1], [1, 0, 0]])
def test_mass_matrices_regular_iff_rows_independent(scales, rows):
    """H = R^T diag(s^2) R: regular exactly when R is, at any scales s (1e-12..1e12,
    exact: a Float 1e16 + 1 is 1e16, so sympy's own arithmetic would make it singular)."""
    regular = sp.Matrix(rows).rank() == 3
    s = System(J, _quadratic(scales, rows))
    assert s.is_regular() == regular
    eom = s.equations("chetaev")
    if regular:
        eom.accelerations()
    else:
        with pytest.raises(LagrangianError, match="singular|no velocity"):
            eom.accelerations()


def test_truly_singular_lagrangians_are_still_refused():
    for L in ((xd + yd)**2 / 2 + zd**2 / 2, xd + yd**2 + zd**2, 1e10 * (xd + yd)**2 + zd**2):
        with pytest.raises(LagrangianError, match="singular"):
            System(J, L).equations("chetaev").accelerations()


@given(_SCALES, _SCALES, st.booleans())
@example(sp.Float(1e10), sp.Float(1.0), True)
@example(sp.Float(1e-12), sp.Float(1e12), False)
def test_constraint_jacobians_at_any_scale(s1, s2, dependent):
    """Constraints s1 f1, s2 f2: independent at any scales (solved, and the solution
    satisfies them); s1 f and s2 f refused as dependent (1e10 f and f included)."""
    f1 = xd - y * zd
    f2 = f1 if dependent else yd + x * zd
    if dependent:
        with pytest.raises(ConstraintError, match="dependent"):
            System(J, T, [s1 * f1, s2 * f2])
        return
    s = System(J, T, [s1 * f1, s2 * f2])
    assert set(s.dependent) == {x, y}
    for f in (f1, f2):
        assert vanishes(s.on_constraints(f))
    s.equations("vakonomic").accelerations()


def test_rank_ignores_rounding_noise_of_exact_zeros():
    """sin^2 + cos^2 - 1 evaluates to rounding noise, not to a small entry."""
    M = sp.Matrix([[1, 0], [0, sp.sin(x)**2 + sp.cos(x)**2 - 1]])
    assert linalg.numeric_rank(M) == 1
    assert linalg.numeric_rank(sp.Matrix([[1, 0], [0, sp.Float(1e-20) * x]])) == 2


# ------------------------------------------------------------------ 4. Abs and sign
def test_abs_and_sign_are_derived_as_their_smooth_forms():
    """Abs(u) is sqrt(u**2), sign(u) is u/sqrt(u**2): derivatives sign(u) du and 0 (the
    old derivation left Derivative(Abs(x), x) in the accelerations)."""
    k = sp.Symbol("k", positive=True)
    with_abs = System(J, T - k * sp.Abs(x), [xd - sp.Abs(y) * zd])
    with_sqrt = System(J, T - k * sp.sqrt(x**2), [xd - sp.sqrt(y**2) * zd])
    for principle in ("chetaev", "vakonomic", "suslov"):
        assert _same_accelerations(with_abs, with_sqrt, principle)
    acc = with_abs.equations("chetaev").accelerations()
    assert not any(e.has(sp.Derivative, sp.Abs, sp.sign, sp.re, sp.im) for e in acc.values())
    signed = System(J, T - k * sp.sign(x) * x)
    assert _same_accelerations(signed, System(J, T - k * sp.Abs(x)))


@pytest.mark.parametrize("bad", [sp.Heaviside(x), sp.Max(x, y), sp.floor(x),
                                 sp.Piecewise((x, x > 0), (0, True)), sp.re(xd)])
def test_other_nonsmooth_functions_are_refused(bad):
    with pytest.raises(LagrangianError, match="not differentiable"):
        System(J, T + bad)
    with pytest.raises(ConstraintError, match="not differentiable"):
        System(J, T, [xd - bad * zd])
    System(J, T + sp.Max(m, a) * x)          # of parameters only: a constant, fine


def test_scene_stops_at_the_kink_of_abs():
    """V = |x| from x = 1 at rest: x = 1 - t^2/2 reaches the kink at t = sqrt(2), where
    the integrator stops (SINGULAR) instead of stepping across it."""
    from jetnh.numeric import Scene
    from jetnh.numeric.methods._common import SINGULAR

    J1 = jn.JetSpace("x")
    s = System(J1, J1.qd[0]**2 / 2 - sp.Abs(J1.q[0]))
    traj = Scene(s, "chetaev", initial=dict(x=1.0, x_t=0.0), t_span=(0.0, 3.0),
                 cache=False).run(rtol=1e-10, atol=1e-12)
    assert traj.status == SINGULAR and traj.singularity["indicator"] == "x"
    assert abs(traj.t[-1] - np.sqrt(2)) < 1e-6


# ------------------------------------------------------------------ 5. other entry points
def test_unconstrained_system_is_integrable():
    """is_integrable() of a system without constraints was a ConstraintError about B."""
    s = System(J, T)
    assert s.is_integrable() and s.frobenius().integrable
    assert s.classify().integrable and s.T().shape == (0, 3)


def test_lagrangian_without_velocities():
    """Deriving is fine; asking for accelerations says there is no kinetic energy."""
    for L in (3, sp.Integer(0), x**2 + m):
        s = System(J, L, [F])
        assert len(s.equations("vakonomic").expressions) == 3
        assert not s.is_regular()
        with pytest.raises(LagrangianError, match="no velocity"):
            s.equations("chetaev").accelerations()


@pytest.mark.parametrize("call", [
    lambda s: s.equations("hamilton"),
    lambda s: s.equations(["chetaev"]),
    lambda s: s.equations("chetaev", convention=None),
    lambda s: s.equations("suslov", form="explicit"),
    lambda s: jn.compare(s, "vakonomic", "lagrange"),
    lambda s: jn.compare(s, "vakonomic", "suslov", convention="both"),
])
def test_unknown_names_are_principle_errors(call):
    with pytest.raises(PrincipleError):
        call(System(J, T, [F]))


def test_name_must_be_text():
    with pytest.raises(ConstraintError, match="name must be a str"):
        System(J, T, name=3)
    assert isinstance(ConstraintError("x"), JetnhError)
