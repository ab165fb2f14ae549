"""The integrator loops compiled ahead of the first run (``jetnh cache warm``).

A loop is compiled on its first use (seconds: numba's typing and LLVM) and kept in the
signed store (``kernels.loop_cache``), from which every later process loads it (tens of
milliseconds).  ``warm()`` compiles ahead of time the loops a first run needs, into the
same store under the same trust rules, so that the first trajectory on a machine loads
its loop instead of compiling it; ``make`` runs it once after installing.

``LOOPS`` names the loops ``warm`` can compile, ``<method>:<parts>`` (``loop.features``):
``plain`` the loop of a run without events, singularity indicators, projection or
``t_eval`` that keeps every step (the most common run), ``final`` the same keeping only
its end (``save="final"``; radau's plain loop serves it), ``t_eval`` with output at
``t_eval``, ``watch+t_eval`` with that and indicators or events watched, ``all`` with
every part; the loops of dla and dvi; ``projection:rows``, the projection of output
rows onto holonomic constraints (``projection.rows``); ``connect:step``, the compiled step of connect's
Levenberg-Marquardt search (``connect.levenberg``), ``connect:small`` its shooting's
small-matrix SVD and finiteness check (``connect.small``), ``connect:verdicts`` the
compiled parts of its verdicts (``connect.verdicts``), ``atlas:change``, a run's
change of chart at an edge (``chart_change``), and ``atlas:<method>:<parts>``, a
switching run's pieces in one call (``chart_driver``, over the watching loop).  ``DEFAULT``, what ``make``
compiles (about a minute of CPU), is the plain and the ``final`` loop of each continuous
method, the default method's loops with ``t_eval`` (those of ``make run``), the rows'
projection, connect's, the change of chart and dop853's switching runs: the first run of each
on a machine loads
its loop.  Each loop compiles in a
process of its own, as many at a time as there are cores.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import time

#: name -> (method, parts): the loops ``warm`` compiles (``loop.features`` gives parts)
PARTS = {"plain": (False, False, False, True), "final": (False, False, False, False),
         "t_eval": (False, False, True, False), "watch+t_eval": (True, False, True, False),
         "all": (True, True, True, True)}
LOOPS = {f"{m}:{name}": (m, parts) for m in ("dop853", "dopri5", "rk4", "radau")
         for name, parts in PARTS.items()
         if not (m == "rk4" and "t_eval" in name or m == "radau" and name == "final")}
LOOPS.update({"dla": ("dla", None), "dvi": ("dvi", None),
              "projection:rows": ("projection", None),
              **{f"connect:{part}": ("connect", part)
                 for part in ("step", "small", "verdicts")},
              "atlas:change": ("atlas", None),
              **{f"atlas:{m}:{name}": ("switching", (m, (True, False) + PARTS[name][2:]))
                 for m in ("dop853", "dopri5", "rk4")
                 for name in ("plain", "final", "t_eval") if not (m == "rk4" and name == "t_eval")}})
DEFAULT = (*(n for n in LOOPS if n.endswith((":plain", ":final"))), "dop853:t_eval",
           "dop853:watch+t_eval", "projection:rows", "connect:step", "connect:small",
           "connect:verdicts", "atlas:change", "atlas:dop853:plain", "atlas:dop853:final")


def compile_loop(name: str) -> tuple[str, float, bool]:
    """Compile (or load) the loop ``name`` of ``LOOPS`` in this process: ``(name,
    seconds, loaded)``, loaded meaning that it was on disk already."""
    from .methods import METHODS, dla, dvi, loop, radau

    method, parts = LOOPS[name]
    tic = time.perf_counter()
    if method == "radau":
        d = radau.solver(parts)
    elif method == "dla":
        d = dla.solver()
    elif method == "dvi":
        d = dvi.solver()
    elif method == "projection":
        from .methods import _common, projection

        d = _common.compiled(projection._rows, projection._ROWS_ARGS)
    elif method == "atlas":
        from . import chart_change

        d = chart_change.compiled()
    elif method == "switching":
        from . import chart_driver

        d = chart_driver.compiled(*parts)
    elif method == "connect":
        from .connect import levenberg, small, verdicts

        d = {"step": levenberg.step, "small": lambda: small.compiled_parts()[0],
             "verdicts": verdicts.compiled_parts}[parts]()
    else:
        d = loop.solver(METHODS[method].tableau, parts)
    hits = getattr(d, "_cache_hits", {})        # numba's (private): loaded, not compiled
    return name, time.perf_counter() - tic, sum(hits.values()) > 0


def warm(names=None, jobs: int | None = None, report=None) -> dict[str, tuple[float, bool]]:
    """Compile the loops ``names`` (default: ``DEFAULT``) into the store, ``jobs``
    processes at a time (default: the number of cores); returns name -> (seconds,
    loaded).  ``report(name, seconds, loaded)`` is called as each one is done."""
    names = list(DEFAULT if names is None else names)
    unknown = [n for n in names if n not in LOOPS]
    if unknown:
        from ..errors import JetnhError

        raise JetnhError(f"unknown loops {unknown}; choose among {', '.join(LOOPS)}")
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(names)))
    done = {}

    def record(name, seconds, loaded):
        done[name] = (seconds, loaded)
        if report is not None:
            report(name, seconds, loaded)

    if jobs > 1:
        # spawned processes: each imports jetnh afresh (numba and forked threads do not
        # mix); where no process pool can start (no semaphores), this process does it all
        context = multiprocessing.get_context("spawn")
        try:
            with concurrent.futures.ProcessPoolExecutor(jobs, mp_context=context) as pool:
                for future in concurrent.futures.as_completed(
                        [pool.submit(compile_loop, n) for n in names]):
                    record(*future.result())
        except (OSError, concurrent.futures.process.BrokenProcessPool):
            pass
    for name in names:
        if name not in done:
            record(*compile_loop(name))
    return done
