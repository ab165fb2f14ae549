"""jetnh.numeric.linearize: A against central differences of the compiled rhs and against
the symbolic A on the graph (random systems, every principle), closed forms (Chaplygin
sleigh, upright rolling coin derived independently here), sympy's Linearizer, split
invariance, removable singularities, steady motions, bad input."""

import numpy as np
import pytest
import sympy as sp
from sympy.core.function import AppliedUndef
from hypothesis import HealthCheck, assume, given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh import models
from jetnh.algebra import dag
from jetnh.mechanics import principles
from jetnh.errors import ConstraintError, JetnhError, LinearizationError, PrincipleError
from jetnh.numeric.linearize import verdicts

SLEIGH = models.get("chaplygin_sleigh")
COIN = models.get("rolling_coin")


# ---------------------------------------------------------------------- two routes to A
def _differences(lin, h=1e-6):
    """Central differences of the compiled rhs on the kept states."""
    ck, keep = lin._kernels, list(lin._keep)
    y, p, t = lin._y, lin._p, lin.t
    f0, f1 = np.empty(len(y)), np.empty(len(y))
    full = np.empty((len(y), len(y)))
    for j in range(len(y)):
        e = np.zeros(len(y))
        e[j] = h
        ck.rhs(t, y + e, p, f1)
        ck.rhs(t, y - e, p, f0)
        full[:, j] = (f1 - f0) / (2 * h)
    return full[np.ix_(keep, keep)], full


@settings(max_examples=8, deadline=None, suppress_health_check=list(HealthCheck))
@given(jst.systems(min_n=2, max_n=3), st.sampled_from(jn.PRINCIPLES),
       st.integers(0, 2**16))
def test_A_against_differences_and_the_graph(s, principle, seed):
    """Random systems (affine and nonlinear constraints), every principle: A equals the
    central differences of the compiled rhs and the symbolic A evaluated on the graph;
    the dropped coordinates' columns vanish."""
    J = s.J
    rng = np.random.default_rng(seed)
    lams = [lam.name for lam in principles.get(principle).multiplier_symbols(s)]
    at = {q.name: rng.uniform(-0.5, 0.5) for q in J.q}
    at.update({v.name: rng.uniform(-0.5, 0.5) for v in s.independent_velocities})
    at.update({n: rng.uniform(-0.5, 0.5) for n in lams})
    try:
        lin = jn.linearize(s, principle, at=at, t=0.1)
    except (LinearizationError, ConstraintError, PrincipleError):
        assume(False)
    assume(np.all(np.isfinite(lin.A)) and not lin.limit)
    D, full = _differences(lin)
    scale = max(1.0, np.abs(lin.A).max())
    assert np.allclose(lin.A, D, atol=1e-6 * scale, rtol=1e-6)
    for c in lin.dropped:                       # the dropped columns vanish
        j = [q.name for q in J.q].index(c)
        assert np.abs(full[list(lin._keep), j]).max() < 1e-7 * scale
    point = {sym: lin.at[sym.name] for sym in J.q + s.independent_velocities}
    point.update({sp.Symbol(n): lin.at[n] for n in lams})
    point[J.t] = 0.1
    S = lin.symbolic()
    names = {sym.name: sym for sym in dag.free_symbols(list(S))}
    vals = dag.evaluate(list(S), {names[k.name]: v for k, v in point.items()
                                  if k.name in names})
    sym_A = np.array([complex(v).real for v in vals]).reshape(lin.A.shape)
    assert np.allclose(lin.A, sym_A, atol=1e-10 * scale, rtol=1e-10)


@pytest.mark.parametrize("principle", jn.PRINCIPLES)
def test_nonlinear_constraint_with_nonzero_multipliers(principle):
    """Appell-Hamel (zdot = (b/a) sqrt(xdot^2 + ydot^2)) off any steady motion, with
    nonzero multipliers: the case where a linearizer that lets the multiplier term
    depend on q and lambda only drops a term; A equals the differences of the rhs."""
    s = models.get("appell_hamel")
    lams = {m.name: 0.7 for m in principles.get(principle).multiplier_symbols(s)}
    lin = jn.linearize(s, principle, at={"x": 0.1, "y": -0.3, "z": 0.2, "x_t": 0.9,
                                         "y_t": 0.4, **lams})
    D, _ = _differences(lin)
    assert lin.residual > 0.1 and np.abs(lin.A).max() > 0.1
    assert np.allclose(lin.A, D, atol=1e-7, rtol=1e-6)


