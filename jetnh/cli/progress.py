"""Progress on stderr: one line per step, a sign of life on a terminal, sweep bars."""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager

#: seconds a step runs before a terminal shows its elapsed time (a sign of life)
SIGN_OF_LIFE = 1.0


class Progress:
    """Step-by-step progress on stderr: ``jetnh: deriving chetaev ... 0.31 s``.  On a
    terminal a step that takes longer than ``SIGN_OF_LIFE`` seconds shows its elapsed
    time while it runs (a tqdm status line), and sweeps show a tqdm bar; elsewhere
    (a pipe, a log) each step is a line.  ``quiet``: nothing."""

    def __init__(self, quiet=False, stream=None):
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def note(self, message: str):
        """A line on stderr, unless quiet (errors are not notes)."""
        if not self.quiet:
            print(message, file=self.stream, flush=True)

    @contextmanager
    def step(self, what: str):
        if self.quiet:
            yield
            return
        t0 = time.perf_counter()
        if not self.tty:
            self.stream.write(f"jetnh: {what} ...\n")
            self.stream.flush()
        ticker = _Ticker(self.stream, f"jetnh: {what} ...") if self.tty else None
        ok = False
        try:
            yield
            ok = True
        finally:
            dt = time.perf_counter() - t0
            if ticker is not None:
                ticker.close()
                self.stream.write(f"jetnh: {what} ... {'done' if ok else 'failed'} "
                                  f"({dt:.2f} s)\n")
            elif dt >= 0.5 or not ok:
                self.stream.write(f"jetnh: {what}: {'done' if ok else 'failed'} ({dt:.2f} s)\n")
            self.stream.flush()

    def bar(self, what: str, unit: str):
        """A ``progress(done, total)`` callback and a function that ends it: a tqdm bar
        on a terminal, else one line per tenth (None when quiet)."""
        if self.quiet:
            return None, lambda: None
        from tqdm import tqdm

        if self.tty:
            bars = []

            def show(done, total):
                if not bars:
                    bars.append(tqdm(total=total, desc=f"jetnh: {what}", unit=unit,
                                     file=self.stream))
                bars[0].update(done - bars[0].n)
            return show, lambda: bars and bars[0].close()
        shown, t0 = [-1], time.perf_counter()

        def line(done, total):
            if 10 * done // total > shown[0]:
                shown[0] = 10 * done // total
                text = tqdm.format_meter(
                    done, total, time.perf_counter() - t0, prefix=f"jetnh: {what}",
                    bar_format="{desc}: {n_fmt}/{total_fmt} " + unit + "s [{elapsed}<"
                               "{remaining}]")
                self.stream.write(text + "\n")
                self.stream.flush()
        return line, lambda: None


class _Ticker:
    """A tqdm status line with the elapsed time of a running step, refreshed from a
    thread, shown once the step has run ``SIGN_OF_LIFE`` seconds; cleared on close."""

    def __init__(self, stream, what):
        import threading

        from tqdm import tqdm

        self.bar = tqdm(total=None, desc=what, file=stream, leave=False,
                        delay=SIGN_OF_LIFE, mininterval=0.2, bar_format="{desc} {elapsed}")
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop.wait(0.25):
            self.bar.update(0)

    def close(self):
        self.stop.set()
        self.thread.join()
        self.bar.close()
