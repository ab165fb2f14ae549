"""Ensemble throughput of jetnh.numeric: right-hand-side evaluations per second over many
initial conditions, for each way of running them -- a Python loop of ``scene.run``, one
compiled serial driver, a Python thread pool of compiled drivers (GIL released) and
numba ``prange`` threads -- on the cores of this machine; and the check that every
ensemble run is bit-for-bit the single run.

    .venv/bin/python benchmarks/numeric_ensemble.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_ensemble.json).  Best of several
interleaved repetitions; machine, date, load average, commit and command in the JSON
(``_common.write``).
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


def measure(make, n_runs_list, reps, loop_max):
    name, sc, a, b = make()
    sc.compile()
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
        for f in modes.values():      # compile / warm up
            f()
        best = {m: (np.inf, None) for m in modes}
        for _ in range(reps):
            for m, f in modes.items():
                e = f()
                if e.wall_time < best[m][0]:
                    best[m] = (e.wall_time, e)
        ref = best["serial"][1]
        row = dict(n_runs=n_runs, rhs_evaluations=int(ref.nfev.sum()), modes={})
        for m, (t, e) in best.items():
            row["modes"][m] = dict(wall_s=t, rhs_per_s=float(e.nfev.sum() / t),
                                   speedup_vs_serial=best["serial"][0] / t,
                                   bitwise_equal_to_serial=bool(np.array_equal(e.y, ref.y)))
        if n_runs <= loop_max:
            Y0 = ref.initial

            def loop():
                return [sc.run(y0=Y0[r], **kw) for r in range(n_runs)]
            loop()
            t_loop = np.inf
            for _ in range(max(2, reps // 2)):
                tic = time.perf_counter()
                trs = loop()
                t_loop = min(t_loop, time.perf_counter() - tic)
            same = all(np.array_equal(trs[r].y[-1], ref.y[r, 0]) for r in range(n_runs))
            row["modes"]["python loop of scene.run"] = dict(
                wall_s=t_loop, rhs_per_s=row["rhs_evaluations"] / t_loop,
                speedup_vs_serial=best["serial"][0] / t_loop, bitwise_equal_to_serial=same)
        rows.append(row)
        for m, d in row["modes"].items():
            print(f"{name:36s} {n_runs:5d} runs  {m:26s} {d['wall_s'] * 1e3:9.2f} ms  "
                  f"{d['rhs_per_s'] / 1e6:7.2f} M rhs/s  x{d['speedup_vs_serial']:.2f}  "
                  f"bitwise {d['bitwise_equal_to_serial']}")
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
