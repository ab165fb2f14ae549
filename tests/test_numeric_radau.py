"""radau (Radau IIA, order 5, of jetnh's own): the method derived from its nodes, the
generated Jacobian, order of convergence, closed forms, agreement with dop853, the stiff
Chaplygin sleigh, events, singular stops, budgets and ensembles."""

import math

import numpy as np
import pytest
import sympy as sp

from jetnh.models import chaplygin_sleigh, damped_chaplygin_sleigh, nonholonomic_particle
from jetnh.numeric import Event, Scene
from jetnh.numeric.methods import radau
from jetnh.numeric.methods._common import EVENT, FINISHED, MAX_STEPS, STIFF

PART0 = dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3)
T = 4.0


# ---------------------------------------------------------------------- the method
def test_collocation_conditions():
    """C(3): sum_j A_ij c_j^(k-1) = c_i^k / k; B(5): sum_i b_i c_i^(k-1) = 1/k (order 5);
    stiffly accurate; c the zeros of the Radau polynomial d^2/dx^2 (x^2 (x - 1)^3)."""
    c, A = radau.C, radau.A
    for k in range(1, 4):
        assert np.allclose(A @ c ** (k - 1), c ** k / k, atol=1e-15)
    b = A[2]
    for k in range(1, 6):
        assert abs(b @ c ** (k - 1) - 1 / k) < 1e-15
    x = sp.Symbol("x")
    roots = sorted(float(r) for r in sp.solve(sp.diff(x**2 * (x - 1)**3, x, 2), x))
    assert np.allclose(roots, c, atol=1e-15)


def test_eigenbasis_and_embedded_formula():
    lam = radau.TI @ np.linalg.inv(radau.A) @ radau.T
    expect = np.array([[radau.GAMMA, 0, 0], [0, radau.ALPHA, radau.BETA],
                       [0, -radau.BETA, radau.ALPHA]])
    assert np.allclose(lam, expect, atol=1e-12)
    # the real eigenvalue of A^-1: the real root of det(A^-1 - g) ~ 3.6378
    assert np.isclose(np.linalg.det(np.linalg.inv(radau.A) - radau.GAMMA * np.eye(3)), 0,
                      atol=1e-10)
    # the embedded weights (gamma0 = 1/gamma at c = 0, then bh) have order 3
    gamma0 = 1 / radau.GAMMA
    bh = radau.ERR_W @ radau.A / radau.GAMMA + radau.A[2]
    nodes = np.concatenate([[0.0], radau.C])
    weights = np.concatenate([[gamma0], bh])
    for k in range(1, 4):
        assert abs(weights @ nodes ** (k - 1) - 1 / k) < 1e-13


def test_lu_real_and_complex():
    rng = np.random.default_rng(3)
    for dtype in (float, complex):
        M = rng.normal(size=(5, 5)) + (1j * rng.normal(size=(5, 5)) if dtype is complex
                                       else 0)
        M = np.ascontiguousarray(M, dtype=dtype)
        b = np.ascontiguousarray(rng.normal(size=5), dtype=dtype)
        want = np.linalg.solve(M, b)
        F, piv = M.copy(), np.empty(5, dtype=np.int64)
        assert radau.lu_factor(F, piv)
        x = b.copy()
        radau.lu_solve(F, piv, x)
        assert np.allclose(x, want, atol=1e-12)


# ---------------------------------------------------------------------- non-stiff
@pytest.fixture(scope="module")
def particle():
    return Scene(nonholonomic_particle(), "chetaev", initial=PART0, t_span=(0.0, T),
                 cache=False).compile()


def exact_x(t):
    v, y0 = PART0["y_t"], PART0["y"]
    c = PART0["x_t"] * np.sqrt(1 + y0**2)
    return PART0["x"] + c / v * (np.arcsinh(y0 + v * t) - np.arcsinh(y0))


def test_scene_jacobian_is_the_generated_one_and_matches_differences(particle):
    """radau's Jacobian is the kernel generated from the derivation (codegen), checked
    against central differences of the compiled rhs."""
    from jetnh.numeric import kernels

    ck = kernels.jacobian_kernels(particle)
    assert particle.jacobian.address.address == ck.jac_fp.address
    kern = particle.kernels
    y, p = particle.y0 + 0.1, particle.p
    J = np.empty((len(y), len(y)))
    particle.jacobian(0.3, y, p, J)            # callable as documented
    f0, f1 = np.empty_like(y), np.empty_like(y)
    for j in range(len(y)):
        e = np.zeros_like(y)
        e[j] = 1e-6
        kern.rhs(0.3, y + e, p, f1)
        kern.rhs(0.3, y - e, p, f0)
        assert np.allclose(J[:, j], (f1 - f0) / 2e-6, atol=1e-8)


def test_observed_order_five(particle):
    """Equal steps (max_step pins h, loose tolerances accept every step): error ~ h^5."""
    errs = []
    for n in (8, 16, 32):
        tr = particle.run(method="radau", rtol=0.5, atol=1.0, first_step=T / n,
                          max_step=T / n, newton_tol=1e-13, max_newton=40, save="final")
        assert tr.diagnostics.steps == n and tr.diagnostics.rejected == 0
        errs.append(abs(tr["x"][-1] - exact_x(T)))
    observed = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert abs(observed[-1] - 5) < 0.4, (errs, observed)


