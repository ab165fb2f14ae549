"""Observed order of each compiled method under step refinement, on the nonholonomic
particle (zdot = y xdot, Chetaev), whose solution is known in closed form."""

import os

import numpy as np
import pytest

import jetnh as jn
from jetnh.mechanics.system import System
from jetnh.numeric import Scene
from jetnh.numeric.methods import loop
from jetnh.numeric.methods.dop853 import DOP853
from jetnh.numeric.methods.dopri5 import DOPRI5
from jetnh.numeric.methods.rk4 import RK4

PART0 = dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3)
T = 4.0


@pytest.fixture(scope="module")
def scene():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])
    return Scene(s, "chetaev", initial=PART0, t_span=(0.0, T), cache=False).compile()


def exact_x(t):
    v, y0 = PART0["y_t"], PART0["y"]
    c = PART0["x_t"] * np.sqrt(1 + y0**2)
    return PART0["x"] + c / v * (np.arcsinh(y0 + v * t) - np.arcsinh(y0))


def fixed_step_error(scene, method, n):
    h = T / n
    if method == "rk4":
        traj = scene.run(method="rk4", n_steps=n, save="final")
    else:
        # tolerances so loose that every step is accepted; max_step pins h
        traj = scene.run(method=method, rtol=0.5, atol=1e6, first_step=h, max_step=h,
                         save="final")
    assert traj.diagnostics.steps == n and traj.diagnostics.rejected == 0
    return abs(traj["x"][-1] - exact_x(T))


@pytest.mark.parametrize("method, ns, order", [
    ("rk4", (20, 40, 80), 4),
    ("dopri5", (16, 32, 64), 5),
    ("dop853", (4, 8, 16), 8),
])
def test_observed_order(scene, method, ns, order):
    errs = np.array([fixed_step_error(scene, method, n) for n in ns])
    observed = np.log2(errs[:-1] / errs[1:])
    assert abs(observed[-1] - order) < 0.35, (errs, observed)


def test_tolerance_proportionality(scene):
    """Error at the end falls with rtol (adaptive control works)."""
    errs = []
    for rtol in (1e-6, 1e-9, 1e-12):
        traj = scene.run(rtol=rtol, atol=rtol * 1e-2, save="final")
        errs.append(abs(traj["x"][-1] - exact_x(T)))
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-11


def test_method_metadata():
    assert DOPRI5.order == 5 and DOPRI5.error_order == 4 and DOPRI5.n_stages == 6
    assert DOP853.order == 8 and DOP853.error_order == 7 and DOP853.n_stages == 12
    assert RK4.order == 4 and not RK4.adaptive and DOP853.adaptive
    # the tableau's row sums are the nodes, the weights sum to one
    for m in (DOPRI5, DOP853, RK4):
        ns = m.n_stages
        assert np.allclose(m.A[:ns].sum(axis=1), m.C[:ns]), m.name
        assert abs(m.B.sum() / m.b_den - 1) < 1e-14, m.name
    assert np.allclose(DOP853.A[13:].sum(axis=1), DOP853.C[13:])
    with pytest.raises(Exception):
        DOP853.order = 3            # a method is an immutable value


def test_initial_step_matches_scipy(scene):
    """The first accepted step is the one scipy's heuristic picks."""
    from scipy.integrate import solve_ivp

    y0 = scene.y0
    out = np.empty_like(y0)
    rhs = scene.kernels.rhs

    def fun(t, y):
        rhs(t, np.ascontiguousarray(y), scene.p, out)
        return out.copy()

    for ours, theirs in (("dop853", "DOP853"), ("dopri5", "RK45")):
        a = scene.run(rtol=1e-7, atol=1e-9, method=ours)
        b = solve_ivp(fun, (0.0, T), y0, method=theirs, rtol=1e-7, atol=1e-9)
        assert a.diagnostics.rhs_evaluations == b.nfev
        assert abs(a.t[1] - b.t[1]) < 1e-12


# ---------------------------------------------------------------------- structure-preserving
def test_dla_order_two(scene):
    errs = []
    for n in (40, 80, 160):
        traj = scene.run(method="dla", n_steps=n, save="final")
        assert traj.diagnostics.steps == n
        errs.append(abs(traj["x"][-1] - exact_x(T)))
    observed = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(observed - 2) < 0.1), observed


@pytest.fixture(scope="module")
def oscillator():
    """The nonholonomic particle in a harmonic potential: bounded motion, so a long run
    shows whether the constraint residual and the energy error drift."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2 - (x**2 + y**2) / 2
    s = System(J, L, [zd - y * xd], dependent=[z])
    return Scene(s, "chetaev", initial=dict(x=0.3, y=0.8, z=0.0, x_t=0.5, y_t=-0.2),
                 t_span=(0.0, 1000.0), cache=False)


def test_dla_long_run_bounded(oscillator):
    traj = oscillator.run(method="dla", h=0.05)
    res = np.abs(traj.residual[:, 0])
    E = traj.energy
    tenth = len(traj) // 10
    # O(h^2) residual at the nodes, no growth over 20000 steps
    assert res.max() < 1e-2
    assert res.max() <= 1.5 * res[:tenth].max()
    dE = np.abs(E - E[0])
    assert dE.max() < 1e-9     # here the energy is conserved up to rounding
    # dependent velocities are the method's own (not recomputed from phi)
    assert "z_t" in traj.names and traj["z_t"].shape == traj.t.shape


def test_dla_rejects_other_principles(oscillator):
    from jetnh.errors import PrincipleError

    sc = Scene(oscillator.system, "vakonomic",
               initial=dict(oscillator.initial, lambda_z=0.0), t_span=(0, 1), cache=False)
    with pytest.raises(PrincipleError, match="Chetaev"):
        sc.run(method="dla", n_steps=10)


def test_integrator_cache_key_carries_the_helpers():
    """numba's cache keys a function by its own code; the compiled loops are cached under
    a name that carries the hash of every integrator module (the helpers compiled into
    them), in jetnh's signed store (``kernels.loop_cache``), and the helpers themselves
    are not cached on their own."""
    from jetnh.numeric.kernels.loop_cache import LOOPS, SignedFunctionCache
    from jetnh.numeric.methods import _common, radau

    h = _common.sources_hash()
    assert len(h) == 16
    for d in (loop.solver(DOPRI5), radau.solver()):
        assert d.py_func.__qualname__.endswith("_" + h)
        assert isinstance(d._cache, SignedFunctionCache)
        assert os.path.basename(d._cache.cache_path) == LOOPS
    assert type(_common.collect._cache).__name__ == "NullCache"
