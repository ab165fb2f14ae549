"""Built-in stops at singular configurations, user events (scipy's semantics), and the
NaN error paths.  Kernels are compiled once per module (fixtures)."""

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh.mechanics.system import System
from jetnh.errors import IntegrationError, JetnhError
from jetnh.models import appell_hamel
from jetnh.numeric import Event, Scene
from jetnh.numeric.methods._common import EVENT, FINISHED, SINGULAR

TOL = 1e-10


# ---------------------------------------------------------------------- Appell-Hamel
@pytest.fixture(scope="module")
def ah_scene():
    """Horizontal speed v decays linearly, (1 + b^2/a^2) dv/dt = -(b/a) g, to v = 0 at
    t* = v0 (1 + b^2/a^2) / (g b/a), where zdot = (b/a) sqrt(xdot^2 + ydot^2) is not
    differentiable."""
    return Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                 t_span=(0.0, 1.0), cache=False).compile()


def ah_times(singular_tol=TOL):
    g, a, b, v0 = 9.81, 1.0, 0.5, 1.0
    decel = g * b / a / (1 + b**2 / a**2)
    t_star = v0 / decel
    # the indicator xdot^2 + ydot^2 = v^2 reaches singular_tol * v0^2 at v = sqrt(tol) v0
    return t_star, t_star - np.sqrt(singular_tol) * v0 / decel


def test_ah_indicator_is_the_sqrt_argument(ah_scene):
    lay = ah_scene.kernels.layout
    kinds = dict(zip(lay.indicators, lay.indicator_kinds))
    assert kinds["x_t**2 + y_t**2"] == "constraint"
    # any other indicator is a denominator of the solve (the reduced mass matrix's
    # determinant, here 1 + b^2/a^2 written unsimplified): it must stay away from zero
    values = ah_scene.indicators(0.0, ah_scene.y0)
    assert values["x_t**2 + y_t**2"] == 1.0
    assert all(abs(v) > 0.5 for v in values.values())


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau", "scipy-DOP853"])
def test_ah_stops_at_zero_horizontal_speed(ah_scene, method):
    traj = ah_scene.run(method=method, rtol=1e-10, atol=1e-12)
    t_star, t_hit = ah_times()
    assert traj.status == SINGULAR and not traj.success
    # v is linear in t, so every dense output is exact: the threshold time to rounding
    assert abs(traj.t[-1] - t_hit) < 1e-9, traj.t[-1] - t_hit
    assert traj.t[-1] < t_star
    sing = traj.singularity
    assert sing["indicator"] == "x_t**2 + y_t**2" and sing["kind"] == "constraint"
    assert abs(sing["value"] - TOL) < 1e-12 and sing["initial"] == 1.0
    for words in ("singular configuration", "x_t**2 + y_t**2", f"t = {traj.t[-1]:.6}",
                  "Appell-Hamel", "not differentiable"):
        assert words in traj.stop_reason, words
    assert traj.diagnostics.singularity is sing
    assert np.all(np.isfinite(traj.y))


@settings(max_examples=10)
@given(st.floats(0.05, 3.0), st.floats(0.0, 2 * np.pi), st.floats(1.01, 5.0))
def test_ah_stop_wherever_the_reversal_falls(ah_scene, v0, angle, span):
    """The speed's zero (a touch of x_t^2 + y_t^2) at random places of the steps (its
    time and the run's span vary): every adaptive method stops at the threshold time."""
    scene = ah_scene.replace(initial=dict(x=0, y=0, z=0, x_t=v0 * np.cos(angle),
                                          y_t=v0 * np.sin(angle)))
    t_star, t_hit = ah_times()
    t_star, t_hit = t_star * v0, t_hit * v0
    scene = scene.replace(t_span=(0.0, span * t_star))
    for method, tol in (("dop853", 1e-10), ("dopri5", 1e-7), ("radau", 1e-8)):
        traj = scene.run(method=method, rtol=tol, atol=tol * 1e-2, save="final")
        assert traj.status == SINGULAR, (method, traj.stop_reason)
        assert abs(traj.t[-1] - t_hit) < 1e-9, (method, traj.t[-1] - t_hit)


