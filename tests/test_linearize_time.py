"""jetnh.numeric.linearize on equations that depend on t: the frozen eigenvalues decide
no stability (damped Mathieu equation at parametric resonance: unstable, against Floquet
multipliers from jetnh's own A(t) and from the closed-form equation), a point where x'
vanishes for an instant is no steady motion (forced oscillator), a moving holonomic
constraint, parameter values that remove t give the frozen verdict again, ``along``,
``verdicts``, ``steady``, the CLI; random systems with a modulated term."""

import json

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, assume, given, settings, strategies as st
from scipy.integrate import solve_ivp

import jetnh as jn
import jetnh.strategies as jst
from jetnh.errors import ConstraintError, LinearizationError, PrincipleError
from jetnh.numeric.linearize import NOT_STEADY, TIME_DEPENDENT, verdicts

a, b, w, c, F = sp.symbols("a b w c F")
MATHIEU = {"a": 1.0, "b": 0.4, "w": 2.0, "c": 0.05}
ORIGIN = {"x": 0.0, "y": 0.0, "x_t": 0.0, "y_t": 0.0}


def _mathieu():
    """x'' + c x' + (a + b cos w t) x = 0 and y'' + c y' + y = 0, from L and forces."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    L = (xt**2 + yt**2) / 2 - (a + b * sp.cos(w * J.t)) * x**2 / 2 - y**2 / 2
    return jn.System(J, L, forces={x: -c * xt, y: -c * yt})


def _monodromy_closed(p):
    """The monodromy matrix of x'' + c x' + (a + b cos w t) x = 0 over 2 pi / w."""
    def f(t, s):
        return [s[1], -p["c"] * s[1] - (p["a"] + p["b"] * np.cos(p["w"] * t)) * s[0]]
    T = 2 * np.pi / p["w"]
    return np.column_stack([solve_ivp(f, (0, T), e, rtol=1e-12, atol=1e-14).y[:, -1]
                            for e in ([1.0, 0.0], [0.0, 1.0])])


def _monodromy_frozen(lin, steps=400):
    """The monodromy matrix of x' = A(t) x over one period from jetnh's frozen A at the
    midpoints (``replace(t=)``), by the implicit midpoint rule (second order)."""
    T = 2 * np.pi / lin.params["w"]
    h = T / steps
    I = M = np.eye(len(lin.state_names))
    for k in range(steps):
        hA = lin.replace(t=(k + 0.5) * h).A * h
        M = np.linalg.solve(I - hA / 2, (I + hA / 2) @ M)
    return M


# ---------------------------------------------------------------------- regressions
def test_mathieu_resonance_is_not_certified_stable():
    """The audit's reproducer: every frozen eigenvalue has real part -c/2 (the frozen
    verdict would be "asymptotically stable"), but the motion is unstable (Floquet
    multiplier 1.264 > 1 by two routes); the verdict says the frozen eigenvalues do not
    decide, and A and the eigenvalues stay available."""
    lin = jn.linearize(_mathieu(), "chetaev", at=ORIGIN, params=MATHIEU)
    assert lin.steady_motion and lin.time_dependent and lin.residual == 0.0
    assert lin.verdict == TIME_DEPENDENT and lin.stable is None and np.isnan(lin.margin)
    # the frozen spectrum at t = 0: lambda^2 + c lambda + k = 0, k = a + b and 1
    want = np.concatenate([np.roots([1.0, 0.05, k]) for k in (1.4, 1.0)])
    assert np.allclose(np.sort_complex(lin.eigenvalues), np.sort_complex(want), atol=1e-12)
    assert np.all(lin.eigenvalues.real < 0)
    mu_closed = np.abs(np.linalg.eigvals(_monodromy_closed(MATHIEU))).max()
    M = _monodromy_frozen(lin)
    mu_frozen = np.abs(np.linalg.eigvals(M[np.ix_([0, 2], [0, 2])])).max()
    assert mu_closed == pytest.approx(1.264, abs=1e-3)
    assert mu_frozen == pytest.approx(mu_closed, rel=1e-3)
    # the y block is autonomous and damped: multipliers exp(-c T / 2) in modulus
    assert np.allclose(np.abs(np.linalg.eigvals(M[np.ix_([1, 3], [1, 3])])),
                       np.exp(-0.05 * np.pi / 2), rtol=1e-4)


