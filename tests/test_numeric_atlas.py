"""Runs past the edge of a split's chart (``jetnh.numeric.atlas``).

A spinning knife edge and a spinning Chaplygin sleigh turn through several full turns,
switching between the splits dependent=['y'] (singular where cos = 0) and ['x'] (where
sin = 0): against the closed forms of the catalogue's docstrings and an independent
body-frame integration (scipy), with the energy conserved; the switches sit where the
measure of the split falls to the edge; the runs are reproducible bit for bit, as are
their ensembles, their dense output and the part before the first switch (equal to a run
that keeps its split).  The multipliers map between splits by the law the derivation
gives (checked on the accelerations of each principle); Suslov's paper-convention motions
depend on the split, so its runs keep theirs; where no split is regular the run stops.
"""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import jetnh as jn
from jetnh.algebra import dag
from jetnh import models
from jetnh.models import chaplygin_sleigh, knife_edge, radial_line
from jetnh.numeric import Event, atlas

TOL = dict(rtol=1e-11, atol=1e-12)
W = 3.0                 # heading rate of the knife edge


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=W),
                    t_span=(0.0, 10.0))


@pytest.fixture(scope="module")
def knife_run(knife):
    return knife.run(**TOL)


def knife_closed_form(t, phi0=0.0, v0=0.5, w=W, g=9.81, alpha=0.3):
    """The catalogue's Chetaev solution: phi = phi0 + w t, v = A + c sin(phi)."""
    c = g * math.sin(alpha) / w
    A = v0 - c * math.sin(phi0)
    phi = phi0 + w * t

    def X(p):
        return (A * np.sin(p) + c * np.sin(p)**2 / 2) / w

    def Y(p):
        return (-A * np.cos(p) + c * (p - np.sin(p) * np.cos(p)) / 2) / w
    v = A + c * np.sin(phi)
    return phi, X(phi) - X(phi0), Y(phi) - Y(phi0), v * np.cos(phi), v * np.sin(phi)


def switch_count(phi_end, phi0=0.0):
    """Switches of a heading from phi0 to phi_end > phi0 (charts y and x, edge 1/8),
    starting in y: y -> x where cos^2 falls to 1/8, x -> y where sin^2 does."""
    a, b = math.acos(math.sqrt(1 / 8)), math.pi - math.asin(math.sqrt(1 / 8))
    n, phi, chart = 0, phi0, "y"
    while True:
        base = a if chart == "y" else b
        nxt = base + math.pi * math.ceil((phi - base) / math.pi + 1e-12)
        if nxt > phi_end:
            return n
        n, phi, chart = n + 1, nxt, "x" if chart == "y" else "y"


def test_knife_edge_spins_through_turns(knife_run):
    tr = knife_run
    assert tr.status == 0 and tr.t[-1] == 10.0
    assert tr["phi"][-1] / (2 * np.pi) > 4.7                 # 4.8 turns
    phi, x, y, xt, yt = knife_closed_form(tr.t)
    assert np.abs(tr["phi"] - phi).max() < 1e-11
    for name, want in (("x", x), ("y", y), ("x_t", xt), ("y_t", yt)):
        assert np.abs(tr[name] - want).max() < 1e-9, name
    d = tr.diagnostics
    assert d.energy_drift_relative < 1e-10 and d.residual_max < 1e-14
    # four switches a turn, alternating, as the split's measure falls to 1/8
    assert len(tr.switches) == len(d.switches) == switch_count(30.0) == 19
    for i, s in enumerate(tr.switches):
        assert s["from"] == (["y"] if i % 2 == 0 else ["x"]) and s["to"] != s["from"]
        measure = math.cos(W * s["t"])**2 if s["from"] == ["y"] else math.sin(W * s["t"])**2
        # (at the start of the step that reached the edge: the other's measure >= 1/4)
        assert 1 / 8 < measure <= 3 / 4
    assert "split switch" in str(d)


def test_switching_runs_reproduce_bit_for_bit(knife, knife_run):
    again = knife.run(**TOL)
    assert np.array_equal(again.t, knife_run.t) and np.array_equal(again.y, knife_run.y)
    assert again.switches == knife_run.switches
    # up to the first switch: the rows of the run that keeps its split, to the bit
    fixed = knife.run(**TOL, split="fixed")
    assert fixed.status == 6 and "use another split" in fixed.stop_reason
    t_s = knife_run.switches[0]["t"]
    n = int(np.searchsorted(fixed.t, t_s))
    assert np.array_equal(knife_run.y[:n], fixed.y[:n])