# ---------------------------------------------------------------------- closed forms
def test_sleigh_straight_motion():
    """Chaplygin sleigh running straight at speed v (heading 0.3): eigenvalues 0, 0 and
    -m a v/(I + m a^2); stable forwards, unstable backwards; steady both ways."""
    m, I, a = 1.0, 0.2, 0.5
    for v in (1.0, -1.0, 2.5):
        lin = jn.linearize(SLEIGH, "chetaev", at={"theta": 0.3, "x_t": v * np.cos(0.3),
                                                  "theta_t": 0.0})
        assert lin.state_names == ("theta", "x_t", "theta_t") and lin.dropped == ("x", "y")
        assert lin.residual == 0.0
        ev = sorted(lin.eigenvalues.real)
        expected = sorted([0.0, 0.0, -m * a * v / (I + m * a**2)])
        assert np.allclose(ev, expected, atol=1e-12)
        assert lin.stable == (v > 0)
        assert lin.verdict == ("marginal" if v > 0 else "unstable")


def test_bead_on_parabola_small_oscillations():
    """y = a x^2 through ydot = 2 a x xdot: rest at the bottom is an equilibrium with
    x'' = -2 a g x, eigenvalues +-i sqrt(2 a g) under Chetaev (the constraint is
    integrable: a holonomic system)."""
    s = models.get("bead_on_parabola")
    lin = jn.linearize(s, at={"x": 0.0, "x_t": 0.0}, params={"a": 0.7, "g": 9.81})
    assert lin.state_names == ("x", "x_t") and lin.residual == 0.0
    assert np.allclose(lin.A, [[0.0, 1.0], [-2 * 0.7 * 9.81, 0.0]], atol=1e-12)
    assert lin.verdict == "marginal" and lin.stable


def _coin_by_hand():
    """The Chetaev equations of the rolling coin by plain sympy (functions of t, the
    Lagrange multiplier rule for the two rolling constraints), independent of jetnh:
    the accelerations of psi, theta, phi in terms of (theta, psi_t, theta_t, phi_t)."""
    t = sp.Symbol("t")
    m, r, A, B, g = sp.symbols("m r A B g", positive=True)
    x, y, psi, th, phi = [sp.Function(n)(t) for n in ("x", "y", "psi", "theta", "phi")]
    q = [x, y, psi, th, phi]
    qd = [sp.diff(v, t) for v in q]
    C = sp.Matrix([x + r * sp.sin(th) * sp.sin(psi), y - r * sp.sin(th) * sp.cos(psi),
                   r * sp.cos(th)])
    vC = C.diff(t)
    L = (m * vC.dot(vC) / 2 + (A * (qd[4] + qd[2] * sp.sin(th))**2
                               + B * (qd[3]**2 + qd[2]**2 * sp.cos(th)**2)) / 2
         - m * g * r * sp.cos(th))
    f = [qd[0] - r * sp.cos(psi) * qd[4], qd[1] - r * sp.sin(psi) * qd[4]]
    l1, l2 = sp.symbols("l1 l2")
    E = [sp.diff(sp.diff(L, qd[i]), t) - sp.diff(L, q[i])
         - l1 * sp.diff(f[0], qd[i]) - l2 * sp.diff(f[1], qd[i]) for i in range(5)]
    qdd = [sp.diff(v, t, 2) for v in q]
    sol = sp.solve(f + [sp.diff(e, t) for e in f], [qd[0], qd[1], qdd[0], qdd[1]],
                   dict=True)[0]
    E = [e.subs(sol) for e in E]
    E = [e.subs(sp.solve(E[:2], [l1, l2], dict=True)[0]) for e in E[2:]]
    acc = sp.solve(E, qdd[2:], dict=True)[0]
    S = sp.symbols("theta psi_t theta_t phi_t")
    # the heading enters as sin^2 + cos^2 only: any value
    R = lambda e: e.subs({qd[2]: S[1], qd[3]: S[2], qd[4]: S[3]}).subs(  # noqa: E731
        {th: S[0], psi: sp.Rational(3, 10)})
    rows = [S[2], R(acc[qdd[2]]), R(acc[qdd[3]]), R(acc[qdd[4]])]
    return rows, S, (m, r, A, B, g)


