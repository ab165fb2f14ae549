"""What every benchmark script shares: the record that goes with a result (machine, date,
commit, command), best-of timing, and the JSON writer.

The API (other scripts import it; keep it small and stable):

    RESULTS                        benchmarks/results/ (a Path)
    parser(doc, name)              argparse parser: --quick, --out (default RESULTS/name.json)
    best(f, reps, budget)          (best wall time, last result) of repeated calls of f()
    best_of(fs, reps, budget)      the same for several functions, their calls interleaved
    record()                       {"date", "command", "commit", "machine"} of this run
    write(name, data, out, quick)  the record + {"benchmark": name, "profile"} + data -> JSON file
    run_worker(script, spec, timeout, env)
                                   one measurement of ``script --worker SPEC`` in a fresh
                                   interpreter: its last stdout line as JSON, or
                                   {"timeout": True, "seconds_lower_bound"} / {"error"}
    fmt_seconds(r)                 such a result as table text: seconds, ">T" or "error"
    rhs_driver()                   ``drive(rhs, y, p, n)``: n calls of a compiled rhs in a
                                   compiled loop (the cost of an evaluation, bare)
    call_ns(cfunc, y, p, n_out, reps)
                                   nanoseconds per call of a kernel callback (``t, y, p,
                                   out``) from a compiled loop, best of rounds
    n_trailer_source(N, principle) the N-trailer's kernel source (``codegen.KernelSource``)
                                   and initial state, as ``Scene`` generates them
    exec_kernels(source, name)     a kernel module compiled from its source, numba's
                                   cache off, as the loader compiles a new entry

Wall times are ``time.perf_counter`` differences; the machine is shared, so compare only
figures measured in the same run and take the best of several repetitions.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def parser(doc: str, name: str) -> argparse.ArgumentParser:
    """The common options: ``--quick`` (seconds, for smoke tests) and ``--out``."""
    ap = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a small profile that runs in seconds")
    ap.add_argument("--out", type=Path, default=RESULTS / f"{name}.json",
                    help="where the JSON goes (figures go next to it)")
    return ap


def best_of(fs, reps: int, budget: float = math.inf):
    """Best wall time of each function in ``fs`` over ``reps`` rounds, the calls
    interleaved so that a change of the machine's load hits every function alike; a
    function is not called again once its calls have taken ``budget`` seconds in all.
    Returns ``[(seconds, last result), ...]``."""
    times = [math.inf] * len(fs)
    spent = [0.0] * len(fs)
    outs = [None] * len(fs)
    for _ in range(reps):
        for i, f in enumerate(fs):
            if spent[i] >= budget:
                continue
            tic = time.perf_counter()
            outs[i] = f()
            dt = time.perf_counter() - tic
            times[i] = min(times[i], dt)
            spent[i] += dt
    return list(zip(times, outs))


def best_of_blocks(fs, reps: int, budget: float = math.inf, block: int = 3):
    """Like ``best_of``, but each round calls each function ``block`` times in a row:
    ``[(best of all calls, best of the first call of each block, last result), ...]``.
    The first figure is a warm call (its code and data in the caches, as a loop of calls
    of the same method has them, and as DiffEqDevTools' ``WorkPrecision`` times each
    method: repeated runs in a row); the second a call right after the other functions'
    (cold caches); the rounds stay interleaved against changes of the machine's load."""
    warm = [math.inf] * len(fs)
    cold = [math.inf] * len(fs)
    spent = [0.0] * len(fs)
    outs = [None] * len(fs)
    for _ in range(reps):
        for i, f in enumerate(fs):
            for k in range(block):
                if spent[i] >= budget:
                    break
                tic = time.perf_counter()
                outs[i] = f()
                dt = time.perf_counter() - tic
                warm[i] = min(warm[i], dt)
                if k == 0:
                    cold[i] = min(cold[i], dt)
                spent[i] += dt
    return list(zip(warm, cold, outs))


def best(f, reps: int, budget: float = math.inf):
    """``(best wall time, last result)`` of ``reps`` calls of ``f()`` (see ``best_of``)."""
    return best_of([f], reps, budget)[0]