def test_dense_output_and_t_eval_agree_across_switches(knife, knife_run):
    te = np.linspace(0.0, 10.0, 201)
    ev = knife.run(**TOL, t_eval=te)
    assert len(ev.switches) == 19 and np.array_equal(ev.y, knife_run.at(te))
    # times inside the steps that a switch cut short
    cut = np.array([s["t"] for s in knife_run.switches[:6]]) - 1e-3
    ev2 = knife.run(**TOL, t_eval=cut)
    assert np.array_equal(ev2.y, knife_run.at(cut))
    phi, x, y, _, _ = knife_closed_form(cut)
    assert np.abs(ev2["y"] - y).max() < 1e-9


def test_events_follow_the_run_across_charts(knife):
    J = knife.system.J
    yt = J.qd[1]
    tr = knife.run(**TOL, events=[Event(yt, name="along x"),
                                  Event(J.q[2] - 7.0, terminal=True, name="stop")])
    # y_t = v sin(phi) vanishes at phi = k pi and where v = A + c sin(phi) = 0
    te = tr.events["along x"]["t"]
    _, _, _, _, yt_at = knife_closed_form(te)
    assert len(te) == 5 and np.abs(yt_at).max() < 1e-9
    assert tr.status == 5 and abs(tr.t[-1] - 7.0 / W) < 1e-12
    assert tr.events["stop"]["phi"][0] == pytest.approx(7.0, abs=1e-11)
    assert len(tr.switches) == switch_count(7.0) == 4 and "chart edge" not in tr.event_names
    # a terminal count runs on across switches
    tr3 = knife.run(**TOL, events=Event(yt, terminal=3))
    assert np.array_equal(tr3.t_events[0], te[:3]) and tr3.t[-1] == te[2]


def test_fixed_step_and_implicit_methods_switch(knife):
    for kw in (dict(method="rk4", n_steps=3000), dict(method="dopri5", rtol=1e-10),
               dict(method="radau", rtol=1e-9)):
        tr = knife.run(**kw)
        phi, x, y, _, _ = knife_closed_form(tr.t)
        assert tr.status == 0 and len(tr.switches) == 19, kw
        assert np.abs(tr["y"] - y).max() < 1e-5, kw


def test_ensembles_and_sweeps_switch_as_runs_do(knife):
    te = np.linspace(0.0, 10.0, 21)
    rates = np.array([0.2, 1.0, 3.0])
    ens = knife.ensemble(initial={"phi_t": rates}, t_eval=te, **TOL)
    counts = [switch_count(10 * w) for w in rates]
    assert [len(ens.switches.get(r, ())) for r in range(3)] == counts
    assert list(ens.diagnostics()["switches"]) == counts
    for r, w in enumerate(rates):
        tr = knife.run(y0={"phi_t": w}, t_eval=te, **TOL)
        assert np.array_equal(ens.y[r], tr.y) and np.array_equal(ens["y_t"][r], tr["y_t"])
    phi, x, y, _, _ = knife_closed_form(te, w=3.0)
    assert np.abs(ens["y"][2] - y).max() < 1e-9
    df = jn.sweep(knife, {"phi_t": [1.0, 3.0]}, **TOL)
    assert list(df["switches"]) == counts[1:] and np.array_equal(df["y"], ens.final["y"][1:])


def test_a_run_that_starts_past_the_edge_starts_in_the_best_split(knife):
    """phi0 = 1.45: cos^2 = 0.014 < 1/8, the run begins in x (a switch at t0)."""
    start = {"phi": 1.45, "x_t": 0.5 * math.cos(1.45)}
    tr = knife.run(y0=start, t_span=(0.0, 2.0), **TOL)
    assert tr.switches[0] == {"t": 0.0, "from": ["y"], "to": ["x"]}
    phi, x, y, _, _ = knife_closed_form(tr.t, 1.45)
    assert np.abs(tr["y"] - y).max() < 1e-9 and np.abs(tr["x"] - x).max() < 1e-9
    te = np.linspace(0.0, 2.0, 5)
    ens = knife.replace(t_span=(0.0, 2.0)).ensemble(
        initial={"phi": np.array([0.0, 1.45]), "x_t": np.array([0.5, 0.5 * math.cos(1.45)])},
        t_eval=te, **TOL)
    assert np.array_equal(ens.y[1], knife.run(y0=start, t_span=(0.0, 2.0), t_eval=te,
                                              **TOL).y)
    assert ens.switches[1][0]["t"] == 0.0