def test_forced_equilibrium_for_an_instant_is_no_steady_motion():
    """The audit's second reproducer: x_t^2/2 - x^2/2 + F cos(w t) x at x = x_t = 0 and
    t = pi/2 w: x' vanishes there (a zero of the forcing) but not an instant later."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    S = jn.System(J, xt**2 / 2 - x**2 / 2 + F * sp.cos(w * J.t) * x, forces={x: -c * xt})
    P = {"F": 1.0, "w": 1.0, "c": 0.1}
    lin = jn.linearize(S, at={"x": 0, "x_t": 0}, params=P, t=np.pi / 2)
    assert lin.residual < 1e-15
    assert not lin.steady_motion and lin.time_dependent
    assert lin.verdict == NOT_STEADY and lin.stable is None
    # A does not depend on t here, only x' does: [[0, 1], [-1, -c]]
    assert np.allclose(lin.A, [[0.0, 1.0], [-1.0, -0.1]], atol=1e-14)
    # steady() finds x' = 0 at this instant only: refused
    with pytest.raises(LinearizationError, match="not at other times"):
        lin.replace(t=0.0).steady(["x"])
    # without the forcing the same point is a steady motion, damped
    calm = lin.replace(params={"F": 0.0})
    assert calm.steady_motion and not calm.time_dependent
    assert calm.verdict == "asymptotically stable" and calm.stable


def test_parameters_that_remove_t_give_the_frozen_verdict():
    """b = 0: the Mathieu pair is autonomous and damped; ``along`` b gives undecided
    values where b != 0 and no crossing between a decided and an undecided value."""
    lin = jn.linearize(_mathieu(), at=ORIGIN, params={**MATHIEU, "b": 0.0})
    assert not lin.time_dependent and lin.verdict == "asymptotically stable" and lin.stable
    scan = lin.along("b", [0.0, 0.4, 0.8])
    assert scan.time_dependent.tolist() == [False, True, True]
    assert scan.steady_motion.tolist() == [True, True, True]
    assert np.isfinite(scan.margins[0]) and np.all(np.isnan(scan.margins[1:]))
    assert scan.stable.tolist() == [True, False, False] and scan.crossings == ()
    assert scan.frame["time_dependent"].tolist() == [False, True, True]


def test_verdicts_inherit():
    """``verdicts`` reports the undecided verdict under every principle (no
    constraints: every principle gives the same motion)."""
    table = verdicts(_mathieu(), ORIGIN, MATHIEU)
    assert set(table["verdict"]) == {TIME_DEPENDENT}


def test_moving_holonomic_constraint():
    """g = x - s sin(w t): a fixed point on g = 0 at t = 0 leaves it at other times, so it
    is no steady motion; s = 0 makes g fixed and the point steady again."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    s = sp.Symbol("s")
    S = jn.System(J, (xt**2 + yt**2) / 2 - y**2 / 2, [x - s * sp.sin(w * J.t)],
                  dependent=[x])
    lin = jn.linearize(S, at={"x": 0.0, "y": 0.0, "y_t": 0.0},
                       params={"s": 0.5, "w": 1.0})
    assert lin.eliminated == ("x",)
    assert lin.time_dependent and not lin.steady_motion and lin.verdict == NOT_STEADY
    fixed = lin.replace(params={"s": 0.0})
    assert not fixed.time_dependent and fixed.steady_motion and fixed.verdict == "marginal"


# ---------------------------------------------------------------------- random systems
def _caldirola_kanai():
    """L = exp(g t) (m q_t^2/2 - k q^2/2): q'' = -g q' - k q / m, its rows with the
    factor exp(g t) exp(-g t), which overflows at g t ~ 710."""
    J = jn.JetSpace("q")
    (q,), (qt,) = J.q, J.qd
    g, m, k = sp.symbols("gamma m k")
    return jn.System(J, sp.exp(g * J.t) * (m * qt**2 / 2 - k * q**2 / 2))


def test_exp_factors_that_cancel_at_large_t():
    """L8: the damped oscillator of Caldirola and Kanai has rows that do not depend on t
    (exp(g t) exp(-g t) cancels), so its linearization is the same at every t: at
    g t = 1e3 (was a LinearizationError blaming the coordinates) as at 0, bit for bit,
    with the closed-form eigenvalues -g/2 +- i sqrt(k/m - g^2/4), and no t in
    ``symbolic()``; off the origin no steady motion, and ``steady`` finds q = 0."""
    S, P = _caldirola_kanai(), {"gamma": 0.1, "m": 2.0, "k": 3.0}
    at = {"q": 0.0, "q_t": 0.0}
    want = -0.05 + 1j * np.sqrt(1.5 - 0.0025) * np.array([-1, 1])
    ref = jn.linearize(S, at=at, params=P)
    for t in (1e2, 7.1e3, 1e4):
        lin = jn.linearize(S, at=at, params=P, t=t)
        assert not lin.time_dependent and lin.verdict == "asymptotically stable"
        np.testing.assert_array_equal(lin.A, ref.A)
        np.testing.assert_allclose(lin.eigenvalues, want, rtol=1e-14)
        off = lin.replace(at={"q": 1e-3})
        assert off.verdict == NOT_STEADY and off.rates[1] == pytest.approx(-1.5e-3)
        assert off.steady(["q"]).at["q"] == pytest.approx(0.0, abs=1e-15)
    g, m, k = sp.symbols("gamma m k")
    assert ref.symbolic() == sp.Matrix([[0, 1], [-k / m, -g]])


