"""A Trajectory survives pickling (results sent through multiprocessing or dask): every
field equal, read-only and immutable after unpickling, evaluated between its rows in a
fresh process from its scene's kernels; its diagnostics print within a bounded size
whatever the number of split switches."""

import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import FrozenError, JetnhError
from jetnh.models import knife_edge
from jetnh.numeric import Event
from jetnh.numeric.methods._common import EVENT, SINGULAR

TOL = dict(rtol=1e-9, atol=1e-12)


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0),
                    t_span=(0.0, 3.0))


@pytest.fixture(scope="module")
def runs(knife):
    x = knife.system.J.q[0]
    return {
        "plain": knife.run(split="fixed", t_span=(0.0, 0.5), **TOL),
        "final": knife.run(save="final", split="fixed", t_span=(0.0, 0.5)),
        "switching": knife.run(**TOL),
        "singular": knife.run(split="fixed", **TOL),
        "event": knife.run(events=[Event(x - 0.05, terminal=True)], split="fixed",
                           t_span=(0.0, 0.5), **TOL),
        "sensitivities": knife.run(sensitivities=True, split="fixed", t_span=(0.0, 0.5),
                                   **TOL),
        "dla": knife.run(method="dla", n_steps=50, t_span=(0.0, 0.5)),
    }


def _same(a, b):
    """Equal values, NaN equal to NaN, through dicts, lists and tuples."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k])
                                                                  for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (a != a and b != b)
    return a == b


FIELDS = ("t", "y", "method", "status", "stop_reason", "success", "names", "event_names",
          "t_events", "y_events", "events", "switches", "singularity", "final",
          "energy", "residual", "holonomic_residual", "power", "sensitivity_columns")


def test_every_field_survives_pickling_read_only(runs):
    # the runs: an event run stopped at its event, a singular one at its indicator
    assert runs["event"].status == EVENT and runs["singular"].status == SINGULAR
    assert len(runs["switching"].switches) >= 1 and runs["dla"]._own
    for kind, tr in runs.items():
        back = pickle.loads(pickle.dumps(tr))
        for name in FIELDS:
            assert _same(getattr(tr, name), getattr(back, name)), (kind, name)
        for name in tr.names:
            assert np.array_equal(tr[name], back[name]), (kind, name)
        assert _same(tr.diagnostics.as_dict(), back.diagnostics.as_dict()), kind
        assert back.layout == tr.layout and back.scene.state_names == tr.scene.state_names
        if kind == "sensitivities":
            assert np.array_equal(back.sensitivities, tr.sensitivities)
            assert not back.sensitivities.flags.writeable
        if kind != "dla":
            assert np.array_equal(back.aux, tr.aux) and not back.aux.flags.writeable
        # read-only and immutable as the original
        arrays = [back.t, back.y, *back.t_events, *back.y_events,
                  *(back[n] for n in back.names)]
        assert not any(a.flags.writeable for a in arrays), kind
        with pytest.raises(FrozenError):
            back.status = 3
        with pytest.raises(FrozenError):
            back.method = "x"
        if back.singularity is not None:
            with pytest.raises(FrozenError):
                back.singularity["t"] = 0.0


def test_an_unpickled_run_is_evaluated_between_its_rows(runs, tmp_path):
    """``at()`` after unpickling: in this process, and in a fresh one (the kernels
    loaded from the scene's cache), bit for bit the original's; a run that changed
    split refuses, saying why."""
    tr = runs["plain"]
    times = np.linspace(0.0, 0.5, 7)
    want = tr.at(times).to_numpy()
    assert np.array_equal(pickle.loads(pickle.dumps(tr)).at(times).to_numpy(), want)
    sens = runs["sensitivities"]
    assert np.array_equal(pickle.loads(pickle.dumps(sens)).at(times).to_numpy(),
                          sens.at(times).to_numpy())
    with pytest.raises(JetnhError, match="changed split and was unpickled"):
        pickle.loads(pickle.dumps(runs["switching"])).at([0.1])
    (tmp_path / "traj.pkl").write_bytes(pickle.dumps(tr))
    np.save(tmp_path / "times.npy", times)
    child = textwrap.dedent(f"""
        import pickle, numpy as np
        tr = pickle.loads(open({str(tmp_path / 'traj.pkl')!r}, 'rb').read())
        times = np.load({str(tmp_path / 'times.npy')!r})
        np.save({str(tmp_path / 'at.npy')!r}, tr.at(times).to_numpy())
        np.save({str(tmp_path / 'aux.npy')!r}, tr.aux)
    """)
    subprocess.run([sys.executable, "-c", child], check=True, env=dict(os.environ),
                   timeout=600)
    assert np.array_equal(np.load(tmp_path / "at.npy"), want)
    assert np.array_equal(np.load(tmp_path / "aux.npy"), tr.aux)


def test_the_repr_of_many_split_switches_is_bounded(knife):
    """A run with a hundred switches prints them as their count, the first and the
    last, no longer than a run with a few."""
    few = knife.run(**TOL)
    many = knife.run(t_span=(0.0, 60.0), **TOL)
    assert len(many.switches) >= 100 > len(few.switches) >= 2
    for tr in (few, many):
        text, summary = repr(tr.diagnostics), str(tr.diagnostics)
        n = len(tr.switches)
        first, last = tr.switches[0], tr.switches[-1]
        line = (f"{n} split switches, the first at t = {first['t']:.6g} "
                f"({', '.join(first['from'])} -> {', '.join(first['to'])}), the last at "
                f"t = {last['t']:.6g} ({', '.join(last['from'])} -> "
                f"{', '.join(last['to'])})")
        assert f"switches=<{line}>" in text and line in summary
        assert f"{n} split switches" in repr(tr)
        assert "[" not in text.split("switches=")[1]
    assert len(repr(many.diagnostics)) <= len(repr(few.diagnostics)) + 40
    assert len(repr(many)) <= len(repr(few)) + 40
    assert "switches=[]" in repr(knife.run(split="fixed", t_span=(0.0, 0.5)).diagnostics)
