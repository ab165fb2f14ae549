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
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="no os.fork")

_k = sp.Symbol("k")


def _hostile(q):
    """A load whose integral sympy does not finish within 300 s (kaneguard, 2026-11-28)."""
    return -_k * sp.exp(-q**2) * sp.cos(q) ** 3 * q**5 / (2 + sp.sin(q))


def _line(force):
    """A particle on a line under the load ``force(q1)``."""
    q1, u1 = me.dynamicsymbols("q1 u1")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q1 * N.x)
    P.set_vel(N, u1 * N.x)
    km = me.KanesMethod(N, q_ind=[q1], u_ind=[u1], kd_eqs=[q1.diff() - u1])
    km.kanes_equations([me.Particle("pa", P, sp.Symbol("m"))], [(P, force(q1) * N.x)])
    return jn.from_mechanics(km)


def _fds():
    return set(os.listdir("/proc/self/fd")) if os.path.isdir("/proc/self/fd") else set()


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
    reaped meanwhile is the budget's, not the minutes sympy would take."""
    monkeypatch.setattr(kane_bridge, "POTENTIAL_SECONDS", 0.3)
    before = _children_cpu()
    with pytest.warns(jn.errors.JetnhWarning, match="the point P: its potential was not "
                      r"found within 0.3 s of CPU time .*out of .* time.*force"):
        S = _line(_hostile)
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
    could send, here a function that does not pickle: exit status 1) leaves a force."""
    load = lambda q: -_k * q  # noqa: E731
    monkeypatch.setattr(kane_bridge, "_integrated", lambda J, Q: _k * J.q[0] ** 3)
    _stays_a_force(_line(load), load)
    monkeypatch.setattr(kane_bridge, "_integrated", lambda J, Q: (lambda: 0))
    with pytest.warns(jn.errors.JetnhWarning, match="exit status 1"):
        _stays_a_force(_line(load), load)
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


@pytest.mark.parametrize("call", ["fork", "read", "close", "waitpid"])
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