def test_ah_fixed_step_stops_before_the_kink(ah_scene):
    """RK4's fixed step jumps over the zero of xdot^2 + ydot^2 and would settle on a
    spurious constant velocity; the kink test stops it at the start of that step."""
    traj = ah_scene.run(method="rk4", n_steps=400)
    t_star = ah_times()[0]
    assert traj.status == SINGULAR and traj.singularity["indicator"] == "x_t**2 + y_t**2"
    assert t_star - 2 * 0.0025 <= traj.t[-1] <= t_star
    assert "jumps over a kink" in traj.stop_reason and "dop853" in traj.stop_reason
    assert np.all(np.diff(traj.t) > 0)          # the stop is not a second copy of its row


def test_ah_singular_tol_moves_the_stop(ah_scene):
    traj = ah_scene.run(rtol=1e-11, atol=1e-13, singular_tol=1e-14, save="final")
    assert len(traj) == 2
    assert abs(traj.t[-1] - ah_times(1e-14)[1]) < 1e-9
    assert np.hypot(traj["x_t"][-1], traj["y_t"][-1]) == pytest.approx(1e-7, rel=1e-6)


def test_ah_t_eval_stops_with_the_singularity(ah_scene):
    te = np.linspace(0.0, 1.0, 11)
    traj = ah_scene.run(rtol=1e-10, atol=1e-12, t_eval=te)
    assert traj.status == SINGULAR
    assert np.array_equal(traj.t, te[te <= ah_times()[1]])


def test_ah_singular_initial_state():
    sc = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.0, y_t=0.0),
               t_span=(0.0, 1.0), cache=False)
    traj = sc.run()
    assert traj.status == SINGULAR and len(traj) == 1 and traj.t[0] == 0.0
    assert "initial state" in traj.stop_reason and "x_t**2 + y_t**2 = 0" in traj.stop_reason


def test_ah_ignore_goes_on_and_chatters(ah_scene):
    """Without the check the integrator crawls along v ~ 0 (here cut by max_steps)."""
    traj = ah_scene.run(rtol=1e-8, atol=1e-10, singular="ignore", max_steps=3000,
                        save="final")
    assert traj.status != SINGULAR
    assert np.hypot(traj["x_t"][-1], traj["y_t"][-1]) < 1e-6


def test_singular_option_errors(ah_scene):
    with pytest.raises(JetnhError, match="singular must be 'stop' or 'ignore'"):
        ah_scene.run(singular="warn")
    with pytest.raises(JetnhError, match=r"singular_tol must be in \[0, 1\)"):
        ah_scene.run(singular_tol=2.0)


# ---------------------------------------------------------------------- knife edge
def knife(dependent):
    """Knife edge: xdot sin(theta) - ydot cos(theta) = 0, free rotation thetadot = 1.
    With y dependent, ydot = xdot tan(theta): singular at cos(theta) = 0."""
    J = jn.JetSpace("x y theta")
    x, y, th = J.q
    xd, yd, thd = J.qd
    return System(J, (xd**2 + yd**2) / 2 + thd**2 / 2, [xd * sp.sin(th) - yd * sp.cos(th)],
                  dependent=[dependent])


KNIFE0 = dict(x=0.0, y=0.0, theta=0.3, theta_t=1.0)


@pytest.fixture(scope="module")
def knife_y():
    return Scene(knife("y"), "chetaev", initial=dict(KNIFE0, x_t=1.0), t_span=(0.0, 2.5),
                 cache=False).compile()


@pytest.mark.parametrize("method", ["dop853", "dopri5", "rk4"])
def test_knife_edge_split_singular(knife_y, method):
    kw = dict(n_steps=250) if method == "rk4" else dict(rtol=1e-10, atol=1e-12)
    traj = knife_y.run(method=method, split="fixed", **kw)     # keep the split
    assert traj.status == SINGULAR
    assert traj.singularity["indicator"] == "cos(theta)"
    assert traj.singularity["kind"] == "split"
    # cos(theta) = tol * cos(0.3) at theta = pi/2 - asin(tol cos 0.3), theta = 0.3 + t
    t_hit = np.pi / 2 - np.arcsin(TOL * np.cos(0.3)) - 0.3
    assert abs(traj.t[-1] - t_hit) < 1e-9
    assert "dependent=['x']" in traj.stop_reason
    assert "split is singular" in traj.stop_reason
    # by default the run goes on in the split x (numeric.atlas), switching before
    on = knife_y.run(method=method, **kw)
    assert on.status == FINISHED and on.switches[0]["to"] == ["x"]
    assert on.switches[0]["t"] < t_hit


