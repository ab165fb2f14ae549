"""A run whose options are numbers and strings finds its plan under those options and
their types (``Scene.run``): the same rows as the general path, bit for bit, and every
bad value refused with the message it gets on a scene that never ran, also right after
a run with a value equal to it (``True == 1``, ``1e-3 + 0j == 1e-3``)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene, StepControl

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    return Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 0.5),
                 cache=False).compile()


def same(a, b):
    assert a.t.tobytes() == b.t.tobytes() and a.y.tobytes() == b.y.tobytes()
    assert (a.status, a.stop_reason) == (b.status, b.stop_reason)
    da, db = a.diagnostics, b.diagnostics
    assert (da.steps, da.rejected, da.rhs_evaluations) == (db.steps, db.rejected,
                                                           db.rhs_evaluations)


OPTIONS = [
    dict(method="dop853", save="final", rtol=1e-3, atol=1e-6, split="fixed",
         singular="ignore", t_span=(0, 1e-6)),
    dict(method="dopri5", rtol=1e-7, atol=1e-9, t_span=(0.0, 0.3)),
    dict(method="rk4", n_steps=20, save="final"),
    dict(method="radau", rtol=1e-6, max_newton=5, singular_tol=1e-8),
    dict(max_steps=7, first_step=1e-3, max_step=0.01),
    dict(method="dla", h=0.05, t_span=(0.0, 0.25)),
    dict(method="scipy-RK45", rtol=1e-6, save="final"),
]


@pytest.mark.parametrize("options", OPTIONS)
def test_the_kept_plan_runs_as_the_general_path(disk, options):
    """The run of the memo (twice: planned, then found) equals the run planned under
    the long key (the default ``StepControl`` given as a value takes the general
    path)."""
    first, again = disk.run(**options), disk.run(**options)
    general = disk.run(step=StepControl(), **options)
    same(first, again)
    same(first, general)


def test_numbers_of_other_types_give_the_same_run(disk):
    """1 and 1.0, numpy's float and Python's: one run (each under its own key)."""
    a = disk.run(method="rk4", n_steps=10, t_span=(0, 1), save="final")
    b = disk.run(method="rk4", n_steps=10.0, t_span=(0.0, 1.0), save="final")
    c = disk.run(method="rk4", n_steps=np.int64(10), t_span=(np.float64(0), 1.0),
                 save="final")
    same(a, b)
    same(a, c)
    d = disk.run(rtol=np.float64(1e-7), atol=1e-10)
    same(d, disk.run(rtol=1e-7, atol=1e-10))


def message(scene, options):
    with pytest.raises(JetnhError) as info:
        scene.run(**options)
    return str(info.value)


# (a run that is accepted, then a value equal to one of its own that is refused)
EQUAL_BUT_REFUSED = [
    (dict(max_steps=1, save="final"), dict(max_steps=True, save="final")),
    (dict(singular_tol=0), dict(singular_tol=False)),
    (dict(singular_tol=0.0), dict(singular_tol=0j)),
    (dict(t_span=(0, 0.5)), dict(t_span=(False, 0.5))),
    (dict(t_span=(0, 0.5)), dict(t_span=(0, 0.5 + 0j))),
    (dict(rtol=1e-3), dict(rtol=1e-3 + 0j)),
    (dict(atol=1), dict(atol=True)),
    (dict(method="rk4", n_steps=1), dict(method="rk4", n_steps=True)),
    (dict(first_step=1.0), dict(first_step=np.True_)),
]


@pytest.mark.parametrize("good, bad", EQUAL_BUT_REFUSED)
def test_a_value_equal_to_a_planned_one_is_still_refused(disk, good, bad):
    assert good == bad                      # (the trap: equal as keys, hashes equal)
    fresh = disk.replace(t_span=(0.0, 0.75))      # (a scene that never ran these)
    expected = message(fresh, bad)
    disk.run(**good)
    disk.run(**good)
    assert message(disk, bad) == expected


@pytest.mark.parametrize("bad", [
    dict(t_span=(0.0, 0.5, 1.0)), dict(t_span=(0.0,)), dict(t_span=(1.0, 1.0)),
    dict(save="all"), dict(singular="skip"), dict(split="never"), dict(rtoll=1e-3),
    dict(method="dop8"), dict(rtol=[1e-3]), dict(max_steps=0), dict(n_steps=5),
])
def test_bad_options_are_refused_on_the_quick_path(disk, bad):
    disk.run(save="final")
    with pytest.raises(JetnhError):
        disk.run(**bad)
    with pytest.raises(JetnhError):     # (and again: nothing was kept for them)
        disk.run(**bad)


def test_a_time_span_given_as_a_list_or_an_iterator_runs_as_a_tuple(disk):
    a = disk.run(t_span=(0.0, 0.2), save="final")
    same(a, disk.run(t_span=[0.0, 0.2], save="final"))
    same(a, disk.run(t_span=iter((0.0, 0.2)), save="final"))


KEYWORDS = st.fixed_dictionaries({}, optional={
    "method": st.sampled_from(["dop853", "dopri5"]),
    "save": st.sampled_from(["steps", "final"]),
    "rtol": st.sampled_from([1e-4, 1e-6, 1e-8]),
    "atol": st.sampled_from([1e-8, 1e-10, 1]),
    "singular": st.sampled_from(["stop", "ignore"]),
    "split": st.sampled_from(["switch", "fixed"]),
    "t_span": st.sampled_from([(0, 0.1), (0.0, 0.2), (0.1, 0.0)]),
    "max_step": st.sampled_from([0.01, 1]),
    "singular_tol": st.sampled_from([1e-10, 0.0]),
})


@settings(deadline=None)
@given(KEYWORDS, st.booleans())
def test_any_keywords_in_any_order_run_as_the_general_path(disk, options, reverse):
    """Random options, in either order: the kept plan's run is the general path's."""
    items = list(options.items())
    ordered = dict(reversed(items) if reverse else items)
    same(disk.run(**ordered), disk.run(step=StepControl(), **options))


def test_an_ensemble_refuses_options_equal_to_planned_ones(disk):
    """Options are equal only with their types (``Options.__eq__``): an ensemble's plan
    of ``max_steps=1`` is not that of ``max_steps=True``, which is refused."""
    from jetnh.numeric.options import options

    assert options(max_steps=1) != options(max_steps=True)
    assert options(rtol=1e-3, max_steps=1) == options(max_steps=1, rtol=1e-3)
    initial = {"phi_t": [0.9, 1.1]}
    disk.ensemble(initial=initial, save="final", max_steps=1)
    with pytest.raises(JetnhError, match="max_steps"):
        disk.ensemble(initial=initial, save="final", max_steps=True)


@pytest.mark.parametrize("options", [
    dict(save="final"), dict(method="radau", rtol=1e-6), dict(method="dopri5"),
    dict(method="scipy-RK45", rtol=1e-6, save="final"),
    dict(method="rk4", h=0.01, save="final"), dict(t_eval=(0.0, 0.05)),
    dict(singular="ignore", split="fixed", rtol=1e-7),
])
def test_a_loop_over_time_spans_runs_as_scenes_of_those_spans(disk, options):
    """Runs on many spans (a plan of the same options taken over on another span where
    only its ends depend on it: ``solve.on_span``) equal the runs of scenes built with
    those spans, bit for bit; the fixed step of ``h`` and the points of ``t_eval`` are
    those of each span."""
    for T in (0.1, 0.15, 0.05, 0.15):
        here = disk.run(t_span=(0.0, T), **options)
        built = Scene(disk.system, "chetaev", initial=DISK0, t_span=(0.0, T),
                      cache=False).run(**options)
        same(here, built)
        assert here.t[-1] == (T if "t_eval" not in options else 0.05)
    if "rk4" in options.values():
        assert disk.run(t_span=(0.0, 0.2), **options).diagnostics.steps == 20
    with pytest.raises(JetnhError):
        disk.run(t_span=(0.1, 0.1), **options)


def test_a_new_time_span_is_not_planned_again(disk, monkeypatch):
    """Options planned on one span are taken over on the next (no new ``solve.plan``);
    options whose plan depends on the span (a fixed step ``h``) are planned anew."""
    from jetnh.numeric import solve

    disk = Scene(disk.system, "chetaev", initial=DISK0, cache=False)    # (its own plans)
    made = []
    plan = solve.plan
    monkeypatch.setattr(solve, "plan", lambda *a, **k: made.append(1) or plan(*a, **k))
    for T in (0.31, 0.32, 0.33):
        disk.run(t_span=(0.0, T), rtol=1e-5, max_step=0.02)
    assert len(made) == 1
    for T in (0.31, 0.32):
        disk.run(t_span=(0.0, T), method="rk4", h=0.01)
    assert len(made) == 3


def test_times_are_keyed_by_their_values(disk):
    """An array of times finds the plan of equal times, not that of the same array
    since changed; times as objects or integers run as their floats."""
    te = np.linspace(0.0, 0.5, 6)
    a = disk.run(t_eval=te)
    same(a, disk.run(t_eval=te, step=StepControl()))
    te[3] = 0.31                            # (the caller's array, changed in place)
    b = disk.run(t_eval=te)
    assert b.t[3] == 0.31 and a.t[3] == np.linspace(0.0, 0.5, 6)[3]
    same(b, disk.run(t_eval=te.astype(object)))
    same(disk.run(t_eval=np.array([0, 1]) / 2), disk.run(t_eval=np.array([0.0, 0.5])))
    with pytest.raises(JetnhError):
        disk.run(t_eval=np.array([0.0, 0.7]))


def test_a_switching_run_on_new_spans_runs_as_scenes_of_those_spans():
    """A run that changes split (``numeric.atlas``) taken over on other spans: the same
    switches and rows as scenes built with those spans."""
    from jetnh.models import knife_edge

    ini = dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0)
    knife = Scene(knife_edge(), "chetaev", initial=ini, t_span=(0.0, 1.0))
    for T in (2.0, 1.5, 2.0):
        here = knife.run(t_span=(0.0, T), rtol=1e-8)
        built = Scene(knife_edge(), "chetaev", initial=ini, t_span=(0.0, T)).run(rtol=1e-8)
        assert len(here.switches) >= 1 and here.switches == built.switches
        same(here, built)


def test_tolerances_per_state_as_a_list_are_planned_once(disk, monkeypatch):
    """``atol`` as a list (one value per state) is a key too (typed entries): planned
    once, refused with its bool entries."""
    from jetnh.numeric import solve

    made = []
    plan = solve.plan
    monkeypatch.setattr(solve, "plan", lambda *a, **k: made.append(1) or plan(*a, **k))
    atol = [1e-10] * len(disk.state_names)
    same(disk.run(atol=atol, rtol=1e-6), disk.run(atol=np.array(atol), rtol=1e-6))
    disk.run(atol=atol, rtol=1e-6)
    assert len(made) == 2                   # (the list and the array)
    disk.run(atol=[1] * len(disk.state_names), rtol=1e-6)         # (an int is taken...)
    with pytest.raises(JetnhError):
        disk.run(atol=[True] * len(disk.state_names), rtol=1e-6)    # (...a bool not)
