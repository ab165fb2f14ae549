"""``run(params=...)`` of run-time parameters by name as finite floats, checked at once
(``Scene._run_params``), against the general route (keys as Symbols, a sequence, numpy
floats) and against a scene built with those values: the same parameters, the same
steps bit for bit; and what is not such a dict still refused with its message."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh.models as models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene


@pytest.fixture(scope="module")
def tuned():
    return Scene(models.get("rolling_disk"), "chetaev",
                 initial=models.initial("rolling_disk"), t_span=(0.0, 0.5),
                 runtime_params=["R", "I1"]).compile()


def _same(a, b):
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.y, b.y)


@settings(max_examples=10, deadline=None)
@given(r=st.floats(0.5, 2.0), i1=st.floats(0.1, 1.0), both=st.booleans())
def test_the_quick_route_is_the_general_one(tuned, r, i1, both):
    given_ = {"R": r, "I1": i1} if both else {"R": r}
    quick = tuned._run_params(given_)
    general = tuned._run_params({sp.Symbol(k): np.float64(v) for k, v in given_.items()})
    np.testing.assert_array_equal(quick, general)
    assert quick is not tuned._p and (tuned._p == tuned.p).all()    # the scene's untouched
    _same(tuned.run(params=given_, save="final"),
          tuned.run(params=[given_["R"], given_.get("I1", tuned.params["I1"])], save="final"))


def test_a_run_with_params_is_a_run_of_the_scene_with_them(tuned):
    changed = {"R": 1.3}
    other = Scene(tuned.system, "chetaev", params={**tuned.params, **changed},
                  initial={n: tuned.initial[n] for n in tuned.state_names},
                  t_span=tuned.t_span, runtime_params=["R", "I1"])
    # (the initial dependent velocities follow from R: the scene's own state, other p)
    np.testing.assert_array_equal(other.y0, tuned.y0)
    _same(tuned.run(params=changed), other.run())
    _same(tuned.run(), tuned.replace(params=dict(tuned.params)).run())


@pytest.mark.parametrize("params, message", [
    ({"R": float("nan")}, "R"),
    ({"R": float("inf")}, "R"),
    ({"I2": 1.0}, "compiled into this scene's kernels"),
    ({"nope": 1.0}, "not a parameter of this system"),
    ({"R": "1.0"}, "R"),
])
def test_what_is_not_a_dict_of_finite_floats_is_refused(tuned, params, message):
    with pytest.raises(JetnhError, match=message):
        tuned.run(params=params, save="final")
