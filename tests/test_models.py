"""The catalogue: every model derives under every principle and simulates with a small
constraint residual; every closed form and first integral its docstring states holds.

Cost: one compiled scene per (model, principle) used here (about 2.5 s each when cold,
milliseconds from the kernel cache afterwards); short spans, rtol 1e-10.
"""

import math
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh import modelfile as mf
from jetnh import models
from jetnh.mechanics.system import PRINCIPLES
from jetnh.errors import LagrangianError, ModelFileError
from jetnh.algebra.zero import vanishes

PAPER = {"rolling_disk", "appell_hamel"}
# small instances of the scalable families, to keep the run short
OPTIONS = {"n_trailer": {"N": 1}, "particle_chain": {"N": 2}}
RTOL, ATOL = 1e-10, 1e-12
_OMEGA = {"wx": "cos(phi)*theta_t + sin(theta)*sin(phi)*psi_t",
          "wy": "sin(phi)*theta_t - sin(theta)*cos(phi)*psi_t",
          "wz": "phi_t + cos(theta)*psi_t"}
# the first integrals the docstrings state, monitored by the scenes (one compile per model)
INTEGRALS = {
    "isokinetic_particle": {"s": "atanh(y_t/v) + g*t/v"},
    "rheonomic_knife_edge": {"jacobi": "m*((x_t - U)**2 + y_t**2)/2 - m*g*sin(alpha)*(x - U*t)"},
    "bead_on_parabola": {"holonomic": "y - a*x**2"},
    "radial_line": {"ratio": "y/x"},
    "rolling_ball": _OMEGA,
    "ball_on_turntable": {"wz": _OMEGA["wz"]},
    "suslov_rigid_body": {"O1": "phi_t*sin(theta)*sin(psi) + theta_t*cos(psi)",
                          "O2": "phi_t*sin(theta)*cos(psi) - theta_t*sin(psi)"},
}


def symbols_of(system):
    return {s.name: s for s in system.parameters + system.J.q + system.J.qd + (system.J.t,)}


@lru_cache(maxsize=None)
def trajectory(name, principle="chetaev", t_end=None, options=(), integrals=(), params=(),
               init=()):
    """A short run of a catalogue model from its default initial state (multipliers 0),
    with ``init`` overriding some values."""
    opts = dict(options) or OPTIONS.get(name, {})
    info = models.info(name)
    system = info.system(**opts)
    initial = info.initial(**opts)
    names = [s.name for s in system.J.q] + [v.name for v in system.independent_velocities]
    init = {n: initial.get(n, 0.0) for n in names} | dict(init)
    if principle != "chetaev":
        init.update({f"lambda_{d.name}": 0.0 for d in system.dependent})
    syms = symbols_of(system)
    syms.update({f"lambda_{d.name}": sp.Symbol(f"lambda_{d.name}") for d in system.dependent})
    given = dict(integrals) or (INTEGRALS.get(name, {}) if principle == "chetaev" else {})
    ints = {k: mf.parse_expression(v, syms, k) for k, v in given.items()}
    scene = jn.Scene(system, principle, params=dict(params), initial=init,
                     t_span=(0.0, t_end or min(info.t_end, 1.0)), integrals=ints)
    traj = scene.run(rtol=RTOL, atol=ATOL, t_eval=np.linspace(0.0, scene.t_span[1], 41))
    assert traj.success, traj.stop_reason
    return system, traj


def close(a, b, tol=1e-7):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    err = np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b))))
    assert err < tol, err
    return err


def drift(col):
    return float(np.max(np.abs(col - col[0])))


# ---------------------------------------------------------------------- the catalogue
def test_catalogue_contents():
    assert len(set(models.CATALOGUE) - PAPER) >= 10
    for name, factory in models.CATALOGUE.items():
        doc = factory.__doc__ or ""
        assert "Source" in doc or name in PAPER, name
        assert "integral" in doc.lower(), name
        info = models.info(name)
        s = info.system()
        assert isinstance(s, jn.System) and s.name
        assert set(s.defaults) == set(s.parameters), name      # every parameter has a default
        assert set(info.initial()) <= {v.name for v in s.J.q + s.J.qd}, name


