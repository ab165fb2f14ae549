"""Holonomic constraints g(t, q) = 0 kept at position level (``jetnh.mechanics.holonomic``,
``System.holonomic``, the projection of ``jetnh.numeric.methods.projection``).

Two routes to every result: the system with g kept against the same system with a
coordinate eliminated by hand (the pendulum in Cartesian coordinates against the
pendulum in its angle; a knife edge carrying a slider z = a sin(theta) against the knife
edge with z substituted), under every principle.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.errors import ConstraintError
from jetnh.mechanics import holonomic
from jetnh.numeric import Scene
from jetnh.numeric.codegen import multiplier_names
from model_texts import PENDULUM_XY

from holonomic_systems import (I_, KNIFE, a_, k_, knife_reduced, knife_slider, l_, pendulum_angle,
                               pendulum_xy)

PRINCIPLES = ("chetaev", "vakonomic", "holder", "suslov")
PARAMS = {"l": 1.0, "G": 9.81}


# ---------------------------------------------------------------------- the System
def test_system_keeps_the_constraint_without_velocities():
    s = pendulum_xy()
    J = s.J
    x, y = J.q
    g = x**2 + y**2 - l_**2
    assert s.holonomic == (g,) and s.holonomic_rows == (0,)
    assert sp.expand(s.constraints[0] - J.D(g)) == 0
    assert s.given_constraints == (g,)
    assert {p.name for p in s.parameters} == {"G", "l"}   # l only in g
    assert s.with_split(["x"]).holonomic == (g,)
    assert s.is_integrable()
    mixed = knife_slider()
    assert mixed.holonomic_rows == (1,) and mixed.k == 2
    assert mixed.given_constraints[0] == mixed.constraints[0]


def test_kernels_of_g_and_of_its_derivative_are_kept_apart():
    kept = knife_slider()
    J = kept.J
    velocity_form = jn.System(J, kept.L, [kept.constraints[0], J.D(kept.holonomic[0])],
                              dependent=["y", "z"])
    assert velocity_form.constraints == kept.constraints and not velocity_form.holonomic
    ini = {"x": 0.0, "y": 0.0, "th": 0.3, "z": 0.4 * np.sin(0.3), "x_t": 1.0, "th_t": 0.7}
    a = Scene(kept, params=KNIFE, initial=ini)
    b = Scene(velocity_form, params=KNIFE, initial=ini)
    assert a.key != b.key
    assert b.kernels.layout.holonomic == 0 and a.kernels.layout.holonomic == 1
    assert b.run(t_span=(0.0, 1.0)).diagnostics.holonomic_residual_max == 0.0


def test_time_only_constraint_is_refused():
    J = jn.JetSpace("x y")
    with pytest.raises(ConstraintError, match="time only"):
        jn.System(J, J.qd[0] ** 2, [J.t - 1])


@settings(deadline=None)
@given(st.data())
def test_holonomic_equations_are_those_of_the_differentiated_constraint(data):
    """Property: keeping g holonomic changes no equation: every principle's accelerations
    equal those of the system given D g (the former contract)."""
    J = data.draw(jst.jet_spaces(min_n=2, max_n=3))
    L = sum(v**2 for v in J.qd) / 2 + data.draw(jst.polynomials(J, order=0, max_degree=2))
    g = J.q[-1] - data.draw(jst.polynomials(
        jn.JetSpace([q.name for q in J.q[:-1]]), order=0, max_degree=2)).xreplace(
        {sp.Symbol(q.name): q for q in J.q[:-1]})
    kept, given_ = jn.System(J, L, [g]), jn.System(J, L, [J.D(g)])
    assert kept.holonomic == (g,) and not given_.holonomic
    for principle in ("chetaev", "vakonomic"):
        a1 = kept.equations(principle).accelerations()
        a2 = given_.equations(principle).accelerations()
        assert set(a1) == set(a2)
        for key in a1:
            assert sp.expand(a1[key] - a2[key]) == 0


def test_every_principle_gives_the_same_motion_with_a_holonomic_constraint():
    """Derived: with f = D g, [lambda D g]_s = -lambda_t dg/dq^s, so lambda itself never
    enters and the coordinates' accelerations are Chetaev's under every principle (only
    the multiplier's normalisation differs)."""
    s = pendulum_xy()
    ref = s.equations("chetaev").accelerations()
    for principle in PRINCIPLES[1:]:
        eom = s.equations(principle)
        acc = eom.accelerations()
        lam = set(eom.multipliers)
        for q in s.J.qdd:
            assert not (acc[q].free_symbols & lam)
            assert sp.expand(sp.together(acc[q] - ref[q])) == 0


# ---------------------------------------------------------------------- initial configurations
def test_initial_configuration_off_g_is_refused_with_the_residual_and_the_fix():
    with pytest.raises(ConstraintError, match=r"g1 = .* is 0\.36.*complete=True to solve for y"):
        Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -1.0, "x_t": 0.0})