def test_tolerance_and_agreement_with_dop853(particle):
    ref = particle.run(method="dop853", rtol=1e-13, atol=1e-14, save="final")
    errs = []
    for rtol in (1e-5, 1e-8, 1e-11):
        tr = particle.run(method="radau", rtol=rtol, atol=rtol * 1e-2, save="final")
        assert tr.status == FINISHED
        errs.append(abs(tr["x"][-1] - exact_x(T)))
        assert np.allclose(tr.y[-1], ref.y[-1], atol=1e3 * rtol)
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-11


def test_t_eval_dense_output(particle):
    te = np.linspace(0.0, T, 23)
    tr = particle.run(method="radau", rtol=1e-10, atol=1e-12, t_eval=te)
    assert np.array_equal(tr.t, te)
    assert np.allclose(tr["x"], exact_x(te), atol=1e-8)


# ---------------------------------------------------------------------- stiff sleigh
def sleigh_closed_form(m, I, a, v0, w0, t, gamma=0.0):
    """v, w, theta of the (damped, c/m = c_r/I = gamma) sleigh from theta0 = 0 (the
    catalogue's docstrings)."""
    K = I + m * a * a
    tau = t if gamma == 0 else (1 - np.exp(-gamma * t)) / gamma
    V = math.sqrt((m * v0**2 + K * w0**2) / m)
    s0 = math.atanh(v0 / V)
    s = m * a * V * tau / K + s0
    gd = lambda u: 2 * np.arctan(np.tanh(u / 2))  # noqa: E731
    decay = np.exp(-gamma * t)
    sech = 2 * np.exp(-s) / (1 + np.exp(-2 * s))
    return (decay * V * np.tanh(s), decay * w0 * np.cosh(s0) * sech,
            w0 * np.cosh(s0) * K / (m * a * V) * (gd(s) - gd(s0)))


@pytest.mark.parametrize("damped", [False, True])
def test_stiff_sleigh(damped):
    """Centre of mass near the blade: the turning rate decays at ~ m a V / (I + m a^2)
    (here ~2500); radau follows the closed form with steps on the time scale of the
    slow motion, dop853 is held to its stability bound, which its stiffness test sees:
    it stops with status STIFF."""
    m, I, a, v0, w0, T_end = 1.0, 1e-8, 1e-4, 0.5, 1.0, 5.0
    params = dict(m=m, I=I, a=a)
    gamma = 0.0
    if damped:
        gamma = 0.3
        params.update(c=gamma * m, c_r=gamma * I)
    system = damped_chaplygin_sleigh() if damped else chaplygin_sleigh()
    sc = Scene(system, "chetaev", params=params, t_span=(0.0, T_end),
               initial=dict(x=0.0, y=0.0, theta=0.0, x_t=v0, theta_t=w0), cache=False)
    v, w, th = sleigh_closed_form(m, I, a, v0, w0, T_end, gamma)
    tr = sc.run(method="radau", rtol=1e-8, atol=1e-12, save="final")
    assert tr.status == FINISHED
    assert abs(tr["theta"][-1] - th) < 1e-9 and abs(tr["theta_t"][-1] - w) < 1e-9
    speed = tr["x_t"][-1] * math.cos(tr["theta"][-1]) + tr["y_t"][-1] * math.sin(
        tr["theta"][-1])
    assert abs(speed - v) < 1e-8
    ex = sc.run(method="dop853", rtol=1e-8, atol=1e-12, save="final")
    assert ex.status == STIFF and ex.t[-1] < T_end and "method='radau'" in ex.stop_reason
    loose = [sc.run(method=m, rtol=1e-6, atol=1e-10, save="final").diagnostics.steps
             for m in ("radau", "dop853")]
    assert loose[0] * 5 < loose[1], loose


# ---------------------------------------------------------------------- stops, events
def test_events_like_dop853(particle):
    x, y = particle.system.J.q[:2]
    evs = [y - 0.25, Event(x - 2.0, terminal=True, direction=1)]
    a = particle.run(method="radau", rtol=1e-10, atol=1e-12, events=evs)
    b = particle.run(method="dop853", rtol=1e-10, atol=1e-12, events=evs)
    assert a.status == EVENT == b.status
    for ta, tb in zip(a.t_events, b.t_events):
        assert len(ta) == len(tb) and np.allclose(ta, tb, atol=1e-8)
    assert abs(a.t[-1] - b.t[-1]) < 1e-8


def test_budget(particle):
    tr = particle.run(method="radau", max_steps=3)
    assert tr.status == MAX_STEPS and tr.diagnostics.steps == 3


def test_ensemble_is_the_run(particle):
    y0 = np.array([particle.y0, particle.y0 * 1.1])
    ens = particle.ensemble(initial=y0, method="radau", rtol=1e-9, atol=1e-11,
                            parallel="serial")
    for r in range(2):
        tr = particle.run(method="radau", rtol=1e-9, atol=1e-11, y0=y0[r], save="final")
        assert np.array_equal(ens.y_final[r], tr.y[-1])
        assert ens.steps[r] == tr.diagnostics.steps