def test_the_catalogue_gives_model_records():
    """models.model is the record model files give (jetnh.modelfile.Model): the System
    with its options, the default initial state and span; written as a model file and
    read back, it keeps them."""
    for name in ("rolling_disk", "n_trailer"):
        opts = OPTIONS.get(name, {})
        m = models.model(name, **opts)
        assert isinstance(m, mf.Model) and m.source == "catalogue"
        assert m.name == name + "".join(f":{k}={v}" for k, v in opts.items())
        assert m.system == models.get(name, **opts)
        assert m.initial == models.initial(name, **opts)
        assert m.simulation == {"t_end": models.info(name).t_end}
        back = mf.loads(mf.dumps(m))
        assert (back.initial, back.simulation, back.system.L, back.system.dependent) == (
            m.initial, m.simulation, m.system.L, m.system.dependent)
    with pytest.raises(ModelFileError, match="no option"):
        models.model("knife_edge", N=3)


def test_catalogue_covers_the_kinds():
    kinds = {name: models.get(name, **OPTIONS.get(name, {})).classify()
             for name in models.CATALOGUE}
    assert not kinds["isokinetic_particle"].affine and not kinds["appell_hamel"].affine
    assert kinds["rheonomic_knife_edge"].rheonomic
    assert kinds["bead_on_parabola"].integrable and kinds["radial_line"].integrable
    for name in set(kinds) - {"bead_on_parabola", "radial_line"}:
        assert not kinds[name].integrable, name
    assert kinds["chaplygin_sleigh"].chaplygin and kinds["knife_edge"].chaplygin


def test_options_and_errors():
    assert models.get("n_trailer", N=0).J.n == 3
    assert models.get("particle_chain", N=4).J.n == 12
    with pytest.raises(ModelFileError, match="no option"):
        models.get("knife_edge", N=3)
    with pytest.raises(ModelFileError, match="integer"):
        models.get("n_trailer", N=-1)
    with pytest.raises(ModelFileError, match="no model named"):
        models.get("nope")


@pytest.mark.parametrize("name", list(models.CATALOGUE))
def test_derives_under_every_principle(name):
    s = models.get(name, **OPTIONS.get(name, {}))
    J = s.J
    for principle in PRINCIPLES:
        eom = s.equations(principle)
        if (name, principle) == ("isokinetic_particle", "suslov"):
            continue          # singular everywhere: test_isokinetic_particle_suslov_is_singular
        acc = eom.accelerations()
        assert set(J.qdd) <= set(acc), (name, principle)
        assert set(eom.multiplier_rates) <= set(acc)


@pytest.mark.parametrize("name", list(models.CATALOGUE))
def test_simulates_with_small_residual(name):
    _, traj = trajectory(name)
    assert traj.diagnostics.residual_max < 1e-8


@pytest.mark.parametrize("name", ["nonholonomic_particle", "knife_edge", "isokinetic_particle",
                                  "bead_on_parabola"])
@pytest.mark.parametrize("principle", ["vakonomic", "holder", "suslov"])
def test_simulates_under_other_principles(name, principle):
    if (name, principle) == ("isokinetic_particle", "suslov"):
        pytest.skip("Suslov's equations are singular everywhere here: see the next test")
    _, traj = trajectory(name, principle, t_end=0.5)
    assert traj.diagnostics.residual_max < 1e-8


def test_isokinetic_particle_suslov_is_singular():
    """L~ = m v^2/2 - m g y does not depend on ydot: (31) degenerates to -m g = 0, and the
    derivation says so (the reduced Hessian vanishes on the constraints) instead of
    handing the integrator equations singular everywhere."""
    s = models.get("isokinetic_particle")
    assert sp.diff(s.L_tilde, s.J.qd[1]) == 0
    with pytest.raises(LagrangianError, match="rank 0 < 1 on the constraints"):
        s.equations("suslov").accelerations()
    scene = jn.Scene(s, "suslov", initial={"x": 0.0, "y": 0.0, "y_t": 0.3, "lambda_x": 0.2},
                     t_span=(0.0, 0.5))
    with pytest.raises(LagrangianError, match="singular"):
        scene.run(rtol=RTOL, atol=ATOL)


