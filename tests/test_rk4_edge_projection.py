"""rk4 on a holonomic system that changes chart: the edge judged before the projection.

A fixed step one of whose stages is past the chart's edge can end anywhere (the chart's
right-hand side has a pole past it); the projection onto the holonomic constraint then
pulled that end back onto the circle, where its edge value could look calm, so the
stages were never checked (``loop.past_edge``) and the garbage went on: the rotating
Cartesian pendulum at n = 300 ended NONFINITE, at v0 = 12, n = 200 it stopped "singular"
with rows up to 3e299 off the circle.  Coarse runs like these are far from the motion (rk4's
own error at 1.3 rad a step); what is asserted is that they are runs of the method:
finite, on the circle, through every switch to the end, energy on the trend of the
neighbouring runs that never met the fault.
"""

import numpy as np
import pytest

import jetnh as jn

from holonomic_systems import pendulum_xy

G = 9.81


def _pendulum(v0, t1):
    return jn.Scene(pendulum_xy(), params={"l": 1.0, "G": G},
                    initial={"x": 0.0, "y": -1.0, "x_t": v0}, t_span=(0, t1))


def _energy_error(tr, v0):
    energy = (tr["x_t"] ** 2 + tr["y_t"] ** 2) / 2 + G * tr["y"]
    return float(np.max(abs(energy - (v0 ** 2 / 2 - G))))


@pytest.mark.parametrize("v0, t1, n, coarser, finer", [(8.0, 50.0, 300, 250, 350),
                                                      (12.0, 20.0, 200, 175, 225)])
def test_a_garbage_end_is_not_projected_onto_the_circle(v0, t1, n, coarser, finer):
    sc = _pendulum(v0, t1)
    tr = sc.run(method="rk4", n_steps=n)
    assert tr.success and tr.t[-1] == t1 and len(tr.switches) > 50
    xy = np.column_stack([tr["x"], tr["y"], tr["x_t"], tr["y_t"]])
    assert np.all(np.isfinite(xy))
    assert np.max(abs(tr["x"] ** 2 + tr["y"] ** 2 - 1.0)) < 1e-12
    # energy: rk4 loses it at this step size, gains none, and loses less with more steps
    energy = (tr["x_t"] ** 2 + tr["y_t"] ** 2) / 2 + G * tr["y"]
    assert np.max(energy) < (v0 ** 2 / 2 - G) + 1.0
    err = {k: _energy_error(sc.run(method="rk4", n_steps=k), v0) for k in (coarser, finer)}
    assert err[finer] < _energy_error(tr, v0) < err[coarser]
