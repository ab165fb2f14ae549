"""The cost of a kernel called from Python (``ck.rhs(t, y, p, out)``: what the scipy
backend pays per evaluation and Python-side evaluation pays per point), against a bare
call of an njit function that computes the same kernel, in the same process.

    .venv/bin/python benchmarks/kernel_call.py [--rounds 7] [--quick] [--out PATH]

(default output: benchmarks/results/kernel_call.json).  On the rolling disk (chetaev):
``ck.rhs`` and ``ck.aux`` (the checked calls through the trampolines of
``jetnh.numeric.kernels.calls``), ``ck.jac`` (the Jacobian kernel), and the baseline, an
njit function with the kernels' signature whose body calls the same C callback (numba
calls a cfunc global by its address: the arithmetic of the kernel and nothing else).
The calls are interleaved, each figure the best over the rounds of the mean of a batch
of calls; the ratio to the baseline is the figure to compare across machines.  The load
(``os.getloadavg``) is recorded next to it.
"""

import os
import timeit

import numba
import numpy as np

from _common import parser, write


def measure(rounds: int, number: int) -> dict:
    import jetnh.models as models
    from jetnh.numeric import Scene, kernels
    from jetnh.numeric.methods._common import RHS, FunctionAddress, entry_point

    sc = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
               t_span=(0.0, 1.0)).compile()
    ck = sc.kernels
    jk = kernels.jacobian_kernels(sc)
    rhs_c, aux_c = ck.rhs_c, ck.aux_c
    sig = "void(float64, float64[::1], float64[::1], float64[::1])"

    @numba.njit(sig)
    def njit_rhs(t, y, p, out):
        rhs_c(t, y, p, out)

    @numba.njit(sig)
    def njit_aux(t, y, p, out):
        aux_c(t, y, p, out)

    @numba.njit(numba.types.void(RHS, numba.float64, numba.float64[::1], numba.float64[::1],
                                 numba.float64[::1]))
    def first_class(f, t, y, p, out):
        f(t, y, p, out)

    before, address = entry_point(first_class), FunctionAddress(rhs_c)
    n = ck.layout.n_state
    y, p = np.array(sc.y0, dtype=float), np.array(sc.p, dtype=float)      # writable copies
    out, aux, J = np.empty(n), np.empty(ck.layout.n_aux), np.empty((n, n))
    ck.rhs(0.1, y, p, out)
    ref = out.copy()
    njit_rhs(0.1, y, p, out)
    assert np.array_equal(out, ref)               # the same kernel, the same numbers
    calls = {
        "njit_rhs": lambda: njit_rhs(0.1, y, p, out),
        "rhs": lambda: ck.rhs(0.1, y, p, out),
        "before_rhs": lambda: before(address, 0.1, y, p, out),
        "njit_aux": lambda: njit_aux(0.1, y, p, aux),
        "aux": lambda: ck.aux(0.1, y, p, aux),
        "jac": lambda: jk.jac(0.1, y, p, J),
    }
    best = {k: float("inf") for k in calls}
    for _ in range(rounds):
        for k, f in calls.items():
            best[k] = min(best[k], timeit.timeit(f, number=number) / number)
    empty = min(timeit.repeat(lambda: None, number=number, repeat=rounds)) / number
    out = {f"{k}_s": v - empty for k, v in best.items()}
    out["lambda_s"] = empty
    out["rhs_vs_njit"] = out["rhs_s"] / out["njit_rhs_s"]
    out["before_vs_njit"] = out["before_rhs_s"] / out["njit_rhs_s"]
    out["aux_vs_njit"] = out["aux_s"] / out["njit_aux_s"]
    out["load"] = os.getloadavg()
    return out


def main(argv=None):
    ap = parser(__doc__, "kernel_call")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args(argv)
    rounds, number = (2, 2000) if args.quick else (args.rounds, 100_000)
    r = measure(rounds, number)
    summary = [
        f"ck.rhs {r['rhs_s'] * 1e6:.3f} us, a bare njit call of the same kernel "
        f"{r['njit_rhs_s'] * 1e6:.3f} us: {r['rhs_vs_njit']:.2f}x (the previous route, "
        f"unchecked: {r['before_vs_njit']:.2f}x); ck.aux "
        f"{r['aux_vs_njit']:.2f}x; ck.jac {r['jac_s'] * 1e6:.3f} us "
        f"(load {r['load'][0]:.1f} on {os.cpu_count()} cores; the lambda each call goes "
        f"through, {r['lambda_s'] * 1e9:.0f} ns, subtracted)"]
    print(summary[0])
    rows = [[name, f"{r[key] * 1e6:.3f}", f"{r[key] / r[base]:.2f}"]
            for name, key, base in (("njit call of the rhs kernel", "njit_rhs_s", "njit_rhs_s"),
                                    ("ck.rhs (checked)", "rhs_s", "njit_rhs_s"),
                                    ("previous route: FunctionAddress unboxed (unchecked)",
                                     "before_rhs_s", "njit_rhs_s"),
                                    ("njit call of the aux kernel", "njit_aux_s", "njit_aux_s"),
                                    ("ck.aux (checked)", "aux_s", "njit_aux_s"),
                                    ("ck.jac (checked)", "jac_s", "njit_rhs_s"))]
    write("kernel_call", dict(
        title="A kernel called from Python", summary=summary, result=r,
        tables=[dict(title="One call from Python, rolling disk (us; best over the rounds)",
                     columns=["call", "us", "vs njit"], rows=rows,
                     note=f"load {r['load'][0]:.1f} on {os.cpu_count()} cores")]),
          args.out, args.quick)


if __name__ == "__main__":
    main()
