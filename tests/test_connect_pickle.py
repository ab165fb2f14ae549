"""A Connection survives pickling (results sent through multiprocessing or dask): every
field equal, frozen after unpickling, its verdicts computed there on first access
equal to those of the original (the same rows, the same compiled kernels reloaded from
the scene's cache), also in a fresh process; a motion that changed split (the damped
sleigh past cos th = 0) carries its verdicts computed before pickling."""

import dataclasses
import os
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import JetnhError
from jetnh.models import get

sys.path.insert(0, str(Path(__file__).parent))
from damped_sleigh import ORIGIN, PARAMS, damped_sleigh  # noqa: E402

O = {"x": 0.0, "y": 0.0, "z": 0.0}
END = {"x": 1.0, "y": 0.5, "z": 0.2}
FIELDS = ("initial", "residual", "principle", "unknowns", "rank", "singular_values",
          "iterations", "_columns", "_rcond", "_run", "conditions", "route", "search")
VERDICTS = ("cost", "gramian_ratio", "normal", "conjugate_times", "legendre", "minimizer")


def _same_fields(a, b):
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, type(a.initial)):
            x, y = dict(x), dict(y)
        assert x == y, name
    ta, tb = a.trajectory, b.trajectory
    assert np.array_equal(ta.t, tb.t) and np.array_equal(ta.y, tb.y)
    assert np.array_equal(ta.sensitivities, tb.sensitivities)
    assert ta.scene.state_names == tb.scene.state_names and ta.status == tb.status


@pytest.fixture(scope="module")
def heisenberg():
    return jn.connect(get("heisenberg"), "vakonomic", O, END, (0.0, 1.0))


def test_a_connection_round_trips_and_rebuilds_its_verdicts(heisenberg):
    c = heisenberg
    data = pickle.dumps(c)              # before any verdict: none travels
    back = pickle.loads(data)
    assert not any(name in back.__dict__ for name in ("cost", "trajectory", "_samples"))
    _same_fields(c, back)
    for name in VERDICTS:               # computed afresh on each side: the same bits
        assert getattr(back, name) == getattr(c, name), name
    assert repr(back) == repr(c)
    # frozen as before
    with pytest.raises(dataclasses.FrozenInstanceError):
        back.residual = 0.0
    with pytest.raises(TypeError):
        back.initial["x_t"] = 0.0
    assert not back.trajectory.y.flags.writeable
    # pickled again after its verdicts: they travel as they are
    again = pickle.loads(pickle.dumps(back))
    assert all(name in again.__dict__ for name in ("cost", "conjugate_times", "legendre"))
    _same_fields(c, again)
    assert all(getattr(again, n) == getattr(c, n) for n in VERDICTS)


def test_a_motion_that_changed_split_carries_its_verdicts():
    c = jn.connect(damped_sleigh(), "vakonomic", ORIGIN, {"x": 0.2, "y": 0.5, "th": 2.0},
                   (0.0, 1.0), params=PARAMS)
    assert c.trajectory.switches
    back = pickle.loads(pickle.dumps(c))
    _same_fields(c, back)
    assert all(name in back.__dict__ for name in ("cost", "gramian_ratio",
                                                  "conjugate_times", "legendre"))
    assert all(getattr(back, n) == getattr(c, n) for n in VERDICTS)
    with pytest.raises(JetnhError, match="changed split and was unpickled"):
        back.trajectory.at([0.5])


def test_a_fresh_process_computes_the_verdicts(tmp_path):
    c = jn.connect(get("heisenberg"), "vakonomic", O, END, (0.0, 1.0))
    assert "cost" not in c.__dict__           # none computed: none travels
    path = tmp_path / "c.pkl"
    path.write_bytes(pickle.dumps(c))
    code = textwrap.dedent(f"""
        import pickle
        c = pickle.loads(open({str(path)!r}, "rb").read())
        print(repr(c.cost), repr(c.gramian_ratio), c.conjugate_times, repr(c.legendre))
    """)
    env = {**os.environ, "PYTHONPATH": str(Path(jn.__file__).parents[1])}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=300, check=True).stdout.split()
    assert out == [repr(c.cost), repr(c.gramian_ratio), str(c.conjugate_times),
                   repr(c.legendre)]