@settings(max_examples=10, deadline=None)
@given(phi0=st.floats(-3.0, 3.0), w=st.floats(0.5, 4.0).map(lambda v: v * 1.0),
       v0=st.floats(-1.0, 1.0))
def test_knife_edge_any_heading_and_rate(knife, phi0, w, v0):
    tr = knife.run(y0={"phi": phi0, "phi_t": w, "x_t": v0 * math.cos(phi0)},
                   t_span=(0.0, 3.0), **TOL, save="final") if abs(math.cos(phi0)) > 0.2 \
        else None
    if tr is None:      # the home split is singular at the start: nothing to test here
        return
    phi, x, y, xt, yt = knife_closed_form(tr.t[-1:], phi0, v0, w)
    assert abs(tr["y"][-1] - y[0]) < 1e-8 and abs(tr["x_t"][-1] - xt[0]) < 1e-8


# ---------------------------------------------------------------------- the sleigh
def sleigh_body(t_end, w0, v0=0.0, m=1.0, I=0.2, a=0.02):
    """The sleigh in its body frame (catalogue docstring): m v' = m a w^2,
    (I + m a^2) w' = -m a v w, theta' = w, x' = v cos(theta), y' = v sin(theta)."""
    K = I + m * a * a

    def f(t, s):
        v, w, th, x, y = s
        return [a * w * w, -m * a * v * w / K, w, v * math.cos(th), v * math.sin(th)]
    return solve_ivp(f, (0.0, t_end), [v0, w0, 0.0, 0.0, 0.0], method="DOP853",
                     rtol=1e-13, atol=1e-13, dense_output=True)


def test_spinning_sleigh_against_body_frame_and_closed_form():
    sys_ = chaplygin_sleigh()
    scene = jn.Scene(sys_, "chetaev", params={"a": 0.02},
                     initial=dict(x=0, y=0, theta=0, x_t=0.0, theta_t=3.0), t_span=(0.0, 20.0))
    tr = scene.run(**TOL)
    assert tr.status == 0 and tr["theta"][-1] / (2 * np.pi) > 5    # five turns
    body = sleigh_body(20.0, 3.0).sol(tr.t)
    for name, row in (("theta", 2), ("x", 3), ("y", 4)):
        assert np.abs(tr[name] - body[row]).max() < 1e-8, name
    # closed form: v = V tanh(s), w = w0 / cosh(s), s = m a V t / K (v0 = 0)
    K = 0.2 + 0.02**2
    V = math.sqrt(K) * 3.0
    s = 0.02 * V * tr.t / K
    assert np.abs(tr["theta_t"] - 3.0 / np.cosh(s)).max() < 1e-9
    gd = 2 * np.arctan(np.tanh(s / 2))
    assert np.abs(tr["theta"] - 3.0 * K / (0.02 * V) * gd).max() < 1e-8
    assert tr.diagnostics.energy_drift_relative < 1e-9
    assert len(tr.switches) == switch_count(float(tr["theta"][-1]))


# ---------------------------------------------------------------------- multipliers
def test_vakonomic_multipliers_keep_their_values_across_splits():
    """A vakonomic run from dependent=['y'] into ['x'] against a run that starts in
    ['x'] and keeps it: the multiplier of the constraint is the same number (named
    lambda_y in one split, lambda_x in the other)."""
    sys_ = knife_edge()
    init = dict(x=0.0, y=0.0, phi=0.7, x_t=0.4, phi_t=W, lambda_y=0.3)
    home = jn.Scene(sys_, "vakonomic", initial=init, t_span=(0.0, 0.6))
    te = np.linspace(0.0, 0.6, 13)
    tr = home.run(**TOL, t_eval=te)
    assert [s["to"] for s in tr.switches] == [["x"]]
    other = jn.Scene(sys_.with_split(["x"]), "vakonomic", t_span=(0.0, 0.6), initial=dict(
        x=0.0, y=0.0, phi=0.7, y_t=0.4 * math.tan(0.7), phi_t=W, lambda_x=0.3))
    ref = other.run(**TOL, t_eval=te, split="fixed")
    for a, b in (("x", "x"), ("y", "y"), ("phi", "phi"), ("x_t", "x_t"), ("y_t", "y_t"),
                 ("lambda_y", "lambda_x")):
        assert np.abs(tr[a] - ref[b]).max() < 1e-9, a
    assert tr.diagnostics.energy_drift < 1e-9


