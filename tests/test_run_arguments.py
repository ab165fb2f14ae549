"""Every argument of Scene.run and of the ensembles is checked before compiled code sees
it; Ctrl-C and the wall-clock budget stop compiled loops."""

import os
import select
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import jetnh as jn
from jetnh import models
from jetnh.errors import ConstraintError, JetnhError
from jetnh.numeric import STOPPED, Scene

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    """The catalogue's vertical rolling disk, R a run-time parameter."""
    return Scene(models.get("rolling_disk"), "chetaev", params={"R": 1.5}, initial=DISK0,
                 t_span=(0.0, 2.0), runtime_params=["R"], cache=False).compile()


def same(a, b):
    assert np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y)


# ---------------------------------------------------------------------- y0 and params
def test_state_of_wrong_length_is_refused(disk):
    n = len(disk.state_names)
    for bad in (disk.y0[:-1], np.append(disk.y0, 1.0), np.zeros(0), disk.y0[:1]):
        with pytest.raises(JetnhError, match=f"y0 has {bad.size} values, but this scene has "
                                             f"{n}.*state_names: x, y, phi, psi"):
            disk.run(y0=bad)
    with pytest.raises(JetnhError, match="1-d"):
        disk.run(y0=np.tile(disk.y0, (2, 1)))


@pytest.mark.parametrize("bad, match", [
    ([np.nan, 0, 0, 0, 1, 0.7], "non-finite value"),
    (["0", "0", "0", "0", "1", "0.7"], "real numbers"),
    ([1j, 0, 0, 0, 1, 0.7], "real numbers"),
    ([sp.Symbol("a"), 0, 0, 0, 1, 0.7], "must be a number"),
    (np.ones(6, dtype=bool), "real numbers"),
    ("x=1", "dict keyed by name or a sequence"),
    (3.0, "dict keyed by name or a sequence"),
])
def test_state_of_wrong_type_is_refused(disk, bad, match):
    with pytest.raises(JetnhError, match=match):
        disk.run(y0=bad)


def test_state_by_name_symbol_or_sequence(disk):
    J = disk.system.J
    ref = disk.replace(initial={**DISK0, "phi_t": 0.5}).run()
    same(disk.run(y0={"phi_t": 0.5}), ref)
    same(disk.run(y0={J.qd[2]: 0.5}), ref)
    seq = [{**DISK0, "phi_t": 0.5}[n] for n in disk.state_names]
    same(disk.run(y0=seq), ref)
    same(disk.run(y0=tuple(seq)), ref)
    same(disk.run(y0=np.array(seq)), ref)
    same(disk.run(y0=[sp.Float(v) for v in seq]), ref)
    with pytest.raises(JetnhError, match="'z', which is not a state"):
        disk.run(y0={"z": 1.0})


def test_state_with_dependent_velocity_is_checked(disk):
    x_t = 1.5 * np.cos(0.4) * 1.0
    same(disk.run(y0={"x_t": x_t}), disk.run())
    with pytest.raises(ConstraintError, match="y0 gives x_t = 3.0 but the constraints"):
        disk.run(y0={"x_t": 3.0})


def test_runtime_parameters_by_name_symbol_or_sequence(disk):
    R = [s for s in disk.system.parameters if s.name == "R"][0]
    ref = disk.run(params=np.array([2.0]))
    same(disk.run(params={"R": 2.0}), ref)
    same(disk.run(params={R: 2.0}), ref)
    same(disk.run(params=[2.0]), ref)
    same(disk.run(params=(2,)), ref)
    same(disk.run(params={}), disk.run())
    with pytest.raises(JetnhError, match="params has 2 values, but this scene has 1"):
        disk.run(params=[2.0, 1.0])
    with pytest.raises(JetnhError, match="params has 0 values"):
        disk.run(params=np.zeros(0))
    with pytest.raises(JetnhError, match="'I1' is compiled into.*runtime_params"):
        disk.run(params={"I1": 1.0})
    with pytest.raises(JetnhError, match="'Q', which is not a parameter"):
        disk.run(params={"Q": 1.0})
    with pytest.raises(JetnhError, match="finite"):
        disk.run(params={"R": np.inf})


