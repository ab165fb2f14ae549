"""Sensitivities to the initial coordinates of a system with holonomic constraints g = 0:
derivatives along g = 0 in the split's chart (``numeric.initial``), the dependent
coordinates following the independent ones, dq^D/dq^I = -(dg/dq^D)^{-1} dg/dq^I.

Independent routes: central differences of runs started on g = 0 (the dependent
coordinates solved from g: by hand on the circle, by ``complete=True`` on Kane's
four-bar), ``expm(A t)`` of ``jn.linearize`` (which eliminates the same coordinates by
the same chart) at an equilibrium, where the variational equations are ``A``'s, and the
tangency G S = 0 of every row, the start's included.  A sensitivity to a dependent
coordinate is refused, by a trajectory and by an ensemble.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh.errors import JetnhError

from holonomic_systems import (FOURBAR, KNIFE, kane_fourbar, knife_slider,
                               pendulum_xy)

P = {"G": 9.81, "l": 1.0}
TIGHT = dict(rtol=1e-12, atol=1e-13)


@pytest.fixture(scope="module")
def pendulum():
    return jn.Scene(pendulum_xy(), "chetaev", params=P,
                    initial={"x": np.sin(0.6), "y": -np.cos(0.6), "x_t": 0.0},
                    t_span=(0.0, 1.0))


def _on_circle(x, x_t=0.0):
    return {"x": x, "y": -np.sqrt(P["l"] ** 2 - x * x), "x_t": x_t}


def _fd_x(scene, x0, x_t=0.0, h=1e-6):
    """d(x, y, x_t)(t1)/dx0 by central differences of runs from x0 +- h, y0 on the
    circle's lower half."""
    ends = [scene.run(y0=_on_circle(x0 + s * h, x_t), save="final", **TIGHT).y[-1]
            for s in (1.0, -1.0)]
    return (ends[0] - ends[1]) / (2 * h)


def test_pendulum_column_of_x_is_the_derivative_on_the_circle(pendulum):
    """The audit's case (th0 = 0.6 at rest, T = 1): dx(1)/dx0 = -0.98719, dy(1)/dx0 =
    0.67265 by central differences (the identity start gave cos(th0)^2 times these)."""
    tr = pendulum.run(sensitivities=True, **TIGHT)
    S = tr.sensitivities
    fd = _fd_x(pendulum, np.sin(0.6))
    assert fd[:2] == pytest.approx([-0.98719461, 0.67265124], abs=1e-7)
    assert np.abs(S[-1][:, 0] - fd).max() < 1e-7
    # the start: y follows x on the circle, dy/dx = -x/y = tan(th0)
    assert tr.sensitivity("x", "x")[0] == 1.0
    assert tr.sensitivity("y", "x")[0] == pytest.approx(np.tan(0.6), rel=1e-14)
    # G S = 0 at every row, the start's too (G = (2x, 2y))
    GS = tr["x"][:, None] * S[:, 0, :] + tr["y"][:, None] * S[:, 1, :]
    assert np.abs(GS).max() < 1e-13 * max(1.0, np.abs(S).max())
    # the dependent coordinate has no column of its own
    assert not S[:, :, 1].any()
    with pytest.raises(JetnhError, match="differentiate by x"):
        tr.sensitivity("x", "y")
    # the velocity's column is untouched: against central differences in x_t
    h = 1e-6
    ends = [pendulum.run(y0=_on_circle(np.sin(0.6), s * h), save="final", **TIGHT).y[-1]
            for s in (1.0, -1.0)]
    assert np.abs(S[-1][:, 2] - (ends[0] - ends[1]) / (2 * h)).max() < 1e-7


@settings(max_examples=10, deadline=None)
@given(th0=st.floats(-1.2, 1.2), w0=st.floats(-1.0, 1.0))
def test_pendulum_sensitivities_from_random_starts(pendulum, th0, w0):
    """Property over starting angles and rates: the column of x is the central
    difference of runs on the circle; every row tangent to it."""
    x0, x_t0 = P["l"] * np.sin(th0), w0 * np.cos(th0)
    tr = pendulum.run(y0=_on_circle(x0, x_t0), sensitivities=True, t_span=(0.0, 0.7),
                      **TIGHT)
    S = tr.sensitivities
    ends = [pendulum.run(y0=_on_circle(x0 + s * 1e-6, x_t0), save="final",
                         t_span=(0.0, 0.7), **TIGHT).y[-1] for s in (1.0, -1.0)]
    fd = (ends[0] - ends[1]) / 2e-6
    assert np.abs(S[-1][:, 0] - fd).max() < 2e-6 * max(1.0, np.abs(fd).max())
    GS = tr["x"][:, None] * S[:, 0, :] + tr["y"][:, None] * S[:, 1, :]
    assert np.abs(GS).max() < 1e-12 * max(1.0, np.abs(S).max())


