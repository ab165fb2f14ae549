"""A run that starts past its chart's edge (``jetnh.numeric.atlas``, ``loop.PAST_EDGE``).

The quick route of an adaptive explicit run (no events, budget, sensitivities) calls its
loop with ``Control.edge = -1``: the loop reads the edge at the start, returns at once
past it, and the run takes the general route (the split of largest measure).  Such a
run equals the same run through the general route from the start (a time budget) bit
for bit; the loop's verdict is the edge kernel's, to the bit, on states on both sides of
the edge; the marker reaches no other call of a loop (runs with events or a budget,
ensembles, sweeps, the pieces after a switch).
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh.models import knife_edge
from jetnh.numeric import Event, atlas, interrupt, solve
from jetnh.numeric.methods._common import FINISHED, SINGULAR
from jetnh.numeric.methods.loop import PAST_EDGE, Control

RUN = dict(rtol=1e-8, atol=1e-11)
#: the edge of dependent=['y'] on the knife edge: cos^2 phi = 1/8
PHI_EDGE = math.acos(math.sqrt(1 / 8))


@pytest.fixture(scope="module")
def knife():
    """Heading rate 3: from phi = 0 the edge comes at t = 0.40, T = 0.3 ends before."""
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0),
                    t_span=(0.0, 0.3))


def _start(phi):
    return dict(x=0.0, y=0.0, phi=phi, x_t=0.5 * math.cos(phi), phi_t=3.0)


def _same(a, b):
    assert a.t.shape == b.t.shape and np.array_equal(a.t, b.t)
    assert np.array_equal(a.y, b.y) and a.switches == b.switches
    assert a.status == b.status and a.stop_reason == b.stop_reason
    for name in ("steps", "rejected", "rhs_evaluations"):
        assert getattr(a.diagnostics, name) == getattr(b.diagnostics, name)


@pytest.fixture
def controls(monkeypatch):
    """Every ``Control`` a loop is called with (``interrupt.call``'s arguments, a chart's
    ``call``), in order."""
    seen = []
    real_call, real_chart = interrupt.call, atlas.Chart.call

    def call(fn, halt, limit, args=(), *rest, **kw):
        seen.extend(a for a in args if isinstance(a, Control))
        return real_call(fn, halt, limit, args, *rest, **kw)

    def chart_call(self, method, ce, watch, t0, t1, y, p, ctl, *rest, **kw):
        seen.append(ctl)
        return real_chart(self, method, ce, watch, t0, t1, y, p, ctl, *rest, **kw)

    monkeypatch.setattr(interrupt, "call", call)
    monkeypatch.setattr(atlas.Chart, "call", chart_call)
    return seen


@pytest.mark.parametrize("method", ["dop853", "dopri5", "rk4", "radau"])
@pytest.mark.parametrize("save", ["final", "steps"])
def test_a_run_past_the_edge_equals_the_general_route(knife, method, save):
    """phi0 = 1.4 (cos^2 = 0.029 < 1/8): the run begins in dependent=['x'] with a switch
    at t0, equal to the run with a time budget (the general route from the start)."""
    kw = dict(y0=_start(1.4), method=method, save=save, **RUN)
    if method == "rk4":
        kw = dict(y0=_start(1.4), method=method, save=save, n_steps=60)
    quick, general = knife.run(**kw), knife.run(timeout=60.0, **kw)
    assert quick.switches[0] == {"t": 0.0, "from": ["y"], "to": ["x"]}
    _same(quick, general)
    _same(quick, knife.run(**kw))                   # (again, its plan made)


def test_the_quick_route_reads_the_edge_in_its_loop(knife, controls, monkeypatch):
    """An adaptive explicit run calls its loop with the marker and no edge in Python;
    past the edge that call is the only one with the marker (then the general route)."""
    def refused(*args):
        raise AssertionError("_edge_at called")

    monkeypatch.setattr(atlas, "_edge_at", refused)
    atlas.atlas(knife)._reaches.clear()     # (no plan's last run reached the edge)
    before = knife.run(**RUN)
    assert before.status == FINISHED and not before.switches
    assert [c.edge for c in controls] == [-1.0]
    controls.clear()
    past = knife.run(y0=_start(1.4), **RUN)
    assert past.switches and controls[0].edge == -1.0
    assert all(c.edge >= 0.0 for c in controls[1:]) and len(controls) > 1
    plans = knife._memo["plans"].values()
    assert plans and all(p.suffix[0].edge >= 0.0 for p in plans if p.suffix)


def test_the_marker_reaches_no_other_call(knife, controls):
    """Runs with events, a budget, sensitivities, fixed steps, radau, ensembles and
    sweeps, and the pieces after a switch, call their loops without the marker."""
    phi = knife.system.J.q[2]
    knife.run(events=[Event(phi - 0.5, name="half")], **RUN)
    knife.run(timeout=60.0, **RUN)
    knife.run(sensitivities=True, **RUN)
    knife.run(method="rk4", n_steps=50)
    knife.run(method="radau", **RUN)
    knife.run(y0=_start(1.4), timeout=60.0, **RUN)
    ens = knife.ensemble(initial={"phi": np.array([0.0, 1.4]),
                                  "x_t": np.array([0.5, 0.5 * math.cos(1.4)])},
                         parallel="serial", **RUN)
    assert ens.switches[1][0]["t"] == 0.0
    jn.sweep(knife, {"phi_t": [1.0, 3.0]}, **RUN)
    assert controls and all(c.edge >= 0.0 for c in controls)
    controls.clear()
    atlas.atlas(knife)._reaches.clear()     # (the first run of a plan to reach the edge)
    long = knife.run(t_span=(0.0, 3.0), **RUN)
    assert len(long.switches) > 2
    assert [c.edge for c in controls[:1]] == [-1.0] and len(controls) > 2
    assert all(c.edge >= 0.0 for c in controls[1:])         # (the pieces after it)
    controls.clear()
    _same(long, knife.run(t_span=(0.0, 3.0), **RUN))        # (``chart_driver``)
    assert all(c.edge >= 0.0 for c in controls)


@settings(max_examples=40, deadline=None)
@given(st.integers(-40, 40), st.floats(-1e-6, 1e-6))
def test_the_loops_verdict_is_the_edge_kernels(knife, ulps, offset):
    """States on both sides of the edge (within ``ulps`` steps of a float of it, or
    ``offset`` from it): the loop with the marker stops at once (``PAST_EDGE``) exactly
    where the edge kernel (``atlas.own_edge``) is negative there."""
    phi0 = PHI_EDGE + offset
    for _ in range(abs(ulps)):
        phi0 = math.nextafter(phi0, math.copysign(math.inf, ulps))
    at = atlas.atlas(knife)
    plan = solve.plan(knife, "dop853", save="final")
    scene = knife.replace(initial=_start(phi0))
    y0, p = scene.y0.copy(), scene._p
    marked = atlas._marked(at, plan)
    out = plan.entry(*plan.head, y0, p, *marked, np.zeros(1, dtype=np.int64))
    past = out[0] == SINGULAR and out[11] == PAST_EDGE
    assert past == (atlas.own_edge(at, plan.ce, plan.t0, y0, p) < 0.0)
    assert past == (atlas._edge_at(at, plan.ce, plan.t0, y0, p) < 0.0)
    if not past:        # (the rest of the run as without the marker)
        plain = plan.entry(*plan.head, y0, p, *plan.suffix, np.zeros(1, dtype=np.int64))
        assert out[0] == plain[0] and np.array_equal(out[2][:out[3] + 1],
                                                     plain[2][:plain[3] + 1])


def test_a_nan_edge_is_not_past_it(knife):
    """An edge that is NaN at the start is not negative: the loop goes on (as
    ``not _edge_at(...) < 0`` did)."""
    at = atlas.atlas(knife)
    plan = solve.plan(knife, "dop853", save="final")
    y0 = knife.y0.copy()
    y0[list(knife.state_names).index("phi")] = np.nan
    assert math.isnan(atlas.own_edge(at, plan.ce, plan.t0, y0, knife._p))
    out = plan.entry(*plan.head, y0, knife._p, *atlas._marked(at, plan),
                     np.zeros(1, dtype=np.int64))
    assert out[11] != PAST_EDGE
