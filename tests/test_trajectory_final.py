"""``Trajectory.final``: the state where a run ended, also where a run with ``t_eval``
stopped early after its last output row (a step budget, a terminal event, a singular
configuration), in a plain run and in one that changed split.

Two routes to each stop: the same run storing every step, whose last row is the state
where it stopped (the same steps: the output mode does not change them), and the closed
forms of the catalogue's rolling disk (phi = phi0 + phi_t t) and knife edge.
"""

import math
import pickle

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh import models
from jetnh.models import knife_edge
from jetnh.numeric import Event

TOL = dict(rtol=1e-11, atol=1e-12)
W = 3.0                 # heading rate of the knife edge


@pytest.fixture(scope="module")
def disk():
    m = models.model("rolling_disk")
    return jn.Scene(m.system, "chetaev", initial=m.initial, t_span=(0.0, 1e3))


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=W),
                    t_span=(0.0, 10.0))


def last_row(traj) -> dict:
    return {name: float(traj[name][-1]) for name in traj.names}


def test_a_budget_stop_keeps_the_state_where_it_stopped(disk):
    """max_steps stops the run at t ~ 259 of 1000, after the output row at t = 200:
    final is the state there, the last row of the run storing every step to the bit."""
    te = np.linspace(0.0, 1e3, 11)
    cut = disk.run(t_eval=te, max_steps=300)
    every = disk.run(max_steps=300)
    assert cut.status == every.status == 1 and cut.t[-1] == 200.0
    assert cut.t_final == every.t[-1] == every.t_final > 250.0
    assert cut.final == last_row(every)
    assert cut.final["phi"] != cut["phi"][-1]               # not the last row
    phi0, w = disk.initial["phi"], disk.initial["phi_t"]
    assert cut.final["phi"] == pytest.approx(phi0 + w * cut.t_final, rel=1e-12)
    assert f"at t = {cut.t_final:.10g}" in cut.stop_reason
    again = pickle.loads(pickle.dumps(cut))
    assert again.final == cut.final and again.t_final == cut.t_final


def test_a_finished_run_ends_at_its_last_row(disk):
    te = np.linspace(0.0, 5.0, 6)
    done = disk.run(t_span=(0.0, 5.0), t_eval=te)
    assert done.status == 0 and done.t_final == 5.0 and done.final == last_row(done)


def test_a_terminal_event_keeps_its_state(disk):
    """A terminal event between two output rows: final is the event's state."""
    phi = sp.Symbol("phi")
    event = Event(phi - 7.25, terminal=True, name="phi=7.25")
    te = np.linspace(0.0, 1e3, 101)
    cut = disk.run(t_eval=te, events=event, **TOL)
    every = disk.run(events=event, **TOL)
    assert cut.status == 5 and cut.t[-1] < cut.t_final < cut.t[-1] + 10.0
    hit = cut.events["phi=7.25"]
    assert cut.t_final == float(hit["t"][-1])
    assert cut.final["phi"] == pytest.approx(7.25, abs=1e-12)
    for name in disk.state_names:
        assert cut.final[name] == float(hit[name][-1]), name
    assert cut.final == pytest.approx(last_row(every), rel=1e-14, abs=1e-14)


@pytest.mark.parametrize("method", ["scipy-DOP853", "scipy-Radau"])
def test_scipy_keeps_the_state_of_its_terminal_event(disk, method):
    """scipy's solve_ivp with t_eval leaves the event out of its rows: final is the
    event's state, the last row of the same run without t_eval."""
    event = Event(sp.Symbol("phi") - 7.25, terminal=True, name="phi=7.25")
    cut = disk.run(t_eval=np.linspace(0.0, 1e3, 101), events=event, method=method, **TOL)
    every = disk.run(events=event, method=method, **TOL)
    assert cut.status == every.status == 5 and cut.t[-1] < cut.t_final
    assert cut.t_final == every.t[-1] == float(cut.events["phi=7.25"]["t"][-1])
    assert cut.final == pytest.approx(last_row(every), rel=1e-14, abs=1e-14)
    assert cut.final["phi"] == pytest.approx(7.25, abs=1e-10)


def test_a_singular_stop_keeps_its_state(knife):
    """The knife edge keeping its split stops where cos(phi) falls to 0 (t = pi/6)."""
    te = np.linspace(0.0, 10.0, 11)
    cut = knife.run(**TOL, split="fixed", t_eval=te)
    every = knife.run(**TOL, split="fixed")
    assert cut.status == 6 and cut.t[-1] == 0.0
    assert cut.t_final == every.t[-1] == pytest.approx(math.pi / 6, rel=1e-6)
    assert cut.final == last_row(every)
    assert cut.final["phi"] == pytest.approx(W * cut.t_final, rel=1e-12)


@pytest.mark.parametrize("budget", [50, 100])
def test_a_run_that_changed_split_keeps_its_stop_in_the_scenes_chart(knife, budget):
    """A budget stop after 4 (even: the scene's own chart) or 9 split switches (odd:
    the other chart, whose state is mapped back; each switch costs a few shorter steps
    of the approach to the edge): final equals the last row of the run
    storing every step (to rounding: the other chart's values mapped from one state
    rather than from all the rows at once) and the closed form; pickled, it keeps it."""
    te = np.linspace(0.0, 10.0, 11)
    cut = knife.run(**TOL, max_steps=budget, t_eval=te)
    every = knife.run(**TOL, max_steps=budget)
    assert cut.status == every.status == 1
    assert len(cut.switches) == len(every.switches) == {50: 4, 100: 9}[budget]
    assert cut.t_final == every.t[-1] > cut.t[-1]
    assert cut.final == pytest.approx(last_row(every), rel=1e-15, abs=1e-15)
    phi = W * cut.t_final
    c = 9.81 * math.sin(0.3) / W
    v = 0.5 + c * math.sin(phi)
    assert cut.final["phi"] == pytest.approx(phi, rel=1e-12)
    assert cut.final["x_t"] == pytest.approx(v * math.cos(phi), abs=1e-9)
    assert cut.final["y_t"] == pytest.approx(v * math.sin(phi), abs=1e-9)
    again = pickle.loads(pickle.dumps(cut))
    assert again.final == cut.final and again.t_final == cut.t_final


@settings(deadline=None)
@given(budget=st.integers(2, 400), points=st.integers(2, 60),
       method=st.sampled_from(["dop853", "dopri5", "radau"]))
def test_final_is_the_last_step_whatever_the_output_times(disk, budget, points, method):
    """Property: a run with t_eval and a step budget ends where the same run storing
    every step ends: its final state is that run's last row."""
    te = np.linspace(0.0, 1e3, points)
    cut = disk.run(t_eval=te, max_steps=budget, method=method)
    every = disk.run(max_steps=budget, method=method)
    assert cut.status == every.status
    assert cut.t_final == every.t[-1]
    assert cut.final == last_row(every)
