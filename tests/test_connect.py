"""Sensitivities (scene.run(sensitivities=True)) and the two-point problem (jn.connect).

Closed forms: the Heisenberg system's vakonomic motions (m = 1: xddot = -2 lambda ydot,
yddot = 2 lambda xdot, lambda constant) are circles of angular rate omega = 2 lambda
traversed at constant speed v, lifted by zdot = x ydot - y xdot; from the origin,
x + i y = v/(i omega) e^{i theta} (e^{i omega t} - 1) and z = v^2/omega (t - sin(omega
t)/omega) (derived in ``heisenberg_end``); the action is v^2 T / 2; the Jacobi map
d(x, y, z)/d(xdot, ydot, lambda) first loses rank at t = 2 pi / |omega| (the circles
close), next where tan(omega t / 2) = omega t / 2.
"""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_bvp
from scipy.optimize import brentq

import jetnh as jn
from jetnh import strategies as jst
from jetnh.models import get
from jetnh.numeric import codegen
from jetnh.numeric.codegen import continuous, llvm
from jetnh.numeric.connect.collocation import problem
from jetnh.numeric.scene import Scene

O = {"x": 0.0, "y": 0.0, "z": 0.0}


@pytest.fixture(scope="module")
def heis():
    return get("heisenberg")


def heisenberg_end(v, theta, omega, t):
    """The closed form above at time t (from the origin, m = 1)."""
    w = v / (1j * omega) * np.exp(1j * theta) * (np.exp(1j * omega * t) - 1.0)
    z = v**2 / omega * (t - np.sin(omega * t) / omega)
    return w.real, w.imag, z


# ---------------------------------------------------------------------- sensitivities
def _interpret(ops, t, y, p):
    """A straight-line program (``codegen.llvm.program``) evaluated in Python: the outputs
    as a dict slot -> value."""
    vals, out = [], {}
    for op in ops:
        k = op[0]
        if k == "y":
            v = y[op[1]]
        elif k == "p":
            v = p[op[1]]
        elif k == "t":
            v = t
        elif k == "c":
            v = op[1]
        elif k == "add":
            v = sum(vals[a] for a in op[1:])
        elif k == "mul":
            v = math.prod(vals[a] for a in op[1:])
        elif k == "div":
            v = vals[op[1]] / vals[op[2]]
        elif k == "powi":
            v = vals[op[1]] ** op[2]
        elif k == "pow":
            v = vals[op[1]] ** vals[op[2]]
        elif k == "fn":
            v = getattr(math, op[1], None) and getattr(math, op[1])(
                *[vals[a] for a in op[2:]])
        else:
            out[op[1]] = vals[op[2]]
            v = None
        vals.append(v)
    return out


@given(jst.systems(min_n=2, max_n=3), st.sampled_from(["chetaev", "vakonomic"]),
       st.data())
def test_variational_program_is_the_derivative_of_the_rhs(system, principle, data):
    """The generated variational equations (``_sensitivity_program``), evaluated with S
    a random matrix, equal (df/dy) S + df/dp by central differences of the generated
    right-hand side, on random systems and states."""
    try:
        phi, rhs = codegen.kernel_expressions(system, principle, {})
    except jn.JetnhError:
        return                               # singular reduced mass matrix: no equations
    em, used = continuous._emitter(phi, rhs)
    try:
        ops = llvm.program(em, used, list(enumerate(rhs)))
    except llvm.Unsupported:
        return
    n, n_p = len(rhs), 0
    m = n + n_p
    sens = llvm.sensitivity_program(ops, n, n_p)
    rnd = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    y = rnd.uniform(0.2, 0.6, n)
    S = rnd.standard_normal((n, m))
    t = 0.3
    try:
        got = _interpret(sens, t, np.concatenate([y, S.ravel()]), [])
        f0 = _interpret(ops, t, y, [])
    except (ZeroDivisionError, ValueError, OverflowError):
        return
    h = 1e-6
    Jfd = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fp, fm = _interpret(ops, t, y + e, []), _interpret(ops, t, y - e, [])
        Jfd[:, j] = [(fp[i] - fm[i]) / (2 * h) for i in range(n)]
    want = Jfd @ S
    assert all(got[i] == f0[i] for i in range(n))          # the state's stores unchanged
    scale = 1.0 + np.abs(Jfd).max() * np.abs(S).max() * n
    for i in range(n):
        for k in range(m):
            assert abs(got[n + i * m + k] - want[i, k]) <= 1e-6 * scale


@pytest.fixture(scope="module")
def heis_scene(heis):
    return Scene(heis, "vakonomic", initial={**O, "x": 0.1, "y": 0.2, "x_t": 1.0,
                                              "y_t": 0.3, "lambda_z": 0.7},
                 t_span=(0.0, 2.0), runtime_params=["m"])