@pytest.fixture(scope="module")
def coin_by_hand():
    return _coin_by_hand()


def test_upright_coin_critical_spin(coin_by_hand):
    """Upright rolling: A equals the hand-derived Jacobian; the characteristic polynomial
    lambda^2 (B (B + m r^2) lambda^2 + A (A + m r^2) Omega^2 - B m g r) gives the critical
    spin Omega_c^2 = B m g r/(A (A + m r^2)) (g/(3 r) for a thin disk), which the scan's
    crossing locates to 1e-10."""
    rows, S, (m, r, A, B, g) = coin_by_hand
    Om, lam = sp.symbols("Omega lambda")
    Jm = sp.Matrix(rows).jacobian(S).subs({S[0]: 0, S[1]: 0, S[2]: 0, S[3]: Om})
    poly = sp.factor(sp.together(Jm.charpoly(lam).as_expr()))
    crit = sp.solve(sp.Poly(sp.numer(poly) / lam**2, lam).coeff_monomial(1), Om)
    crit2 = sp.simplify(max(crit, key=lambda c: c.subs({m: 1, r: 1, A: 1, B: 1, g: 1}))**2)
    assert sp.simplify(crit2 - B * m * g * r / (A * (A + m * r**2))) == 0
    thin = {A: m * r**2 / 2, B: m * r**2 / 4}
    assert sp.simplify(crit2.subs(thin) - g / (3 * r)) == 0
    values = {m: 1.3, r: 0.7, A: 0.3, B: 0.2, g: 9.81}
    lin = jn.linearize(COIN, at={"theta": 0.0, "psi_t": 0.0, "theta_t": 0.0, "phi_t": 3.0},
                       params={k.name: v for k, v in values.items()})
    assert lin.state_names == ("theta", "psi_t", "theta_t", "phi_t")
    assert set(lin.dropped) == {"x", "y", "psi", "phi"}     # psi: by the zero test
    hand = np.array(Jm.subs(values).subs(Om, 3.0), dtype=float)
    assert np.allclose(lin.A, hand, atol=1e-12)
    omega_c = float(sp.sqrt(crit2.subs(values)))
    scan = lin.along("phi_t", np.linspace(0.2, 4.0, 20))
    assert len(scan.crossings) == 1
    assert abs(scan.crossings[0] - omega_c) < 1e-10
    assert not scan.stable[0] and scan.stable[-1]
    frame = scan.frame
    assert list(frame.columns[:2]) == ["phi_t", "re_1"] and len(frame) == 20
    ax = scan.plot()
    assert ax.get_xlabel() == "phi_t" and ax.get_ylabel()
    # the thin disk: sqrt(g/(3 r)), along a parameter too
    thin_lin = lin.replace(params={"A": 0.5, "B": 0.25, "m": 1.0, "r": 1.0})
    scan = thin_lin.along("phi_t", [1.0, 3.0])
    assert abs(scan.crossings[0] - np.sqrt(9.81 / 3)) < 1e-10
    # at fixed spin, along gravity: stable below g_c = Omega^2 A (A + m r^2)/(B m r)
    g_scan = thin_lin.replace(at={"phi_t": 2.0}).along("g", [1.0, 20.0])
    assert abs(g_scan.crossings[0] - 4.0 * 0.5 * 1.5 / 0.25) < 1e-9


def test_coin_steady_turning(coin_by_hand):
    """Given the lean and the turning rate, ``steady`` finds the spin at which the coin
    turns steadily: the hand-derived accelerations vanish there."""
    rows, S, params = coin_by_hand
    values = dict(zip(params, (1.0, 1.0, 0.5, 0.25, 9.81)))
    lin = jn.linearize(COIN, at={"theta": 0.2, "psi_t": 1.5, "theta_t": 0.0, "phi_t": 4.0})
    assert lin.residual > 1e-3
    st_ = lin.steady(["phi_t"])
    assert st_.residual < 1e-10
    point = {S[0]: 0.2, S[1]: 1.5, S[2]: 0.0, S[3]: st_.at["phi_t"]}
    assert all(abs(float(e.subs(values).subs(point))) < 1e-9 for e in rows)
    with pytest.raises(LinearizationError, match="no steady motion"):
        lin.replace(at={"theta": 1.4, "psi_t": 0.0}).steady(["phi_t"])