def test_start_check_reads_the_users_events_only(knife_y):
    """A switching run watches its chart's edge as an event of its own: the check of the
    events at the initial state (NaN or infinite: a warning) names the user's events
    only, and a run that watches the edge alone checks nothing.  ``values`` (one call of
    the compiled events) agrees with the events called one by one."""
    import warnings

    from jetnh.errors import JetnhWarning
    from jetnh.numeric import atlas
    from jetnh.numeric.events import warn_not_finite

    J = knife_y.system.J
    x = J.q[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert knife_y.run().switches                   # the edge alone
        assert knife_y.run(events=[x - 1]).switches
    with pytest.warns(JetnhWarning, match=r"^the events 'sqrt\(x - 2\)' are NaN") as rec:
        tr = knife_y.run(events=[sp.sqrt(x - 2), x - 1])
    assert len(rec) == 1 and "chart edge" not in str(rec[0].message)
    assert tr.switches and len(tr.t_events) == 2 and len(tr.t_events[0]) == 0
    at = atlas.atlas(knife_y)
    edge_only = at.events(at.own, [], True)
    nan = np.full(len(knife_y.state_names), np.nan)
    assert edge_only.user == () and np.isnan(edge_only.values(0.0, nan, knife_y.p)[0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_not_finite(edge_only, 0.0, nan, knife_y.p)
    ce = knife_y.compile_events([x - 1, sp.sqrt(x + 2), lambda t, y: y[2] * t])
    y, p = knife_y.y0 + 0.25, np.ascontiguousarray(knife_y.p, dtype=float)
    assert ce.values(0.5, y, p) == [f(0.5, y, p) for f in ce.python_funcs]
    assert ce.values(0.5, y, p) == [-0.75, np.sqrt(2.25), 0.55 * 0.5]


def test_knife_edge_other_split_passes(knife_y):
    """The motion is regular: with x dependent the run crosses theta = pi/2 and agrees
    with the closed form (the speed u along the blade is constant)."""
    sc = Scene(knife("x"), "chetaev", initial=dict(KNIFE0, y_t=np.sin(0.3)),
               t_span=(0.0, 2.5), cache=False)
    traj = sc.run(rtol=1e-11, atol=1e-13)
    assert traj.status == FINISHED
    th = traj["theta"]
    u = 1.0      # the speed along the blade, xdot cos(theta) + ydot sin(theta), at t = 0
    assert np.max(np.abs(traj["y_t"] - u * np.sin(th))) < 1e-9
    assert np.max(np.abs(traj["x_t"] - u * np.cos(th))) < 1e-9


# ---------------------------------------------------------------------- NaN paths
@pytest.fixture(scope="module")
def sqrt_potential():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    s = System(J, xd**2 / 2 + sp.sqrt(x), [])
    return Scene(s, "chetaev", initial=dict(x=1.0, x_t=-3.0), t_span=(0.0, 2.0),
                 cache=False).compile()


def test_nan_explained_by_an_indicator_is_a_stop(sqrt_potential):
    """xdd = 1/(2 sqrt(x)): RK4's fixed step jumps to x < 0 (NaN); the indicator x explains
    it, so the run stops with the reason instead of raising."""
    traj = sqrt_potential.run(method="rk4", n_steps=50)
    assert traj.status == SINGULAR
    assert "NaN or infinite" in traj.stop_reason and "x = " in traj.stop_reason
    adaptive = sqrt_potential.run(rtol=1e-10, atol=1e-12)
    assert adaptive.status == SINGULAR and adaptive.singularity["indicator"] == "x"


def test_nan_unexplained_raises(sqrt_potential):
    with pytest.raises(IntegrationError, match=r"NaN or infinite .* t = 0\.\d+.*x = .*"
                                               r"singular='ignore'"):
        sqrt_potential.run(method="rk4", n_steps=50, singular="ignore")
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    blowup = Scene(System(J, xd**2 / 2 + x**4 / 4, []), "chetaev",
                   initial=dict(x=1.0, x_t=3.0), t_span=(0.0, 5.0), cache=False)
    with pytest.raises(IntegrationError, match=r"NaN or infinite in the step from t = 1\.1"
                                               r".*No singularity indicator explains it"):
        blowup.run(method="rk4", n_steps=50)


# ---------------------------------------------------------------------- user events
PART0 = dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3)


@pytest.fixture(scope="module")
def particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])
    return Scene(s, "chetaev", initial=PART0, t_span=(0.0, 6.0), cache=False).compile()


