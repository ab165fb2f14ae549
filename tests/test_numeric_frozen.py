"""Scene and Trajectory are immutable: assignments raise, and what they compute lazily
(kernels' key, compiled events, derived columns) never lands in their ``__dict__``."""

import copy
import json
import pickle

import numpy as np
import pytest

from jetnh.errors import FrozenError, JetnhError
from jetnh.models import appell_hamel
from jetnh.numeric import Event, Scene
from jetnh.frozen import Frozen, memo


@pytest.fixture(scope="module")
def scene():
    return Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                 t_span=(0.0, 0.5), cache=False)


def snapshot(obj):
    return {k: id(v) for k, v in vars(obj).items()}


def test_scene_refuses_assignment(scene):
    for name, value in (("t_span", (0.0, 2.0)), ("principle", "vakonomic"), ("new", 1)):
        with pytest.raises(FrozenError, match="Scene is immutable.*replace"):
            setattr(scene, name, value)
    with pytest.raises(AttributeError):       # FrozenError is an AttributeError too
        del scene.params
    with pytest.raises(JetnhError):
        scene.key = "x"
    assert scene.t_span == (0.0, 0.5) and not hasattr(scene, "new")


def test_scene_mappings_are_read_only(scene):
    params, initial = dict(scene.params), dict(scene.initial)
    writes = (lambda d: d.__setitem__("x", 1.0), lambda d: d.__delitem__("x"),
              lambda d: d.update(x=1.0), lambda d: d.pop("x"), lambda d: d.setdefault("q", 1),
              lambda d: d.clear(), lambda d: d.popitem())
    for mapping in (scene.initial, scene.params, scene.integrals):
        for write in writes:
            with pytest.raises(FrozenError, match="read-only.*Scene.replace"):
                write(mapping)
    with pytest.raises(FrozenError):
        scene.initial["x"] += 1.0
    assert dict(scene.params) == params and dict(scene.initial) == initial
    # reads as a dict: lookups, copies, JSON, pickling, a new scene from it
    assert scene.initial["x_t"] == 0.6 and {**scene.initial} == initial
    assert json.loads(json.dumps(scene.initial)) == initial
    back = pickle.loads(pickle.dumps(scene.initial))
    assert back == initial and type(back) is type(scene.initial)
    moved = scene.replace(initial={**scene.initial, "x": 1.0})
    assert moved.initial["x"] == 1.0 and scene.initial["x"] == 0.0


def test_scene_lazy_state_not_in_dict(scene):
    before = snapshot(scene)
    key = scene.key
    x_t = scene.system.J.qd[0]
    ev = [Event(x_t - 0.3, name="slow")]
    traj = scene.run(events=ev)
    again = scene.run(events=ev)
    assert snapshot(scene) == before
    assert scene.key is key
    assert scene.compile_events(ev) is scene.compile_events(ev)   # compiled once
    np.testing.assert_array_equal(traj.t_events[0], again.t_events[0])
    assert scene.replace(t_span=(0.0, 1.0)).t_span == (0.0, 1.0)
    assert scene.t_span == (0.0, 0.5)
    # a pickled scene keeps its kernels' key (plain data), not its compiled events
    back = pickle.loads(pickle.dumps(scene))
    assert back._memo == {"key": key}
    with pytest.raises(FrozenError):
        back.t_span = (0.0, 1.0)


def test_trajectory_refuses_assignment_and_keeps_dict(scene):
    traj = scene.run()
    before = snapshot(traj)
    aux, diag = traj.aux, traj.diagnostics
    assert traj.aux is aux and traj.diagnostics is diag
    assert snapshot(traj) == before
    for name in ("t", "y", "method", "aux", "diagnostics"):
        with pytest.raises(FrozenError, match="Trajectory is immutable"):
            setattr(traj, name, None)
    # the derived columns are the kernels' values at the rows
    out = np.empty_like(aux)
    traj._kernels.aux_rows(traj.t, traj.y, traj._p, out)
    np.testing.assert_array_equal(out, aux)


class Point(Frozen):
    def __init__(self, x):
        self.x = x

    @memo
    def norm(self):
        return abs(self.x)


class Labelled(Point):
    def __init__(self, x, label):
        super().__init__(x)
        self.label = label          # the base's __init__ must not freeze too early


class Plain(Point):
    pass


def test_frozen_subclasses_copies_and_pickles():
    p = Labelled(-2.0, "a")
    assert (p.x, p.label, p.norm) == (-2.0, "a", 2.0)
    with pytest.raises(FrozenError):
        p.label = "b"
    with pytest.raises(FrozenError):
        Plain(1.0).x = 2.0
    for q in (copy.copy(p), pickle.loads(pickle.dumps(p))):
        assert (q.x, q.label, q.norm) == (-2.0, "a", 2.0)
        assert q._memo is not p._memo
        with pytest.raises(FrozenError):
            q.x = 0.0


def test_made_reads_the_dict_first_and_memo_refuses_assignment():
    """``made`` and ``memo`` are one descriptor: a value the object holds in its
    ``__dict__`` is read first (``made``), else made once, kept and handed out
    read-only; ``memo`` cannot be set."""
    import numpy as np

    from jetnh.errors import FrozenError
    from jetnh.frozen import Frozen, made, memo

    class Thing(Frozen):
        def __init__(self, held=None):
            if held is not None:
                self.value = held

        @made
        def value(self):
            return np.arange(3.0)

        @memo
        def other(self):
            return [1]

    made_now = Thing()
    assert made_now.value is made_now.value and not made_now.value.flags.writeable
    assert Thing(np.zeros(2)).value.tolist() == [0.0, 0.0]
    with pytest.raises(FrozenError):
        made_now.other = [2]
    assert made_now.other == [1]
