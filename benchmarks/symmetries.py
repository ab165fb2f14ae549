"""How the search for conserved quantities and Noether symmetries scales with n and degree.

    .venv/bin/python benchmarks/symmetries.py [--quick] [--out PATH]

The system is ``particle_chain(N)`` (n = 3N coordinates, N constraints, the parameters
m and k), under the Chetaev and vakonomic principles.  For each N and degree:

- ``conserved_quantities`` with the default ansatz (monomials in t and q of degree <=
  degree) while it fits the budget of unknowns, and with ``coefficients=[1]`` (constant
  coefficient functions, the momenta and the kinetic part of energy-like integrals);
- ``noether_symmetries`` at degree 1 (point generators with linear components).

Each row gives the unknowns, the number found and the best wall time.  Baseline, in the
same run: the linear algebra of one search (the first sampled rows, N = 1, degree 2)
by jetnh's fixed-point elimination against sympy's exact ``Matrix.nullspace`` on the same
rational rows.
Output: benchmarks/results/symmetries.json.
"""

import random
import time
import warnings

import sympy as sp

from _common import best, parser, write

import jetnh as jn
from jetnh.algebra import ansatz
from jetnh import models
from jetnh.errors import ArgumentError


def count_unknowns(fn, *args, **kw):
    """The ansatz size: ``fn`` with the budget set to 0 reports it in its error."""
    old, ansatz.BUDGET = ansatz.BUDGET, 0
    try:
        fn(*args, **kw)
    except ArgumentError as e:
        return int(str(e).split("has ")[1].split(" unknowns")[0])
    finally:
        ansatz.BUDGET = old
    return None


def case(kind, N, principle, degree, coefficients, reps):
    s = models.get("particle_chain", N=N)
    s.equations(principle).accelerations()          # derivation is not what is measured
    fn = jn.conserved_quantities if kind == "integrals" else jn.noether_symmetries
    size = count_unknowns(fn, s, principle, degree=degree, coefficients=coefficients)
    row = dict(search=kind, N=N, n=3 * N, principle=principle, degree=degree,
               ansatz="default" if coefficients is None else "[1]", unknowns=size)
    if size is not None and size > ansatz.BUDGET:
        row.update(found=None, seconds=None, note=f"over the budget of {ansatz.BUDGET}")
        return row
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t, out = best(lambda: fn(s, principle, degree=degree, coefficients=coefficients),
                      reps, budget=60.0)
    row.update(found=len(out), seconds=round(t, 3), note="")
    return row


def baseline():
    """Fixed-point elimination vs sympy's exact nullspace on the same sampled rows."""
    s = models.get("particle_chain", N=1)
    cap = {}
    solve = ansatz.solve

    def grab(problem, what, **kw):
        cap["p"] = problem
        return []
    ansatz.solve = grab
    try:
        jn.conserved_quantities(s, "chetaev", degree=2)
    finally:
        ansatz.solve = solve
    p = cap["p"]
    rng = random.Random(1)
    theta = ansatz.random_parameters(p.parameters, rng, wide=True)
    rows = [r for r, _ in p.rows(rng, 2 * p.n + 4, theta)]
    exact = sp.Matrix([[sp.Rational(v.numerator, v.denominator) for v in r] for r in rows])
    tic = time.perf_counter()
    A, piv = ansatz._rref(rows, p.n)
    ours = len(ansatz._null_vectors(A, piv, p.n))
    t_ours = time.perf_counter() - tic
    tic = time.perf_counter()
    theirs = len(exact.nullspace())
    t_sympy = time.perf_counter() - tic
    return dict(unknowns=p.n, rows=len(rows), null_jetnh=ours, null_sympy=theirs,
                seconds_jetnh=round(t_ours, 3), seconds_sympy=round(t_sympy, 3),
                ratio=round(t_sympy / t_ours, 1))


def main():
    args = parser(__doc__, "symmetries").parse_args()
    Ns = (1, 2) if args.quick else (1, 2, 3)
    reps = 1 if args.quick else 2
    rows = []
    for N in Ns:
        for principle in ("chetaev", "vakonomic"):
            for degree in (1, 2):
                for coeffs in (None, [1]):
                    rows.append(case("integrals", N, principle, degree, coeffs, reps))
                    print(rows[-1], flush=True)
            rows.append(case("noether", N, principle, 1, None, reps))
            print(rows[-1], flush=True)
    base = baseline()
    print(base)
    done = [r for r in rows if r["seconds"] is not None]
    big = max(done, key=lambda r: r["unknowns"] or 0)
    summary = [
        f"Elimination of one search (N = 1, degree 2, {base['unknowns']} unknowns, "
        f"{base['rows']} rows): jetnh {base['seconds_jetnh']} s, sympy's exact nullspace "
        f"{base['seconds_sympy']} s ({base['ratio']}x); both find {base['null_jetnh']} and "
        f"{base['null_sympy']} null vectors.",
        f"Largest search within the budget: {big['unknowns']} unknowns "
        f"({big['search']}, N = {big['N']}, {big['principle']}, degree {big['degree']}, "
        f"{big['ansatz']} ansatz) in {big['seconds']} s.",
        f"The default ansatz outgrows the budget of {ansatz.BUDGET} unknowns at degree 2 "
        "from N = 2 (n = 6): its size grows like C(n + 1 + d, d) C(n - k + d, d); "
        "coefficients=[1] keeps it to C(n - k + d, d).",
    ]
    write("symmetries", dict(
        title="Conserved quantities and Noether symmetries: scaling with n and degree",
        summary=summary,
        columns=["search", "N", "n", "principle", "degree", "ansatz", "unknowns", "found",
                 "seconds", "note"],
        rows=rows, baseline=base), args.out, args.quick)


if __name__ == "__main__":
    main()