def t_x_equals(X):
    """Closed form: x = x0 + c/v (asinh y - asinh y0), y = y0 + v t."""
    v, y0, c = 0.3, -0.5, np.sqrt(1.25)
    return (np.sinh(np.arcsinh(y0) + (X - 0.1) * v / c) - y0) / v


def y_minus_quarter(t, y):
    return y[1] - 0.25


def test_events_located_like_scipy(particle):
    from scipy.integrate import solve_ivp

    J = particle.system.J
    x, y, z = J.q
    zd = J.qd[2]
    evs = [y, Event(x - 1, name="x=1"), Event(zd, direction=1), y_minus_quarter]
    traj = particle.run(rtol=1e-10, atol=1e-12, events=evs)
    assert traj.status == FINISHED and traj.event_names == ("y", "x=1", "z_t",
                                                            "y_minus_quarter")
    # closed forms: y = 0 at 5/3, zdot = y xdot crosses upwards there too, y = 1/4 at 2.5
    # (y is linear in t, so those roots are exact; x's to the accuracy of rtol)
    for k, t_exact, tol in ((0, 5 / 3, 1e-13), (1, t_x_equals(1.0), 1e-9), (2, 5 / 3, 1e-13),
                            (3, 2.5, 1e-13)):
        assert traj.t_events[k].shape == (1,)
        assert abs(traj.t_events[k][0] - t_exact) < tol, k
    assert traj.y_events[0].shape == (1, 5) and abs(traj.y_events[0][0, 1]) < 1e-15
    assert traj.events["x=1"]["x"][0] == pytest.approx(1.0, abs=1e-13)
    assert traj.diagnostics.events == {"y": 1, "x=1": 1, "z_t": 1, "y_minus_quarter": 1}

    rhs, aux, p = particle.kernels.rhs, particle.kernels.aux, particle.p
    out, a = np.empty(5), np.empty(particle.kernels.layout.n_aux)

    def fun(t, yv):
        rhs(t, np.ascontiguousarray(yv), p, out)
        return out.copy()

    def zt(t, yv):
        aux(t, np.ascontiguousarray(yv), p, a)
        return a[0]
    zt.direction = 1
    sol = solve_ivp(fun, (0.0, 6.0), particle.y0, method="DOP853", rtol=1e-10, atol=1e-12,
                    events=[lambda t, yv: yv[1], lambda t, yv: yv[0] - 1, zt,
                            y_minus_quarter])
    assert traj.diagnostics.rhs_evaluations == sol.nfev
    for ours, theirs in zip(traj.t_events, sol.t_events):
        assert np.allclose(ours, theirs, rtol=0, atol=1e-13)
    # the scipy backend with the same events
    via = particle.run(method="scipy-DOP853", rtol=1e-10, atol=1e-12, events=evs)
    for ours, theirs in zip(traj.t_events, via.t_events):
        assert np.allclose(ours, theirs, rtol=0, atol=1e-13)


def test_direction_filters_crossings(particle):
    x = particle.system.J.q[0]
    # sin(8 x) crosses zero several times; up and down crossings alternate
    both = particle.run(rtol=1e-10, atol=1e-12, events=sp.sin(8 * x), save="final")
    up = particle.run(rtol=1e-10, atol=1e-12, events=Event(sp.sin(8 * x), direction=1),
                      save="final")
    down = particle.run(rtol=1e-10, atol=1e-12, events=Event(sp.sin(8 * x), direction=-1),
                        save="final")
    tb = both.t_events[0]
    assert len(tb) >= 4
    assert np.array_equal(np.sort(np.concatenate([up.t_events[0], down.t_events[0]])), tb)
    xs = both.events["sin(8*x)"]["x"]
    assert np.allclose(np.sin(8 * xs), 0.0, atol=1e-12)