def test_completion_in_the_dependent_or_the_named_coordinates():
    sc = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -1.0, "x_t": 0.0},
               complete=True)
    assert sc.initial["y"] == pytest.approx(-0.8, abs=1e-15) and sc.initial["x"] == 0.6
    assert sc.completed == {"y": (-1.0, sc.initial["y"])}
    sc2 = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.5, "y": -0.8, "x_t": 0.0},
                complete=["x"])
    assert sc2.initial["x"] == pytest.approx(0.6, abs=1e-15) and sc2.initial["y"] == -0.8
    # the dependent velocity follows the completed configuration: x x_t + y y_t = 0
    sc3 = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -1.0, "x_t": 1.0},
                complete=True)
    assert sc3.initial["y_t"] == pytest.approx(0.6 / 0.8, rel=1e-14)
    tr = sc.run(t_span=(0.0, 0.1))
    assert tr.diagnostics.completed == sc.completed
    # replace keeps the completed values; a new start off g = 0 is refused again
    assert sc.replace(t_span=(0.0, 2.0)).initial["y"] == sc.initial["y"]
    with pytest.raises(ConstraintError, match="off the holonomic"):
        sc.replace(initial={"x": 0.1, "y": -0.1, "x_t": 0.0})


def test_configurations_that_cannot_be_completed():
    s = pendulum_xy()
    with pytest.raises(ConstraintError, match="cannot be completed.*complete=\\[...\\]"):
        Scene(s, params=PARAMS, initial={"x": 1.6, "y": -1.0, "x_t": 0.0}, complete=True)
    with pytest.raises(ConstraintError, match="rank-deficient.*rank 0 < 1"):
        Scene(s, params=PARAMS, initial={"x": 0.0, "y": 0.0, "x_t": 0.0}, complete=True)
    with pytest.raises(ConstraintError, match="cannot be solved for \\['x'\\]"):
        Scene(s, params=PARAMS, initial={"x": 0.0, "y": -0.9, "x_t": 0.0}, complete=["x"])
    with pytest.raises(ConstraintError, match="not a coordinate"):
        Scene(s, params=PARAMS, initial={"x": 0.6, "y": -0.9, "x_t": 0.0}, complete=["w"])


def test_rank_deficient_jacobian_on_g_is_refused():
    J = jn.JetSpace("x y w")
    x, y, w = J.q
    L = sum(v**2 for v in J.qd) / 2
    # the parabola y = x^2 touches the line y = 0 at the origin: dependent gradients there
    s = jn.System(J, L, [y - x**2, y])
    with pytest.raises(ConstraintError, match="rank-deficient.*rank 1 < 2"):
        Scene(s, initial={"x": 0.0, "y": 0.0, "w": 0.0, "w_t": 0.0})
    circle = jn.System(J, L, [x**2 + y**2 - 1])
    with pytest.raises(ConstraintError, match="rank-deficient.*rank 0 < 1"):
        Scene(circle, initial={"x": 0.0, "y": 0.0, "w": 0.0, "w_t": 0.0, "x_t": 0.0},
              complete=True)
    Scene(circle, initial={"x": 0.6, "y": 0.8, "w": 0.0, "w_t": 0.0, "x_t": 0.0})  # regular


def test_run_and_ensemble_starts_off_g_are_refused():
    sc = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -0.8, "x_t": 0.0})
    with pytest.raises(ConstraintError, match="y0: .*off the holonomic"):
        sc.run(y0={"x": 0.3})
    with pytest.raises(ConstraintError, match="run 1: .*off the holonomic"):
        sc.ensemble(initial={"x": np.array([0.6, 0.3]), "y": np.array([-0.8, -0.8])},
                    save="final")


