"""The short paths of a run give what the general ones give: a loop that watches nothing
(no indicators, no events) returns fewer arrays and its last state as a spare output row,
and its trajectory is bit for bit the watched loop's; scenes copied before their origin's
first run share its plans."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from jetnh import models
from jetnh.numeric import Scene
from jetnh.numeric.methods._common import FINISHED


@pytest.fixture(scope="module")
def particle():
    """isokinetic_particle: it has singularity indicators, so ``singular="stop"`` runs
    the watched loop and ``singular="ignore"`` the loop that watches nothing."""
    return Scene(models.get("isokinetic_particle"), "chetaev",
                 initial=models.initial("isokinetic_particle"), t_span=(0.0, 0.5)).compile()


def _same(a, b):
    assert a.status == b.status == FINISHED
    assert a.t.tobytes() == b.t.tobytes() and a.y.tobytes() == b.y.tobytes()
    da, db = a.diagnostics, b.diagnostics
    assert (da.steps, da.rejected, da.rhs_evaluations) == (db.steps, db.rejected,
                                                           db.rhs_evaluations)


@settings(max_examples=10, deadline=None)
@given(st.floats(-0.5, 0.5), st.sampled_from(["dop853", "dopri5", "rk4"]),
       st.sampled_from(["steps", "final", "t_eval"]))
def test_unwatched_loop_equals_the_watched_one(particle, shift, method, save):
    y0 = particle.y0.copy()
    y0[0] += shift
    kw = dict(y0=y0, method=method)
    if method == "rk4":
        kw.update(n_steps=40, save="final" if save == "t_eval" else save)
    elif save == "t_eval":
        kw.update(t_eval=np.linspace(0.0, 0.5, 7))
    else:
        kw.update(save=save)
    watched = particle.run(singular="stop", **kw)
    plain = particle.run(singular="ignore", **kw)
    assert particle.kernels.layout.indicators      # (else both ran the same loop)
    _same(watched, plain)
    assert plain.t.flags.writeable is False and plain.y.flags.writeable is False
    if save == "steps" and method != "rk4":
        # the dense output re-takes steps through the loop that watches nothing
        at = plain.at([0.123, 0.377])
        ref = watched.at([0.123, 0.377])
        assert np.array_equal(at.to_numpy(), ref.to_numpy())


@settings(max_examples=6, deadline=None)
@given(st.floats(-0.5, 0.5), st.sampled_from(["dop853", "dopri5", "rk4"]),
       st.booleans())
def test_a_run_that_keeps_its_end_ends_where_every_step_does(particle, shift, method,
                                                             watched):
    """``save="final"`` runs a loop compiled without the per-step store
    (``loop.features``); its end and its counts are bit for bit those of the last row of
    ``save="steps"``, whose loop stores every step."""
    from jetnh.numeric.methods import _common, explicit_solver, loop

    y0 = particle.y0.copy()
    y0[0] += shift
    kw = dict(y0=y0, method=method, singular="stop" if watched else "ignore",
              **({"n_steps": 40} if method == "rk4" else {}))
    steps, final = particle.run(save="steps", **kw), particle.run(save="final", **kw)
    assert final.t.shape[0] == 2 and steps.t.shape[0] > 2
    last = steps.t.shape[0] - 1
    assert final.t[-1] == steps.t[-1] and final.y[-1].tobytes() == steps.y[last].tobytes()
    ds, df = steps.diagnostics, final.diagnostics
    assert (ds.steps, ds.rejected, ds.rhs_evaluations) == (df.steps, df.rejected,
                                                           df.rhs_evaluations)
    ctl = loop.Control(1e-6, np.ones(1), 0.0, 1.0, 1, 0)
    none = np.zeros(0, dtype=np.int64)
    w = loop.Watch(0, 0.0, none, none)
    parts = [loop.features(ctl, mode, w) for mode in (_common.EVERY_STEP, _common.ENDPOINTS)]
    assert parts == [(False, False, False, True), (False, False, False, False)]
    assert explicit_solver(method, parts[0]) is not explicit_solver(method, parts[1])


def test_copies_made_before_the_first_run_share_its_plans(particle):
    origin = particle.replace(t_span=(0.0, 0.25))
    a = origin.replace(initial={**dict(origin.initial), "x": 0.1})
    b = origin.replace(initial={**dict(origin.initial), "x": 0.2})
    store = origin._memo["plans"]
    assert a._memo["plans"] is store and b._memo["plans"] is store
    before = set(store)
    ra = a.run(save="final")
    assert len(set(store) - before) == 1            # a planned its run once, for all
    rb = b.run(save="final")
    assert len(set(store) - before) == 1            # b found it
    fresh = Scene(models.get("isokinetic_particle"), "chetaev",
                  initial={**dict(origin.initial), "x": 0.2}, t_span=(0.0, 0.25))
    assert rb.y.tobytes() == fresh.run(save="final").y.tobytes()
    assert ra.y[-1, 0] != rb.y[-1, 0]
