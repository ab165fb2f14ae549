"""``run(params=...)`` without ``y0`` starts from the scene's own state at the new
parameter values: that state is checked there as ``run(y0=...)`` checks a given one (a
pendulum written in x, y with its length a run-time parameter was run off its circle,
|g| = 3 for the whole run, where every other route refused)."""

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ConstraintError

from holonomic_systems import pendulum_xy


@pytest.fixture(scope="module")
def scene():
    return jn.Scene(pendulum_xy(), params={"l": 1.0, "G": 9.81},
                    initial={"x": 0.0, "y": -1.0, "x_t": 0.5}, t_span=(0, 1.0),
                    runtime_params=["l"])


@pytest.mark.parametrize("kw", [{}, {"method": "rk4", "n_steps": 100},
                                {"save": "final"}])
def test_the_own_start_off_the_constraints_at_new_params_is_refused(scene, kw):
    with pytest.raises(ConstraintError, match="holonomic"):
        scene.run(params={"l": 2.0}, **kw)
    with pytest.raises(ConstraintError, match="holonomic"):     # the general route too
        scene.run(params={"l": np.float64(2.0)}, **kw)


def test_the_own_start_on_the_constraints_at_new_params_runs_as_with_y0(scene):
    """Where the state stays on g = 0 (a length that is the same), the run is the one
    ``run(y0=...)`` makes, bit for bit."""
    a = scene.run(params={"l": 1.0})
    b = scene.run(y0=scene.y0.copy(), params={"l": 1.0})
    assert a.status == b.status == 0
    assert np.array_equal(a.y, b.y) and np.array_equal(a.t, b.t)
    g = a["x"] ** 2 + a["y"] ** 2 - 1.0
    assert float(np.max(np.abs(g))) < 1e-12
