"""An ensemble refuses the starts a single run refuses on holonomic constraints: off
g = 0, and on g = 0 where dg/dq has not full rank (``ensemble._check_holonomic`` against
``Scene._check_holonomic``, which both end in ``mechanics.holonomic.check``).

The constraint x y = 0 (the two axes) is regular on each axis and singular where they
cross: its gradient (y, x) vanishes at the origin, where the split y_t = -x_t y / x is
singular too; the holonomic refusal comes first, in single runs and ensembles alike.
"""

from __future__ import annotations

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ConstraintError
from jetnh.numeric import Scene

RANK = "rank-deficient Jacobian dg/dq \\(rank {} < {}\\)"


@pytest.fixture(scope="module")
def axes():
    J = jn.JetSpace("x y w")
    x, y, w = J.q
    L = sum(v**2 for v in J.qd) / 2
    system = jn.System(J, L, [x * y])
    return Scene(system, initial={"x": 1.0, "y": 0.0, "w": 0.0, "x_t": 0.5, "w_t": 0.0},
                 t_span=(0.0, 0.01))


def test_a_single_run_refuses_the_crossing(axes):
    with pytest.raises(ConstraintError, match="y0: .*" + RANK.format(0, 1)):
        axes.run(y0={"x": 0.0})


@pytest.mark.parametrize("initial, bad", [
    ({"x": np.array([1.0, 0.0, 2.0])}, 1),                          # columns
    (np.array([[2.0, 0.0, 0.0, 0.5, 0.0], [0.0, 0.0, 0.0, 0.5, 0.0]]), 1),   # rows
    (np.array([[0.0, 0.0, 0.0, 0.5, 0.0]]), 0),                      # one row, at once
])
def test_an_ensemble_refuses_it_as_a_single_run_does(axes, initial, bad):
    with pytest.raises(ConstraintError, match=f"run {bad}: .*" + RANK.format(0, 1)) as got:
        axes.ensemble(initial, save="final")
    assert "split" not in str(got.value)        # not the split's refusal, which follows


def test_regular_starts_on_both_axes_run(axes):
    ens = axes.ensemble({"x": np.array([1.0, 2.0])}, save="final")
    assert (ens.status == 0).all()
    one = axes.run(y0={"x": 2.0}, save="final")
    np.testing.assert_array_equal(ens.y[1, -1], one.y[-1])
    # off g = 0 is refused as before
    with pytest.raises(ConstraintError, match="run 1: .*off the holonomic"):
        axes.ensemble({"x": np.array([1.0, 0.5]), "y": np.array([0.0, 0.5])}, save="final")


def test_dependent_gradients_of_two_constraints():
    J = jn.JetSpace("x y w")
    x, y, w = J.q
    L = sum(v**2 for v in J.qd) / 2
    # y = 0 and x w = 0: gradients (0, 1, 0) and (w, 0, x), independent but where
    # x = w = 0
    system = jn.System(J, L, [y, x * w])
    free = {v.name: 0.0 for v in system.independent_velocities}
    sc = Scene(system, initial={"x": 1.0, "y": 0.0, "w": 0.0, **free})
    start = dict(zip(sc.state_names, sc.y0.tolist()), x=0.0)
    with pytest.raises(ConstraintError, match="y0: .*" + RANK.format(1, 2)):
        sc.run(y0=start)
    with pytest.raises(ConstraintError, match="run 1: .*" + RANK.format(1, 2)):
        sc.ensemble({"x": np.array([2.0, 0.0])}, save="final")