# ---------------------------------------------------------------------- closed forms
def test_knife_edge():
    s, traj = trajectory("knife_edge")
    p = {k.name: v for k, v in s.defaults.items()}
    i = models.initial("knife_edge")
    t, w, phi0 = traj.t, i["phi_t"], i["phi"]
    c = p["g"] * math.sin(p["alpha"]) / w
    A = i["x_t"] / math.cos(phi0) - c * math.sin(phi0)
    phi = phi0 + w * t
    close(traj["phi"], phi)
    close(traj["x"], i["x"] + (A * (np.sin(phi) - math.sin(phi0))
                               + c / 2 * (np.sin(phi)**2 - math.sin(phi0)**2)) / w)
    close(traj["y"], i["y"] + (-A * (np.cos(phi) - math.cos(phi0))
                               + c / 2 * ((phi - phi0) - (np.sin(phi) * np.cos(phi)
                                                          - math.sin(phi0) * math.cos(phi0)))) / w)
    assert traj.diagnostics.energy_drift < 1e-8


def test_chaplygin_sleigh():
    s, traj = trajectory("chaplygin_sleigh")
    p = {k.name: v for k, v in s.defaults.items()}
    i = models.initial("chaplygin_sleigh")
    m, a, K = p["m"], p["a"], p["I"] + p["m"] * p["a"]**2
    th = traj["theta"]
    v = traj["x_t"] * np.cos(th) + traj["y_t"] * np.sin(th)
    v0, w0 = v[0], i["theta_t"]
    E = m * v0**2 / 2 + K * w0**2 / 2
    V = math.sqrt(2 * E / m)
    c = math.atanh(v0 / V)
    s_ = m * a * V * traj.t / K + c
    close(v, V * np.tanh(s_))
    close(traj["theta_t"], w0 * math.cosh(c) / np.cosh(s_))
    assert traj.diagnostics.energy_drift < 1e-9


def test_nonholonomic_particle_chetaev():
    _, traj = trajectory("nonholonomic_particle")
    i = models.initial("nonholonomic_particle")
    u, y0 = i["y_t"], i["y"]
    c = i["x_t"] * math.sqrt(1 + y0**2)
    y = y0 + u * traj.t
    close(traj["y"], y)
    close(traj["x"], i["x"] + c / u * (np.arcsinh(y) - math.asinh(y0)))
    close(traj["z"], i["z"] + c / u * (np.sqrt(1 + y**2) - math.sqrt(1 + y0**2)))
    close(traj["x_t"] * np.sqrt(1 + y**2), np.full_like(y, c))
    assert traj.diagnostics.energy_drift < 1e-9


def test_nonholonomic_particle_vakonomic_integrals():
    _, traj = trajectory("nonholonomic_particle", "vakonomic",
                         integrals=(("px", "m*x_t - lambda_z*y"), ("pz", "m*z_t + lambda_z")))
    d = traj.diagnostics
    assert d.integral_drift["px"] < 1e-9 and d.integral_drift["pz"] < 1e-9
    assert d.energy_drift < 1e-9


def test_isokinetic_particle():
    s, traj = trajectory("isokinetic_particle")
    p = {k.name: v for k, v in s.defaults.items()}
    i = models.initial("isokinetic_particle")
    g, v = p["g"], p["v"]
    s0 = math.atanh(i["y_t"] / v)
    s_ = s0 - g * traj.t / v
    gd = lambda z: np.arctan(np.sinh(z))  # noqa: E731
    close(traj["y_t"], v * np.tanh(s_))
    close(traj["x_t"], v / np.cosh(s_))
    close(traj["x"], i["x"] - v**2 / g * (gd(s_) - gd(s0)))
    close(traj["y"], i["y"] - v**2 / g * (np.log(np.cosh(s_)) - math.log(math.cosh(s0))))
    assert traj.diagnostics.integral_drift["s"] < 1e-9


def test_rheonomic_knife_edge():
    s, traj = trajectory("rheonomic_knife_edge")
    p = {k.name: v for k, v in s.defaults.items()}
    i = models.initial("rheonomic_knife_edge")
    w, U = p["w"], p["U"]
    c = p["g"] * math.sin(p["alpha"]) / w
    A = i["x_t"] - U
    wt = w * traj.t
    close(traj["x"], i["x"] + U * traj.t + (A * np.sin(wt) + c * np.sin(wt)**2 / 2) / w)
    close(traj["y"], i["y"] + (c * (wt - np.sin(wt) * np.cos(wt)) / 2
                               - A * (np.cos(wt) - 1)) / w)
    assert traj.diagnostics.integral_drift["jacobi"] < 1e-9
    assert traj.diagnostics.energy_drift > 1e-3          # the belt works on the skate