def test_explicit_form_multipliers_map_across_splits():
    """The vakonomic explicit form (17): its multiplier weighs ydot - phi^y in one split
    and xdot - phi^x in the other, lambda~_y = A_y^T A_x^-T lambda~_x = -cot(phi)
    lambda~_x (A = (sin phi, -cos phi, 0))."""
    sys_ = knife_edge()
    init = dict(x=0.0, y=0.0, phi=0.7, x_t=0.4, phi_t=W, lambda_y=0.3)
    lam_y = sp.Symbol("lambda_y")
    home = jn.Scene(sys_, "vakonomic", initial=init, t_span=(0.0, 0.6), form="explicit",
                    integrals={"lam": lam_y * sys_.J.qd[2]})
    te = np.linspace(0.0, 0.6, 13)
    tr = home.run(**TOL, t_eval=te)
    assert [s["to"] for s in tr.switches] == [["x"]]
    lam_x = -0.3 * math.tan(0.7)            # lambda~_x = -tan(phi) lambda~_y at the start
    other = jn.Scene(sys_.with_split(["x"]), "vakonomic", form="explicit", t_span=(0.0, 0.6),
                     initial=dict(x=0.0, y=0.0, phi=0.7, y_t=0.4 * math.tan(0.7), phi_t=W,
                                  lambda_x=lam_x))
    ref = other.run(**TOL, t_eval=te, split="fixed")
    for name in ("x", "y", "phi", "x_t", "y_t"):
        assert np.abs(tr[name] - ref[name]).max() < 1e-9, name
    assert np.abs(tr["lambda_y"] + ref["lambda_x"] / np.tan(ref["phi"])).max() < 1e-9
    # a first integral in the multiplier, computed in the split x after the switch
    assert np.abs(tr["lam"] - tr["lambda_y"] * tr["phi_t"]).max() < 1e-12


def _rates(system, principle, form, point, lam):
    eom = system.equations(principle, form=form)
    acc = eom.accelerations()
    J = system.J
    values = {**point, **dict(zip(eom.multipliers, lam))}
    qdd = {J.jet(s, 2): float(dag.evaluate(acc[J.jet(s, 2)], values))
           for s in system.independent}
    for s in system.dependent:
        e = system.dependent_accelerations[J.jet(s, 2)]
        qdd[J.jet(s, 2)] = float(dag.evaluate(e, {**values, **qdd}))
    rates = [float(dag.evaluate(acc[r], values)) for r in eom.multiplier_rates]
    return qdd, np.array(rates), eom.explicit


@pytest.mark.parametrize("principle,form", [("chetaev", None), ("vakonomic", None),
                                            ("vakonomic", "explicit"), ("holder", None)])
def test_the_multiplier_map_carries_solutions_between_splits(principle, form):
    """At a point on the constraints, the accelerations of split x equal those of split
    y, and the rates of the mapped multipliers lambda_x = A_x^T A_y^-T lambda_y (explicit
    forms; the same number otherwise) are the derivative of the map along the motion."""
    base = knife_edge()
    sy, sx = base.with_split(["y"]), base.with_split(["x"])
    J = base.J
    x, y, phi = J.q
    xd, yd, phid = J.qd
    point = {J.t: 0.0, x: 0.3, y: -0.2, phi: 0.7, xd: 0.4, phid: 1.3,
             **{s: v for s, v in base.defaults.items()}}
    point[yd] = math.tan(0.7) * 0.4
    lam_y = [0.37]
    qy, ry, explicit = _rates(sy, principle, form, point, lam_y)
    A = np.array([math.sin(0.7), -math.cos(0.7), 0.0])
    M = A[0] / A[1] if explicit else 1.0            # A_x^T A_y^-T
    qx, rx, _ = _rates(sx, principle, form, point, [M * lam_y[0]] if lam_y and ry.size
                       else [])
    assert max(abs(qx[k] - qy[k]) for k in qx) < 1e-12
    if ry.size:
        dM = 0.0
        if explicit:        # d/dt (sin(phi) / -cos(phi)) = -phid / cos(phi)^2
            dM = -1.3 / math.cos(0.7)**2
        assert abs(rx[0] - (dM * lam_y[0] + M * ry[0])) < 1e-12


