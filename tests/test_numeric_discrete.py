"""Structure-preserving fixed-step integrators: the discrete Lagrange-d'Alembert
integrator with node projection, and the discrete vakonomic (midpoint variational)
integrator -- order under refinement and long-run residual / energy."""

import numpy as np
import pytest

import jetnh as jn
from jetnh.mechanics.system import System
from jetnh.errors import JetnhError, PrincipleError
from jetnh.numeric import Scene

OSC0 = dict(x=0.3, y=0.8, z=0.0, x_t=0.5, y_t=-0.2)


def oscillator():
    """The nonholonomic particle zdot = y xdot in a harmonic potential: bounded motion."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2 - (x**2 + y**2) / 2
    return System(J, L, [zd - y * xd], dependent=[z])


@pytest.fixture(scope="module")
def chetaev():
    return Scene(oscillator(), "chetaev", initial=OSC0, t_span=(0.0, 2.0), cache=False)


@pytest.fixture(scope="module")
def vakonomic():
    return Scene(oscillator(), "vakonomic", initial=dict(OSC0, lambda_z=0.3),
                 t_span=(0.0, 2.0), cache=False)


def observed_orders(errors):
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


# ---------------------------------------------------------------------- dla + projection
def test_dla_projection_satisfies_constraints_and_keeps_order(chetaev):
    ref = chetaev.run(rtol=1e-13, atol=1e-14, save="final")
    errs = []
    for n in (50, 100, 200):
        tr = chetaev.run(method="dla", n_steps=n, projection=True)
        assert tr.method == "dla+projection"
        assert np.max(np.abs(tr.residual)) < 1e-12          # nodes on the constraint set
        errs.append(max(abs(tr[s][-1] - ref[s][-1]) for s in ("x", "y", "z", "x_t")))
    orders = observed_orders(errs)
    assert np.all(np.abs(orders - 2) < 0.25), (errs, orders)
    # without projection the node residual is O(h^2), not zero
    plain = chetaev.run(method="dla", n_steps=50)
    assert np.max(np.abs(plain.residual)) > 1e-6


def test_dla_projection_long_run(chetaev):
    """The trade-off, measured: projection puts every node on the constraint set, but it
    is not symmetric, so the energy drifts linearly in t (here ~1e-6 per unit time at
    h = 0.05), where the plain symmetric method keeps it to rounding."""
    tr = chetaev.run(method="dla", h=0.05, t_span=(0.0, 500.0), projection=True)
    assert np.max(np.abs(tr.residual)) < 1e-12
    dE = np.abs(tr.energy - tr.energy[0])
    tenth = len(tr) // 10
    assert dE.max() < 1e-3
    assert 5.0 < dE.max() / dE[:tenth].max() < 20.0            # linear growth
    plain = chetaev.run(method="dla", h=0.05, t_span=(0.0, 500.0))
    assert np.max(np.abs(plain.energy - plain.energy[0])) < 1e-9
    assert np.max(np.abs(plain.residual)) < 1e-2


def test_projection_is_a_dla_option(chetaev):
    with pytest.raises(JetnhError, match="projection= is an option of the dla"):
        chetaev.run(projection=True)


# ---------------------------------------------------------------------- discrete vakonomic
def test_dvi_order_two(vakonomic):
    ref = vakonomic.run(rtol=1e-13, atol=1e-14, save="final")
    errs, lam_errs = [], []
    for n in (40, 80, 160):
        tr = vakonomic.run(method="dvi", n_steps=n, save="final")
        assert tr.method == "dvi" and tr.diagnostics.steps == n
        errs.append(max(abs(tr[s][-1] - ref[s][-1]) for s in ("x", "y", "z", "x_t", "y_t")))
        lam_errs.append(abs(tr["lambda_z"][-1] - ref["lambda_z"][-1]))
    for e in (errs, lam_errs):
        orders = observed_orders(e)
        assert np.all(np.abs(orders - 2) < 0.25), (e, orders)


def test_dvi_long_run_bounded(vakonomic):
    """20000 steps: the node residual stays O(h^2) without growth, the energy of
    L + lambda f oscillates without drift."""
    tr = vakonomic.run(method="dvi", h=0.05, t_span=(0.0, 1000.0))
    res = np.abs(tr.residual[:, 0])
    tenth = len(tr) // 10
    assert res.max() < 1e-2 and res.max() <= 1.5 * res[:tenth].max()
    dE = np.abs(tr.energy - tr.energy[0])
    assert dE.max() < 1e-2 and dE.max() <= 1.5 * dE[:tenth].max()
    # compared with DOP853 at a loose tolerance over the same span: no secular drift there
    assert "lambda_z" in tr.names and tr["z_t"].shape == tr.t.shape


def test_dvi_rejects_other_principles(chetaev):
    with pytest.raises(PrincipleError, match="vakonomic"):
        chetaev.run(method="dvi", n_steps=10)
    sc = Scene(oscillator(), "vakonomic", initial=dict(OSC0, lambda_z=0.3), cache=False)
    with pytest.raises(PrincipleError, match="dvi"):
        sc.run(method="dla", n_steps=10)