def _git(*args) -> str | None:
    try:
        r = subprocess.run(["git", "--no-optional-locks", *args], cwd=ROOT, capture_output=True,
                           text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def _versions() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for pkg in ("numpy", "scipy", "sympy", "numba", "mpmath", "jetnh"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            pass
    return out


def record() -> dict:
    """Date (UTC), the command that reproduces the run, the git commit (with ``+dirty``
    when the work tree differs from it), and the machine (with its load average)."""
    python = os.path.relpath(sys.executable, ROOT)
    script = os.path.relpath(os.path.abspath(sys.argv[0]), ROOT)
    commit = _git("rev-parse", "--short=12", "HEAD")
    if commit and _git("status", "--porcelain", "--untracked-files=no"):
        commit += "+dirty"
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join([python, script] + sys.argv[1:]),
        "commit": commit,
        "machine": {"platform": platform.platform(), "processor": platform.processor()
                    or platform.machine(), "cpus": os.cpu_count(),
                    "python": platform.python_version(), "versions": _versions(),
                    "loadavg": list(os.getloadavg())},
    }


def write(name: str, data: dict, out: Path | None = None, quick: bool = False) -> Path:
    """Write ``{"benchmark": name, "profile": "quick"|"full", **record(), **data}`` as JSON
    to ``out`` (default ``RESULTS/name.json``); returns the path."""
    out = Path(out) if out else RESULTS / f"{name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    doc = {"benchmark": name, "profile": "quick" if quick else "full", **record(), **data}
    out.write_text(json.dumps(doc, indent=1, default=_jsonable) + "\n")
    print("wrote", os.path.relpath(out))
    return out


def _jsonable(obj):
    """numpy scalars and arrays, paths and tuples-as-keys in results."""
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


def run_worker(script: str, spec: dict, timeout: float, env: dict | None = None) -> dict:
    """One measurement in a fresh interpreter: ``script --worker SPEC`` prints its result
    as JSON on its last line; ``{"timeout": True, "seconds_lower_bound": timeout}`` when
    it runs out, ``{"error": <its last stderr line>}`` when it fails."""
    cmd = [sys.executable, os.path.abspath(script), "--worker", json.dumps(spec)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"timeout": True, "seconds_lower_bound": timeout}
    if proc.returncode != 0:
        return {"error": (proc.stderr.strip().splitlines() or ["?"])[-1][:200]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def fmt_seconds(r) -> str:
    """A ``run_worker`` result as table text: its seconds, ">T" for a time-out, "error"."""
    if not r:
        return "-"
    if r.get("timeout"):
        return f">{r['seconds_lower_bound']:.0f}"
    return "error" if "error" in r else f"{r['seconds']:.2f}"


def rhs_driver():
    """A compiled loop calling an rhs kernel n times (``drive(rhs, y, p, n)``), ``rhs`` a
    C callback by address (``FunctionAddress``), as the integrators call it."""
    import numba
    import numpy as np

    from jetnh.numeric.methods._common import RHS, entry_point, f8, i8

    @numba.njit((RHS, f8[::1], f8[::1], i8))
    def drive(rhs, y, p, n):
        out = np.empty(y.shape[0])
        acc = 0.0
        for i in range(n):
            y[0] += 1e-15                     # keep the compiler from hoisting the call
            rhs(0.0, y, p, out)
            acc += out[-1]
        return acc
    return entry_point(drive)


def n_trailer_source(N: int, principle: str):
    """``(KernelSource, y0)`` of ``models.get("n_trailer", N=N)`` under ``principle``:
    the steadily turning rig, multipliers 0, t in [0, 1]."""
    from jetnh import models
    from jetnh.numeric import Scene, codegen
    from jetnh.numeric.codegen import multiplier_names

    system = models.get("n_trailer", N=N)
    ini = dict(models.initial("n_trailer", N=N))
    ini.update({m: 0.0 for m in multiplier_names(system, principle)})
    sc = Scene(system, principle, initial=ini, t_span=(0.0, 1.0))
    return codegen.generate(sc.spec), list(sc.y0)


def exec_kernels(source: str, name: str):
    """The module of a generated kernel ``source`` compiled (as ``name``, from a file in a
    temporary directory) with numba's cache off, as the loader compiles a new entry."""
    import tempfile
    import types

    with tempfile.TemporaryDirectory(prefix="jetnh-bench-") as tmp:
        path = os.path.join(tmp, f"{name}.py")
        with open(path, "w") as fh:
            fh.write(source)
        mod = types.ModuleType(name)
        mod.__file__ = path
        mod.JETNH_NUMBA_CACHE = False
        sys.modules[name] = mod
        exec(compile(source, path, "exec"), mod.__dict__)  # noqa: S102 - our own source
        return mod


def call_ns(cfunc, y, p, n_out: int, reps: int, rounds: int = 7) -> float:
    """Nanoseconds per call of the kernel callback ``cfunc`` (``(t, y, p, out)``, ``out``
    of ``n_out``) from a compiled loop, as the integrators call it: best of ``rounds``
    rounds of ``reps`` calls."""
    import numpy as np

    from jetnh.numeric.methods._common import FunctionAddress

    loop = _call_loop()
    f = FunctionAddress(cfunc)
    y, p, out = np.array(y, dtype=float), np.array(p, dtype=float), np.zeros(n_out)
    loop(f, y, p, out, 2)
    best = math.inf
    for _ in range(rounds):
        tic = time.perf_counter()
        loop(f, y, p, out, reps)
        best = min(best, (time.perf_counter() - tic) / reps)
    return 1e9 * best


def _call_loop():
    import numba

    from jetnh.numeric.methods._common import RHS, entry_point

    global _LOOP
    if _LOOP is None:
        f8 = numba.types.float64

        @numba.njit(numba.types.void(RHS, f8[::1], f8[::1], f8[::1], numba.types.int64))
        def loop(f, y, p, out, n):
            for _ in range(n):
                y[0] += 1e-15                 # keep the compiler from hoisting the call
                f(0.25, y, p, out)
        _LOOP = entry_point(loop)
    return _LOOP


_LOOP = None
