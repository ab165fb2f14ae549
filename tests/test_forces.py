"""Non-potential generalized forces Q_s(t, q, qdot): ``System(..., forces=, dissipation=)``.

Every principle's accelerations with forces are checked against a route that shares no
code with ``jetnh.mechanics.equations`` or ``jetnh.mechanics.accelerations``: the rows assembled here by hand
(partial derivatives and a chain-rule total derivative) and solved numerically --
vakonomic: [L + lambda f]_s + Q_s = 0 with D f = 0; Chetaev: [L]_s + Q_s + nu df/dqdot^s = 0
with D f = 0; Suslov: (31) on L~ with the projected force Q_mu + Phi^alpha_mu Q_alpha --
and Chetaev's against sympy.physics.mechanics.LagrangesMethod with a force list.  Every
printed form vanishes on the accelerations of its principle.  The damped knife edge and
the damped Chaplygin sleigh of the catalogue are integrated against their closed forms.
"""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st
from sympy.physics.mechanics import LagrangesMethod, Point, ReferenceFrame

import jetnh as jn
import jetnh.strategies as jst
from jetnh import models
from jetnh.mechanics.system import System
from jetnh.mechanics.equations import FORMS, multiplier_symbols
from jetnh.errors import ConstraintError, JetnhError, JetSpaceError
from jetnh.numeric import codegen
from numbers30 import f30, num

TOL = 1e-18          # residuals that vanish identically, at 30 digits
RTOL = 1e-10         # two routes to the same numbers

randoms = st.randoms(use_true_random=False)


# ------------------------------------------------------------------ helpers


def manifold_state(system: System, rnd: random.Random, extra=()) -> dict:
    """t, q, independent velocities and ``extra`` at random; dependent velocities from phi.
    (Seeded from ``rnd``: hypothesis' own values favour 0 and 1, where random systems
    can be exactly singular.)"""
    J = system.J
    rnd = random.Random(rnd.getrandbits(64))
    vals = {s: f30(rnd.uniform(-1, 1))
            for s in (J.t,) + J.q + system.independent_velocities + tuple(extra)}
    for v, phi in system.phi.items():
        vals[v] = num(phi, vals)
    return vals


def assert_close(a, b, what):
    assert abs(a - b) <= RTOL * max(1, abs(a), abs(b)), f"{what}: {a} != {b}"


def total_derivative(e, J, rates=()):
    """d/dt of a first-order expression by the chain rule (``rates``: (symbol, rate) pairs
    of further variables such as multipliers)."""
    out = sp.diff(e, J.t)
    for q, v, a in zip(J.q, J.qd, J.qdd):
        out += sp.diff(e, q) * v + sp.diff(e, v) * a
    for s, r in rates:
        out += sp.diff(e, s) * r
    return out


def solve_linear(rows, unknowns, vals) -> dict:
    """The numeric solution of rows affine in ``unknowns``, at ``vals``."""
    M = sp.Matrix([[num(sp.diff(r, u), vals) for u in unknowns] for r in rows])
    b = sp.Matrix([num(r.xreplace({u: 0 for u in unknowns}), vals) for r in rows])
    sol = M.LUsolve(-b)
    return dict(zip(unknowns, sol))


@st.composite
def forced_systems(draw, affine=None, dissipation=False):
    system = draw(jst.systems(min_n=2, max_n=3, affine=affine, forced=True))
    if not dissipation:
        return system
    J = system.J
    c = draw(st.integers(1, 3))
    D = c * J.qd[0]**2 / 2 + draw(jst.polynomials(J, max_degree=2, max_terms=2))
    return system.replace(dissipation=D)


# ------------------------------------------------------------------ the equations, by hand
def vakonomic_by_hand(system, lams, vals):
    """q'' and lambda' of [L + lambda f]_s + Q_s = 0 and D f = 0."""
    J = system.J
    rates = [sp.Symbol(f"{m.name}_t") for m in lams]
    F = system.L + sp.Add(*[m * f for m, f in zip(lams, system.constraints)])
    rows = [sp.diff(F, q) - total_derivative(sp.diff(F, v), J, zip(lams, rates)) + Q
            for q, v, Q in zip(J.q, J.qd, system.Q)]
    rows += [total_derivative(f, J) for f in system.constraints]
    return solve_linear(rows, list(J.qdd) + rates, vals)