def test_bead_on_parabola():
    s, traj = trajectory("bead_on_parabola")
    assert traj.diagnostics.integral_drift["holonomic"] < 1e-9
    assert traj.diagnostics.energy_drift < 1e-8
    x, xd = s.J.q[0], s.J.qd[0]
    a, g = sp.symbols("a g")
    acc = s.equations("chetaev").accelerations()[s.J.qdd[0]]
    assert vanishes(acc + (4 * a**2 * x * xd**2 + 2 * a * g * x) / (1 + 4 * a**2 * x**2), s)


def test_bead_on_parabola_vakonomic_is_chetaev():
    """Integrable: [f]_s = 0, so the vakonomic equations are Chetaev's for every lambda."""
    _, chetaev = trajectory("bead_on_parabola")
    _, vak = trajectory("bead_on_parabola", "vakonomic")
    close(vak["x"], chetaev["x"], 1e-8)
    close(vak["y"], chetaev["y"], 1e-8)


def test_radial_line():
    s, traj = trajectory("radial_line")
    k = s.defaults[sp.Symbol("k")]
    i = models.initial("radial_line")
    r = math.sqrt(k)
    x = i["x"] * np.cosh(r * traj.t) + i["x_t"] / r * np.sinh(r * traj.t)
    close(traj["x"], x)
    close(traj["y"], i["y"] / i["x"] * x)
    assert traj.diagnostics.integral_drift["ratio"] < 1e-9
    assert traj.diagnostics.energy_drift < 1e-8


def test_rolling_ball():
    s, traj = trajectory("rolling_ball")
    close(traj["x"], traj["x"][0] + traj["x_t"][0] * traj.t)
    close(traj["y"], traj["y"][0] + traj["y_t"][0] * traj.t)
    d = traj.diagnostics
    assert max(d.integral_drift.values()) < 1e-9 and d.energy_drift < 1e-9


def test_ball_on_turntable():
    s, traj = trajectory("ball_on_turntable")
    p = {k.name: v for k, v in s.defaults.items()}
    kappa = p["I"] / (p["I"] + p["m"] * p["r"]**2)
    w = kappa * p["Omega"]
    v0 = traj["x_t"][0] + 1j * traj["y_t"][0]
    z0 = traj["x"][0] + 1j * traj["y"][0]
    z = z0 + v0 * (np.exp(1j * w * traj.t) - 1) / (1j * w)
    close(traj["x"], z.real)
    close(traj["y"], z.imag)
    assert traj.diagnostics.integral_drift["wz"] < 1e-9
    assert abs(kappa - 2 / 7) < 1e-12                      # the solid ball: 2 Omega / 7


def test_suslov_rigid_body():
    s, traj = trajectory("suslov_rigid_body")
    p = {k.name: v for k, v in s.defaults.items()}
    I1, I2, I13 = p["I1"], p["I2"], p["I13"]
    o1, o2 = traj["O1"], traj["O2"]
    h = (I1 * o1[0]**2 + I2 * o2[0]**2) / 2
    W = math.sqrt(2 * h / I2)
    c = math.atanh(o2[0] / W)
    s_ = I13 * W * traj.t / I1 + c
    close(o2, W * np.tanh(s_))
    close(o1, o1[0] * math.cosh(c) / np.cosh(s_))
    assert traj.diagnostics.energy_drift < 1e-9


@pytest.mark.parametrize("N", [0, 2])
def test_n_trailer_steady_turning(N):
    s, traj = trajectory("n_trailer", options=(("N", N),))
    i = models.n_trailer_turning(N)
    Om, R0 = i["theta0_t"], -i["y"]
    close(traj["x"], R0 * np.sin(Om * traj.t))
    close(traj["y"], -R0 * np.cos(Om * traj.t))
    for j in range(N + 1):
        close(traj[f"theta{j}"], i.get(f"theta{j}", 0.0) + Om * traj.t)
    assert traj.diagnostics.energy_drift < 1e-9


def test_n_trailer_energy_off_equilibrium():
    _, traj = trajectory("n_trailer", options=(("N", 1),),
                         init=(("theta1", 0.3), ("x_t", 1.0), ("theta0_t", -0.4)))
    assert traj.diagnostics.energy_drift < 1e-9
    assert traj.diagnostics.residual_max < 1e-8