@pytest.mark.parametrize("method, kw", [("dop853", {}), ("dopri5", {}), ("radau", {}),
                                        ("rk4", dict(n_steps=600))])
def test_terminal_event(particle, method, kw):
    y = particle.system.J.q[1]
    traj = particle.run(method=method, events=Event(y, terminal=True), **kw)
    assert traj.status == EVENT and traj.success
    assert traj.stop_reason.startswith("terminal event 'y' at t = 1.66666")
    assert abs(traj.t[-1] - 5 / 3) < 1e-12 and abs(traj["y"][-1]) < 1e-14
    assert traj.t_events[0][0] == traj.t[-1]


def test_terminal_count_and_t_eval(particle):
    x = particle.system.J.q[0]
    free = particle.run(rtol=1e-10, atol=1e-12, events=sp.sin(8 * x), save="final")
    te = np.linspace(0.0, 6.0, 61)
    traj = particle.run(rtol=1e-10, atol=1e-12, t_eval=te,
                        events=Event(sp.sin(8 * x), terminal=3))
    t3 = free.t_events[0][2]
    assert traj.status == EVENT and np.array_equal(traj.t_events[0], free.t_events[0][:3])
    assert np.array_equal(traj.t, te[te <= t3])     # scipy: t_eval up to the stop


def test_callable_event_with_attributes(particle):
    def turn(t, y):
        return y[1] - 0.25
    turn.terminal = True
    turn.direction = 1
    traj = particle.run(rtol=1e-10, atol=1e-12, events=[turn])
    assert traj.status == EVENT and abs(traj.t[-1] - 2.5) < 1e-12


def test_event_errors(particle):
    x = particle.system.J.q[0]
    with pytest.raises(JetnhError, match="strings are not evaluated"):
        particle.run(events=["x - 1"])
    with pytest.raises(JetnhError, match="write x - 1 instead"):
        particle.run(events=[sp.Gt(x, 1)])
    with pytest.raises(JetnhError, match="contains w, which are not states"):
        particle.run(events=[x - sp.Symbol("w")])
    with pytest.raises(JetnhError, match="terminal must be a bool or a positive integer"):
        Event(x, terminal=-1)

    def not_numba(t, y):
        return float(sp.pi) * y[0]       # a sympy object: numba cannot type it
    with pytest.raises(JetnhError, match="cannot be compiled by numba"):
        particle.run(events=[not_numba])


# ---------------------------------------------------------------------- discrete methods
def test_dla_events_on_the_nodes(particle):
    """dla: events located on the linear interpolant of the nodes (second order, the
    method's), scipy's semantics as the Runge-Kutta methods; a terminal one ends the
    trajectory there, with the state interpolated to it."""
    x, y = particle.system.J.q[:2]
    evs = [Event(y + 0.25, name="y=-1/4"), Event(x - 2.0, terminal=True, direction=1)]
    ref = particle.run(rtol=1e-12, atol=1e-13, events=evs)
    errs = []
    for n in (300, 600):
        tr = particle.run(method="dla", n_steps=n, events=evs)
        assert tr.status == EVENT and tr.success
        assert [len(te) for te in tr.t_events] == [len(te) for te in ref.t_events]
        assert tr.t[-1] == tr.t_events[1][0] and np.all(np.diff(tr.t) > 0)
        assert abs(tr["x"][-1] - 2.0) < 1e-12           # the root on the interpolant
        assert tr.stop_reason.startswith("terminal event")
        errs.append(abs(tr.t_events[1][0] - ref.t_events[1][0]))
    assert errs[1] < errs[0] / 3                        # O(h^2)
    final = particle.run(method="dla", n_steps=600, events=evs, save="final")
    assert len(final) == 2 and final.t[-1] == tr.t[-1]


