"""The lean parts of connect's search, each against the route it stands in for: a
shooting run read off its loop (``shooting.Shot``) against ``solve.run``'s Trajectory;
the compiled Levenberg-Marquardt step (``levenberg.step``) against the same formula in
numpy; the search's runs under one shared watch (``interrupt.shared``) still stopped by
Ctrl-C.
"""
import os
import select
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh.models import get
from jetnh.numeric import solve
from jetnh.numeric.connect import levenberg
from jetnh.numeric.connect.problem import _scene
from jetnh.numeric.connect.solve import Search

O = {"x": 0.0, "y": 0.0, "z": 0.0}


@pytest.fixture(scope="module")
def heis_search():
    system = get("heisenberg")
    unknowns = ("x_t", "y_t", "lambda_z")
    scene = _scene(system, "vakonomic", None, {**O, "x_t": 1.0, "y_t": 0.5,
                                               "lambda_z": 0.0}, (0.0, 1.0))
    return Search(scene, O, {"x": 1.0, "y": 0.5, "z": 0.2}, unknowns, {}, 1e-10, 1e-12,
                  "dop853", 1e-9)


@pytest.mark.parametrize("save", ["steps", "final"])
def test_shot_is_the_run_of_its_plan(heis_search, save):
    """The end a Shot reads off the loop and the Trajectory it makes are solve.run's,
    bit for bit."""
    sh = heis_search
    y = sh.state(np.array([1.1, -0.2, 0.4]))
    plan = sh.plan(sh.span, save)
    shot = sh.start(y.copy(), sh.span, save)
    tr = solve.run(sh.scene, plan, y.copy(), sh.scene._p)
    assert tr.status == 0 and shot.t == tr.t[-1]
    assert np.array_equal(shot.y, tr.y[-1])
    assert np.array_equal(shot.S, tr.sensitivities[-1])
    made = shot.trajectory
    assert made is shot.trajectory                       # made once
    assert np.array_equal(made.t, tr.t) and np.array_equal(made.y, tr.y)
    assert np.array_equal(made.sensitivities, tr.sensitivities)
    assert made.stop_reason == tr.stop_reason and made.method == tr.method
    times = np.linspace(0.0, 1.0, 7)
    if save == "steps":
        assert np.array_equal(made.at(times).to_numpy(), tr.at(times).to_numpy())


def test_shot_of_a_run_that_stops_early_is_none(heis_search):
    """A run cut by its step budget (a non-finite start too) gives no Shot: the search
    counts it as failed."""
    sh = heis_search
    y = sh.state(np.array([1.0, 0.0, 1e6]))           # spins too fast for MAX_STEPS
    tr = solve.run(sh.scene, sh.plan(sh.span), y.copy(), sh.scene._p)
    assert tr.status != 0
    assert sh.start(y, sh.span) is None
    assert sh.start(sh.state(np.array([np.nan, 0.0, 0.0])), sh.span) is None


def _numpy_step(F, Jm, d, u, limit, mu, rcond, first):
    """``levenberg._step`` in numpy, an independent transcription of its formula."""
    if np.all(np.abs(F) <= limit):
        return levenberg.CONVERGED, None, None, mu, None, None, None
    norms = np.linalg.norm(Jm, axis=0)
    norms = np.maximum(norms, 1e-6 * norms.max()) if norms.max() > 0 else np.ones(len(u))
    d = norms if first else np.maximum(d, norms)
    U, s, Vt = np.linalg.svd(Jm / d, full_matrices=False)
    r = int(np.sum(s > rcond * s[0])) if s[0] > 0 else 0
    if not r:
        return levenberg.NO_RANK, None, d, mu, None, None, None
    U, s, Vt = U[:, :r], s[:r], Vt[:r]
    mu = 1e-6 * s[0] ** 2 if mu < 0 else mu
    du = -(Vt.T @ (s * (U.T @ F) / (s**2 + mu))) / d
    du /= max(1.0, np.linalg.norm(du) / max(1.0, np.linalg.norm(u)))
    lin = F + Jm @ du
    return levenberg.STEP, du, d, mu, s[0], F @ F, F @ F - lin @ lin


@settings(deadline=None)
@given(st.integers(1, 5), st.integers(1, 5), st.integers(0, 2**32 - 1),
       st.sampled_from(["full", "deficient", "column", "zero"]), st.booleans(),
       st.floats(-1.0, 1.0))