def chetaev_by_hand(system, vals):
    """q'' of [L]_s + Q_s + nu_a df^a/dqdot^s = 0 and D f = 0."""
    J = system.J
    nus = sp.symbols(f"nu0:{system.k}")
    rows = [sp.diff(system.L, q) - total_derivative(sp.diff(system.L, v), J) + Q
            + sp.Add(*[nu * sp.diff(f, v) for nu, f in zip(nus, system.constraints)])
            for q, v, Q in zip(J.q, J.qd, system.Q)]
    rows += [total_derivative(f, J) for f in system.constraints]
    return solve_linear(rows, list(J.qdd) + list(nus), vals)


def suslov_by_hand(system, vals):
    """The independent q'' of (31) with forces: [L~]_mu + Phi^alpha_mu dL~/dq^alpha
    + Q_mu + Phi^alpha_mu Q_alpha = 0, L~ and Q on the constraints."""
    J = system.J
    phi = system.phi
    Lt = system.L.xreplace(phi)
    Q = [e.xreplace(phi) for e in system.Q]
    rows = []
    for m, (qm, vm) in enumerate(zip(system.independent, system.independent_velocities)):
        Phi = [sp.diff(phi[va], vm) for va in system.dependent_velocities]
        row = sp.diff(Lt, qm) - total_derivative(sp.diff(Lt, vm), J) + Q[system.ind_index[m]]
        row += sp.Add(*[P * (sp.diff(Lt, qa) + Q[i])
                        for P, qa, i in zip(Phi, system.dependent, system.dep_index)])
        rows.append(row)
    unknowns = [J.jet(q, 2) for q in system.independent]
    return solve_linear(rows, unknowns, vals)


@settings(max_examples=6)
@given(forced_systems(dissipation=True), randoms)
def test_accelerations_with_forces_match_the_equations_built_by_hand(system, rnd):
    J = system.J
    chet = system.equations("chetaev").accelerations()
    vak_eom = system.equations("vakonomic")
    vak = vak_eom.accelerations()
    sus = system.equations("suslov").accelerations()
    vals = manifold_state(system, rnd, extra=vak_eom.multipliers)
    ref_c = chetaev_by_hand(system, vals)
    ref_v = vakonomic_by_hand(system, vak_eom.multipliers, vals)
    ref_s = suslov_by_hand(system, vals)
    for a in J.qdd:
        assert_close(num(chet[a], vals), ref_c[a], f"chetaev {a}")
        assert_close(num(vak[a], vals), ref_v[a], f"vakonomic {a}")
    for r in vak_eom.multiplier_rates:
        assert_close(num(vak[r], vals), ref_v[sp.Symbol(r.name)], f"vakonomic {r}")
    for q in system.independent:
        a = J.jet(q, 2)
        assert_close(num(sus[a], vals), ref_s[a], f"suslov {a}")


@settings(max_examples=6)
@given(forced_systems(), randoms)
def test_every_form_with_forces_vanishes_on_its_principles_accelerations(system, rnd):
    for principle, forms in FORMS.items():
        for form in forms:
            for convention in ("paper", "imposed"):
                eom = system.equations(principle, form, convention)
                acc = eom.accelerations()
                # every lambda and rate: imposed rows keep them with coefficients that vanish
                lams = multiplier_symbols(system)
                vals = manifold_state(system, rnd, extra=lams + tuple(
                    system.J.with_fields([m.name for m in lams]).jet(m, 1) for m in lams))
                solved = {a: num(e, vals) for a, e in acc.items()}
                vals.update(solved)
                rows = eom.expressions
                if eom.reactions:                 # Chetaev's multiplier form: nu from rows
                    vals.update(solve_linear([rows[i] for i in system.dep_index],
                                             eom.reactions, vals))
                # relative to the accelerations (huge near a singular reduced Hessian)
                scale = max([1] + [abs(v) for v in solved.values()])
                for i, e in enumerate(rows):
                    v = num(e, vals)
                    assert abs(v) <= TOL * scale, f"{principle} {form} {convention} row {i}: {v}"


@settings(max_examples=5)
@given(forced_systems(affine=True), randoms)
def test_suslov_with_forces_is_vakonomic_on_the_branch_32(system, rnd):
    from jetnh.mechanics.equivalence import compare

    assert compare(system, "vakonomic", "suslov").on_branch_32 in (True, None)
    eom = system.equations("vakonomic", "embedded")
    vak, sus = eom.accelerations(), system.equations("suslov").accelerations()
    vals = manifold_state(system, rnd)
    vals.update({lam: -num(p, vals) for lam, p in zip(eom.multipliers, system.p_dependent)})
    for a in system.J.qdd:
        assert_close(num(vak[a], vals), num(sus[a], vals), str(a))


