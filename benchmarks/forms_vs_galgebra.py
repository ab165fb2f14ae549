"""Could galgebra's exterior algebra be the engine of jetnh.geometry.forms?  Measure it.

On the coordinates (t, q^1..q^n, qdot^1..qdot^n) of J^1 M (dimension 2n+1) this times,
for dense random 1-forms a, b, c (every component a small random expression):

* wedge2: a ^ b        * wedge3: a ^ b ^ c        * d: the exterior derivative of a

with ``jetnh.geometry.forms`` (sparse dict of sorted coordinate tuples -> coefficients) and with
galgebra (``Ga`` with a Euclidean metric on those coordinates: the outer product ``^`` of
grade-1 multivectors is the wedge of 1-forms, and ``grad ^ A`` is d A in Cartesian
coordinates), in the same process, on the same inputs.  Before every timed call sympy's
cache is cleared, so neither library profits from results the other (or an earlier
repetition) put there.  galgebra returns expanded coefficients while jetnh leaves them as
sums of products, so jetnh is also timed with ``.expand()`` on its result
("jetnh+expand"), the like-for-like comparison.  For n <= 3 every result of the two
libraries is checked to agree component by component.

    .venv/bin/python benchmarks/forms_vs_galgebra.py [--quick] [--ns 1 2 3 4 6]
        [--repeats 3] [--out PATH]

(default output: benchmarks/results/forms_vs_galgebra.json)
"""

from __future__ import annotations

import random
import statistics
import time

import sympy as sp
from sympy.core.cache import clear_cache

from _common import parser, write

from jetnh import JetSpace
from jetnh.algebra.zero import expr_is_zero
from jetnh.geometry.forms import Form, d

BUDGET_S = 120.0          # stop repeating an operation once one call took longer than this


def random_coefficient(rng: random.Random, pool):
    """k1 * u * v + k2 * sin(w): a small dense expression in the coordinates."""
    return (rng.randint(1, 3) * rng.choice(pool) * rng.choice(pool)
            + rng.choice((-2, -1, 1, 2)) * sp.sin(rng.choice(pool)))


def setup(n: int):
    J = JetSpace([f"q{i}" for i in range(1, n + 1)])
    pool = (J.t,) + J.q + J.qd
    return J, pool


def build_ga(pool):
    from galgebra.ga import Ga
    names = " ".join("e_" + s.name.replace("_", "") for s in pool)
    t0 = time.perf_counter()
    g, *basis = Ga.build(names, g=[1] * len(pool), coords=pool)
    return g, basis, time.perf_counter() - t0


def timed(fn):
    clear_cache()
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def agree(form: Form, mv, g, pool) -> bool:
    p = form.degree
    try:
        coefs = mv.get_coefs(p)
    except TypeError:            # galgebra 0.6: zero multivector
        coefs = [0] * len(g.indexes[p])
    return all(expr_is_zero(form[tuple(pool[i] for i in idx)] - c)
               for idx, c in zip(g.indexes[p], coefs))


def run(ns, repeats: int, seed: int = 2024):
    import galgebra
    rows = []
    for n in ns:
        J, pool = setup(n)
        g, basis, t_ga_setup = build_ga(pool)
        row = {"n": n, "dim": 2 * n + 1, "galgebra_setup_s": t_ga_setup, "ops": {}}
        rng = random.Random(seed + n)
        instances = []
        for _ in range(repeats):
            comps = [[random_coefficient(rng, pool) for _ in pool] for _ in range(3)]
            forms = [Form(J, 1, {(s,): c for s, c in zip(pool, cs)}) for cs in comps]
            mvs = [sum((c * e for c, e in zip(cs, basis)), g.mv(sp.S.Zero, "scalar"))
                   for cs in comps]
            instances.append((forms, mvs))
        ops = {
            "wedge2": (lambda f: f[0] ^ f[1], lambda m: m[0] ^ m[1]),
            "wedge3": (lambda f: f[0] ^ f[1] ^ f[2], lambda m: m[0] ^ m[1] ^ m[2]),
            "d": (lambda f: d(f[0]), lambda m: g.grad ^ m[0]),
        }
        for name, (fj, fg) in ops.items():
            tj, tje, tg, checks = [], [], [], []
            for forms, mvs in instances:
                dt, rj = timed(lambda: fj(forms))
                tj.append(dt)
                dt, _ = timed(lambda: fj(forms).expand())
                tje.append(dt)
                if tg and max(tg) > BUDGET_S:
                    continue
                dt, rg = timed(lambda: fg(mvs))
                tg.append(dt)
                if n <= 3:
                    checks.append(agree(rj, rg, g, pool))
            med = {k: statistics.median(v) for k, v in
                   (("jetnh_s", tj), ("jetnh_expand_s", tje), ("galgebra_s", tg))}
            row["ops"][name] = {
                **med,
                "ratio_galgebra_over_jetnh": med["galgebra_s"] / med["jetnh_s"],
                "ratio_galgebra_over_jetnh_expand": med["galgebra_s"] / med["jetnh_expand_s"],
                "samples": {"jetnh": len(tj), "galgebra": len(tg)},
                "results_agree": (all(checks) if checks else None),
            }
            print(f"n={n} dim={2 * n + 1:2d} {name:7s} jetnh {med['jetnh_s']:.4f}s "
                  f"(+expand {med['jetnh_expand_s']:.4f}s)  galgebra {med['galgebra_s']:.4f}s  "
                  f"ratio {med['galgebra_s'] / med['jetnh_s']:.1f}x "
                  f"({med['galgebra_s'] / med['jetnh_expand_s']:.1f}x vs +expand)"
                  + ("" if not checks else f"  agree={all(checks)}"), flush=True)
        rows.append(row)
    return rows, galgebra.__version__


def main(argv=None):
    ap = parser(__doc__, "forms_vs_galgebra")
    ap.add_argument("--ns", type=int, nargs="+", default=None,
                    help="values of n (default 1 2 3 4 6; --quick: 1 2)")
    ap.add_argument("--repeats", type=int, default=None, help="default 3 (--quick: 1)")
    args = ap.parse_args(argv)
    ns = args.ns or ([1, 2] if args.quick else [1, 2, 3, 4, 6])
    t0 = time.perf_counter()
    rows, ga_version = run(ns, args.repeats or (1 if args.quick else 3))
    write("forms_vs_galgebra", {
        "title": "jetnh.geometry.forms vs galgebra exterior algebra on J^1 coordinates (2n+1 dims)",
        "galgebra": ga_version,
        "method": ("median over `repeats` random instances of dense 1-forms; sympy cache "
                   "cleared before every timed call; jetnh result left unexpanded "
                   "(jetnh_s) and expanded (jetnh_expand_s); galgebra: Ga with Euclidean "
                   "metric on (t, q, qdot), outer product ^ and grad ^ for d"),
        "total_wall_s": time.perf_counter() - t0,
        "results": rows}, args.out, args.quick)


if __name__ == "__main__":
    main()