@pytest.mark.parametrize("t", [1.0, 3.0])
def test_a_switch_in_t_is_evaluated_at_the_point_s_t(t):
    """x'' = -k(t) x with k switching from 1 to 4 at t = 2 (sign(t - 2), which jetnh
    rewrites smoothly: its derivative in t vanishes on each side of the kink): the rows
    are not the same at every t, so they are evaluated at t, not at t = 0."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    k = 1 + 3 * (1 + sp.sign(J.t - 2)) / 2
    lin = jn.linearize(jn.System(J, xt**2 / 2 - k * x**2 / 2), "chetaev",
                       at={"x": 0.0, "x_t": 0.0}, t=t)
    assert np.array_equal(lin.A, [[0.0, 1.0], [-float(k.subs(J.t, t)), 0.0]])


def test_exp_factors_that_cancel_with_a_constraint():
    """A knife edge with L = exp(g t) L0 under Chetaev's principle is L0 with the forces
    -g dL0/dq_t (a second route, no exp in it): the same A, rates and verdict at
    g t = 900 as that system's, under which the overflow used to stop it."""
    J = jn.JetSpace("x y th")
    (x, y, th), (xt, yt, tht) = J.q, J.qd
    g, m, I, k = sp.symbols("gamma m I k")
    L0 = m * (xt**2 + yt**2) / 2 + I * tht**2 / 2 - k * th**2 / 2
    f = [sp.sin(th) * xt - sp.cos(th) * yt]
    S = jn.System(J, sp.exp(g * J.t) * L0, f, [y])
    S0 = jn.System(J, L0, f, [y], forces={q: -g * sp.diff(L0, v) for q, v in zip(J.q, J.qd)})
    P = {"gamma": 0.3, "m": 2.0, "I": 0.5, "k": 1.0}
    rest, running = ({"x": 0, "y": 0, "th": 0.0, "x_t": 0.0, "th_t": 0},
                     {"x": 0, "y": 0, "th": 0.1, "x_t": 1.0, "th_t": 0})
    for at, verdict in ((rest, "asymptotically stable"), (running, NOT_STEADY)):
        lin, lin0 = jn.linearize(S, at=at, params=P, t=3e3), jn.linearize(S0, at=at, params=P)
        assert lin.state_names == lin0.state_names == ("th", "x_t", "th_t")
        np.testing.assert_allclose(lin.A, lin0.A, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(lin.rates, lin0.rates, rtol=1e-14, atol=1e-15)
        assert lin.verdict == lin0.verdict == verdict


def _modulated_drag():
    """x'' = -c (1 + b cos(w t)) x': at rest a steady motion whose A = -c (1 + b cos w t)
    changes with t (x is cyclic: the state is x_t alone, A a rate)."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    return jn.System(J, xt**2 / 2, forces={x: -c * (1 + b * sp.cos(w * J.t)) * xt})


@pytest.mark.parametrize("unit", [1e-6, 1e-3, 1.0, 1e3])
@pytest.mark.parametrize("t", [0.0, 1e4])
def test_time_dependence_in_every_unit_of_time(unit, t):
    """The same motion with time in units of ``unit`` seconds (rates times unit): A
    changes with t in every unit (``time_dependent``; the frozen verdict, asymptotically
    stable, decides nothing), at t = 0 and at 1e4 s.  It was judged against max(1, |A|)
    with offsets in units of max(1, |t|): at t = 1e4 s in milliseconds (A = -1e-6 per
    ms, changes of 1e-13 below an absolute 1e-12) and at t = 0 in microseconds the
    verdict was the frozen one."""
    P = {"c": 1e-3 * unit, "b": 1e-7, "w": 2.0 * unit}
    lin = jn.linearize(_modulated_drag(), at={"x_t": 0.0}, params=P, t=t / unit)
    assert lin.state_names == ("x_t",) and lin.steady_motion
    assert lin.eigenvalues[0].real == pytest.approx(-1e-3 * unit * (1 + 1e-7 * np.cos(2 * t)),
                                                    rel=1e-15)
    assert lin.time_dependent and lin.verdict == TIME_DEPENDENT
    assert not lin.replace(params={"b": 0.0}).time_dependent


@settings(max_examples=4, deadline=None, suppress_health_check=list(HealthCheck))
@given(jst.constrained_systems(min_n=2, max_n=3), st.integers(0, 2**16))
def test_modulated_term_on_random_systems(case, seed):
    """Random constrained systems (t set to 0) with a modulated term
    beta cos(w t) (q0 - k)^2 / 2 added to L (q0 an independent coordinate), linearized
    at q0 = k (where the term and its force vanish): at beta = 0 A does not change with
    t and the verdict is the frozen one; at beta != 0 x' is that of beta = 0,
    A(t) = A0 + cos(w t) B with B only in the column of q0, and where B != 0 no
    stability is certified."""
    J, L, constraints, dependent = case
    frozen = {J.t: sp.Integer(0)}                     # an autonomous system to start from
    L, constraints = L.xreplace(frozen), [f.xreplace(frozen) for f in constraints]
    beta, k = sp.symbols("beta k")
    q0 = next(q for q in J.q if q not in set(dependent or ()))
    try:
        S = jn.System(J, L + beta * sp.cos(w * J.t) * (q0 - k)**2 / 2, constraints,
                      dependent)
    except jn.JetnhError:
        assume(False)
    rng = np.random.default_rng(seed)
    at = {q.name: rng.uniform(-0.5, 0.5) for q in J.q}
    at.update({v.name: rng.uniform(-0.5, 0.5) for v in S.independent_velocities})
    P = {"beta": 0.0, "w": 1.3, "k": at[q0.name]}
    try:
        lin0 = jn.linearize(S, "chetaev", at=at, params=P, drop=None)
    except (LinearizationError, ConstraintError, PrincipleError):
        assume(False)
    assume(np.all(np.isfinite(lin0.A)) and not lin0.limit)
    assert not lin0.time_dependent
    assert np.allclose(lin0.replace(t=2.9).A, lin0.A, rtol=1e-13, atol=1e-13)
    lin1 = lin0.replace(params={"beta": 0.7})
    assert lin1.steady_motion == lin0.steady_motion
    assert np.allclose(lin1.rates, lin0.rates, rtol=1e-12, atol=1e-12)
    scale = max(1.0, np.abs(lin0.A).max())
    B = lin1.A - lin0.A                               # cos(w t) = 1 at t = 0
    i = lin1.state_names.index(q0.name)
    assert np.abs(np.delete(B, i, axis=1)).max() <= 1e-10 * scale
    half = lin1.replace(t=np.pi / 2 / 1.3).A          # cos = 0
    turn = lin1.replace(t=np.pi / 1.3).A              # cos = -1
    assert np.allclose(half, lin0.A, atol=1e-10 * scale)
    assert np.allclose(turn - lin0.A, -B, atol=1e-10 * scale)
    if np.abs(B).max() > 1e-9 * scale:
        assert lin1.time_dependent and lin1.stable is None and np.isnan(lin1.margin)
        assert lin1.verdict == (TIME_DEPENDENT if lin1.steady_motion else NOT_STEADY)
    else:                                             # the constraints absorb the term
        assert not lin1.time_dependent and lin1.verdict == lin0.verdict


MATHIEU_TOML = '''name = "damped Mathieu pair"
coordinates = ["x", "y"]
lagrangian = "(x_t**2 + y_t**2)/2 - (a + b*cos(w*t))*x**2/2 - y**2/2"
constraints = []
[parameters]
a = 1.0
b = 0.4
w = 2.0
c = 0.05
[forces]
x = "-c*x_t"
y = "-c*y_t"
'''


def test_cli_inherits(capsys, tmp_path):
    """``jetnh linearize`` of the model file: the verdict (text and JSON) and a scan in
    b stable only at b = 0."""
    from jetnh.cli import main

    path = tmp_path / "mathieu.toml"
    path.write_text(MATHIEU_TOML)
    assert main(["linearize", str(path), "-q", "--at", "x=0,y=0,x_t=0,y_t=0"]) == 0
    out = capsys.readouterr().out
    assert f"verdict: {TIME_DEPENDENT}" in out
    assert main(["linearize", str(path), "-q", "--at", "x=0,y=0,x_t=0,y_t=0",
                 "--param", "b=0:0.4:3", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["verdict"] == TIME_DEPENDENT and data["steady_motion"] is True
    assert data["scan"]["stable"] == [True, False, False]
    assert data["scan"]["crossings"] == []