# ---------------------------------------------------------------------- runs stay on g = 0
def _g(tr):
    return tr["x"] ** 2 + tr["y"] ** 2 - 1.0


@pytest.mark.parametrize("method, kw", [("dop853", dict(rtol=1e-9, atol=1e-11)),
                                        ("dopri5", dict(rtol=1e-9, atol=1e-11)),
                                        ("rk4", dict(n_steps=20000)),
                                        ("radau", dict(rtol=1e-8, atol=1e-10))])
def test_long_runs_stay_on_g_at_roundoff(method, kw):
    sc = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -0.8, "x_t": 2.0},
               t_span=(0.0, 200.0))
    tr = sc.run(method=method, **kw)
    assert tr.status == 0
    assert np.max(np.abs(_g(tr))) < 1e-14
    assert tr.diagnostics.holonomic_residual_max < 1e-14
    assert np.allclose(tr.holonomic_residual[:, 0], _g(tr), atol=1e-15)
    again = sc.run(method=method, **kw)
    assert np.array_equal(tr.y, again.y) and np.array_equal(tr.t, again.t)   # bit for bit


def test_ensembles_and_dense_output_of_projected_runs():
    sc = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -0.8, "x_t": 2.0},
               t_span=(0.0, 50.0))
    ens = sc.ensemble(initial={"x_t": np.array([0.5, 2.0])}, save="final")
    single = sc.run(save="final")
    assert np.array_equal(ens.y[1, -1], single.y[-1])          # the same projected loop
    assert np.all(ens.holonomic_residual_max < 1e-14)
    assert "holonomic_residual_max" in ens.diagnostics()
    tr = sc.run()
    te = np.linspace(0.0, 50.0, 17)
    assert np.array_equal(tr.at(te), sc.run(t_eval=te).y)      # re-taken steps project too


def test_projection_keeps_the_order_of_rk4():
    """The error at T against the angle form solved tightly shrinks by ~2^4 per halving
    of h: the projection does not lower the order (HLW IV.4)."""
    T = 3.0
    th0 = np.arcsin(0.6)
    ref = Scene(pendulum_angle(), params=PARAMS, initial={"th": th0, "th_t": 2.0 / 0.8},
                t_span=(0.0, T)).run(rtol=1e-13, atol=1e-14, save="final")
    x_ref = np.sin(ref["th"][-1])
    sc = Scene(pendulum_xy(), params=PARAMS, initial={"x": 0.6, "y": -0.8, "x_t": 2.0},
               t_span=(0.0, T))
    errs = [abs(sc.run(method="rk4", n_steps=n, save="final")["x"][-1] - x_ref)
            for n in (200, 400, 800)]
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(rates > 3.7) and np.all(rates < 4.3), rates


@pytest.mark.parametrize("principle", ("chetaev", "suslov"))
def test_cartesian_pendulum_against_the_angle_form(principle):
    th0, w0 = np.arcsin(0.6), 1.5
    lam = {n: 0.3 for n in multiplier_names(pendulum_xy(), principle)}
    sc = Scene(pendulum_xy(), principle, params=PARAMS,
               initial={"x": 0.6, "y": -0.8, "x_t": 0.8 * w0, **lam}, t_span=(0.0, 10.0))
    ref = Scene(pendulum_angle(), principle, params=PARAMS,
                initial={"th": th0, "th_t": w0}, t_span=(0.0, 10.0))
    te = np.linspace(0.0, 10.0, 41)
    a = sc.run(rtol=1e-11, atol=1e-13, t_eval=te)
    b = ref.run(rtol=1e-11, atol=1e-13, t_eval=te)
    assert np.max(np.abs(a["x"] - np.sin(b["th"]))) < 1e-8
    assert np.max(np.abs(a["y"] + np.cos(b["th"]))) < 1e-8


def _on_manifold(system, values):
    """``values`` (name -> number: coordinates, independent velocities, multipliers,
    parameters) completed by the dependent velocities phi, keyed by Symbol."""
    from jetnh.algebra import dag

    syms = {s.name: s for s in (*system.J.q, *system.J.qd, *system.parameters)}
    point = {syms.get(k, sp.Symbol(k)): v for k, v in values.items()}
    point[system.J.t] = 0.0
    for v in system.dependent_velocities:
        point[v] = float(dag.evaluate([system.phi[v]], point)[0])
    return point