# ------------------------------------------------------------------ LagrangesMethod
def lagranges_method_accelerations(system) -> dict:
    """q'' from LagrangesMethod: each Q_s acts on a point P_s at q_s N.x (velocity
    qdot_s N.x), so that its generalized force is Q_s on q_s alone."""
    J = system.J
    N = ReferenceFrame("N")
    O = Point("O")
    forcelist = []
    for s, q in enumerate(J.q):
        P = O.locatenew(f"P{s}", J.to_dynamic(q) * N.x)
        P.set_vel(N, J.to_dynamic(J.qd[s]) * N.x)
        forcelist.append((P, J.to_dynamic(system.Q[s]) * N.x))
    lm = LagrangesMethod(J.to_dynamic(system.L), [J.to_dynamic(q) for q in J.q],
                         forcelist=forcelist, frame=N,
                         nonhol_coneqs=[J.to_dynamic(f) for f in system.constraints])
    lm.form_lagranges_equations()
    rhs = lm.rhs()
    return {J.qdd[s]: J.from_dynamic(rhs[J.n + s]) for s in range(J.n)}


@settings(max_examples=6)
@given(forced_systems(affine=True, dissipation=True), randoms)
def test_chetaev_with_forces_matches_lagranges_method(system, rnd):
    ref = lagranges_method_accelerations(system)
    acc = system.equations("chetaev").accelerations()
    for _ in range(2):
        vals = manifold_state(system, rnd)
        for a in system.J.qdd:
            assert_close(num(acc[a], vals), num(ref[a], vals), f"{a} vs LagrangesMethod")


def test_forces_change_the_accelerations_by_the_inverse_reduced_mass():
    """A viscous force on a free particle: x'' = -c x'/m, and nothing without it."""
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    m, c = sp.symbols("m c", positive=True)
    free = System(J, m * xd**2 / 2)
    damped = System(J, m * xd**2 / 2, forces={"x": -c * xd})
    assert free.equations("chetaev").accelerations()[J.qdd[0]] == 0
    assert sp.simplify(damped.equations("vakonomic").accelerations()[J.qdd[0]] + c * xd / m) == 0
    assert damped.equations("suslov").expressions == (-c * xd - m * J.qdd[0],)


# ------------------------------------------------------------------ closed forms
def _run(name, t_end, params=None, principle="chetaev", **run):
    info = models.info(name)
    system = info.system()
    init = info.initial()
    if principle != "chetaev":
        init.update({f"lambda_{d.name}": 0.0 for d in system.dependent})
    scene = jn.Scene(system, principle, params={**{k.name: v for k, v in
                                                   system.defaults.items()}, **(params or {})},
                     initial=init, t_span=(0.0, t_end), runtime_params=("c", "c_r"))
    run = run or dict(rtol=1e-12, atol=1e-14, t_eval=np.linspace(0.0, t_end, 41))
    traj = scene.run(**run)
    assert traj.success, traj.stop_reason
    return scene, traj


