"""The search for a load's potential runs sympy's integrate in a forked child process
(``kane_bridge._bounded``): the kernel ends it at ``POTENTIAL_SECONDS`` of CPU time, the
parent at three times that and a second of wall time, and Ctrl-C at once; the load then
stays a generalized force (with a JetnhWarning, or the KeyboardInterrupt), and no child
is left behind.  The budgets here are tiny: each test waits at most a few seconds."""

import os
import resource
import signal
import threading
import time

import pytest
import sympy as sp

import jetnh as jn
from jetnh.mechanics import kane_bridge

me = pytest.importorskip("sympy.physics.mechanics")
from test_kane_conservative import _line  # noqa: E402  (a particle on a line under a load)
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="no os.fork")

_k = sp.Symbol("k")


def _hostile(q):
    """A load whose integral sympy does not finish within 300 s (kaneguard, 2026-11-28)."""
    return -_k * sp.exp(-q**2) * sp.cos(q) ** 3 * q**5 / (2 + sp.sin(q))


def _fds():
    return set(os.listdir("/proc/self/fd")) if os.path.isdir("/proc/self/fd") else set()


@pytest.fixture(autouse=True)
def python_sigint():
    """Python's own SIGINT handler during each test (a pytest-xdist worker ignores
    SIGINT: the import leaves a handler that is not a Python function alone)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.fixture
def forks(monkeypatch):
    """The pids of the children forked meanwhile (``os.fork`` wrapped); checked reaped
    after the test (waitpid finds no such child: a zombie would be found), and the
    pipes closed (the open fds are those before, where /proc tells)."""
    pids, fork, fds = [], os.fork, _fds()

    def recorded():
        pid = fork()
        if pid:
            pids.append(pid)
        return pid

    monkeypatch.setattr(os, "fork", recorded)
    yield pids
    for pid in pids:
        with pytest.raises(ChildProcessError):
            os.waitpid(pid, os.WNOHANG)
    assert _fds() == fds


def _children_cpu():
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def _stays_a_force(S, load):
    (q,), (qt,) = S.J.q, S.J.qd
    assert sp.expand(S.forces[q] - load(q)) == 0
    assert sp.expand(S.L - sp.Symbol("m") * qt**2 / 2) == 0


def test_an_integral_past_the_cpu_budget_leaves_a_force_and_a_warning(monkeypatch, forks):
    """The child is ended by the kernel at the budget: the CPU time of the children
    reaped meanwhile is the budget's, not the minutes sympy would take.  The warning
    points at the user's call."""
    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 0.3)
    before = _children_cpu()
    with pytest.warns(jn.errors.JetnhWarning, match="the point P: its potential was not "
                      r"found within 0.3 s of CPU time .*out of .* time.*force") as record:
        S = _line(_hostile)
    # the user's call (``_line``'s from_mechanics), not jetnh's
    assert record[0].filename == _line.__code__.co_filename
    assert len(forks) == 1
    assert _children_cpu() - before < 0.3 + 0.5
    _stays_a_force(S, _hostile)


def test_a_child_stuck_on_a_lock_is_ended_by_the_wall_clock(monkeypatch, forks):
    """A lock another thread held at the fork is held forever in the child (using no
    CPU time): the parent ends it after 3 x budget + 1 s of wall time."""
    held = threading.Lock()
    held.acquire()

    def stuck(J, Q):
        held.acquire()

    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 0.1)
    monkeypatch.setattr(kane_bridge, "_integrated", stuck)
    load = lambda q: -_k * q  # noqa: E731
    try:
        with pytest.warns(jn.errors.JetnhWarning, match=r"out of wall time \(1.3 s\)"):
            S = _line(load)
    finally:
        held.release()
    assert len(forks) == 1
    _stays_a_force(S, load)


