"""jetnh.linearize against sympy.physics.mechanics' Linearizer on the Chaplygin sleigh
(Chetaev dynamics, affine constraint: where sympy's linearizer is right): the whole route
-- derive, linearize, eigenvalues of straight running at 100 speeds -- each in a fresh
interpreter, and the eigenvalues of the two compared.

sympy: LagrangesMethod with the nonholonomic constraint, ``to_linearizer``,
``linearize`` with the speed symbolic (its multiplier and accelerations set to their
operating values 0, which it leaves in A), ``lambdify``, numpy eigenvalues.  jetnh:
``linearize`` (derivation, Jacobian kernel from the disk cache or compiled), then
``replace`` per speed.  The cold jetnh figure uses an empty kernel cache.  On a model
this small the fixed costs of each route (importing sympy, jetnh and numba, loading the
compiled kernels) dominate; the comparison that matters is on large models, where sympy's
symbolic linearization grows with the size of the flattened expressions.

    PYTHONPATH=. python benchmarks/linearize_sympy.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    from _common import parser, write
except ImportError:
    from benchmarks._common import parser, write

SPEEDS = np.linspace(-2.0, 2.0, 100)


def sympy_route():
    import sympy as sp
    from sympy.core.function import AppliedUndef

    from jetnh.models.planar import chaplygin_sleigh_lagranges

    LM, (x, y, th), (xd, yd, thd) = chaplygin_sleigh_lagranges()
    lin = LM.to_linearizer(q_ind=[x, y, th], qd_ind=[xd, thd], qd_dep=[yd])
    v = sp.Symbol("v")
    A = lin.linearize(op_point={x: 0, y: 0, th: 0, xd: v, yd: 0, thd: 0}, A_and_B=True)[0]
    A = A.subs({d: 0 for d in A.atoms(sp.Derivative)})
    A = A.subs({f: 0 for f in A.atoms(AppliedUndef)})
    f = sp.lambdify(v, A, "numpy")
    return [np.linalg.eigvals(np.array(f(s), dtype=float)) for s in SPEEDS]


def jetnh_route():
    import jetnh as jn
    from jetnh import models

    lin = jn.linearize(models.get("chaplygin_sleigh"), at={"x": 0.0, "y": 0.0, "theta": 0.0,
                                                          "x_t": 1.0, "theta_t": 0.0},
                       drop=None)
    return [lin.replace(at={"x_t": s}).eigenvalues for s in SPEEDS]


def worker(which):
    tic = time.perf_counter()
    ev = sympy_route() if which == "sympy" else jetnh_route()
    wall = time.perf_counter() - tic
    top = [float(max(e.real)) for e in ev]
    print(json.dumps({"seconds": wall, "max_real": top}))


def measure(which, env=None):
    out = subprocess.run([sys.executable, __file__, "--worker", which], capture_output=True,
                         text=True, env={**os.environ, **(env or {})}, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        return worker(sys.argv[2])
    args = parser(__doc__, "linearize_sympy").parse_args()
    with tempfile.TemporaryDirectory() as cold:
        jc = measure("jetnh", {"JETNH_CACHE": cold})
    jw = min((measure("jetnh") for _ in range(2)), key=lambda r: r["seconds"])
    sy = min((measure("sympy") for _ in range(2)), key=lambda r: r["seconds"])
    agree = float(np.max(np.abs(np.array(jw["max_real"]) - np.array(sy["max_real"]))))
    print(f"sympy Linearizer route: {sy['seconds']:.2f} s; jetnh: {jw['seconds']:.2f} s "
          f"(cold kernel cache {jc['seconds']:.2f} s); largest real parts agree to "
          f"{agree:.1e}")
    write("linearize_sympy", {"speeds": len(SPEEDS), "sympy_s": sy["seconds"],
                              "jetnh_s": jw["seconds"], "jetnh_cold_s": jc["seconds"],
                              "max_real_difference": agree}, args.out, args.quick)


if __name__ == "__main__":
    main()
