"""Symbolic and numeric results are values: immutable, and systems equal by content."""

import pickle

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.errors import FrozenError


@pytest.fixture(scope="module")
def disk():
    return models.get("rolling_disk")


def test_identical_systems_are_equal_and_hash_alike(disk):
    again = models.get("rolling_disk")
    assert disk is not again and disk == again and hash(disk) == hash(again)
    assert len({disk, again}) == 1
    assert pickle.loads(pickle.dumps(disk)) == disk
    assert disk.with_split(disk.dependent) == disk
    assert disk.with_split(["phi", "y"]) != disk
    assert disk.replace(name="another") != disk
    J = jn.JetSpace(["x", "y"])
    x, y = J.q
    xd, yd = J.qd
    one = jn.System(J, (xd**2 + yd**2) / 2, [yd - x * xd], forces={"x": -x})
    two = jn.System(jn.JetSpace(["x", "y"]), (xd**2 + yd**2) / 2, [yd - x * xd],
                    forces={x: -x})
    assert one == two and hash(one) == hash(two)
    assert one != jn.System(J, (xd**2 + yd**2) / 2, [yd - x * xd], forces={"x": -2 * x})


def test_a_system_cannot_be_changed(disk):
    Q = disk.Q
    for name, value in (("L", sp.S.Zero), ("dependent", ()), ("name", "x"), ("forces", {})):
        with pytest.raises(FrozenError, match="System is immutable"):
            setattr(disk, name, value)
    with pytest.raises(FrozenError):
        del disk.L
    q = disk.J.q[0]
    with pytest.raises(FrozenError, match="read-only"):
        disk.forces[q] = sp.Symbol("F")
    with pytest.raises(FrozenError):
        disk.defaults.clear()
    assert disk.Q == Q and disk == models.get("rolling_disk")


def test_replace_makes_a_new_checked_system(disk):
    other = disk.replace(forces={"x": -sp.Symbol("c") * disk.J.qd[0]})
    assert other.forced and not disk.forced and other.L == disk.L
    with pytest.raises(jn.ConstraintError, match="no input mass"):
        disk.replace(mass=1)


def test_equations_are_derived_once_per_principle_form_and_convention(disk):
    eom = disk.equations("chetaev")
    assert disk.equations("lagrange-d'alembert") is eom
    assert models.get("rolling_disk").equations("chetaev") is not eom   # per system
    assert disk.equations("chetaev", form="multiplier") is not eom
    assert disk.equations("vakonomic", convention="imposed") is not disk.equations("vakonomic")
    with pytest.raises(FrozenError):
        eom.form = "voronets"
    with pytest.raises(jn.PrincipleError):
        disk.equations("hamilton")


def test_events_are_values_and_renaming_copies():
    from jetnh.numeric.events import Event, as_events

    x = sp.Symbol("x")
    a, b = Event(x), Event(x, terminal=True)
    with pytest.raises(FrozenError):
        a.terminal = True
    out = as_events([a, b])
    assert [e.name for e in out] == ["x", "x#1"] and b.name == "x"
    assert out[1].max_events == 1 and out[1].fun == x


def test_diagnostics_and_ensembles_are_immutable():
    scene = jn.Scene(models.get("knife_edge"), "chetaev", initial={"x": 0.0, "y": 0.0, "phi": 0.0, "phi_t": 1.0, "x_t": 1.0},
                     t_span=(0.0, 0.5))
    traj = scene.run(method="rk4", n_steps=10)
    with pytest.raises(AttributeError):
        traj.diagnostics.steps = 0
    Y0 = np.tile(scene.y0, (2, 1))
    ens = jn.numeric.run_ensemble(scene, Y0, method="rk4", n_steps=10)
    with pytest.raises(FrozenError):
        ens.method = "dop853"
    with pytest.raises(ValueError):
        ens.y[0, 0, 0] = 1.0
    with pytest.raises(ValueError):
        ens.status[0] = 0
    Y0[0, 0] = 2.0                        # the caller's array stays writable
    assert Y0.flags.writeable and not ens.initial.flags.writeable


def test_jetnh_sweep_is_the_module_and_calls_the_function():
    import jetnh.sweep
    import jetnh.sweep as module

    assert module is jetnh.sweep is jn.sweep
    assert module.__name__ == "jetnh.sweep" and callable(module)
    assert jn.sweep.plot_map is module.plot_map


def test_compiled_kernels_have_no_dead_integrator():
    from jetnh.numeric.kernels import CompiledKernels

    from jetnh.numeric import methods

    assert not hasattr(CompiledKernels, "integrator")
    assert not hasattr(CompiledKernels, "implicit")     # plans keep radau's entry
    assert callable(methods.implicit_solver)


def test_a_holonomic_constraint_and_its_derivative_are_different_systems():
    J = jn.JetSpace(["x", "y"])
    x, y = J.q
    xd, yd = J.qd
    L = (xd**2 + yd**2) / 2 - y
    g = jn.System(J, L, [x**2 + y**2 - 1], dependent=["y"])
    dg = jn.System(J, L, [2 * x * xd + 2 * y * yd], dependent=["y"])
    assert g.constraints == dg.constraints and g.holonomic and not dg.holonomic
    assert g != dg and g == jn.System(J, L, [x**2 + y**2 - 1], dependent=["y"])
    assert g.replace(name="circle").holonomic == g.holonomic
    assert g.with_split(["x"]).given_constraints == g.given_constraints