def test_ctrl_c_ends_the_child_and_interrupts_the_import(monkeypatch, forks):
    """SIGINT to the parent alone (sent 0.3 s after the fork, so that it meets the wait
    on the child): the child is killed and reaped, KeyboardInterrupt is raised well
    before the budget (60 s) and the SIGINT handler is the one before."""
    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 60.0)
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    handler, fork, sent = signal.getsignal(signal.SIGINT), os.fork, []
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))

    def fork_then_interrupt():
        pid = fork()
        if pid:
            sent.append(time.monotonic())
            timer.start()
        return pid

    monkeypatch.setattr(os, "fork", fork_then_interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            _line(_hostile)
    finally:
        timer.cancel()      # (an import that ended first must not interrupt pytest)
    assert sent and time.monotonic() - sent[0] < 20     # not the budget's 60 s (181 s wall)
    assert signal.getsignal(signal.SIGINT) is handler
    assert len(forks) == 1


def test_the_childs_potential_is_checked_here(monkeypatch, forks):
    """The child is not trusted: a V that does not stand for the load (or none it
    could send, here a function that does not pickle: the child's error named, without
    the advice to raise the budget) leaves a force."""
    load = lambda q: -_k * q  # noqa: E731
    monkeypatch.setattr(kane_bridge, "_integrated", lambda J, Q: _k * J.q[0] ** 3)
    _stays_a_force(_line(load), load)
    monkeypatch.setattr(kane_bridge, "_integrated", lambda J, Q: (lambda: 0))
    with pytest.warns(jn.errors.JetnhWarning, match="it failed: .*pickle") as record:
        _stays_a_force(_line(load), load)
    assert "POTENTIAL_SECONDS" not in str(record[0].message)
    assert len(forks) == 2


def test_symbols_keep_their_assumptions_through_the_child(forks):
    """The child's V comes back pickled: Symbols keep their assumptions, so the parent's
    check compares the same Symbols (a positive k is not a plain k)."""
    J = jn.JetSpace("q")
    k = sp.Symbol("k", positive=True)
    V = kane_bridge._conservative(J, [-k * J.q[0]])
    assert V == k * J.q[0] ** 2 / 2 and V.free_symbols == {k, J.q[0]}
    assert len(forks) == 1


def test_without_fork_the_integration_runs_in_process(monkeypatch):
    """No os.fork (Windows): the potential is integrated in process, as before (without
    a bound)."""
    monkeypatch.delattr(os, "fork")
    J = jn.JetSpace("q")
    assert kane_bridge._conservative(J, [-_k * J.q[0]]) == _k * J.q[0] ** 2 / 2


@pytest.mark.parametrize("call", ["fork", "read", "close", "wait4"])
def test_ctrl_c_at_any_step_of_the_child_leaves_none_behind(monkeypatch, forks, call):
    """SIGINT right after each system call of the parent's side (after ``fork`` a
    KeyboardInterrupt would come before the pid is kept): the child is reaped all the
    same, KeyboardInterrupt is raised, and the handler is the one before."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    handler, real, fired = signal.getsignal(signal.SIGINT), getattr(os, call), []

    def then_interrupt(*args):
        out = real(*args)
        if forks and not fired:
            fired.append(call)
            os.kill(os.getpid(), signal.SIGINT)
        return out

    monkeypatch.setattr(os, call, then_interrupt)
    J = jn.JetSpace("q")
    with pytest.raises(KeyboardInterrupt):
        kane_bridge._conservative(J, [-_k * J.q[0]])
    assert fired == [call] and len(forks) == 1
    assert signal.getsignal(signal.SIGINT) is handler


def test_a_thread_other_than_the_main_one_searches_as_well(forks):
    """Off the main thread (no SIGINT handler to change) the child does the same."""
    J, got = jn.JetSpace("q"), []
    worker = threading.Thread(target=lambda: got.append(
        kane_bridge._conservative(J, [-_k * J.q[0]])))
    worker.start()
    worker.join()
    assert got == [_k * J.q[0] ** 2 / 2] and len(forks) == 1


def _sleeps(J, Q):
    """An integration that never ends (it waits, using no CPU time)."""
    time.sleep(60)


def test_the_programs_signal_handlers_do_not_run_in_the_child(monkeypatch, forks, tmp_path):
    """A SIGTERM that reaches the child (a process group stopped) ends it as by default:
    the program's handler runs in the program only, not on the child's copy of it; the
    warning names the signal, without blaming the budget."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are set in the main thread only")
    out = tmp_path / "handled"
    out.write_text("")

    def on_term(signum, frame):
        with open(out, "a") as f:
            f.write(f"{os.getpid()}\n")

    fork = os.fork

    def fork_then_terminate():     # at once: the child may not have started
        pid = fork()
        if pid:
            os.kill(pid, signal.SIGTERM)
        return pid

    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 0.5)
    monkeypatch.setattr(kane_bridge, "_integrated", _sleeps)
    monkeypatch.setattr(os, "fork", fork_then_terminate)
    load = lambda q: -_k * q  # noqa: E731
    before = signal.signal(signal.SIGTERM, on_term)
    try:
        with pytest.warns(jn.errors.JetnhWarning, match="killed by signal SIGTERM") as record:
            _stays_a_force(_line(load), load)
    finally:
        signal.signal(signal.SIGTERM, before)
    assert out.read_text() == ""
    assert "POTENTIAL_SECONDS" not in str(record[0].message)
    assert len(forks) == 1