# ---------------------------------------------------------------------- no hangs
@pytest.mark.parametrize("kw, match", [
    (dict(rtol=np.nan), "rtol"),
    (dict(rtol=0.0, atol=0.0), "without an error scale"),
    (dict(rtol=-1e-6), "rtol"),
    (dict(atol=-1e-6), "atol must be >= 0"),
    (dict(atol=[1e-9] * 3), "one value per state"),
    (dict(atol=np.nan), "non-finite"),
    (dict(rtol=1e-20), "float64 cannot honour"),
    (dict(max_step=0.0), "max_step must be a positive"),
    (dict(max_step=np.nan), "max_step"),
    (dict(first_step=np.nan), "first_step"),
    (dict(first_step=0.0), "first_step"),
    (dict(first_step=-1.0), "first_step"),
    (dict(t_eval=[0.0, np.nan, 1.0]), "non-finite"),
    (dict(t_eval=[1.0, 0.5]), "sorted"),
    (dict(max_steps=0), "max_steps"),
    (dict(max_steps=2.5), "max_steps"),
    (dict(timeout=0.0), "timeout"),
    (dict(timeout=np.nan), "timeout"),
    (dict(h=0.1), "not an option of the dop853"),
    (dict(newton_tol=1e-10), "not an option"),
    (dict(method="rk4", h=0.0), "h must be a positive"),
    (dict(method="rk4", h=np.nan), "h must be a positive"),
    (dict(method="rk4", h=-0.1), "h must be a positive"),
    (dict(method="rk4", h=1e-300), "beyond the budget max_steps"),
    (dict(method="rk4", n_steps=10.5), "n_steps must be a positive integer"),
    (dict(method="rk4", n_steps=np.nan), "n_steps"),
    (dict(method="rk4", n_steps=True), "n_steps"),
    (dict(method="rk4", n_steps=0), "n_steps"),
    (dict(method="rk4", n_steps=10, h=0.1), "not both"),
    (dict(method="rk4", n_steps=10, max_steps=5), "beyond the budget"),
    (dict(method="rk4", n_steps=10**9, max_steps=10**10), "GiB"),
    (dict(method="rk4", n_steps=10, max_step=1.0), "not an option of the rk4"),
    (dict(method="dla", h=0.0), "h must be a positive"),
    (dict(method="dla", n_steps=10, newton_tol=np.nan), "newton_tol"),
    (dict(method="dla", n_steps=10, max_newton=0), "max_newton"),
    (dict(method="dla", n_steps=10, t_eval=[0.5]), "not an option of the dla"),
    (dict(method="scipy-RK45", max_step=0.0), "max_step"),
    (dict(method="scipy-RK45", n_steps=3), "not an option"),
    (dict(singular_tol=np.nan), "singular_tol"),
    (dict(save="all"), "save"),
    (dict(sensitivities="yes"), "sensitivities must be True or False"),
    (dict(sensitivities=True, sensitivity_error=1), "sensitivity_error must be True"),
])
def test_arguments_that_would_hang_or_crash_are_refused(disk, kw, match):
    tic = time.perf_counter()
    with pytest.raises(JetnhError, match=match):
        disk.run(**kw)
    assert time.perf_counter() - tic < 5.0


def test_integral_float_step_counts_are_accepted(disk):
    same(disk.run(method="rk4", n_steps=100.0), disk.run(method="rk4", n_steps=100))
    same(disk.run(method="rk4", n_steps=np.int32(100)), disk.run(method="rk4", n_steps=100))


def test_ensemble_arguments_are_checked(disk):
    with pytest.raises(JetnhError, match="shape"):
        disk.ensemble(initial=np.zeros((2, 3)))
    with pytest.raises(JetnhError, match="non-finite"):
        disk.ensemble(initial={"phi_t": [1.0, np.nan]})
    with pytest.raises(JetnhError, match="without an error scale"):
        disk.ensemble(initial={"phi_t": [1.0, 2.0]}, rtol=0, atol=0)
    with pytest.raises(JetnhError, match="h must be a positive"):
        disk.ensemble(initial={"phi_t": [1.0, 2.0]}, method="rk4", h=0.0)
    with pytest.raises(JetnhError, match="real numbers"):
        disk.ensemble(params={"R": ["1", "2"]})


# ---------------------------------------------------------------------- property
CANON = dict(rtol=1e-9, atol=1e-12, t_eval=[0.5, 1.0, 2.0], y0=None, params=None)


