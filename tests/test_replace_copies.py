"""The copies ``Scene.replace`` makes without building a scene: ``initial`` and ``y0`` made
when first read, checked at once all the same; ``replace(params=...)`` of run-time
parameters only on the same kernels; each equal to the scene built anew."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jetnh import models
from jetnh.errors import ConstraintError, FrozenError, JetnhError
from jetnh.frozen import FrozenDict
from jetnh.numeric import Scene

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    return Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 0.2),
                 runtime_params=["R"], cache=False).compile()


def built(scene, **changes):
    """The scene ``replace`` stands for, built by the constructor."""
    args = dict(params=dict(scene.params), initial=dict(DISK0), t_span=scene.t_span,
                runtime_params=scene.runtime_params, cache=False)
    args.update(changes)
    return Scene(scene.system, scene.principle, **args)


def test_a_copy_makes_initial_and_y0_when_read_and_they_are_frozen(disk):
    disk.run(save="final")
    moved = disk.replace(initial={**DISK0, "phi_t": 1.3})
    assert "initial" not in moved.__dict__ and "y0" not in moved.__dict__
    assert type(moved.initial) is FrozenDict and moved.initial is moved.initial
    assert list(moved.initial)[:6] == list(DISK0)       # the order given, then phi^alpha
    assert moved.y0.tolist() == [*DISK0.values()][:4] + [1.3, 0.7]
    assert not moved.y0.flags.writeable and moved.y0 is moved.y0
    with pytest.raises(FrozenError):
        moved.initial["x"] = 1.0
    with pytest.raises(FrozenError):
        moved.y0 = np.zeros(6)


@settings(deadline=None)
@given(phi_t=st.floats(-5, 5), psi_t=st.floats(-5, 5), x=st.floats(-1e3, 1e3))
def test_a_copy_equals_the_scene_built_anew(disk, phi_t, psi_t, x):
    """Its initial values (the dependent velocities to rounding: the compiled kernels
    against 30 digits), its state bit for bit, and its run bit for bit."""
    ini = {**DISK0, "x": x, "phi_t": phi_t, "psi_t": psi_t}
    moved = disk.replace(initial=ini)
    new = built(disk, initial=ini)
    assert moved.y0.tolist() == new.y0.tolist()
    assert moved.initial.keys() == new.initial.keys()
    for k, v in new.initial.items():
        assert moved.initial[k] == pytest.approx(v, rel=1e-14, abs=1e-300)
    a, b = moved.run(save="final"), new.run(save="final")
    assert np.array_equal(a.y, b.y) and np.array_equal(a.t, b.t)


def test_a_copy_of_a_copy_and_its_pickle_keep_its_values(disk):
    first = disk.replace(initial={**DISK0, "phi_t": 1.3})
    second = first.replace(initial={**DISK0, "psi_t": 0.2}, t_span=(0.0, 0.1))
    assert second.initial["psi_t"] == 0.2 and second.t_span == (0.0, 0.1)
    assert first.replace().initial == first.initial         # made from the lazy ones
    back = pickle.loads(pickle.dumps(second))
    assert back.initial == second.initial and np.array_equal(back.y0, second.y0)
    assert np.array_equal(back.run(save="final").y, second.run(save="final").y)


@pytest.mark.parametrize("bad, error", [
    (float("nan"), JetnhError), (float("inf"), JetnhError), (True, JetnhError),
    ("1", JetnhError)])
def test_a_copy_refuses_what_the_constructor_refuses(disk, bad, error):
    with pytest.raises(error):
        disk.replace(initial={**DISK0, "phi_t": bad})
    with pytest.raises(error):
        built(disk, initial={**DISK0, "phi_t": bad})


def test_a_copy_refuses_a_missing_or_unknown_state(disk):
    with pytest.raises(JetnhError, match="missing initial values: psi_t"):
        disk.replace(initial={k: v for k, v in DISK0.items() if k != "psi_t"})
    with pytest.raises(JetnhError, match="'z'"):
        disk.replace(initial={**{k: v for k, v in DISK0.items() if k != "psi_t"}, "z": 0.0})
    with pytest.raises(ConstraintError):
        disk.replace(initial={**DISK0, "x_t": 100.0})


@pytest.mark.parametrize("R", [0.5, 1.0, 2.5])
def test_replace_of_run_time_parameters_equals_the_scene_built_anew(disk, R):
    moved = disk.replace(params={**disk.params, "R": R})
    new = built(disk, params={**disk.params, "R": R})
    assert moved._memo["key"] == disk._memo["key"]          # the same kernels
    assert moved.params == new.params and moved.p.tolist() == [R] == moved._p.tolist()
    assert moved.initial == new.initial and moved.y0.tolist() == new.y0.tolist()
    a, b = moved.run(save="final"), new.run(save="final")
    assert np.array_equal(a.y, b.y)
    assert np.array_equal(a.y, disk.run(params={"R": R}, save="final").y)
    assert disk.p.tolist() == [1.0]                         # the scene's own unchanged


def test_replace_of_a_compiled_parameter_builds_other_kernels(disk):
    other = disk.replace(params={**disk.params, "I1": 0.7})
    assert other.key != disk.key and other.params["I1"] == 0.7
    for bad in ({**disk.params, "R": "x"}, {**disk.params, "R": float("nan")},
                {**disk.params, "Q": 1.0}):
        with pytest.raises(JetnhError):
            disk.replace(params=bad)


def test_copies_of_a_scene_that_never_ran_share_one_store_of_quick_plans():
    """A loop of ``replace(initial=...).run()`` on a scene that never ran plans once: the
    copies fill and read the scene's store of quick plans, and a copy on another span
    keeps its own."""
    scene = Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 0.2),
                  cache=False).compile()
    first = scene.replace(initial={**DISK0, "phi_t": 1.1})
    first.run(save="final")
    second = scene.replace(initial={**DISK0, "phi_t": 1.2})
    assert second._memo["quick"] is first._memo["quick"] is scene._memo["quick"]
    assert len(scene._memo["quick"]) == 1
    second.run(save="final")
    assert len(scene._memo["quick"]) == 1
    assert "quick" not in scene.replace(t_span=(0.0, 0.1))._memo


def test_replace_params_by_name_equals_by_symbol_and_takes_the_defaults(disk):
    """A dict of floats keyed by name (checked at once) gives the params of the general
    route (keyed by Symbol, or by name with a whole number), in the same order; the
    parameters it omits keep the system's defaults; a bool is refused."""
    R = next(s for s in disk.system.parameters if s.name == "R")
    by_name = disk.replace(params={"R": 1.5})
    assert list(by_name.params.items()) == list(disk.replace(params={R: 1.5}).params.items())
    assert dict(by_name.params) == {**dict(disk.params), "R": 1.5}
    assert disk.replace(params={"R": 2}).params == disk.replace(params={"R": 2.0}).params
    assert by_name.initial == built(disk, params={**disk.params, "R": 1.5}).initial
    with pytest.raises(JetnhError):
        disk.replace(params={"R": True})


def test_replace_of_nothing_keeps_the_state_and_checks_it_again(disk):
    """``replace()`` and ``replace(t_span=...)`` keep the scene's states (in the order of
    ``state_names``, the dependent velocities after them) and run as the scene does."""
    same = disk.replace()
    assert list(same.initial) == list(disk.state_names) + list(disk.dependent_velocities)
    assert same.initial == disk.initial and same.y0.tolist() == disk.y0.tolist()
    assert np.array_equal(same.run(save="final").y, disk.run(save="final").y)
    assert disk.replace(t_span=(0.0, 0.1)).initial == disk.initial
