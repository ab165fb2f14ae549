"""Ensemble throughput of jetnh.numeric: right-hand-side evaluations per second over many
initial conditions, for each way of running them -- a Python loop of ``scene.run``, one
compiled serial driver, a Python thread pool of compiled drivers (GIL released), numba
``prange`` threads and ``jn.sweep`` on this machine (the thread pool) -- on the cores of
this machine; and the check that every ensemble run is bit-for-bit the single run.

    .venv/bin/python benchmarks/numeric_ensemble.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_ensemble.json).  Best of several
interleaved repetitions (serial and parallel in the same run: the speed-up is their
ratio); machine, date, load average, commit and command in the JSON
(``_common.write``).

"CPU per evaluation / single run" (``per_eval_vs_single_run``): the CPU time per rhs
evaluation of a mode (all its threads) over that of one long ``scene.run`` of the same
scene, as many evaluations as 64 runs: the cost of a trajectory in an ensemble against
a single run's (1.0 is the same cost; CPU time, which the machine's load disturbs less
than wall time).  The speed-ups need a quiet machine: under load there is no idle core
to scale onto.

"Two fixed blocks" (``two_blocks_bound``): the speed-up two threads could reach at best
if each ran one fixed half of the runs (numba's ``prange`` over the runs, which the
OpenMP layer schedules statically whatever ``parallel_chunksize`` says): the runs'
evaluations over those of the costlier half.  The drivers hand out runs one by one
instead (``prange``: each thread takes the next run; the thread pool: the next chunk), so
their bound is set by the largest run (``largest_run_share``).  Both come from the
evaluation counts, not the clock, so they hold on a loaded machine too.

"Serial Python" of ``jn.sweep`` (``sweep_python_cpu_s``): its CPU time beyond that of the
thread-pool ensemble it runs (the grid, the columns, the DataFrame: work on one thread,
outside the compiled driver); ``two_core_bound``: the speed-up over serial that leaves
on two idle cores (Amdahl, the driver's work split evenly).  CPU times again, so this
holds under load too.
"""

import time

import numba
import numpy as np
import sympy as sp

from _common import parser, write

import jetnh as jn
from jetnh.mechanics.system import System
from jetnh.numeric import Scene


def particle_scene():
    """The nonholonomic particle zdot = y xdot in a harmonic potential (cheap rhs)."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2 - (x**2 + y**2) / 2
    s = System(J, L, [zd - y * xd], dependent=[z])
    sc = Scene(s, "chetaev", initial=dict(x=0.3, y=0.8, z=0.0, x_t=0.5, y_t=-0.2),
               t_span=(0.0, 50.0))
    return "nonholonomic oscillator (chetaev)", sc, "x_t", "y_t"


def disk_scene():
    J = jn.JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2 = sp.symbols("R I1 I2")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2
    s = System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid],
               dependent=[x, y])
    sc = Scene(s, "vakonomic", params={"R": 1.5, "I1": 0.5, "I2": 0.25},
               initial=dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7,
                            lambda_x=0.1, lambda_y=-0.2), t_span=(0.0, 50.0))
    return "vertical rolling disk (vakonomic)", sc, "phi_t", "psi_t"


def single_per_eval(sc, kw, reps):
    """CPU seconds per rhs evaluation of one long run of ``sc`` (no ensemble driver):
    64 times the scene's span."""
    t0, t1 = sc.t_span
    long = sc.replace(t_span=(t0, t0 + 64 * (t1 - t0)))
    run = lambda: long.run(**kw)           # noqa: E731
    run()
    _, cpu, tr = min((_timed(run) for _ in range(reps)), key=lambda x: x[1])
    return cpu / tr.diagnostics.rhs_evaluations


#: seconds of rest before each timed call: numba's OpenMP threads spin on after a
#: ``prange`` region (~4 ms of a core here), which would count against, and compete
#: with, whichever mode comes next (jn.sweep, measured after prange)
SETTLE = 0.05


def _timed(f):
    """``(wall seconds, CPU seconds of the process, f())``, after ``SETTLE``."""
    time.sleep(SETTLE)
    tic, cpu = time.perf_counter(), time.process_time()
    out = f()
    return time.perf_counter() - tic, time.process_time() - cpu, out