def test_sympy_linearizer_on_the_sleigh():
    """sympy's LagrangesMethod linearizer (affine constraint, Chetaev dynamics: where it is
    right, once its multiplier and accelerations are given their operating values) gives
    the full-state A of jetnh (drop=None)."""
    from jetnh.models.planar import chaplygin_sleigh_lagranges

    LM, (x, y, th), (xd, yd, thd) = chaplygin_sleigh_lagranges()
    linr = LM.to_linearizer(q_ind=[x, y, th], qd_ind=[xd, thd], qd_dep=[yd])
    v = 0.8
    op = {x: 0.1, y: -0.2, th: 0.3, xd: v * np.cos(0.3), yd: v * np.sin(0.3), thd: 0.0}
    A = linr.linearize(op_point=op, A_and_B=True)[0]
    A = A.subs({d: 0 for d in A.atoms(sp.Derivative)})       # steady: no acceleration
    A = np.array(A.subs({f: 0 for f in A.atoms(AppliedUndef)}), dtype=float)  # lam1 = 0
    lin = jn.linearize(SLEIGH, at={"x": 0.1, "y": -0.2, "theta": 0.3,
                                   "x_t": v * np.cos(0.3), "theta_t": 0.0}, drop=None)
    assert lin.state_names == ("x", "y", "theta", "x_t", "theta_t")
    assert np.allclose(lin.A, A, atol=1e-12)


def test_eigenvalues_invariant_under_the_split():
    """The sleigh with y or x dependent (both regular at heading 0.6, neither past the
    edge of its chart), at a steady motion: the same eigenvalues under chetaev and
    vakonomic."""
    J = SLEIGH.J
    other = jn.System(J, SLEIGH.L, SLEIGH.constraints, [J.q[0]], defaults=SLEIGH.defaults)
    v = 1.3
    for principle, lam in (("chetaev", {}), ("vakonomic", {"lambda": 0.0})):
        a = jn.linearize(SLEIGH, principle, at={"theta": 0.6, "x_t": v * np.cos(0.6),
                                                "theta_t": 0.0,
                                                **{f"{k}_y": x for k, x in lam.items()}})
        b = jn.linearize(other, principle, at={"theta": 0.6, "y_t": v * np.sin(0.6),
                                               "theta_t": 0.0,
                                               **{f"{k}_x": x for k, x in lam.items()}})
        assert a.residual < 1e-14 and b.residual < 1e-14
        assert a.state_names != b.state_names
        assert np.allclose(np.sort_complex(a.eigenvalues), np.sort_complex(b.eigenvalues),
                           atol=1e-9)


def test_verdicts_across_principles():
    """One steady motion (the sleigh running forwards) under the four principles; the
    Suslov multiplier is solved for to make the point steady."""
    at = {"theta": 0.0, "x_t": 1.0, "theta_t": 0.0}
    table = verdicts(SLEIGH, at, solve_for={"suslov": ["lambda_y"]})
    assert list(table.index) == list(jn.PRINCIPLES)
    assert (table["residual"] < 1e-10).all()
    assert table.loc["chetaev", "verdict"] == "marginal"
    assert table.loc["vakonomic", "verdict"] == "unstable"
    for pr in jn.PRINCIPLES:                       # each row is linearize's own answer
        point = {**at, **({"lambda_y": 0.0} if pr != "chetaev" else {})}
        lin = jn.linearize(SLEIGH, pr, at=point)
        if pr == "suslov":
            lin = lin.steady(["lambda_y"])
        assert table.loc[pr, "verdict"] == lin.verdict