def _variants(disk):
    """(value, whether it means the canonical argument) per argument."""
    seq = [DISK0[n] for n in disk.state_names]
    return {
        "rtol": st.sampled_from([(1e-9, True), (np.float64(1e-9), True), (np.nan, False),
                                 (-1e-9, False), (0.0, False), ("1e-9", False),
                                 (np.inf, False), (1e-30, False), (None, False)]),
        "atol": st.sampled_from([(1e-12, True), ([1e-12] * 6, True), (np.nan, False),
                                 ([1e-12] * 5, False), (-1.0, False), ([[1e-12]], False)]),
        "t_eval": st.sampled_from([([0.5, 1.0, 2.0], True), (np.array([0.5, 1.0, 2.0]), True),
                                   ([0.5, np.nan, 2.0], False), ([2.0, 1.0], False),
                                   ([0.5, 1.0, 3.0], False), ("0.5", False),
                                   ([[0.5, 1.0]], False)]),
        "y0": st.sampled_from([(None, True), (seq, True), (dict(DISK0), True),
                               (seq[:-1], False), (seq + [0.0], False),
                               ([np.nan] + seq[1:], False), ({"zz": 1.0}, False),
                               (np.array(seq, dtype=complex), False)]),
        "params": st.sampled_from([(None, True), ([1.5], True), ({"R": 1.5}, True),
                                   ([], False), ([1.5, 0.0], False), ([np.inf], False),
                                   ({"I2": 1.0}, False), ("1.5", False)]),
    }


@given(data=st.data())
def test_run_arguments_error_or_canonical_result(disk, data):
    """Either a JetnhError or exactly the canonical trajectory: never a crash, a hang or
    a different answer."""
    ref = disk.run(**CANON)
    kw, canonical = {}, True
    for name, strategy in _variants(disk).items():
        value, ok = data.draw(strategy, label=name)
        kw[name] = value
        canonical &= ok
    if canonical:
        same(disk.run(**kw), ref)
    else:
        with pytest.raises(JetnhError):
            disk.run(**kw)


# ---------------------------------------------------------------------- budgets
@pytest.mark.parametrize("method, kw", [("dop853", dict(max_step=1e-9)),
                                        ("rk4", dict(n_steps=10**8, save="final")),
                                        ("dla", dict(n_steps=10**8, save="final"))])
def test_timeout_stops_a_long_run(disk, method, kw):
    disk.run(method=method, t_span=(0.0, 0.01), **{**kw, "n_steps": 10} if "n_steps" in kw
             else kw)                                         # compile first
    tic = time.perf_counter()
    tr = disk.run(method=method, timeout=0.3, max_steps=10**9, **kw)
    wall = time.perf_counter() - tic
    assert tr.status == STOPPED and "timeout = 0.3 s" in tr.diagnostics.stop_reason
    assert 0.0 < tr.t[-1] < 2.0 and np.all(np.isfinite(tr.y[-1]))
    assert wall < 3.0


def test_timeout_stops_an_ensemble(disk):
    disk.replace(t_span=(0.0, 0.01)).ensemble(initial={"phi_t": [0.5, 1.0]},
                                              parallel="serial")        # compile first
    ens = disk.ensemble(initial={"phi_t": np.linspace(0.5, 1.0, 4)}, max_step=1e-8,
                        max_steps=10**9, timeout=0.3, parallel="serial")
    assert set(ens.status.tolist()) == {STOPPED}
    assert ens.wall_time < 3.0


CHILD = textwrap.dedent("""
    import signal
    # Ctrl-C as in a terminal: a child of a background job inherits SIGINT ignored, and
    # jetnh leaves an ignored SIGINT ignored
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import jetnh as jn
    from jetnh import models
    sc = jn.Scene(models.get("rolling_disk"), "chetaev",
                  initial=dict(x=0, y=0, phi=0, psi=0, phi_t=1, psi_t=0.7),
                  t_span=(0, 1e9), cache=False).compile()
    runs = [lambda: sc.run(max_step=1e-6, save="final", max_steps=10**12),
            lambda: sc.run(method="dla", n_steps=10**10, max_steps=10**12, save="final"),
            lambda: sc.ensemble(initial={"phi_t": [1.0, 2.0]}, max_step=1e-6,
                                max_steps=10**12)]
    sc.run(t_span=(0, 1e-3))                     # compile everything before the signals
    sc.run(method="dla", n_steps=2, t_span=(0, 1e-3))
    sc.replace(t_span=(0, 1e-3)).ensemble(initial={"phi_t": [1.0, 2.0]})
    for i, run in enumerate(runs):
        print("ready", i, flush=True)
        try:
            run()
            print("finished", i, flush=True)
        except KeyboardInterrupt:
            print("interrupted", i, flush=True)
""")


def _line(child, seconds):
    """The child's next line of output, or its stderr once it has been killed after
    ``seconds`` without one (the test fails; it never hangs)."""
    ready, _, _ = select.select([child.stdout], [], [], seconds)
    if ready:
        return child.stdout.readline().decode()
    child.kill()
    return f"no line within {seconds} s; stderr: {child.stderr.read()[-2000:].decode()}"