@pytest.mark.parametrize("principle", PRINCIPLES)
def test_knife_edge_with_slider_accelerations_against_the_slider_eliminated(principle):
    """Mixed constraints, every principle: at random states on the constraints, the
    accelerations and the nonholonomic multiplier's rate of the full system equal those
    of the system with z = a sin(th) substituted by hand (the holonomic multiplier's own
    value is arbitrary: it enters through its rate only)."""
    from jetnh.algebra import dag

    full, red = knife_slider(), knife_reduced()
    fe, re_ = full.equations(principle), red.equations(principle)
    fa, ra = fe.accelerations(), re_.accelerations()
    rng = np.random.default_rng(7)
    for _ in range(3):
        x, y, th, xt, tht, lam, other = rng.uniform(-1.0, 1.0, 7)
        base = {"x": x, "y": y, "th": th, "x_t": xt, "th_t": tht, **KNIFE}
        lams = {m.name: lam for m in re_.multipliers}
        pr = _on_manifold(red, {**base, **lams})
        pf = _on_manifold(full, {**base, "z": KNIFE["a"] * np.sin(th), **lams,
                                 **{m.name: other for m in fe.multipliers
                                    if m.name not in lams}})
        for key in (*red.J.qdd, *re_.multiplier_rates):
            fkey = next(k for k in fa if k.name == key.name)
            a = float(dag.evaluate([fa[fkey]], pf)[0])
            b = float(dag.evaluate([ra[key]], pr)[0])
            assert abs(a - b) <= 1e-12 * max(1.0, abs(b)), (key, a, b)


@pytest.mark.parametrize("principle", ("chetaev", "vakonomic"))
def test_knife_edge_with_slider_against_the_slider_eliminated(principle):
    """Mixed constraints: the holonomic one's multiplier drops out (it enters through its
    rate only), the nonholonomic one's multiplier and motion are those of the reduced
    system, under every principle."""
    ini = {"x": 0.0, "y": 0.0, "th": 0.3, "x_t": 1.0, "th_t": 0.7}
    mult = {n: 0.2 for n in multiplier_names(knife_reduced(), principle)}
    extra = {n: -0.5 for n in multiplier_names(knife_slider(), principle) if n not in mult}
    full = Scene(knife_slider(), principle, params=KNIFE,
                 initial={**ini, "z": 0.4 * np.sin(0.3), **mult, **extra}, t_span=(0.0, 6.0))
    red = Scene(knife_reduced(), principle, params=KNIFE, initial={**ini, **mult},
                t_span=(0.0, 6.0))
    te = np.linspace(0.0, 6.0, 31)
    a = full.run(rtol=1e-11, atol=1e-13, t_eval=te)
    b = red.run(rtol=1e-11, atol=1e-13, t_eval=te)
    for name in ("x", "y", "th", "x_t", "th_t", "y_t", *mult):
        assert np.max(np.abs(a[name] - b[name])) < 1e-8, name
    # between steps (t_eval: the dense output) g is the interpolant's error; at the
    # steps, roundoff, the row where the run changes chart (the heading passes the
    # split's edge, located on the dense output, then projected) included
    assert np.max(np.abs(a["z"] - 0.4 * np.sin(a["th"]))) < 1e-9
    steps = full.run(rtol=1e-11, atol=1e-13)
    assert steps.switches
    g = np.abs(steps["z"] - 0.4 * np.sin(steps["th"]))
    assert np.max(g) < 1e-15


