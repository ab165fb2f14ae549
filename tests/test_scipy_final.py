"""scipy's methods with ``save="final"``: t0 and the last state alone, without storing
every step (``scipy_backend._final``).  Two routes to each row: the same run keeping every
step (its first and last rows, bit for bit: the output does not change the steps), and
the closed form of the knife edge (phi = W t) and its singular stop at cos(phi) = 0."""

import math

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.models import knife_edge
from jetnh.numeric import Event

from holonomic_systems import pendulum_xy

W = 3.0


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=W),
                    t_span=(0.0, 0.5))


def _the_ends(every, final):
    """``final`` holds the first and the last row of ``every``, bit for bit."""
    assert final.t.tobytes() == every.t[[0, -1]].tobytes()
    assert final.y.tobytes() == every.y[[0, -1]].tobytes()
    assert (final.status, final.stop_reason) == (every.status, every.stop_reason)
    assert final.diagnostics.rhs_evaluations == every.diagnostics.rhs_evaluations
    d = final.diagnostics       # (a singular stop's row is left out of the figures)
    assert (d.saved, len(final), d.rows) == ("final", 2, 2 - bool(d.stop_row))
    assert every.diagnostics.saved == "steps" and len(every) > 5


@pytest.mark.parametrize("method", ["RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"])
def test_final_is_the_last_row_of_every_step(knife, method):
    kw = dict(method=f"scipy-{method}", rtol=1e-8, atol=1e-10)
    every, final = knife.run(**kw), knife.run(save="final", **kw)
    _the_ends(every, final)
    assert final.t[-1] == 0.5 and final.final["phi"] == pytest.approx(W * 0.5, rel=1e-7)


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_a_terminal_event_ends_the_rows(knife, method):
    """The last row is the event's state (solve_ivp's at the root), and the events are
    those of the run that keeps every step."""
    ev = [Event(sp.Symbol("phi") - 0.6, name="pass"),
          Event(sp.Symbol("phi") - 1.2, terminal=True, name="stop")]
    kw = dict(method=f"scipy-{method}", rtol=1e-9, atol=1e-11, events=ev)
    every, final = knife.run(**kw), knife.run(save="final", **kw)
    _the_ends(every, final)
    assert final.status == 5 and final.t[-1] == pytest.approx(0.4, rel=1e-9)
    for name in ("pass", "stop"):
        assert (final.events[name]["t"].tobytes() == every.events[name]["t"].tobytes())
    assert final.final["phi"] == pytest.approx(1.2, abs=1e-10)


def test_a_singular_stop_keeps_its_state(knife):
    """Keeping its split the knife edge stops where cos(phi) falls to 0 (t = pi/6)."""
    kw = dict(method="scipy-DOP853", rtol=1e-10, atol=1e-12, split="fixed",
              t_span=(0.0, 1.0))
    every, final = knife.run(**kw), knife.run(save="final", **kw)
    _the_ends(every, final)
    assert final.status == 6 and final.t[-1] == pytest.approx(math.pi / 6, rel=1e-8)


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_projected_steps(method):
    """With holonomic constraints every step is projected onto g = 0 (the Cartesian
    pendulum, x^2 + y^2 = 1): the final state is the projected last step."""
    sc = jn.Scene(pendulum_xy(), params={"l": 1.0, "G": 9.81},
                  initial={"x": 0.3, "y": -math.sqrt(1 - 0.09), "x_t": 0.0},
                  t_span=(0, 3.0))
    kw = dict(method=f"scipy-{method}", rtol=1e-9, atol=1e-9)
    every, final = sc.run(**kw), sc.run(save="final", **kw)
    _the_ends(every, final)
    assert abs(final["x"][-1] ** 2 + final["y"][-1] ** 2 - 1) < 1e-14


def test_t_eval_is_kept_over_save(knife):
    """With ``t_eval`` the rows are its points, as for the compiled methods."""
    tr = knife.run(method="scipy-RK45", t_eval=[0.0, 0.25, 0.5], save="final")
    assert tr.diagnostics.saved == "t_eval" and len(tr) == 3


def test_a_state_not_finite_is_a_singular_stop_at_the_last_finite_one():
    """LSODA accepts a step whose end is NaN (sqrt(2 - x) past x = 2): the run keeping
    every step stops singular at the row before it, and so does the final run."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    past = jn.Scene(jn.System(J, xt**2 / 2 - sp.Rational(1, 1000) * sp.sqrt(2 - x)),
                    initial={"x": 0.0, "x_t": 1.0}, t_span=(0.0, 3.0))
    every, final = past.run(method="scipy-LSODA"), past.run(method="scipy-LSODA",
                                                             save="final")
    _the_ends(every, final)
    assert final.status == 6 and "became NaN or infinite" in final.stop_reason
    assert 1.99 < final.t[-1] < 2.0