def test_ctrl_c_stops_compiled_runs(tmp_path):
    """SIGINT to a long compiled run (dop853, dla, an ensemble) in a child process: each
    stops within a few seconds with a KeyboardInterrupt."""
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    env = dict(os.environ, JETNH_CACHE=str(tmp_path / "cache"))
    # unbuffered: a line read leaves the next one in the pipe, where select sees it
    child = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, bufsize=0, env=env)
    try:
        for i in range(3):
            line = _line(child, 900.0)           # (compiling under load: minutes)
            assert line.split() == ["ready", str(i)], line
            time.sleep(1.0)                      # well inside the compiled loop
            tic = time.perf_counter()
            child.send_signal(signal.SIGINT)
            line = _line(child, 30.0)
            assert line.split() == ["interrupted", str(i)], line
            assert time.perf_counter() - tic < 3.0
        assert child.wait(timeout=30) == 0
    finally:
        child.kill()


def test_strings_are_never_evaluated(tmp_path):
    """A string where an expression belongs is refused, never handed to sympify (which
    would run it): scene integrals, form coefficients."""
    from jetnh.errors import JetSpaceError
    from jetnh.geometry.forms import Form

    canary = tmp_path / "ran"
    code = f"__import__('pathlib').Path({str(canary)!r}).touch() or 1"
    J = jn.JetSpace("x y")
    with pytest.raises(JetSpaceError, match="never parses strings"):
        Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, integrals={"I": code})
    with pytest.raises(JetSpaceError, match="never parses strings"):
        Form.function(J, code)
    assert not canary.exists()


@pytest.mark.parametrize("kw, match", [
    (dict(params=[1.0]), "params must be a dict"),
    (dict(initial=[0.0] * 6), "initial must be a dict"),
    (dict(integrals=["x"]), "integrals must be a dict"),
    (dict(consistency_tol=np.nan), "consistency_tol"),
    (dict(t_span=(0.0, np.nan)), "finite"),
    (dict(runtime_params="R", params={"R": 2.0}), None),
])
def test_scene_arguments(kw, match):
    args = {"initial": DISK0, "t_span": (0.0, 1.0), **kw}
    if match is None:
        assert Scene(models.get("rolling_disk"), "chetaev", **args).runtime_params == ("R",)
    else:
        with pytest.raises(JetnhError, match=match):
            Scene(models.get("rolling_disk"), "chetaev", **args)


def test_a_watch_whose_thread_cannot_start_leaves_nothing_behind(monkeypatch):
    """Where no thread can start (process limits), the call fails with that error and
    leaves no watch registered and no SIGINT deferred: the next call runs normally."""
    import signal

    import numpy as np

    from jetnh.numeric import interrupt

    wd = interrupt._Watchdog()
    monkeypatch.setattr(interrupt, "_WATCHDOG", wd)

    def refuse(*args):
        raise RuntimeError("can't start new thread")

    monkeypatch.setattr(interrupt._thread, "start_new_thread", refuse)
    halt = np.zeros(1, dtype=np.int64)
    before = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(before)
    with pytest.raises(RuntimeError, match="can't start new thread"):
        interrupt.call(lambda: 1, halt, timeout=5.0)
    assert wd.calls == {} and interrupt._DEPTH[0] == 0
    monkeypatch.undo()
    monkeypatch.setattr(interrupt, "_WATCHDOG", wd)
    try:
        assert interrupt.call(lambda x: x + 1, halt, timeout=5.0, args=(1,)) == 2
        assert wd.calls == {} and interrupt._DEPTH[0] == 0
    finally:
        signal.set_wakeup_fd(before)       # not this test's watchdog's socket
        monkeypatch.undo()


def test_a_run_stopped_by_its_budget_says_where(disk):
    """With t_eval a run the step budget stops keeps only the rows before the stop (here
    the one at t = 0): its reason gives the time it reached, the one save='final' ends
    at (the stop was only 'stopped after max_steps steps', and final the initial
    state)."""
    far = disk.replace(t_span=(0.0, 1e300))
    tr = far.run(t_eval=np.linspace(0.0, 1e300, 11), max_steps=50)
    end = far.run(save="final", max_steps=50)
    assert tr.status == end.status == 1 and list(tr.t) == [0.0] and end.t[-1] > 0
    assert tr.stop_reason == end.stop_reason == (
        f"stopped after max_steps steps, at t = {end.t[-1]:.10g}")