# ---------------------------------------------------------------------- linearization helpers
def test_tangent_basis_and_independent_coordinates():
    s = knife_slider()
    J = s.J
    point = {J.t: 0.0, **dict(zip(J.q, (0.1, 0.2, 0.3, 0.4 * np.sin(0.3)))), a_: 0.4,
             k_: 3.0, I_: 0.7}
    B = holonomic.tangent_basis(s, point)
    G = holonomic.jacobian_at(s, point)
    assert B.shape == (4, 3)
    assert np.allclose(B.T @ B, np.eye(3), atol=1e-14)
    assert np.max(np.abs(G @ B)) < 1e-15
    assert [q.name for q in holonomic.independent_coordinates(s, point)] == ["x", "y", "th"]
    # a perturbation along the basis stays on g = 0 to second order
    eps = 1e-6
    for j in range(3):
        moved = dict(point)
        moved.update({q: point[q] + eps * B[i, j] for i, q in enumerate(J.q)})
        assert abs(holonomic.residual(s, moved)[0]) < 10 * eps**2
    assert np.array_equal(holonomic.tangent_basis(pendulum_angle(), {}), np.eye(1))
    by_name = {"t": 0.0, "x": 0.1, "y": 0.2, "th": 0.3, "z": 0.4 * np.sin(0.3), **KNIFE}
    assert np.array_equal(holonomic.tangent_basis(s, by_name), B)


# ---------------------------------------------------------------------- interfaces
PENDULUM_TOML = PENDULUM_XY + """[initial]
x = 0.6
y = -0.8
"""


def test_model_file_constraint_without_velocities_is_holonomic():
    from jetnh import modelfile

    m = modelfile.loads(PENDULUM_TOML)
    x, y = m.system.J.q
    assert m.system.holonomic == (x**2 + y**2 - sp.Symbol("l") ** 2,)
    back = modelfile.loads(modelfile.dumps(m.system, m.initial))
    assert back.system.holonomic == m.system.holonomic


def test_rolling_disk_from_lagranges_method_refuses_or_completes_z():
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame,
                                         RigidBody, dynamicsymbols, inertia)

    x, y, z, yaw, lean, spin = dynamicsymbols("x y z yaw lean spin")
    m, r, g = sp.symbols("m r g", positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [yaw, N.z])
    B = A.orientnew("B", "Axis", [lean, A.x])
    C = B.orientnew("C", "Axis", [spin, B.y])
    O = Point("O")
    O.set_vel(N, 0)
    D = O.locatenew("D", x * N.x + y * N.y + z * N.z)
    D.set_vel(N, D.pos_from(O).dt(N))
    disk = RigidBody("disk", D, C, m, (inertia(B, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4), D))
    disk.potential_energy = m * g * z
    contact = D.vel(N) + C.ang_vel_in(N).cross(-r * B.z)
    lm = LagrangesMethod(Lagrangian(N, disk), [x, y, z, yaw, lean, spin],
                         hol_coneqs=[z - r * sp.cos(lean)],
                         nonhol_coneqs=[contact.dot(A.x), contact.dot(A.y)], frame=N)
    s = jn.from_mechanics(lm, dependent=["x", "y", "z"])
    Z, LEAN = s.J.q[2], s.J.q[4]
    assert s.holonomic == (Z - r * sp.cos(LEAN),)
    params = {"m": 1.0, "r": 0.5, "g": 9.81}
    ini = {"x": 0.0, "y": 0.0, "z": 0.5 * np.cos(0.2) + 1.0, "yaw": 0.0, "lean": 0.2,
           "spin": 0.0, "yaw_t": 0.5, "lean_t": 0.0, "spin_t": 4.0}
    with pytest.raises(ConstraintError, match=r"g1 = .*z is 1 \(should be 0\).*solve for z"):
        Scene(s, params=params, initial=ini)
    sc = Scene(s, params=params, initial=ini, complete=True, t_span=(0.0, 20.0))
    assert sc.completed == {"z": (ini["z"], pytest.approx(0.5 * np.cos(0.2), abs=1e-15))}
    tr = sc.run(rtol=1e-9, atol=1e-11)
    assert tr.status == 0
    assert np.max(np.abs(tr["z"] - 0.5 * np.cos(tr["lean"]))) < 1e-14
    assert tr.diagnostics.holonomic_residual_max < 1e-14


def test_cli_simulate_refuses_or_completes_the_configuration(tmp_path, capsys):
    from jetnh.cli import main

    path = tmp_path / "pendulum.toml"
    path.write_text(PENDULUM_TOML.replace("y = -0.8", "y = -1.0"))
    assert main(["simulate", str(path), "--t-end", "1"]) == 1
    err = capsys.readouterr().err
    assert "off the holonomic constraints" in err and "pass --complete to solve for y" in err
    assert main(["simulate", str(path), "--t-end", "1", "--complete"]) == 0
