"""Compiled loops that Ctrl-C and a wall-clock budget can stop.

A compiled loop holds no Python frame, so a KeyboardInterrupt cannot reach it until it
returns, and it reads no clock.  Every compiled solve therefore takes a ``halt`` flag (an
int64 array of one element) and reads it before each step.  ``call(fn, halt, timeout)``
runs ``fn()`` (a compiled call that receives ``halt``; compiled with ``nogil``) on a worker
thread while the calling thread waits in short slices:

- Ctrl-C sets ``halt[0] = INTERRUPT``; the loop stops within one step and the
  KeyboardInterrupt goes on from the caller;
- past ``timeout`` seconds it sets ``halt[0] = TIMEOUT``; the loop stops within one step
  and returns what it has, with status STOPPED.

The worker is one daemon thread, started on first use and ended after ``IDLE`` seconds
without work (repeated short runs pay a hand-over of ~20 us, not a thread start, and no
thread is left behind for a fork).  Off the main thread, where signals never arrive,
``fn`` runs in the calling thread, with a timer only when a timeout is set.
"""

from __future__ import annotations

import os
import queue
import threading
import time

import numpy as np

INTERRUPT, TIMEOUT = 1, 2
#: seconds the worker thread waits for new work before it ends
IDLE = 1.0
#: seconds between two looks at the clock while waiting
POLL = 0.05


def flag() -> np.ndarray:
    """A fresh ``halt`` flag."""
    return np.zeros(1, dtype=np.int64)


class _Job:
    __slots__ = ("fn", "done", "value", "error")

    def __init__(self, fn):
        self.fn = fn
        self.done = threading.Event()
        self.value = None
        self.error = None

    def run(self):
        try:
            self.value = self.fn()
        except BaseException as exc:     # handed to the caller's thread
            self.error = exc
        finally:
            self.done.set()


class _Worker:
    """One daemon thread running jobs in order; it ends when idle."""

    def __init__(self):
        self.lock = threading.Lock()
        self.jobs = queue.SimpleQueue()
        self.thread = None

    def submit(self, fn) -> _Job:
        job = _Job(fn)
        with self.lock:
            self.jobs.put(job)
            if self.thread is None:
                self.thread = threading.Thread(target=self._loop, name="jetnh-compiled",
                                               daemon=True)
                self.thread.start()
        return job

    def _loop(self):
        while True:
            try:
                job = self.jobs.get(timeout=IDLE)
            except queue.Empty:
                with self.lock:
                    if self.jobs.empty():
                        self.thread = None
                        return
                continue
            job.run()


_WORKER = _Worker()


def _after_fork():
    global _WORKER
    _WORKER = _Worker()


os.register_at_fork(after_in_child=_after_fork)


def call(fn, halt: np.ndarray, timeout: float | None = None):
    """``fn()``, stoppable by Ctrl-C and by ``timeout`` through ``halt`` (see the module
    docstring)."""
    if threading.current_thread() is not threading.main_thread():
        if timeout is None:
            return fn()
        timer = threading.Timer(timeout, halt.__setitem__, (0, TIMEOUT))
        timer.daemon = True
        timer.start()
        try:
            return fn()
        finally:
            timer.cancel()
    job = _WORKER.submit(fn)
    deadline = None if timeout is None else time.monotonic() + timeout
    try:
        while not job.done.wait(POLL):
            if deadline is not None and time.monotonic() >= deadline:
                halt[0] = TIMEOUT
                deadline = None
    except KeyboardInterrupt:
        halt[0] = INTERRUPT
        job.done.wait()
        raise
    if job.error is not None:
        raise job.error
    return job.value