def measure(make, n_runs_list, reps, loop_max):
    import pandas as pd

    name, sc, a, b = make()
    sc.compile()
    single = single_per_eval(sc, dict(rtol=1e-10, atol=1e-12, save="final"), reps)
    rows = []
    for n_runs in n_runs_list:
        ini = {a: np.linspace(0.5, 1.5, n_runs) * sc.initial[a],
               b: np.linspace(0.8, 1.2, n_runs) * sc.initial[b]}
        kw = dict(rtol=1e-10, atol=1e-12, save="final")
        modes = {
            "serial": lambda: sc.ensemble(ini, parallel="serial", **kw),
            "threads x2": lambda: sc.ensemble(ini, parallel="threads", workers=2, **kw),
            "prange x2": lambda: sc.ensemble(ini, parallel="prange", workers=2, **kw),
        }
        grid = pd.DataFrame(ini)
        for f in modes.values():      # compile / warm up
            f()
        best = {m: (np.inf, None) for m in modes}
        cpu = {m: np.inf for m in modes}
        best_sweep = (np.inf, None)
        cpu_sweep = np.inf
        for _ in range(reps):
            for m, f in modes.items():
                _, c, e = _timed(f)
                cpu[m] = min(cpu[m], c)
                if e.wall_time < best[m][0]:
                    best[m] = (e.wall_time, e)
            t, c, df = _timed(lambda: jn.sweep(sc, grid, outputs=list(sc.state_names),
                                               rtol=1e-10, atol=1e-12))
            cpu_sweep = min(cpu_sweep, c)
            if t < best_sweep[0]:
                best_sweep = (t, df)
        ref = best["serial"][1]
        nfev = int(ref.nfev.sum())
        half = int(ref.nfev[:n_runs // 2].sum())
        row = dict(n_runs=n_runs, rhs_evaluations=nfev, single_run_s_per_eval=single,
                   two_blocks_bound=nfev / max(half, nfev - half),
                   largest_run_share=float(ref.nfev.max() / nfev), modes={})
        for m, (t, e) in best.items():
            row["modes"][m] = dict(wall_s=t, rhs_per_s=float(e.nfev.sum() / t),
                                   speedup_vs_serial=best["serial"][0] / t,
                                   per_eval_vs_single_run=cpu[m] / nfev / single,
                                   bitwise_equal_to_serial=bool(np.array_equal(e.y, ref.y)))
        t, df = best_sweep
        extra = max(cpu_sweep - cpu["threads x2"], 0.0)
        row["modes"]["jn.sweep (threads)"] = dict(
            wall_s=t, rhs_per_s=nfev / t, speedup_vs_serial=best["serial"][0] / t,
            per_eval_vs_single_run=cpu_sweep / nfev / single,
            sweep_python_cpu_s=extra,
            two_core_bound=1.0 / (extra / cpu["serial"] + (1 - extra / cpu["serial"]) / 2),
            bitwise_equal_to_serial=bool(np.array_equal(
                df[list(sc.state_names)].to_numpy(), ref.y[:, -1])))
        if n_runs <= loop_max:
            Y0 = ref.initial

            def loop():
                return [sc.run(y0=Y0[r], **kw) for r in range(n_runs)]
            loop()
            t_loop = c_loop = np.inf
            for _ in range(max(2, reps // 2)):
                t, c, trs = _timed(loop)
                t_loop, c_loop = min(t_loop, t), min(c_loop, c)
            same = all(np.array_equal(trs[r].y[-1], ref.y[r, 0]) for r in range(n_runs))
            row["modes"]["python loop of scene.run"] = dict(
                wall_s=t_loop, rhs_per_s=row["rhs_evaluations"] / t_loop,
                speedup_vs_serial=best["serial"][0] / t_loop,
                per_eval_vs_single_run=c_loop / nfev / single, bitwise_equal_to_serial=same)
        rows.append(row)
        print(f"{name:36s} {n_runs:5d} runs  two fixed blocks could reach "
              f"x{row['two_blocks_bound']:.2f} at best (evaluations per half)")
        for m, d in row["modes"].items():
            print(f"{name:36s} {n_runs:5d} runs  {m:26s} {d['wall_s'] * 1e3:9.2f} ms  "
                  f"{d['rhs_per_s'] / 1e6:7.2f} M rhs/s  x{d['speedup_vs_serial']:.2f}  "
                  + (f"per eval / single run {d['per_eval_vs_single_run']:.2f}  "
                     if "per_eval_vs_single_run" in d else "")
                  + (f"serial Python {d['sweep_python_cpu_s'] * 1e3:.2f} ms "
                     f"(bound x{d['two_core_bound']:.2f})  " if "two_core_bound" in d else "")
                  + f"bitwise {d['bitwise_equal_to_serial']}")
    return dict(problem=name, rows=rows)


def main(argv=None):
    args = parser(__doc__, "numeric_ensemble").parse_args(argv)
    sizes = [64, 1024] if args.quick else [64, 1024, 4096]
    reps = 2 if args.quick else 3
    problems = [measure(make, ns, reps, loop_max=1024)
                for make, ns in ((particle_scene, sizes), (disk_scene, sizes[:2]))]
    write("numeric_ensemble", dict(
        threads=dict(numba_threads=numba.config.NUMBA_NUM_THREADS,
                     threading_layer=numba.threading_layer()),
        problems=problems), args.out, args.quick)


if __name__ == "__main__":
    main()
