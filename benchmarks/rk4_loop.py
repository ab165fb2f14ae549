"""The cost of jetnh's rk4 per right-hand-side evaluation against a bare RK4 loop on the
same compiled right-hand side.

    .venv/bin/python benchmarks/rk4_loop.py [--quick] [--out PATH]

(default output: benchmarks/results/rk4_loop.json).  The bare loop is a plain numba
function: four stages into four arrays, the classical weights, nothing else (no checks,
no output rows, no budget); it calls the scene's compiled rhs through its address as
jetnh's loops do.  jetnh's side is its compiled rk4 loop called directly (its entry
point, ``loops.entry``: what ``scene.run(method="rk4", n_steps=N, save="final",
singular="ignore")`` calls, without the run's fixed cost), nothing watched, so the two
make the same evaluations.  Short runs (``n_steps`` each), the two called alternately,
many pairs: the figure (``ratio``) is the median over the pairs of jetnh's time over the
bare loop's (1.0: the same cost; a pair shares the machine's load), with the ratio of
the best times beside it.  Both must end on the same bits (``bitwise_equal``), a check
that jetnh's rk4 is the classical method with these roundings.  Machine, date, load
average, commit and command in the JSON (``_common.write``).
"""

import time

import numba
import numpy as np

from _common import parser, write

import jetnh.models as models
from jetnh.numeric import Scene, loops, methods
from jetnh.numeric.methods._common import ENDPOINTS, function_at
from jetnh.numeric.methods.loop import Control, Watch


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


def measure(name, sc, n_steps, pairs):
    t0, t1 = sc.t_span
    y0, p = sc.y0.copy(), np.ascontiguousarray(sc.p, dtype=float)
    kern = sc.kernels
    address = kern.rhs_fp.address
    none = np.zeros(0, dtype=np.int64)
    loop, prefix, suffix, callbacks = loops.entry(
        sc, methods.method("rk4"), kern, None, None,
        Control(1e-9, np.full(len(y0), 1e-12), 0.0, np.inf, 10**9, n_steps), np.zeros(0),
        ENDPOINTS, Watch(0, 0.0, none, none), None)
    halt = np.zeros(1, dtype=np.int64)
    args = (*prefix, t0, t1, y0, p, *suffix, halt)

    def bare():
        return bare_rk4(address, t0, t1, y0, p, n_steps)

    def jetnh():
        return loop(*args)

    y_bare, out = bare(), jetnh()       # compile / warm
    times = np.empty((pairs, 2))
    for i in range(pairs):
        order = ((0, bare), (1, jetnh)) if i % 2 else ((1, jetnh), (0, bare))
        for k, f in order:
            tic = time.perf_counter()
            f()
            times[i, k] = time.perf_counter() - tic
    res = loops.result(out)
    nfev = int(res.stats[2])
    assert nfev == 4 * n_steps
    row = dict(problem=name, n_steps=n_steps, pairs=pairs,
               bare_ns_per_eval=times[:, 0].min() / nfev * 1e9,
               jetnh_ns_per_eval=times[:, 1].min() / nfev * 1e9,
               ratio=float(np.median(times[:, 1] / times[:, 0])),
               ratio_of_best=float(times[:, 1].min() / times[:, 0].min()),
               bitwise_equal=bool(np.array_equal(res.y, y_bare)))
    print(f"{name:18s} {n_steps} steps x {pairs}  bare {row['bare_ns_per_eval']:7.2f} "
          f"ns/eval  jetnh rk4 {row['jetnh_ns_per_eval']:7.2f} ns/eval  ratio "
          f"{row['ratio']:.3f} (of the best {row['ratio_of_best']:.3f})  bitwise "
          f"{row['bitwise_equal']}")
    del callbacks                       # (alive until here: the loop calls into them)
    return row


def main(argv=None):
    args = parser(__doc__, "rk4_loop").parse_args(argv)
    pairs = 200 if args.quick else 1000
    rows = [measure(name, sc, 2000, pairs) for name, sc in scenes()]
    summary = ("jetnh rk4 per evaluation / bare RK4 loop: "
               + ", ".join(f"{r['problem']} {r['ratio']:.3f}" for r in rows)
               + f"; same final bits: {all(r['bitwise_equal'] for r in rows)}")
    write("rk4_loop", dict(title="rk4 against a bare RK4 loop", summary=summary, rows=rows),
          args.out, args.quick)


if __name__ == "__main__":
    main()