def test_particle_chain():
    _, traj = trajectory("particle_chain", options=(("N", 3),))
    i = models.initial("particle_chain", N=3)
    for j in (1, 2, 3):
        close(traj[f"y{j}"], i[f"y{j}"] + i[f"y{j}_t"] * traj.t)
    assert traj.diagnostics.energy_drift < 1e-9
    _, free = trajectory("particle_chain", options=(("N", 3),), params=(("k", 0.0),))
    for j in (1, 2, 3):
        y0, u = i[f"y{j}"], i[f"y{j}_t"]
        c = i[f"x{j}_t"] * math.sqrt(1 + y0**2)
        y = y0 + u * free.t
        close(free[f"x{j}"], i[f"x{j}"] + c / u * (np.arcsinh(y) - math.asinh(y0)))


def test_appell_hamel_speed_decays_linearly():
    s, traj = trajectory("appell_hamel")
    p = {k.name: v for k, v in s.defaults.items()}
    r = p["b"] / p["a"]
    v = np.hypot(traj["x_t"], traj["y_t"])
    close(v, v[0] - r * p["g"] * traj.t / (1 + r**2))
    assert traj.diagnostics.energy_drift < 1e-8


# ---------------------------------------------------------------------- first integrals
# model -> principle -> (degree, coefficients, the integrals its docstring lists); each is
# found by jn.conserved_quantities (in the span of the basis it returns, over the
# parameters), and each listed "not" integral is not
_TH = "sin(theta)*sin(phi), sin(theta)*cos(phi), cos(phi), sin(phi), cos(theta)"
_ENERGY_DISK = "((R**2 + I1)*phi_t**2 + I2*psi_t**2)/2"
_E_KNIFE = "m*x_t**2/cos(phi)**2/2 + I*phi_t**2/2 - m*g*sin(alpha)*x"
_E_SLEIGH = "m*x_t**2/cos(theta)**2/2 + (I + m*a**2)*theta_t**2/2"
_E_PARTICLE = "m*((1 + y**2)*x_t**2 + y_t**2)/2"
CATALOGUE_INTEGRALS = {
    "rolling_disk": {
        "chetaev": (2, "1", ["phi_t", "psi_t", _ENERGY_DISK]),
        "suslov": (2, "1", ["phi_t", "psi_t", _ENERGY_DISK]),
        "vakonomic": (2, "1", [_ENERGY_DISK], ["phi_t"])},
    "appell_hamel": {
        p: (2, "1, z", ["m*(1 + b**2/a**2)*(x_t**2 + y_t**2)/2 + m*g*z"])
        for p in ("chetaev", "vakonomic", "suslov")},
    "knife_edge": {
        "chetaev": (2, "1, x, 1/cos(phi)**2", ["phi_t", _E_KNIFE]),
        "vakonomic": (2, "1, x, 1/cos(phi)**2", [_E_KNIFE], ["phi_t"]),
        "suslov": (2, "1, x, 1/cos(phi)**2", [_E_KNIFE], ["phi_t"])},
    "chaplygin_sleigh": {
        "chetaev": (2, "1, 1/cos(theta)**2", [_E_SLEIGH]),
        "vakonomic": (2, "1, 1/cos(theta)**2",
                      [_E_SLEIGH, "lambda_y**2 + 2*a*m*lambda_y*theta_t - I*m*theta_t**2"]),
        "suslov": (2, "1, 1/cos(theta)**2", [_E_SLEIGH, "x_t/cos(theta)**2"])},
    "nonholonomic_particle": {
        "chetaev": (2, "1, y, y**2, z", ["y_t", "(1 + y**2)*x_t**2", _E_PARTICLE,
                                         "(1 + y**2)*x_t - z*y_t"]),
        "vakonomic": (2, "1, y, y**2", [_E_PARTICLE, "m*x_t - lambda_z*y",
                                        "m*y*x_t + lambda_z"], ["y_t"]),
        "suslov": (2, "1, y, y**2", ["(1 + y**2)*x_t", _E_PARTICLE], ["y_t"])},
    "heisenberg": {
        "chetaev": (2, "1, x, y", ["x_t", "y_t", "x*y_t - y*x_t", "m*(x_t**2 + y_t**2)/2"]),
        "vakonomic": (2, "1, x, y", ["lambda_z", "m*x_t + 2*lambda_z*y",
                                     "m*y_t - 2*lambda_z*x", "m*(x_t**2 + y_t**2)/2"],
                      ["x_t", "y_t"])},
    "isokinetic_particle": {"chetaev": (2, "1, t, y", [])},
    "rheonomic_knife_edge": {
        "chetaev": (2, "1/cos(w*t)**2, x, t",
                    ["m*((x_t - U)**2 + y_t**2)/2 - m*g*sin(alpha)*(x - U*t)"]),
        "suslov": (2, "1/cos(w*t)**2, x, t", ["(x_t - U)/cos(w*t)**2 - g*sin(alpha)*t"])},
    "bead_on_parabola": {
        "chetaev": (2, "1, x, x**2, y", ["y - a*x**2", "m*(x_t**2 + y_t**2)/2 + m*g*y"]),
        "vakonomic": (2, "1, x, x**2, y, t", ["y - a*x**2", "m*(x_t**2 + y_t**2)/2 + m*g*y",
                                              "a*m*x*x_t + g*m*t/2 + lambda_y/2"])},
    "radial_line": {
        "chetaev": (2, "1, x**2, y**2, x*y, y/x, 1/x**2, y**2/x**2",
                    ["y/x", "m*(x_t**2 + y_t**2)/2 - m*k*(x**2 + y**2)/2"])},
    "rolling_ball": {
        "chetaev": (1, "1, " + _TH, list(_OMEGA.values())),
        "suslov": (1, "1, " + _TH, [_OMEGA["wz"]], [_OMEGA["wx"]]),
        "vakonomic": (1, "1, " + _TH, [f"m*r*({_OMEGA['wx']}) - lambda_y",
                                       f"m*r*({_OMEGA['wy']}) + lambda_x"])},
    "suslov_rigid_body": {
        "suslov": (1, "sin(theta)*sin(psi), cos(psi), sin(theta)*cos(psi), sin(psi)",
                   [INTEGRALS["suslov_rigid_body"]["O1"], INTEGRALS["suslov_rigid_body"]["O2"]])},
    "ball_on_turntable": {"chetaev": (1, "1, cos(theta)", [_OMEGA["wz"]])},
    "damped_knife_edge": {
        "chetaev": (1, "exp(c*t/m)/cos(phi), exp(c_r*t/I)",
                    ["exp(c*t/m)*x_t/cos(phi)", "exp(c_r*t/I)*phi_t"])},
    "damped_chaplygin_sleigh": {"chetaev": (2, "1, 1/cos(theta)**2", [])},
}