def test_dvi_events_counted_like_dop853():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])
    sc = Scene(s, "vakonomic", initial=dict(PART0, lambda_z=0.1), t_span=(0.0, 3.0),
               cache=False)
    ev = Event(sp.sin(4 * x), name="sin4x")
    a = sc.run(method="dvi", n_steps=600, events=[ev])
    b = sc.run(rtol=1e-11, atol=1e-12, events=[ev])
    assert a.status == FINISHED and len(a.t_events[0]) == len(b.t_events[0]) > 1
    assert np.allclose(a.t_events[0], b.t_events[0], atol=1e-3)


@pytest.mark.parametrize("method", ["dla", "dvi"])
def test_discrete_terminal_event_stops_the_run(particle, method):
    """dla and dvi evaluate the events at every node and stop at the node after a
    terminal one (the m-th occurrence for terminal=m): the steps end there, and the rows,
    the event times and states are those of the run without the terminal flag, cut at
    the terminal event's time."""
    J = particle.system.J
    x, y = J.q[:2]
    principle, initial = (("chetaev", PART0) if method == "dla" else
                          ("vakonomic", dict(PART0, lambda_z=0.1)))
    sc = Scene(particle.system, principle, initial=initial, t_span=(0.0, 6.0), cache=False,
               integrals={"x_t^2": J.qd[0] ** 2})
    n = 600
    quiet = [Event(sp.sin(4 * x), name="wave"), Event(y + 0.25, name="low")]
    full = sc.run(method=method, n_steps=n, events=quiet)
    assert len(full.t_events[0]) >= 3 and len(full.t_events[1]) == 1
    for terminal, stop in ((True, 0), (3, 2)):
        watched = [Event(sp.sin(4 * x), name="wave", terminal=terminal), quiet[1]]
        tr = sc.run(method=method, n_steps=n, events=watched)
        t_stop = full.t_events[0][stop]
        assert tr.status == EVENT and tr.t[-1] == t_stop
        # the loop ended at the node after the event: steps taken = rows before it
        assert tr.diagnostics.steps == len(tr.t) - 1 < n
        keep = full.t < t_stop
        np.testing.assert_array_equal(tr.t[:-1], full.t[keep])
        np.testing.assert_array_equal(tr.y[:-1], full.y[keep])
        for k in range(2):
            before = full.t_events[k] <= t_stop
            np.testing.assert_array_equal(tr.t_events[k], full.t_events[k][before])
            np.testing.assert_array_equal(tr.y_events[k], full.y_events[k][before])
        assert len(tr.t_events[0]) == stop + 1
        # energy, constraint residual and integrals from their own columns (a terminal
        # event's index once shadowed the number of constraints: the energy read the
        # residual's column); the last row is the rows' linear interpolant at the stop
        j = int(np.count_nonzero(keep))
        theta = (t_stop - full.t[j - 1]) / (full.t[j] - full.t[j - 1])
        for a, b in ((tr.energy, full.energy), (tr.residual, full.residual),
                     (tr["x_t^2"], full["x_t^2"])):
            assert a.shape == (len(tr.t),) + b.shape[1:]
            np.testing.assert_array_equal(a[:-1], b[keep])
            np.testing.assert_allclose(a[-1], b[j - 1] + theta * (b[j] - b[j - 1]),
                                       rtol=1e-12, atol=1e-15)
        assert abs(tr.energy[0] - 0.67) < 1e-12       # |v|^2 / 2, z_t = y x_t = -1/2
        assert tr.diagnostics.energy_drift <= full.diagnostics.energy_drift
        assert 0.0 < tr.diagnostics.residual_max <= full.diagnostics.residual_max


@pytest.fixture(scope="module")
def oscillator():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    return Scene(System(J, xd**2 / 2 - x**2 / 2, []), "chetaev", initial=dict(x=1.0, x_t=0.0),
                 t_span=(0.0, 10.0), cache=False)