def test_suslov_motions_depend_on_the_split_so_its_runs_keep_it():
    assert not atlas.split_invariant("suslov", "paper")
    assert atlas.split_invariant("suslov", "imposed") and atlas.split_invariant("holder", "paper")
    base = knife_edge()
    J = base.J
    x, y, phi = J.q
    xd, yd, phid = J.qd
    point = {J.t: 0.0, x: 0.3, y: -0.2, phi: 0.7, xd: 0.4, yd: math.tan(0.7) * 0.4,
             phid: 1.3, **{s: v for s, v in base.defaults.items()}}
    qy, _, _ = _rates(base.with_split(["y"]), "suslov", None, point, [0.2])
    qx, _, _ = _rates(base.with_split(["x"]), "suslov", None, point, [0.2])
    assert max(abs(qx[k] - qy[k]) for k in qx) > 1e-3
    scene = jn.Scene(base, "suslov", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=W,
                                                  lambda_y=0.0), t_span=(0.0, 2.0))
    tr = scene.run(**TOL)
    assert tr.status == 6 and not tr.switches and "use another split" in tr.stop_reason
    assert "a run cannot change split" in tr.stop_reason


def test_where_no_split_is_regular_the_run_stops():
    """The line through the origin y xdot - x ydot = 0: at the origin df/dqdot = 0."""
    scene = jn.Scene(radial_line(), "chetaev", initial=dict(x=1.0, y=0.5, x_t=-2.0),
                     t_span=(0.0, 2.0))
    tr = scene.run(**TOL)
    assert tr.status == 6 and not tr.switches
    assert tr.singularity["kind"] == "split"
    assert abs(tr.t[-1] - math.atanh(0.5)) < 1e-6      # x = cosh t - 2 sinh t = 0
    assert "No other split was found regular" in tr.stop_reason


def test_bad_split_option(knife):
    with pytest.raises(jn.JetnhError, match="split must be 'switch' or 'fixed'"):
        knife.run(split="other")


# ---------------------------------------------------------------------- the switch's parts
@settings(max_examples=25, deadline=None)
@given(k=st.integers(1, 3), entries=st.lists(st.floats(-10.0, 10.0), min_size=9, max_size=9))
def test_the_small_determinant_is_lapacks(k, entries):
    M = np.array(entries[:k * k]).reshape(k, k)
    assert atlas._det(M.tolist()) == pytest.approx(np.linalg.det(M), rel=1e-9, abs=1e-9)


def test_measures_of_three_constraints_against_numpy_and_cauchy_binet():
    """The 2-trailer (k = 3 of n = 5): m_beta = det(A_beta)^2 / det(A A^T) from the
    small determinants equals LAPACK's, and the measures of the splits sum to 1 (the
    minors left out are identically zero)."""
    from jetnh.models import initial, n_trailer

    sys_ = n_trailer()
    at = atlas.Atlas(jn.Scene(sys_, "chetaev", initial=initial("n_trailer"), t_span=(0.0, 1.0)))
    J = sys_.J
    rng = np.random.default_rng(3)
    for _ in range(5):
        point = {s: v for s, v in zip([*J.q, *J.qd], rng.uniform(-2, 2, 2 * J.n))}
        point.update({s: float(v) for s, v in sys_.defaults.items()})
        A = np.array([float(v) for v in dag.evaluate_numpy(list(sys_.jacobian), point)]
                     ).reshape(sys_.k, J.n)
        m = at.measures(A)
        gram = np.linalg.det(A @ A.T)
        want = [np.linalg.det(A[:, cols]) ** 2 / gram for cols in at.columns]
        assert np.allclose(m, want, rtol=1e-10, atol=1e-14)
        assert sum(m) == pytest.approx(1.0, abs=1e-12)
    assert at.measures(np.zeros((sys_.k, J.n))) == [0.0] * len(at.splits)  # no split


