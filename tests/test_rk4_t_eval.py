"""rk4 takes no ``t_eval`` (its compiled loop writes a row at every step or at the
ends, in single runs and ensembles alike): the refusal says why and what to do, and each
thing it offers works (``traj.at`` on its cubic Hermite interpolant, times that are
steps, the adaptive methods with t_eval)."""

import numpy as np
import pytest

import jetnh as jn

J = jn.JetSpace("x")
(X,), (XT,) = J.q, J.qd
OSC = jn.Scene(jn.System(J, XT**2 / 2 - X**2 / 2), initial={"x": 1.0, "x_t": 0.0},
               t_span=(0.0, 3.0))          # x = cos t
TIMES = [0.5, 1.25, 2.75]


def test_the_refusal_says_why_and_what_to_do():
    with pytest.raises(jn.JetnhError) as single:
        OSC.run(method="rk4", n_steps=120, t_eval=TIMES)
    text = str(single.value)
    for part in ("takes no t_eval", "writes a row at every step", "single runs and ensembles",
                 "traj.at(times)", "O(h^4)", "t0 + k (t1 - t0) / n_steps",
                 "dop853, dopri5 or radau with t_eval"):
        assert part in text, part
    with pytest.raises(jn.JetnhError, match="t_eval needs dense output"):
        OSC.ensemble(initial={"x": [1.0, 0.5]}, method="rk4", n_steps=120, t_eval=TIMES)


def test_what_it_offers_works():
    tr = OSC.run(method="rk4", n_steps=120)
    at = tr.at(TIMES)["x"].to_numpy()
    assert np.max(np.abs(at - np.cos(TIMES))) < 1e-7          # h = 0.025: O(h^4)
    steps = tr.t[np.isin(tr.t, TIMES)]                          # times that are steps
    assert list(steps) == TIMES
    assert np.array_equal(tr.at(TIMES).to_numpy(), tr.y[np.isin(tr.t, TIMES)])
    for method in ("dop853", "dopri5", "radau"):
        rows = OSC.run(method=method, t_eval=TIMES, rtol=1e-10, atol=1e-12)
        assert np.max(np.abs(rows["x"] - np.cos(TIMES))) < 1e-8