@pytest.mark.parametrize("method", ["dop853", "dopri5", "rk4", "radau", "scipy-DOP853"])
def test_sensitivities_against_central_differences(heis_scene, method):
    sc = heis_scene
    kw = dict(n_steps=2000) if method == "rk4" else dict(rtol=1e-11, atol=1e-12)
    tr = sc.run(method=method, sensitivities=True, **kw)
    assert tr.sensitivities.shape == (len(tr.t), 6, 7) and not tr.sensitivities.flags.writeable
    assert tr.sensitivity_columns == sc.state_names + ("m",)
    h = 1e-6
    base = {k: sc.initial[k] for k in sc.state_names}
    for to in sc.state_names + ("m",):
        if to == "m":
            a, b = (sc.run(method=method, params={"m": 1 + s * h}, save="final", **kw)
                    for s in (1, -1))
        else:
            a, b = (sc.run(method=method, y0={**base, to: base[to] + s * h}, save="final",
                           **kw) for s in (1, -1))
        fd = (a.y[-1] - b.y[-1]) / (2 * h)
        S = np.array([tr.sensitivity(of, to)[-1] for of in sc.state_names])
        assert np.max(np.abs(fd - S)) < 1e-8, (to, fd, S)


def test_sensitivities_closed_form(heis_scene):
    """d z(t)/d lambda(t0) from the closed form (x0 = y0 = 0, m = 1): the derivative in
    omega = 2 lambda of z = v^2/omega (t - sin(omega t)/omega)."""
    sc = heis_scene.replace(initial={**O, "x_t": 0.6, "y_t": 0.8, "lambda_z": 1.5})
    tr = sc.run(sensitivities=True, rtol=1e-12, atol=1e-13)
    t, v, w = tr.t, 1.0, 3.0
    dz_dw = (-v**2 / w**2 * (t - np.sin(w * t) / w)
             + v**2 / w * (np.sin(w * t) / w**2 - t * np.cos(w * t) / w))
    assert np.max(np.abs(tr.sensitivity("z", "lambda_z") - 2 * dz_dw)) < 1e-9
    assert np.allclose(tr.sensitivity("x", "x")[-1], 1.0) and tr.sensitivity("z", "x")[0] == 0


def test_plain_runs_unchanged_and_uncontrolled_sensitivities_take_its_steps(heis_scene):
    sc = heis_scene
    plain = sc.run(rtol=1e-9, atol=1e-12)
    ctl = sc.run(rtol=1e-9, atol=1e-12, sensitivities=True)
    free = sc.run(rtol=1e-9, atol=1e-12, sensitivities=True, sensitivity_error=False)
    assert np.allclose(free.t, plain.t, rtol=0, atol=1e-12) and len(free.t) == len(plain.t)
    assert np.allclose(free.y, plain.y, rtol=0, atol=1e-12)
    assert len(ctl.t) >= len(plain.t)
    # dense output of a run with sensitivities re-takes the augmented steps
    mid = 0.5 * (ctl.t[1] + ctl.t[2])
    assert np.allclose(ctl.at([mid]).to_numpy()[0], sc.run(rtol=1e-9, atol=1e-12, t_eval=[mid]).y[0],
                       atol=1e-9)
    with pytest.raises(jn.JetnhError, match="sensitivities=True"):
        plain.sensitivity("x", "y")
    with pytest.raises(jn.JetnhError, match="not a state"):
        ctl.sensitivity("z_t", "x")
    with pytest.raises(jn.JetnhError, match="runtime_params"):
        ctl.sensitivity("x", "R")
    with pytest.raises(jn.JetnhError, match="continuous methods"):
        sc.run(method="dvi", h=0.01, sensitivities=True)
    with pytest.raises(jn.JetnhError, match="sensitivity_error"):
        sc.run(sensitivity_error=False)


# ---------------------------------------------------------------------- connect
def test_heisenberg_geodesic_closed_form(heis):
    v, theta, omega, T = 1.3, 0.4, 2.5, 1.0
    x1, y1, z1 = heisenberg_end(v, theta, omega, T)
    c = jn.connect(heis, "vakonomic", O, {"x": x1, "y": y1, "z": z1}, (0.0, T))
    assert isinstance(c, jn.Connection) and c.normal and c.residual < 1e-9
    assert abs(c.initial["x_t"] - v * math.cos(theta)) < 1e-8
    assert abs(c.initial["y_t"] - v * math.sin(theta)) < 1e-8
    assert abs(c.initial["lambda_z"] - omega / 2) < 1e-8
    assert abs(c.cost - v**2 * T / 2) < 1e-9
    tr = c.trajectory
    for got, want in zip((tr["x"], tr["y"], tr["z"]), heisenberg_end(v, theta, omega, tr.t)):
        assert np.max(np.abs(got - want)) < 1e-8
    assert c.conjugate_times == ()          # omega T < 2 pi: before the first
    with pytest.raises(Exception):
        c.cost = 0.0