def test_a_ctrl_c_in_the_child_before_it_starts_leaves_the_callers_code(monkeypatch, forks,
                                                                        tmp_path):
    """Off the main thread the program's SIGINT handler is not swapped, and in the child
    the forking thread is the main one: a KeyboardInterrupt raised there at once (as by
    a Ctrl-C to the process group; here ``interrupt_main`` in the child) does not unwind
    into the caller's code in the child, which computes its result all the same."""
    import _thread

    out = tmp_path / "finally"
    out.write_text("")
    fork = os.fork

    def fork_interrupted_in_the_child():
        pid = fork()
        if pid == 0:
            _thread.interrupt_main()
        return pid

    monkeypatch.setattr(os, "fork", fork_interrupted_in_the_child)
    J, got = jn.JetSpace("q"), []

    def caller():
        try:
            got.append(kane_bridge._conservative(J, [-_k * J.q[0]]))
        finally:
            with open(out, "a") as f:
                f.write(f"{os.getpid()}\n")

    worker = threading.Thread(target=caller)
    worker.start()
    worker.join()
    assert got == [_k * J.q[0] ** 2 / 2] and len(forks) == 1
    assert out.read_text() == f"{os.getpid()}\n"


def test_the_child_finalizes_none_of_the_programs_garbage(monkeypatch, tmp_path):
    """A collection in the child (sympy allocates a lot) leaves the parent's objects
    alone: garbage in a cycle that the parent has not collected yet is finalized once,
    by the parent's collector, not by the child's as well.  (Not with ``forks``: the
    parent's collection here may close files of earlier garbage.)"""
    import gc

    fd = os.open(tmp_path / "log", os.O_WRONLY | os.O_CREAT | os.O_APPEND)

    class Finalized:
        def __init__(self):
            self.me = self          # a cycle: freed by the collector only

        def __del__(self):
            os.write(fd, f"{os.getpid()}\n".encode())

    def collecting(J, Q):
        gc.collect()
        return _k * J.q[0] ** 2 / 2

    monkeypatch.setattr(kane_bridge, "_integrated", collecting)
    J = jn.JetSpace("q")
    enabled = gc.isenabled()
    gc.disable()                    # (no collection in the parent before the fork)
    try:
        Finalized()
        V = kane_bridge._conservative(J, [-_k * J.q[0]])
        before = (tmp_path / "log").read_text()
    finally:
        gc.collect()
        os.close(fd)
        if enabled:
            gc.enable()
    assert V == _k * J.q[0] ** 2 / 2 and before == ""
    assert (tmp_path / "log").read_text() == f"{os.getpid()}\n"


