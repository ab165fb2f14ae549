"""The cost of jetnh's rk4 per right-hand-side evaluation against a bare RK4 loop on the
same compiled right-hand side.

    .venv/bin/python benchmarks/rk4_loop.py [--quick] [--out PATH]

(default output: benchmarks/results/rk4_loop.json).  The bare loop is a plain numba
function: four stages into four arrays, the classical weights, nothing else (no checks,
no output rows, no budget); it calls the scene's compiled rhs through its address as
jetnh's loops do.  jetnh's side is ``scene.run(method="rk4", n_steps=N, save="final",
singular="ignore")`` (nothing watched, so the same evaluations): a long run, whose fixed
cost is a small fraction.  The two alternate within each repetition (best of
``reps``); the figure is their ratio per evaluation (1.0: the same cost).  Both must end
on the same bits (``bitwise_equal``), a check that jetnh's rk4 is the classical method
with these roundings.  Machine, date, load average, commit and command in the JSON
(``_common.write``).
"""

import time

import numba
import numpy as np

from _common import parser, write

import jetnh.models as models
from jetnh.numeric import Scene
from jetnh.numeric.methods._common import function_at


@numba.njit(nogil=True, error_model="numpy")
def bare_rk4(rhs_at, t0, t1, y0, p, n_steps):
    """``n_steps`` classical RK4 steps from (t0, y0) to t1: the final state."""
    rhs = function_at(rhs_at)
    n = y0.shape[0]
    y = y0.copy()
    k1, k2, k3, k4, ytmp = (np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                            np.empty(n))
    h = (t1 - t0) / n_steps
    t = t0
    for step in range(n_steps):
        rhs(t, y, p, k1)
        for i in range(n):
            ytmp[i] = y[i] + h * (0.5 * k1[i])
        rhs(t + 0.5 * h, ytmp, p, k2)
        for i in range(n):
            ytmp[i] = y[i] + h * (0.5 * k2[i])
        rhs(t + 0.5 * h, ytmp, p, k3)
        for i in range(n):
            ytmp[i] = y[i] + h * k3[i]
        rhs(t + h, ytmp, p, k4)
        hb = h / 6.0
        for i in range(n):
            y[i] = y[i] + hb * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        t = t0 + (step + 1) * h
    return y


def scenes():
    """(name, scene) of catalogue models (Chetaev) whose runs stay in their chart (a
    chart switch would run more than the loop)."""
    for name in ("rolling_disk", "rolling_ball", "suslov_rigid_body"):
        yield name, Scene(models.get(name), "chetaev", initial=models.initial(name),
                          t_span=(0.0, 10.0)).compile()


def measure(name, sc, n_steps, reps):
    t0, t1 = sc.t_span
    y0, p = sc.y0.copy(), np.ascontiguousarray(sc.p, dtype=float)
    address = sc.kernels.rhs_fp.address

    def bare():
        return bare_rk4(address, t0, t1, y0, p, n_steps)

    def jetnh():
        return sc.run(method="rk4", n_steps=n_steps, save="final", singular="ignore")

    bare(), jetnh()                     # compile / warm
    best = {"bare": np.inf, "jetnh": np.inf}
    for _ in range(reps):
        for k, f in (("bare", bare), ("jetnh", jetnh)):
            tic = time.perf_counter()
            out = f()
            best[k] = min(best[k], time.perf_counter() - tic)
            if k == "bare":
                y_bare = out
            else:
                tr = out
    nfev = int(tr.diagnostics.rhs_evaluations)
    row = dict(problem=name, n_steps=n_steps, rhs_evaluations=nfev,
               bare_ns_per_eval=best["bare"] / (4 * n_steps) * 1e9,
               jetnh_ns_per_eval=best["jetnh"] / nfev * 1e9,
               bitwise_equal=bool(np.array_equal(tr.y[-1], y_bare)))
    row["ratio"] = row["jetnh_ns_per_eval"] / row["bare_ns_per_eval"]
    print(f"{name:18s} {n_steps} steps  bare {row['bare_ns_per_eval']:7.2f} ns/eval  "
          f"jetnh rk4 {row['jetnh_ns_per_eval']:7.2f} ns/eval  ratio {row['ratio']:.3f}  "
          f"bitwise {row['bitwise_equal']}")
    return row


def main(argv=None):
    args = parser(__doc__, "rk4_loop").parse_args(argv)
    n_steps, reps = (20_000, 15) if args.quick else (100_000, 41)
    rows = [measure(name, sc, n_steps, reps) for name, sc in scenes()]
    summary = ("jetnh rk4 per evaluation / bare RK4 loop: "
               + ", ".join(f"{r['problem']} {r['ratio']:.3f}" for r in rows)
               + f"; same final bits: {all(r['bitwise_equal'] for r in rows)}")
    write("rk4_loop", dict(title="rk4 against a bare RK4 loop", summary=summary, rows=rows),
          args.out, args.quick)


if __name__ == "__main__":
    main()