def _lateral_pendulum():
    """The Cartesian pendulum under gravity and a constant side force F: its equilibrium
    hangs at tan(th) = F/G, where y follows x with slope dy/dx = tan(th) != 0."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    G, F, ell = sp.symbols("G F l", positive=True)
    return jn.System(J, (xt**2 + yt**2) / 2 - G * y + F * x, [x**2 + y**2 - ell**2])


def test_equilibrium_sensitivities_are_the_linearization_flow():
    """At an equilibrium the variational equations are x' = A x of ``linearize`` (y
    eliminated by the same chart): S over (x, x_t) equals expm(A t) at every row, and
    y's row is tan(th) times x's."""
    s, prm = _lateral_pendulum(), {"G": 9.81, "F": 4.0, "l": 1.0}
    th = np.arctan2(prm["F"], prm["G"])
    at = {"x": np.sin(th), "y": -np.cos(th), "x_t": 0.0}
    lin = jn.linearize(s, at=at, params=prm)
    assert lin.state_names == ("x", "x_t") and lin.eliminated == ("y",)
    assert lin.residual < 1e-12
    tr = jn.Scene(s, "chetaev", params=prm, initial=at, t_span=(0.0, 0.5)).run(
        sensitivities=True, t_eval=np.linspace(0.0, 0.5, 6), **TIGHT)
    S = tr.sensitivities
    cols = [tr.sensitivity_columns.index(n) for n in ("x", "x_t")]
    rows = [tr.layout.states.index(n) for n in ("x", "x_t")]
    for k, t in enumerate(tr.t):
        E = scipy.linalg.expm(lin.A * t)
        assert np.abs(S[k][np.ix_(rows, cols)] - E).max() < 1e-9, t
    assert np.abs(S[:, 1, cols] - np.tan(th) * S[:, 0, cols]).max() < 1e-9


def test_knife_slider_equilibrium_against_linearize():
    """Mixed constraints (a knife edge carrying z = a sin(th)), at rest at th = 0
    (dz/dth = a): S over the kept states equals expm(A t) of ``linearize`` with
    drop=None, z's row a cos(th) times th's; z itself is refused."""
    s = knife_slider()
    at = {"x": 0.1, "y": -0.2, "th": 0.0, "z": 0.0, "x_t": 0.0, "th_t": 0.0}
    lin = jn.linearize(s, at=at, params=KNIFE, drop=None)
    assert lin.eliminated == ("z",)
    tr = jn.Scene(s, "chetaev", params=KNIFE, initial=at, t_span=(0.0, 0.8)).run(
        sensitivities=True, split="fixed", t_eval=np.linspace(0.0, 0.8, 5), **TIGHT)
    S = tr.sensitivities
    names = lin.state_names
    cols = [tr.sensitivity_columns.index(n) for n in names]
    rows = [tr.layout.states.index(n) for n in names]
    for k, t in enumerate(tr.t):
        assert np.abs(S[k][np.ix_(rows, cols)] - scipy.linalg.expm(lin.A * t)).max() < 1e-9
    iz, ith = tr.layout.states.index("z"), tr.layout.states.index("th")
    assert np.abs(S[:, iz, cols] - KNIFE["a"] * np.cos(tr["th"])[:, None]
                  * S[:, ith, cols]).max() < 1e-12
    assert S[0, iz, tr.sensitivity_columns.index("th")] == pytest.approx(KNIFE["a"])
    with pytest.raises(JetnhError, match="'z' has no initial value"):
        tr.sensitivity("th", "z")


def test_kane_fourbar_against_runs_completed_onto_the_loop():
    """Kane's four-bar (q2, q3 follow q1 by two loop-closure constraints): the column
    of q1 against central differences of runs whose q2, q3 are completed onto g = 0
    (``complete=True``, the same chart); q2 and q3 refused."""
    pytest.importorskip("sympy.physics.mechanics")
    s = kane_fourbar()
    start = {"q1": 1.2, "q2": 0.3, "q3": -1.5, "q1_t": 2.0}
    sc = jn.Scene(s, "chetaev", params=FOURBAR, initial=start, complete=True,
                  t_span=(0.0, 0.5))
    tr = sc.run(sensitivities=True, **TIGHT)
    h = 1e-6
    ends = [sc.replace(initial={**start, "q1": 1.2 + d}, complete=True).run(
        save="final", **TIGHT).y[-1] for d in (h, -h)]
    fd = (ends[0] - ends[1]) / (2 * h)
    col = tr.sensitivities[-1][:, tr.sensitivity_columns.index("q1")]
    assert np.abs(col - fd).max() < 1e-6 * max(1.0, np.abs(fd).max())
    for dep in ("q2", "q3"):
        with pytest.raises(JetnhError, match="differentiate by q1"):
            tr.sensitivity("q1", dep)


def test_ensemble_sensitivities_along_the_circle(pendulum):
    """An ensemble's runs: each the single run's S, bit for bit, with its own chart at
    its own start; a dependent coordinate refused there too."""
    xs = np.array([0.2, 0.5, -0.7])
    ens = pendulum.ensemble(initial={"x": xs, "y": -np.sqrt(1.0 - xs**2)},
                            sensitivities=True, t_eval=np.linspace(0.0, 1.0, 5), **TIGHT)
    for r, x0 in enumerate(xs):
        one = pendulum.run(y0=_on_circle(x0), sensitivities=True,
                           t_eval=np.linspace(0.0, 1.0, 5), **TIGHT)
        assert np.array_equal(ens.sensitivities[r], one.sensitivities)
        assert ens.sensitivities[r, 0, 1, 0] == pytest.approx(-x0 / -np.sqrt(1 - x0**2))
    with pytest.raises(JetnhError, match="differentiate by x"):
        ens.sensitivity("x", "y")
    assert ens.sensitivity("y", "x").shape == (3, 5)