def test_replace_is_the_same_as_a_new_linearization():
    lin = jn.linearize(COIN, at={"theta": 0.1, "psi_t": 0.2, "theta_t": 0.0, "phi_t": 3.0})
    other = lin.replace(params={"g": 1.62}, at={"theta": 0.05})
    fresh = jn.linearize(COIN, at={"theta": 0.05, "psi_t": 0.2, "theta_t": 0.0,
                                   "phi_t": 3.0}, params={"g": 1.62})
    assert np.array_equal(other.A, fresh.A) and other.params["g"] == 1.62
    assert lin.params["g"] == 9.81                   # unchanged: values are immutable
    with pytest.raises(ValueError):
        lin.A[0, 0] = 1.0
    with pytest.raises(jn.errors.FrozenError):
        lin.residual = 0.0


def test_limit_at_a_removable_singularity():
    """V = -sin(x)/x: the compiled kernel is 0/0 at x = 0, the linearization is the
    limit x'' = -x/3 (no NaN)."""
    J = jn.JetSpace("x")
    x, = J.q
    s = jn.System(J, J.qd[0]**2 / 2 + sp.sin(x) / x)
    lin = jn.linearize(s, at={"x": 0.0, "x_t": 0.0})
    assert lin.limit
    assert np.allclose(lin.A, [[0.0, 1.0], [-1.0 / 3.0, 0.0]], atol=1e-9)
    assert lin.residual < 1e-9


def test_bad_input():
    at = {"theta": 0.0, "x_t": 1.0, "theta_t": 0.0}
    with pytest.raises(PrincipleError):
        jn.linearize(SLEIGH, "newtonian", at=at)
    with pytest.raises(JetnhError, match="missing operating-point values: theta_t"):
        jn.linearize(SLEIGH, at={"theta": 0.0, "x_t": 1.0})
    with pytest.raises(JetnhError, match="lambda_y"):
        jn.linearize(SLEIGH, "vakonomic", at=at)
    with pytest.raises(ConstraintError, match="off the constraints"):
        jn.linearize(SLEIGH, at={**at, "y_t": 0.5})
    with pytest.raises(JetnhError, match="cannot drop 'theta'"):
        jn.linearize(SLEIGH, at=at, drop=["theta"])
    with pytest.raises(JetnhError, match="not a coordinate"):
        jn.linearize(SLEIGH, at=at, drop=["x_t"])
    with pytest.raises(JetnhError, match="not a parameter"):
        jn.linearize(SLEIGH, at=at, params={"R": 1.0})
    with pytest.raises(JetnhError, match="not a state"):
        jn.linearize(SLEIGH, at={**at, "zeta": 1.0})
    with pytest.raises(JetnhError, match="drop must be"):
        jn.linearize(SLEIGH, at=at, drop="all")
    lin = jn.linearize(SLEIGH, at={**at, "y": 0.0}, drop=["x"])
    assert lin.state_names == ("y", "theta", "x_t", "theta_t")
    assert jn.linearize(SLEIGH, at={**at, "x": 0.0, "y": 0.0}, drop=None).A.shape == (5, 5)


@pytest.mark.parametrize("name", ["rolling_disk", "suslov_rigid_body", "ball_on_turntable",
                                  "n_trailer"])
@pytest.mark.parametrize("principle", ["chetaev", "vakonomic"])
def test_term_sizes_program_is_evaluate_numpy_bit_for_bit(name, principle):
    """The straight-line program of the term sizes (and of the reduced mass matrix) gives
    dag.evaluate_numpy's numbers bit for bit (NaN where it gives NaN), at random points
    of both signs, also where a size overflows or divides by zero."""
    from jetnh.numeric.linearize import _model, _Program

    model = _model(getattr(models, name)(), principle)
    rng = np.random.default_rng(7)
    for exprs in (list(model.sizes), dag.nodes(list(model.sizes))):
        program = _Program(exprs)
        assert program.function is not None
        syms = sorted(dag.free_symbols(exprs), key=lambda s: s.name)
        for scale in (1.0, 1e-160, 1e160):
            for _ in range(8):
                point = dict(zip(syms, scale * rng.uniform(-3, 3, len(syms))))
                want = np.array([float(v) for v in dag.evaluate_numpy(exprs, point)])
                np.testing.assert_array_equal(program(point), want)