@pytest.mark.parametrize("method", ["rk4", "dla", "dvi", "dop853"])
def test_a_root_on_a_node_counted_once(oscillator, method):
    """t - 1 vanishes on the node t = 1 of a step h = 0.01: the step ending there finds
    the root, the step starting there does not count it again (scipy's rule alone counts
    it twice), so terminal=2 goes on to the second root; x = cos t - cos 1 (a root at t =
    1, 2 pi - 1, 2 pi + 1, off the nodes) counted once each by every method."""
    t = oscillator.system.J.t
    x = oscillator.system.J.q[0]
    sc = oscillator if method != "dvi" else oscillator.replace(principle="vakonomic")
    kw = dict(n_steps=1000) if method in ("rk4", "dla", "dvi") else {}
    tr = sc.run(method=method, events=[t - 1, t - 5, Event(t - 1, direction=1)], **kw)
    assert tr.status == FINISHED
    assert [len(te) for te in tr.t_events] == [1, 1, 1]
    np.testing.assert_allclose(np.concatenate(tr.t_events), [1.0, 5.0, 1.0], rtol=0,
                               atol=1e-14)
    assert [ye.shape for ye in tr.y_events] == [(1, 2), (1, 2), (1, 2)]
    assert abs(tr.y_events[0][0, 0] - np.cos(1.0)) < 1e-3
    # terminal=2: the first root is t = 1 (once), the second t = 3 (a node as well)
    tr = sc.run(method=method, events=[Event((t - 1) * (t - 3), terminal=2)], **kw)
    assert tr.status == EVENT and abs(tr.t[-1] - 3.0) < 1e-14
    np.testing.assert_allclose(tr.t_events[0], [1.0, 3.0], rtol=0, atol=1e-14)
    # a root at the start of the run counts (the run's first step)
    tr = sc.run(method=method, events=[t, x - np.cos(1.0)], **kw)
    assert list(tr.t_events[0]) == [0.0]
    np.testing.assert_allclose(tr.t_events[1], [1.0, 2 * np.pi - 1.0, 2 * np.pi + 1.0],
                               rtol=0, atol=1e-3)
    if method == "rk4":         # an ensemble's runs: the same loop
        ens = sc.ensemble(initial={"x": [1.0, 2.0]}, method=method, n_steps=1000,
                          events=[t - 1, Event((t - 1) * (t - 3), terminal=2)])
        np.testing.assert_array_equal(ens.event_counts, [[1, 2], [1, 2]])
        np.testing.assert_array_equal(ens.status, [EVENT, EVENT])


@pytest.mark.parametrize("method", ["dop853", "rk4", "dla"])
def test_degenerate_events(oscillator, method):
    """An event constant along a run is refused; one NaN at the initial state warns; one
    that stays zero (x on a body at rest) is one root, at the start, whatever the method
    (it was one per step: 27 with dop853, 1000 with rk4)."""
    from jetnh.errors import JetnhWarning

    J = oscillator.system.J
    x = J.q[0]
    kw = dict(n_steps=1000) if method in ("rk4", "dla") else {}
    for const in (sp.Integer(0), x - x, sp.Integer(2)):
        with pytest.raises(JetnhError, match="depends on neither t nor the state"):
            oscillator.run(method=method, events=[J.t - 1, const], **kw)
    with pytest.warns(JetnhWarning, match=r"'sqrt\(x - 2\)' are NaN or infinite at the "
                                          r"initial state \(t = 0\)"):
        tr = oscillator.run(method=method, events=[sp.sqrt(x - 2)], **kw)
    assert tr.status == FINISHED and len(tr.t_events[0]) == 0
    rest = oscillator.replace(initial=dict(x=0.0, x_t=0.0))
    for ev in (x, Event(x, direction=1)):
        tr = rest.run(method=method, events=[ev], **kw)
        assert list(tr.t_events[0]) == [0.0]


def test_huge_states_are_named_in_the_stop(oscillator):
    """x0 cos t from x0 = 1e150 / 1e200 stays finite, but squares of such states overflow
    in the error norms: the stop says so, not that the solution blows up."""
    tr = oscillator.replace(initial=dict(x=1e150, x_t=0.0)).run(method="radau")
    assert tr.status != FINISHED
    assert "1e+150 in size: beyond ~1e+145 the squares" in tr.stop_reason
    assert "blow up" not in tr.stop_reason
    with pytest.raises(IntegrationError, match=r"1e\+200 in size: beyond ~1e\+145 the "
                                               r"squares .* rescale the states"):
        oscillator.replace(initial=dict(x=1e200, x_t=0.0)).run(method="dop853")