def test_first_conjugate_time(heis):
    v, theta, omega, T = 1.0, -0.7, 2 * math.pi / 0.6, 1.0
    end = dict(zip("xyz", heisenberg_end(v, theta, omega, T)))
    c = jn.connect(heis, "vakonomic", O, end, (0.0, T),
                   guess={"x_t": 0.9 * v * math.cos(theta), "y_t": v * math.sin(theta),
                          "lambda_z": 0.95 * omega / 2})
    assert abs(c.initial["lambda_z"] - omega / 2) < 1e-8
    second = 2 * brentq(lambda s: math.tan(s) - s, 4.0, 4.6) / omega
    assert len(c.conjugate_times) == 2
    assert abs(c.conjugate_times[0] - 2 * math.pi / omega) < 1e-9
    assert abs(c.conjugate_times[1] - second) < 1e-9


def test_degenerate_endpoint_on_the_z_axis(heis):
    """(0, 0, z1): every rotation of a closing circle arrives -- a circle of solutions,
    the Jacobian of rank 2 at t1 = the conjugate time; the single loop costs pi z1 / T."""
    z1, T = 0.5, 1.0
    c = jn.connect(heis, "vakonomic", O, {**O, "z": z1}, (0.0, T),
                   guess={"x_t": 1.0, "y_t": 1.0, "lambda_z": 3.0})
    assert c.residual < 1e-9 and c.rank == 2
    assert abs(c.cost - math.pi * z1 / T) < 1e-8
    assert c.conjugate_times[-1] == T


def test_abnormal_extremal_is_recognised():
    """Martinet: zdot = y^2 xdot / 2; the segment y = 0 is an abnormal extremal (the
    endpoint map cannot move z at first order along it).  From y_t = 0 the search stays
    on it; from the default guess it returns y = A sin(pi t) with A ~ 1e-5, whose end
    z = A^2 / 4, refused (z returns: judged on its own excursion, all of it missed; it
    was admitted on x's displacement), its best a normal extremal to another end,
    within its miss of the abnormal segment (the Gramian's z-row changes by half along
    the correction of that miss: ``gramian_change``), so not normal (was: normal, its
    unit-free Gramian ratio 0.1)."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    mart = jn.System(J, (xd**2 + yd**2) / 2, [zd - y**2 * xd / 2], dependent=[z])
    c = jn.connect(mart, "vakonomic", O, {"x": 1.0, "y": 0.0, "z": 0.0}, (0.0, 1.0),
                   guess={"x_t": 1.0, "y_t": 0.0, "lambda_z": 0.0})
    assert c.residual < 1e-8 and not c.normal and c.gramian_ratio < 1e-9
    with pytest.raises(jn.ConnectError) as e:
        jn.connect(mart, "vakonomic", O, {"x": 1.0, "y": 0.0, "z": 0.0}, (0.0, 1.0))
    near = e.value.best          # z (returning) judged on its own excursion: refused
    assert near.relative_residual > 0.1 and 0.0 < abs(near.trajectory["y"]).max() < 1e-3
    assert near.gramian_ratio > 1e-2 and near.gramian_change > 0.3
    assert near.normal is False
    off = jn.connect(mart, "vakonomic", O, {"x": 1.0, "y": 0.0, "z": 0.05}, (0.0, 1.0))
    assert off.normal and off.residual < 1e-9 and off.gramian_change < 1e-6


@pytest.mark.parametrize("model, principle, start, end, T", [
    ("heisenberg", "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 0.2}, 1.0),
    ("rolling_disk", "chetaev", {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0},
     {"x": 0.5, "y": 0.3}, 1.0),
])
def test_against_collocation(model, principle, start, end, T):
    """scipy's solve_bvp on the same compiled equations, from a straight-line guess."""
    system = get(model)
    c = jn.connect(system, principle, start, end, (0.0, T))
    sc = c.trajectory.scene
    names = sc.state_names
    assert len(names) == len(sc.coordinates) + len(end) or principle == "chetaev"
    fun, _, bc, t, Y = problem(sc, start, end, T, jacobian=False)
    sol = solve_bvp(fun, bc, t, Y, tol=1e-9, max_nodes=100_000)
    assert sol.status == 0
    found = np.array([c.initial[k] for k in names])
    assert np.max(np.abs(sol.y[:, 0] - found)) < 1e-6