def _in_span_numeric(system, exprs, basis, points=12):
    """Whether each of ``exprs`` is a combination of ``basis`` (constants at one generic
    value of the parameters): ranks of their values at random points, 40 digits."""
    import random

    from jetnh.algebra import dag
    rng = random.Random(5)
    syms = set().union(*(e.free_symbols for e in exprs + basis)) if exprs + basis else set()
    fixed = {s: sp.Rational(rng.randint(20, 80), 41) for s in system.parameters}
    syms -= set(fixed)
    out = []
    n = len(basis) + points
    for e in exprs:
        cols = [[], []]
        while len(cols[0]) < n:
            p = {s: sp.Rational(rng.randint(1, 90), rng.randint(41, 47)) for s in syms}
            p.update(fixed)
            try:
                v = dag.evaluate(basis + [e], p, dps=40)
            except (ZeroDivisionError, ValueError):
                continue
            cols[0].append(v[:-1])
            cols[1].append(v)
        r0 = np.linalg.matrix_rank(np.array(cols[0], dtype=float), tol=1e-9) if basis else 0
        r1 = np.linalg.matrix_rank(np.array(cols[1], dtype=float), tol=1e-9)
        out.append(r0 == r1)
    return out


@pytest.mark.parametrize("name,principle", [(n, p) for n, d in CATALOGUE_INTEGRALS.items()
                                            for p in d])
def test_first_integrals_found(name, principle):
    s = models.get(name)
    degree, coeffs, expected, *absent = CATALOGUE_INTEGRALS[name][principle]
    syms = symbols_of(s)
    syms.update({f"lambda_{d.name}": sp.Symbol(f"lambda_{d.name}") for d in s.dependent})
    parse = lambda e: s.on_constraints(mf.parse_expression(e, syms, name))  # noqa: E731
    coefficients = [parse(c) for c in coeffs.split(", ")]
    basis = jn.conserved_quantities(s, principle, degree=degree, coefficients=coefficients)
    if not expected:
        assert basis == []
    assert all(_in_span_numeric(s, [parse(e) for e in expected], basis)), basis
    for e in (absent[0] if absent else []):
        assert not any(_in_span_numeric(s, [parse(e)], basis)), e
    for I in basis:                                  # the docstring lists them
        assert "integral" in (models.CATALOGUE[name].__doc__ or "").lower()
