"""jetnh's compiled DOP853 against scipy's solve_ivp(method="DOP853") with a lambdified
right-hand side, at equal tolerance, on the vertical rolling disk and the nonholonomic
particle (both Chetaev); plus the cost of one rhs evaluation against a hand-written numba
function, and cold (derive + compile + run) against warm (disk cache) start.

    .venv/bin/python benchmarks/numeric_speed.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_speed.json)

Wall times are the best of several repetitions; the machine, date and command are in the
JSON.  atol = 1e-3 * rtol (the SciML work-precision convention).
"""

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np
import scipy
import sympy as sp
from scipy.integrate import solve_ivp

import jetnh as jn
from jetnh.constraints import System
from jetnh.numeric import Scene


def best(f, reps):
    out, t = None, float("inf")
    for _ in range(reps):
        tic = time.perf_counter()
        out = f()
        t = min(t, time.perf_counter() - tic)
    return t, out


def disk():
    J = jn.JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2 = sp.symbols("R I1 I2")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2
    s = System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid],
               dependent=[x, y])
    ini = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)
    params = {"R": 1.5, "I1": 0.5, "I2": 0.25}
    T = 100.0

    def exact(t):
        psi_ = 0.4 + 0.7 * t
        return {"x": 0.1 + 1.5 / 0.7 * (np.sin(psi_) - np.sin(0.4))}
    return "vertical rolling disk", s, params, ini, T, exact


def particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])
    ini = dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3)
    T = 100.0

    def exact(t):
        c = np.sqrt(1.25)
        return {"x": 0.1 + c / 0.3 * (np.arcsinh(-0.5 + 0.3 * t) - np.arcsinh(-0.5))}
    return "nonholonomic particle (zdot = y xdot)", s, {}, ini, T, exact


def lambdified_rhs(system, params):
    """The researcher's route: accelerations with phi and numbers substituted,
    sympy.lambdify (with cse) to a Python function f(t, y)."""
    J = system.J
    acc = system.equations("chetaev").accelerations()
    num = {s: params[s.name] for s in system.parameters}
    phi = {v: e.xreplace(num) for v, e in system.phi.items()}
    states = list(J.q) + list(system.independent_velocities)
    exprs = [phi.get(v, v) for v in J.qd]
    exprs += [acc[J.jet(J.split(v)[0], 2)].xreplace(phi).xreplace(num)
              for v in system.independent_velocities]
    f = sp.lambdify((J.t, states), exprs, modules="math", cse=True)
    return lambda t, y: np.array(f(t, y))


