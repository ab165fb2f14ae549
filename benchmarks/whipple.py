"""The Whipple bicycle written for KanesMethod (``jetnh.models.whipple``), imported by
``jn.from_mechanics`` and linearized by ``jn.linearize`` about upright straight running:
the eigenvalues against the benchmark's (Meijaard et al. 2007), here the lean/steer
state matrix A(v) precomputed in sympy's own benchmark test
(``sympy/physics/mechanics/tests/test_kane3.py``), at several forward speeds v.

Reports the wall time of each stage (sympy's Kane equations, the import, the
linearization's derivation, the other speeds by ``replace``) and the largest difference
of the eigenvalues.  The split keeps roll, rear wheel and steer rates independent (Kane's
own choice); the pitch q4 is fixed by the front contact's configuration constraint (kept
holonomic); the zero eigenvalues (the cyclic coordinates' rates) are left out of the
comparison.

    PYTHONPATH=. python benchmarks/whipple.py [--quick]
"""

from __future__ import annotations

import time

import numpy as np

try:
    from _common import parser, write
except ImportError:
    from benchmarks._common import parser, write


def reference_eigenvalues(v: float) -> np.ndarray:
    """The eigenvalues of the benchmark's lean/steer A(v) (sympy's test_kane3)."""
    A = np.array([[0, 0, 1.0, 0], [0, 0, 0, 1.0],
                  [9.48977444677355, -0.891197738059089 * v**2 - 0.571523173729245,
                   -0.105522449805691 * v, -0.330515398992311 * v],
                  [11.7194768719633, -1.97171508499972 * v**2 + 30.9087533932407,
                   3.67680523332152 * v, -3.08486552743311 * v]])
    return np.sort_complex(np.linalg.eigvals(A))


def main():
    import jetnh as jn
    from jetnh.models.whipple import DEPENDENT, benchmark_parameters, upright, whipple_kane

    args = parser(__doc__, "whipple").parse_args()
    speeds = [5.0] if args.quick else [1.0, 3.0, 4.5, 5.0, 6.0, 8.0, 10.0]
    stages = {}
    tic = time.perf_counter()
    km = whipple_kane()
    stages["kane_equations_s"] = time.perf_counter() - tic
    tic = time.perf_counter()
    bike = jn.from_mechanics(km, dependent=DEPENDENT)
    stages["import_s"] = time.perf_counter() - tic
    params = benchmark_parameters()
    rows, worst = [], 0.0
    lin = None
    for v in speeds:
        at = upright(bike, v, params)
        tic = time.perf_counter()
        lin = (jn.linearize(bike, "chetaev", at=at, params=params) if lin is None
               else lin.replace(at=at))
        stages.setdefault("linearize_first_s", time.perf_counter() - tic)
        eig = np.sort_complex(lin.eigenvalues)
        nonzero = np.sort_complex(eig[np.abs(eig) > 1e-9])
        ref = reference_eigenvalues(v)
        err = float(np.max(np.abs(nonzero - ref))) if nonzero.shape == ref.shape else float("inf")
        worst = max(worst, err)
        rows.append({"v": v, "residual": float(lin.residual),
                     "eigenvalues": [[z.real, z.imag] for z in nonzero],
                     "reference": [[z.real, z.imag] for z in ref], "max_abs_error": err})
        print(f"v = {v:5.2f}  jetnh {np.round(nonzero, 6)}  max |error| {err:.2e}", flush=True)
    print({k: round(x, 2) for k, x in stages.items()}, f"worst eigenvalue error {worst:.2e}")
    write("whipple", {"stages": stages, "speeds": rows, "max_abs_error": worst},
          args.out, args.quick)


if __name__ == "__main__":
    main()