def test_a_sigint_handler_that_returns_lets_the_search_go_on(monkeypatch, forks):
    """A SIGINT handler that does not raise (a "stop after this item" flag) is called
    while the child works, once, and the search goes on: the load gets its potential."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    calls, fork = [], os.fork
    timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT))

    def fork_then_interrupt():
        pid = fork()
        if pid:
            timer.start()
        return pid

    def slow(J, Q):
        time.sleep(0.6)
        return _k * J.q[0] ** 2 / 2

    monkeypatch.setattr(kane_bridge, "_integrated", slow)
    monkeypatch.setattr(os, "fork", fork_then_interrupt)
    J = jn.JetSpace("q")
    before = signal.signal(signal.SIGINT, lambda signum, frame: calls.append(signum))
    try:
        V = kane_bridge._conservative(J, [-_k * J.q[0]])
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, before)
    assert calls == [signal.SIGINT]
    assert V == _k * J.q[0] ** 2 / 2 and len(forks) == 1


def test_an_unbounded_budget_integrates(monkeypatch, forks):
    """POTENTIAL_SECONDS = inf (no bound) arms no limit: the search runs, in a child; a
    budget that is no number of seconds is refused, naming the constant."""
    import math

    J = jn.JetSpace("q")
    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", math.inf)
    assert kane_bridge._conservative(J, [-_k * J.q[0]]) == _k * J.q[0] ** 2 / 2
    assert len(forks) == 1
    for bad in (math.nan, -1.0, "5"):
        monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", bad)
        with pytest.raises(jn.errors.JetnhError, match="POTENTIAL_SECONDS is .* >= 0"):
            kane_bridge._conservative(J, [-_k * J.q[0]])


def test_the_childs_error_and_signal_are_named_not_the_budget(monkeypatch, forks):
    """The budget is blamed only where the child had used it: an error of the child's
    is named, and so is a signal that ended it early (the OOM killer's SIGKILL)."""
    def fails(J, Q):
        raise ValueError("no antiderivative here")

    def killed(J, Q):
        os.kill(os.getpid(), signal.SIGKILL)

    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 30.0)
    load = lambda q: -_k * q  # noqa: E731
    for fn, why in ((fails, "it failed: ValueError: no antiderivative here"),
                    (killed, "it was killed by signal SIGKILL")):
        monkeypatch.setattr(kane_bridge, "_integrated", fn)
        with pytest.warns(jn.errors.JetnhWarning, match=why) as record:
            _stays_a_force(_line(load), load)
        message = str(record[0].message)
        assert "CPU time" not in message and "POTENTIAL_SECONDS" not in message
    assert len(forks) == 2


def test_a_refused_fork_integrates_in_process(monkeypatch):
    """A fork refused (no memory for a large process, a process limit): the search runs
    in process, as where there is no fork, without a warning."""
    import errno
    import warnings

    def refused():
        raise OSError(errno.ENOMEM, "Cannot allocate memory")

    monkeypatch.setattr(os, "fork", refused)
    J, fds = jn.JetSpace("q"), _fds()
    with warnings.catch_warnings():
        warnings.simplefilter("error", jn.errors.JetnhWarning)
        assert kane_bridge._conservative(J, [-_k * J.q[0]]) == _k * J.q[0] ** 2 / 2
    assert _fds() == fds


def test_a_pipe_held_open_by_another_fork_does_not_hold_the_wait(monkeypatch, forks):
    """Another process forked while the pipe is open (another thread's worker) holds
    its end: the child's exit ends the wait all the same, with its potential, not the
    wall clock (0.5 s budget: 2.5 s)."""
    fork, workers = os.fork, []

    def fork_and_a_worker():
        pid = fork()
        if pid and not workers:     # as if another thread forked a worker now
            worker = fork()
            if worker == 0:
                try:
                    time.sleep(60)
                finally:
                    os._exit(0)
            workers.append(worker)
        return pid

    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 0.5)
    monkeypatch.setattr(os, "fork", fork_and_a_worker)
    J = jn.JetSpace("q")
    try:
        assert kane_bridge._conservative(J, [-_k * J.q[0]]) == _k * J.q[0] ** 2 / 2
    finally:
        for worker in workers:
            os.kill(worker, signal.SIGKILL)
            os.waitpid(worker, 0)
    assert len(workers) == 1 and len(forks) == 2       # (the worker's fork recorded too)