def compare(problem, rtols, reps):
    name, s, params, ini, T, exact = problem()
    scene = Scene(s, "chetaev", params=params, initial=ini, t_span=(0.0, T))
    scene.run(rtol=1e-6, atol=1e-9, save="final")           # compile / load once
    f = lambdified_rhs(s, params)
    rows = []
    xe = exact(np.array([T]))["x"][0]
    ix = scene.state_names.index("x")
    for rtol in rtols:
        atol = 1e-3 * rtol
        tj, tr = best(lambda: scene.run(rtol=rtol, atol=atol, save="final"), reps)
        ts, sol = best(lambda: solve_ivp(f, (0.0, T), scene.y0, method="DOP853", rtol=rtol,
                                         atol=atol), max(1, reps // 3))
        rows.append(dict(
            rtol=rtol, atol=atol,
            jetnh_s=tj, scipy_s=ts, ratio=ts / tj,
            jetnh_err=abs(tr["x"][-1] - xe), scipy_err=abs(sol.y[ix, -1] - xe),
            jetnh_nfev=tr.diagnostics.rhs_evaluations, scipy_nfev=int(sol.nfev)))
        print(f"{name:40s} rtol {rtol:.0e}: jetnh {tj * 1e3:9.3f} ms  scipy {ts * 1e3:9.1f} ms"
              f"  ratio {ts / tj:7.0f}x  err {rows[-1]['jetnh_err']:.1e} / "
              f"{rows[-1]['scipy_err']:.1e}  nfev {rows[-1]['jetnh_nfev']} / "
              f"{rows[-1]['scipy_nfev']}")
    return dict(problem=name, t_end=T, rows=rows), scene


def rhs_cost(scene, n_calls=2_000_000):
    """ns per rhs call: generated kernel vs a hand-written numba function of the same
    expressions (disk), both called through the same compiled loop."""
    from jetnh.numeric.integrators._common import RHS, f8, i8

    @numba.njit((RHS, f8[::1], f8[::1], i8))
    def drive(rhs, y, p, n):
        out = np.empty(y.shape[0])
        acc = 0.0
        for i in range(n):
            y[5] = 0.7 + 1e-12 * i
            rhs(0.0, y, p, out)
            acc += out[0]
        return acc

    @numba.njit("void(float64, float64[::1], float64[::1], float64[::1])",
                error_model="numpy")
    def hand(t, y, p, out):
        s3, s4, s5 = y[3], y[4], y[5]
        c, s = np.cos(s3), np.sin(s3)
        out[0] = 1.5 * s4 * c
        out[1] = 1.5 * s4 * s
        out[2] = s4
        out[3] = s5
        out[4] = 0.0
        out[5] = 0.0

    y = scene.y0.copy()
    p = scene.p
    res = {}
    for label, fn in (("generated", scene.kernels.rhs), ("hand_written", hand)):
        drive(fn, y, p, 10)
        t, _ = best(lambda: drive(fn, y, p, n_calls), 3)
        res[label + "_ns"] = t / n_calls * 1e9
    res["ratio"] = res["generated_ns"] / res["hand_written_ns"]
    print(f"rhs call: generated {res['generated_ns']:.1f} ns, hand-written "
          f"{res['hand_written_ns']:.1f} ns (ratio {res['ratio']:.2f})")
    return res


COLD = r"""
import time, json
t0 = time.perf_counter()
import sympy as sp, jetnh as jn
from jetnh.constraints import System
from jetnh.numeric import Scene
J = jn.JetSpace("x y phi psi"); x, y, phi, psi = J.q; xd, yd, phid, psid = J.qd
R, I1, I2 = sp.symbols("R I1 I2")
s = System(J, (xd**2 + yd**2)/2 + (I1*phid**2 + I2*psid**2)/2,
           [xd - R*sp.cos(psi)*phid, yd - R*sp.sin(psi)*phid], dependent=[x, y])
t1 = time.perf_counter()
sc = Scene(s, "chetaev", params={R: 1.5, I1: 0.5, I2: 0.25},
           initial=dict(x=0, y=0, phi=0, psi=0, phi_t=1, psi_t=0.7), t_span=(0, 100))
k = sc.kernels
t2 = time.perf_counter()
tr = sc.run(rtol=1e-10, atol=1e-13, save="final")
t3 = time.perf_counter()
print(json.dumps(dict(import_s=t1 - t0, kernels_s=t2 - t1, first_run_s=t3 - t2,
                      total_s=t3 - t0, cache_hit=k.hit, timings=k.timings)))
"""


def cold_warm():
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, JETNH_CACHE=d)
        out = []
        for _ in range(2):
            r = subprocess.run([sys.executable, "-c", COLD], env=env, capture_output=True,
                               text=True, check=True)
            out.append(json.loads(r.stdout.strip().splitlines()[-1]))
    cold, warm = out
    print(f"new process, disk: cold {cold['total_s']:.2f} s (kernels {cold['kernels_s']:.2f} s)"
          f", warm {warm['total_s']:.2f} s (kernels {warm['kernels_s']:.2f} s)")
    return dict(cold=cold, warm=warm, saved_s=cold["total_s"] - warm["total_s"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer tolerances and repetitions")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results",
                                                  "numeric_speed.json"))
    args = ap.parse_args()
    rtols = [1e-6, 1e-10] if args.quick else [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
    reps = 3 if args.quick else 9
    results = dict(
        benchmark="numeric_speed",
        date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        command=" ".join([os.path.relpath(sys.executable)] + sys.argv),
        machine=dict(platform=platform.platform(), processor=platform.processor(),
                     cpus=os.cpu_count(), python=platform.python_version(),
                     numba=numba.__version__, scipy=scipy.__version__,
                     numpy=np.__version__, sympy=sp.__version__,
                     loadavg=os.getloadavg()),
        comparisons=[])
    scene = None
    for problem in (disk, particle):
        comp, sc = compare(problem, rtols, reps)
        results["comparisons"].append(comp)
        scene = scene or sc
    results["rhs_call"] = rhs_cost(scene)
    results["cold_warm"] = cold_warm()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(results, fh, indent=2)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