def test_a_state_at_the_edge_in_each_chart(knife, knife_run):
    """``Chart.point`` (the compiled df/dqdot) at states of both charts: the knife's
    A = (sin phi, -cos phi, 0), the velocities and multipliers of ``universal`` to the
    bit, and the measures cos^2, sin^2; rows of the other chart mapped home equal the
    general route (``universal`` then ``state``) to the bit."""
    at = atlas.atlas(knife)
    p = np.ascontiguousarray(knife.p, dtype=float)
    for lo, hi, chart, seg, a, _ in knife_run._segments.pieces[:3]:
        t, Y = seg.t[a:a + hi - lo], seg.y[a:a + hi - lo]
        for i in (0, len(t) // 2, len(t) - 1):
            q, qd, lam, A = chart.point(float(t[i]), np.ascontiguousarray(Y[i]), p)
            q2, qd2, lam2, A2, _ = chart.universal(t[i:i + 1], Y[i:i + 1], p, jacobian=True)
            assert np.array_equal(qd, qd2[0]) and np.array_equal(A, A2[0])
            assert np.array_equal(q, q2[0]) and np.array_equal(lam, lam2[0])
            phi = float(q[2])
            assert np.allclose(A, [[math.sin(phi), -math.cos(phi), 0.0]], rtol=0, atol=1e-15)
            m = at.measures(A)
            assert m == pytest.approx([math.cos(phi)**2, math.sin(phi)**2], abs=1e-14)
        if chart is not at.own:
            q, qd, lam, A, _ = chart.universal(t, Y, p)
            assert np.array_equal(atlas.to_home(at.own, chart, t, Y, p),
                                  at.own.state(q, qd, lam, A))


@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_event_states_of_a_switching_run_are_rows(knife, method):
    """``y_events[k]`` of a run that changed split has one row of states per occurrence,
    as in a run that keeps its split (it was flattened to one long vector, so
    ``y_events[k][1]`` read a coordinate of the first occurrence), equal to ``events``."""
    t = knife.system.J.t
    kw = dict(n_steps=3000) if method == "rk4" else TOL
    tr = knife.run(method=method, events=[sp.sin(3 * t)], **kw)
    assert len(tr.switches) >= 2
    ye, te = tr.y_events[0], tr.t_events[0]
    assert ye.shape == (te.shape[0], len(knife.state_names)) and te.shape[0] >= 5
    for i, name in enumerate(knife.state_names):
        assert np.array_equal(ye[:, i], tr.events["sin(3*t)"][name])
    # each row is the state at its time: the trajectory's dense output there
    at = tr.at(te[1:3])
    for i, name in enumerate(knife.state_names):
        assert ye[1:3, i] == pytest.approx(at[name], abs=1e-6)


@pytest.mark.parametrize("n_steps", [100, 2000])
def test_rk4_at_inside_the_cut_step_before_a_switch(n_steps):
    """``at`` in the last, cut step before a switch reruns the chart's loop with those
    times; rk4's loop stores its start row in every mode, which the rerun took for a
    missing time ("did not reach the times asked for").  Now the Hermite values there,
    continuous with the times around them, against a tight dop853 run."""
    sc = jn.Scene(chaplygin_sleigh(), "chetaev", initial=models.initial("chaplygin_sleigh"),
                  t_span=(0.0, 5.0))
    ref = sc.run(rtol=1e-13, atol=1e-14)
    tr = sc.run(method="rk4", n_steps=n_steps)
    (switch,) = tr.switches
    cut = tr.t[tr.t < switch["t"]][-1]
    times = np.array([0.5 * (cut + switch["t"]), switch["t"] - 1e-9 * switch["t"], 4.0])
    assert cut < times[0] < times[1] < switch["t"]
    got, want = tr.at(times), ref.at(times)
    tol = 1e-11 if n_steps == 2000 else 1e-6
    for name in sc.state_names:
        assert np.asarray(got[name]) == pytest.approx(np.asarray(want[name]), abs=tol)