def test_chetaev_reach_and_refusal(heis):
    c = jn.connect(heis, "chetaev", O, {"x": 1.0, "y": 0.5}, (0.0, 2.0))
    assert c.residual < 1e-12 and abs(c.cost - (0.5**2 + 0.25**2) / 2 * 2.0) < 1e-12
    with pytest.raises(jn.ConnectError, match="name at most 2 coordinates") as e:
        jn.connect(heis, "chetaev", O, {"x": 1.0, "y": 0.5, "z": 0.2}, (0.0, 1.0))
    assert e.value.best is not None and abs(e.value.best.residual - 0.2) < 1e-9
    with pytest.raises(jn.ConnectError, match="least-squares"):
        jn.connect(heis, "suslov", O, {"x": 1.0, "y": 0.5, "z": 0.2}, (0.0, 1.0))


@pytest.mark.parametrize("args, match", [
    (dict(start={"x": 0, "y": 0, "w": 0}), "not a coordinate"),
    (dict(start={"x": 0, "y": 0}), "missing z"),
    (dict(end={"q": 1.0}), "not a coordinate"),
    (dict(end={}), "names no coordinate"),
    (dict(t_span=(1.0, 1.0)), "zero length"),
    (dict(guess=[1.0, 2.0]), "must hold 3 values"),
    (dict(guess={"x_t": 1.0}), "guess lacks"),
    (dict(guess={"z_t": 1.0}), "not an unknown"),
    (dict(principle="newton"), "principle"),
    (dict(t_span=(1.0, 0.0)), r"^t_span \(1\.0, 0\.0\) runs backwards"),
    (dict(segments=1000), "segments"),
    (dict(rcond=2.0), "rcond must be below 1, got 2.0"),
    (dict(rcond=0.0), "rcond must be a positive"),
])
def test_bad_input(heis, args, match):
    kw = dict(principle="vakonomic", start=O, end={"x": 1.0, "y": 0.5, "z": 0.2},
              t_span=(0.0, 1.0))
    kw.update(args)
    with pytest.raises(jn.JetnhError, match=match):
        jn.connect(heis, kw.pop("principle"), kw.pop("start"), kw.pop("end"),
                   kw.pop("t_span"), **kw)


def test_unreachable_in_budget_says_where_it_stopped(heis):
    with pytest.raises(jn.ConnectError, match="stopped at s =") as e:
        jn.connect(heis, "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 4000.0}, (0.0, 1.0),
                   max_iter=2, max_continuation=2)
    assert "collocation stopped" in str(e.value) and "continuation in T" in str(e.value)


def test_collocation_route_where_the_budget_stops_shooting(heis):
    """z = 40 with two iterations and three continuation steps: the collocation warm
    start finds a geodesic (the closed form from its initial state) that winds round
    more than once -- its conjugate times say it is no minimizer."""
    c = jn.connect(heis, "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 40.0}, (0.0, 1.0),
                   max_iter=2, max_continuation=3)
    assert c.route == "collocation" and c.residual < 1e-8
    xt, yt, lam = c.initial["x_t"], c.initial["y_t"], c.initial["lambda_z"]
    v, theta, omega = math.hypot(xt, yt), math.atan2(yt, xt), 2 * lam
    assert np.max(np.abs(np.array(heisenberg_end(v, theta, omega, 1.0))
                         - [1.0, 0.5, 40.0])) < 1e-8
    assert abs(c.cost - v**2 / 2) < 1e-8
    assert abs(c.conjugate_times[0] - 2 * math.pi / abs(omega)) < 1e-9


def test_cli_connect(tmp_path):
    import json
    import subprocess
    import sys

    def run(*args):
        return subprocess.run([sys.executable, "-m", "jetnh", "connect", *args],
                              capture_output=True, text=True, timeout=600)

    png = tmp_path / "g.png"
    r = run("heisenberg", "--from", "x=0,y=0,z=0", "--to", "x=1,y=0.5,z=0.2", "--t-end", "1",
            "--format", "json", "--plot", str(png), "-q")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert abs(data["cost"] - 0.672290367016) < 1e-9 and data["normal"] is True
    assert data["conjugate_times"] == [] and png.stat().st_size > 1000
    r = run("heisenberg", "--to", "w=1", "--t-end", "1", "-p", "chetaev")
    assert r.returncode == 1 and "not a coordinate" in r.stderr
    assert "Traceback" not in r.stderr
    r = run("heisenberg", "--t-end", "1")
    assert r.returncode != 0 and "--to" in r.stderr