def _err(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def test_damped_knife_edge_closed_form():
    scene, traj = _run("damped_knife_edge", 2.0)
    p, i = scene.params, scene.initial
    m, I, c, cr = p["m"], p["I"], p["c"], p["c_r"]
    g = c / m
    assert g == cr / I
    t, w0, v0, phi0 = traj.t, i["phi_t"], i["x_t"], i["phi"]
    tau = (1 - np.exp(-g * t)) / g
    phi = phi0 + w0 * tau
    v = traj["x_t"] * np.cos(traj["phi"]) + traj["y_t"] * np.sin(traj["phi"])
    assert _err(v, v0 * np.exp(-g * t)) < 1e-9
    assert _err(traj["phi_t"], w0 * np.exp(-g * t)) < 1e-9
    assert _err(traj["phi"], phi) < 1e-9
    assert _err(traj["x"], i["x"] + v0 / w0 * (np.sin(phi) - math.sin(phi0))) < 1e-9
    assert _err(traj["y"], i["y"] - v0 / w0 * (np.cos(phi) - math.cos(phi0))) < 1e-9
    # the energy decays at the rate 2D: the power of the forces, reported as such
    E = m * v**2 / 2 + I * traj["phi_t"]**2 / 2
    assert _err(traj.energy, (m * v0**2 + I * w0**2) / 2 * np.exp(-2 * g * t)) < 1e-9
    assert _err(traj.energy, E) < 1e-12
    assert _err(traj.power, -(c * v**2 + cr * traj["phi_t"]**2)) < 1e-12
    d = traj.diagnostics
    assert d.forced and d.energy_drift_relative > 0.5 and "not conserved" in str(d)


def test_damped_knife_edge_decays_independently():
    """c/m != c_r/I: the speed and the heading rate each decay at their own rate."""
    scene, traj = _run("damped_knife_edge", 2.0, params={"c": 0.3, "c_r": 0.5})
    p, i = scene.params, scene.initial
    a, b = p["c"] / p["m"], p["c_r"] / p["I"]
    t, w0 = traj.t, i["phi_t"]
    v = traj["x_t"] * np.cos(traj["phi"]) + traj["y_t"] * np.sin(traj["phi"])
    assert _err(v, i["x_t"] * np.exp(-a * t)) < 1e-9
    assert _err(traj["phi_t"], w0 * np.exp(-b * t)) < 1e-9
    assert _err(traj["phi"], i["phi"] + w0 / b * (1 - np.exp(-b * t))) < 1e-9


def test_damped_chaplygin_sleigh_closed_form():
    scene, traj = _run("damped_chaplygin_sleigh", 3.0)
    p, i = scene.params, scene.initial
    m, I, a, c, cr = p["m"], p["I"], p["a"], p["c"], p["c_r"]
    g, K = c / m, I + m * a**2
    assert g == cr / I
    t, th = traj.t, traj["theta"]
    v = traj["x_t"] * np.cos(th) + traj["y_t"] * np.sin(th)
    v0, w0 = i["x_t"], i["theta_t"]
    V = math.sqrt((m * v0**2 + K * w0**2) / m)
    s0 = math.atanh(v0 / V)
    s = m * a * V * (1 - np.exp(-g * t)) / g / K + s0
    gd = lambda u: 2 * np.arctan(np.tanh(u / 2))  # noqa: E731
    assert _err(v, np.exp(-g * t) * V * np.tanh(s)) < 1e-9
    assert _err(traj["theta_t"], np.exp(-g * t) * w0 * math.cosh(s0) / np.cosh(s)) < 1e-9
    assert _err(th, i["theta"] + w0 * math.cosh(s0) * K / (m * a * V) * (gd(s) - gd(s0))) < 1e-9
    decay = np.exp(2 * g * t) * (m * v**2 + K * traj["theta_t"]**2) / 2
    assert _err(decay, decay[0]) < 1e-9


def test_discrete_integrators_carry_the_forces():
    """The midpoint steps with the discrete forces h/2 Q at both ends: second order."""
    scene, traj = _run("damped_knife_edge", 1.0, method="dla", h=1e-3)
    i, g = scene.initial, scene.params["c"] / scene.params["m"]
    phi = i["phi"] + i["phi_t"] * (1 - np.exp(-g * traj.t)) / g
    assert _err(traj["phi"], phi) < 1e-6
    assert _err(traj["x"], i["x_t"] / i["phi_t"] * np.sin(phi)) < 1e-6
    with pytest.raises(JetnhError, match="no power column"):
        traj.power                                          # noqa: B018
    # the discrete vakonomic step follows the forced vakonomic flow
    _, ref = _run("damped_knife_edge", 1.0, principle="vakonomic")
    _, dvi = _run("damped_knife_edge", 1.0, principle="vakonomic", method="dvi", h=1e-3)
    for name in ("x", "y", "phi", "lambda_y"):
        assert abs(dvi[name][-1] - ref[name][-1]) < 1e-6, name
    assert abs(ref["phi"][-1] - phi[-1]) > 1e-3             # not Chetaev's motion


# ------------------------------------------------------------------ bookkeeping
J3 = jn.JetSpace("x y phi")
x, y, phi = J3.q
xd, yd, phid = J3.qd
c = sp.Symbol("c")
L3 = (xd**2 + yd**2 + phid**2) / 2
KNIFE = [sp.sin(phi) * xd - sp.cos(phi) * yd]


def knife(**kw):
    return System(J3, L3, KNIFE, [y], **kw)


def test_forces_are_kept_by_every_derived_system_and_shown():
    s = knife(forces={"x": -c * xd, y: -c * yd}, dissipation=c * phid**2)
    assert s.forces == {x: -c * xd, y: -c * yd}
    assert s.Q == (-c * xd, -c * yd, -2 * c * phid)
    assert s.parameters == (c,) and s.forced
    assert "forces={x: -c*x_t, y: -c*y_t}" in repr(s) and "dissipation=c*phi_t**2" in repr(s)
    s2 = s.with_split("x")
    assert (s2.forces, s2.dissipation, s2.dependent) == (s.forces, s.dissipation, (x,))
    assert s.is_regular() and s.classify() == knife().classify()
    plain = knife()
    assert not plain.forced and plain.Q == (0, 0, 0) and "forces" not in repr(plain)
    # zero forces are no forces
    assert not knife(forces={x: 0}).forced and knife(forces={x: 0}).forces == {}
    # dynamicsymbols keys and values
    xt = sp.Function("x")(J3.t)
    s3 = knife(forces={xt: -c * xt.diff(J3.t)})
    assert s3.forces == {x: -c * xd}


def test_the_kernel_key_and_the_compiled_rhs_carry_the_forces():
    params = {"c": 0.5}
    keys = {codegen.KernelSpec(s, "chetaev", params).key for s in (
        knife(), knife(forces={x: -c * xd}), knife(forces={y: -c * yd}),
        knife(dissipation=c * xd**2 / 2), knife(forces={x: -c * xd}, dissipation=c * xd**2))}
    assert len(keys) == 5
    init = {x: 0.0, y: 0.0, phi: 0.3, xd: 1.0, phid: 0.2}
    runs = [jn.Scene(s, "chetaev", params=params if s.parameters else {}, initial=init,
                     t_span=(0, 1)).run(rtol=1e-12, atol=1e-14)
            for s in (knife(), knife(dissipation=c * (xd**2 + yd**2) / 2))]
    v = [r["x_t"][-1] / math.cos(r["phi"][-1]) for r in runs]
    assert abs(v[0] - 1 / math.cos(0.3)) < 1e-10
    assert abs(v[1] - math.exp(-0.5) / math.cos(0.3)) < 1e-10
    assert not np.any(runs[0].power) and not runs[0].diagnostics.forced


@pytest.mark.parametrize("forces, err, match", [
    ([(x, -xd)], ConstraintError, "must be a dict"),
    ({"x_t": 1}, ConstraintError, "x_t is a jet of x"),
    ({"z": 1}, ConstraintError, r"not a coordinate.*\(Symbol or name: x, y, phi\)"),
    ({1: 1}, ConstraintError, "not a coordinate"),
    ({c: 1}, ConstraintError, "not a coordinate"),
    ({x: J3.qdd[0]}, ConstraintError, "the force on x contains accelerations"),
    ({x: "-c*x_t"}, JetSpaceError, "never parses strings"),
    ({x: sp.Eq(xd, 1)}, ConstraintError, "the force on x is the relation"),
    ({x: sp.Piecewise((1, xd > 0), (0, True))}, ConstraintError, "not differentiable"),
    ({x: sp.I * xd}, ConstraintError, "imaginary"),
    ({x: None}, ConstraintError, "None"),
    ({x: -xd, "x": 1}, ConstraintError, "two forces given for the coordinate 'x'"),
    ({x: sp.Symbol("lambda_y")}, JetSpaceError, "multiplier"),
])
def test_bad_forces_are_refused_with_the_reason(forces, err, match):
    with pytest.raises(err, match=match):
        knife(forces=forces)


def test_bad_dissipation_is_refused_and_kinks_are_smoothed():
    with pytest.raises(ConstraintError, match="contains no velocity"):
        knife(dissipation=c * x**2)
    with pytest.raises(JetSpaceError, match="never parses strings"):
        knife(dissipation="c*x_t**2")
    with pytest.raises(ConstraintError, match="accelerations"):
        knife(dissipation=J3.qdd[0] ** 2)
    s = knife(forces={x: -c * sp.sign(xd)})               # Coulomb-like: kept smoothly
    assert s.forces[x] == -c * xd / sp.sqrt(xd**2)


def test_derive_prints_the_forces(capsys):
    from jetnh.cli import main

    assert main(["derive", "damped_knife_edge"]) == 0
    out = capsys.readouterr().out
    assert "dissipation D = " in out and "force Q_phi = -c_r*phi_t" in out
    assert "phi_tt = -c_r*phi_t/I" in out
