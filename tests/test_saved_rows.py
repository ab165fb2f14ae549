"""``Diagnostics.saved`` is the output mode the run was made with, for every method: not
guessed from the number of rows against the number of steps (a scipy run with t_eval
stores no step; a radau run with a two-point t_eval, or a dla run of one step with
save="final", holds two rows that are neither its steps nor its ends by accident)."""

import pickle

import numpy as np
import pytest

import jetnh as jn
from jetnh import models


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(models.get("knife_edge"), "chetaev",
                    initial=models.initial("knife_edge"), t_span=(0, 1.2))


@pytest.mark.parametrize("method", ["scipy-RK45", "radau", "dop853"])
@pytest.mark.parametrize("t_eval", [[0.0, 1.2], [0.0, 0.4, 0.8, 1.2]])
def test_t_eval_runs_say_t_eval(knife, method, t_eval):
    tr = knife.run(method=method, t_eval=t_eval)
    d = tr.diagnostics
    assert (d.saved, d.rows, len(tr)) == ("t_eval", len(t_eval), len(t_eval))
    assert f"over {len(t_eval)} rows (t_eval)" in str(d)
    assert pickle.loads(pickle.dumps(tr)).diagnostics.saved == "t_eval"


@pytest.mark.parametrize("method", ["scipy-RK45", "radau", "dop853"])
def test_every_step(knife, method):
    d = knife.run(method=method).diagnostics
    assert d.saved == "steps" and "these figures" not in str(d)


@pytest.mark.parametrize("save", ["steps", "final"])
@pytest.mark.parametrize("n_steps", [1, 2, 5])
def test_discrete_runs_say_what_they_kept(knife, save, n_steps):
    tr = knife.run(method="dla", n_steps=n_steps, save=save)
    d = tr.diagnostics
    assert d.saved == save and d.steps == n_steps
    assert len(tr) == (n_steps + 1 if save == "steps" else 2)


def test_rows_sampled_between_the_steps_are_not_the_steps(knife):
    from jetnh.numeric.dense import resampled

    tr = knife.run(method="rk4", n_steps=20)
    smooth = resampled(tr, points=100)
    assert len(smooth) > len(tr)
    assert smooth.diagnostics.saved == "t_eval"


def test_saved_is_checked():
    with pytest.raises(jn.errors.ArgumentError, match="saved must be one of"):
        jn.numeric.trajectory.Trajectory(None, [0.0], [[0.0]], np.zeros(0), method="x",
                                         status=0, stop_reason="", steps=0, rejected=0,
                                         nfev=0, wall_time=0.0, kernels=None,
                                         saved="all")