def test_compiled_step_is_the_numpy_step(k, m, seed, kind, first, log_mu):
    """Square, tall and wide Jacobians, of full rank, rank-deficient, with a column
    the end does not feel, or zero; the first step (mu < 0: its own) or a later one."""
    rnd = np.random.default_rng(seed)
    F = rnd.standard_normal(k)
    Jm = rnd.standard_normal((k, m)) * 10.0 ** rnd.uniform(-3, 3, m)
    if kind == "deficient" and min(k, m) > 1:
        Jm[:, -1] = Jm[:, :-1] @ rnd.standard_normal(m - 1)
    elif kind == "column":
        Jm[:, 0] = 0.0
    elif kind == "zero":
        Jm[:] = 0.0
    d = 10.0 ** rnd.uniform(-2, 2, m)
    u = rnd.standard_normal(m) * 3.0
    limit = np.full(k, 1e-9)
    mu = -1.0 if first else 10.0 ** (6 * log_mu)
    want = _numpy_step(F, Jm, d, u, limit, mu, 1e-9, first)
    scales, du = d.copy(), np.empty(m)                   # written by the step
    status, mu_, s0, FF, predicted = levenberg.step()(F, Jm, scales, u, limit, mu, 1e-9,
                                                      first, du)
    assert status == want[0]
    if status != levenberg.STEP:
        return
    assert np.allclose(du, want[1], rtol=1e-9, atol=1e-12 * np.abs(want[1]).max())
    assert np.allclose(scales, want[2], rtol=1e-14)
    assert abs(mu_ - want[3]) <= 1e-14 * abs(want[3])
    assert abs(s0 - want[4]) <= 1e-12 * want[4]
    assert abs(FF - want[5]) <= 1e-13 * want[5]
    assert abs(predicted - want[6]) <= 1e-8 * want[5]


def test_converged_step():
    F = np.array([1e-10, -2e-10])
    got = levenberg.step()(F, np.eye(2), np.ones(2), np.zeros(2), np.full(2, 1e-9), -1.0,
                           1e-9, True, np.empty(2))
    assert got[0] == levenberg.CONVERGED


@pytest.mark.parametrize("bad, match", [(dict(atol=-1.0), "atol must be"),
                                        (dict(rtol=float("nan")), "rtol must be")])
def test_a_bad_tolerance_is_named_at_once(bad, match):
    """The runs' plan checks the tolerances and says what is wrong, at once: not a
    failed run of the search (which would go through every route to a ConnectError)."""
    with pytest.raises(jn.JetnhError, match=match):
        jn.connect(get("heisenberg"), "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 0.2},
                   (0.0, 1.0), **bad)


CHILD = textwrap.dedent("""
    import signal
    # Ctrl-C as in a terminal (a background job's child inherits SIGINT ignored)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import jetnh as jn
    from jetnh.models import get
    from jetnh.numeric import interrupt
    s = get("heisenberg")
    O = dict(x=0.0, y=0.0, z=0.0)
    near = dict(x=1.0, y=0.5, z=0.2)
    kw = dict(rtol=1e-13, atol=1e-14, tol=1e-14)
    jn.connect(s, "vakonomic", O, near, (0, 1), **kw)          # compiled first
    print("ready", flush=True)
    try:
        # a wild guess: seconds of multiple shooting (thousands of runs of ~2 ms)
        jn.connect(s, "vakonomic", O, dict(x=0.0, y=0.0, z=50.0), (0, 1),
                   guess=[1e3, -1e3, 3e3], max_iter=10**4, **kw)
        print("finished", flush=True)
    except KeyboardInterrupt:
        print("interrupted", len(interrupt._WATCHDOG.calls), interrupt._DEPTH[0],
              flush=True)
    c = jn.connect(s, "vakonomic", O, near, (0, 1), **kw)
    print("again", c.residual < 1e-12, flush=True)
""")


def _line(child, seconds):
    """The child's next line, or its stderr once it has been killed after ``seconds``
    without one (the test fails; it never hangs)."""
    ready, _, _ = select.select([child.stdout], [], [], seconds)
    if ready:
        return child.stdout.readline().decode()
    child.kill()
    return f"no line within {seconds} s; stderr: {child.stderr.read()[-2000:].decode()}"


def test_ctrl_c_stops_a_search_whose_runs_share_a_watch(tmp_path):
    """SIGINT a second into a long search (its runs under one ``interrupt.shared``
    watch): a KeyboardInterrupt within seconds, no watch left registered, no SIGINT
    held back, and the next connect runs as before."""
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    child = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, bufsize=0, env=dict(os.environ))
    try:
        line = _line(child, 900.0)               # (compiling under load: minutes)
        assert line.split() == ["ready"], line
        time.sleep(1.0)                          # inside the multiple shooting's runs
        tic = time.perf_counter()
        child.send_signal(signal.SIGINT)
        line = _line(child, 30.0)
        assert line.split() == ["interrupted", "0", "0"], line
        assert time.perf_counter() - tic < 3.0
        assert _line(child, 120.0).split() == ["again", "True"]
        assert child.wait(timeout=30) == 0
    finally:
        child.kill()
