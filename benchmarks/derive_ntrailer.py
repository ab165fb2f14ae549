"""Derivation scaling on the N-trailer: time from the model to the equations solved for
the accelerations, jetnh (all four principles) against sympy.physics.mechanics
LagrangesMethod and KanesMethod (Chetaev / Lagrange-d'Alembert dynamics), N = 1..32.

    .venv/bin/python benchmarks/derive_ntrailer.py [--quick] [--ns 1,2,4,8,16,32]
        [--budget 120] [--timeout 600] [--no-sizes] [--out PATH]

(default output: benchmarks/results/derive_ntrailer.json)

The model is the kinematic car pulling N trailers with on-axle hitches (Murray and
Sastry, "Nonholonomic motion planning: steering using sinusoids", IEEE TAC 38 (1993)
700-716, sec. V; Sordalen, ICRA 1993): coordinates (x, y) of the car's rear axle, heading
th0 of the car and th1..thN of the trailers, hitch length d.  Axle i sits at
    x_i = x - d sum_{j<=i} cos th_j,   y_i = y - d sum_{j<=i} sin th_j
and does not slip sideways (a knife edge per body):
    x' sin th_i - y' cos th_i + d sum_{1<=j<=i} cos(th_i - th_j) th_j' = 0,   i = 0..N:
N + 1 affine constraints on N + 3 coordinates.  Each body: a point mass m at its axle and
a rotational inertia I; L = sum_i m/2 (x_i'^2 + y_i'^2) + I/2 th_i'^2, with m = 1, I = 1/3,
d = 1 (exact rationals).  Split: dependent y, th1..thN.

Measured, each in a fresh interpreter (so that sympy's cache does not carry over), with
the clock started once the model is written in the tool's own terms:
- jetnh: ``System(...)`` to ``equations(p).accelerations()``, for each principle;
- LagrangesMethod: ``LagrangesMethod(L, q, nonhol_coneqs)``, ``form_lagranges_equations()``
  and ``rhs()``;
- KanesMethod: ``KanesMethod(N, q, u_ind, u_dependent, kd_eqs, velocity_constraints)``
  with one RigidBody per axle, ``kanes_equations(bodies)`` and ``rhs()``.
Expression size: ``count_ops`` of the accelerations after ``cse`` (the replacements plus
the reduced expressions), in a separate run after the timing.  A tool is no longer run
for larger N once one of its runs takes more than ``--budget`` seconds (or hits
``--timeout``); the baselines are always attempted at N = 8, where the target ratio is
stated.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import fmt_seconds, parser, run_worker, write  # noqa: E402

PRINCIPLES = ("chetaev", "vakonomic", "holder", "suslov")
BASELINES = ("lagranges_method", "kanes_method")
M, I_NUM, I_DEN, D = 1, 1, 3, 1


# ---------------------------------------------------------------------- the model
def ntrailer(N: int):
    """(J, L, constraints, dependent) of the car with N trailers, in jetnh's terms."""
    import sympy as sp

    from jetnh import JetSpace

    J = JetSpace(["x", "y"] + [f"th{i}" for i in range(N + 1)])
    x, y, *th = J.q
    xd, yd, *thd = J.qd
    m, inertia, d = sp.Integer(M), sp.Rational(I_NUM, I_DEN), sp.Integer(D)
    L = sp.S.Zero
    vx, vy = xd, yd
    for i in range(N + 1):
        if i:
            vx = vx + d * sp.sin(th[i]) * thd[i]
            vy = vy - d * sp.cos(th[i]) * thd[i]
        L += m * (vx**2 + vy**2) / 2 + inertia * thd[i] ** 2 / 2
    constraints = [xd * sp.sin(th[i]) - yd * sp.cos(th[i])
                   + sum((d * sp.cos(th[i] - th[j]) * thd[j] for j in range(1, i + 1)), sp.S.Zero)
                   for i in range(N + 1)]
    return J, L, constraints, [y] + th[1:]


def cse_size(exprs) -> int:
    import sympy as sp

    repl, red = sp.cse(list(exprs))
    return int(sum(sp.count_ops(e) for _, e in repl) + sum(sp.count_ops(e) for e in red))


# ---------------------------------------------------------------------- workers
def work_jetnh(N: int, principle: str, sizes: bool) -> dict:
    from jetnh.mechanics.system import System

    J, L, cons, dep = ntrailer(N)
    tic = time.perf_counter()
    acc = System(J, L, cons, dependent=dep).equations(principle).accelerations()
    out = {"seconds": time.perf_counter() - tic, "outputs": len(acc)}
    if sizes:
        out["cse_count_ops"] = cse_size(acc[a] for a in sorted(acc, key=str))
    return out


def work_lagranges(N: int, sizes: bool) -> dict:
    from sympy.physics.mechanics import LagrangesMethod

    J, L, cons, _ = ntrailer(N)
    Ld, qs = J.to_dynamic(L), [J.to_dynamic(q) for q in J.q]
    nh = [J.to_dynamic(f) for f in cons]
    tic = time.perf_counter()
    lm = LagrangesMethod(Ld, qs, nonhol_coneqs=nh)
    lm.form_lagranges_equations()
    rhs = lm.rhs()
    out = {"seconds": time.perf_counter() - tic, "outputs": rhs.rows}
    if sizes:
        out["cse_count_ops"] = cse_size(rhs[J.n:2 * J.n])
    return out


def work_kane(N: int, sizes: bool) -> dict:
    import sympy as sp
    from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)

    x, y = dynamicsymbols("x y")
    th = dynamicsymbols(f"th0:{N + 1}")
    q = [x, y, *th]
    u = dynamicsymbols(f"u0:{N + 3}")
    m, Iz, d = sp.Integer(M), sp.Rational(I_NUM, I_DEN), sp.Integer(D)
    t = dynamicsymbols._t
    qd_to_u = {qi.diff(t): ui for qi, ui in zip(q, u)}
    Nf, O = ReferenceFrame("N"), Point("O")
    O.set_vel(Nf, 0)
    bodies = []
    px, py = x, y
    for i in range(N + 1):
        if i:
            px, py = px - d * sp.cos(th[i]), py - d * sp.sin(th[i])
        B = Nf.orientnew(f"B{i}", "Axis", (th[i], Nf.z))
        P = O.locatenew(f"P{i}", px * Nf.x + py * Nf.y)
        P.set_vel(Nf, (px.diff(t) * Nf.x + py.diff(t) * Nf.y).xreplace(qd_to_u))
        B.set_ang_vel(Nf, u[2 + i] * Nf.z)
        bodies.append(RigidBody(f"b{i}", P, B, m, (inertia(B, 0, 0, Iz), P)))
    cons = [(x.diff(t) * sp.sin(th[i]) - y.diff(t) * sp.cos(th[i])
             + sum((d * sp.cos(th[i] - th[j]) * th[j].diff(t) for j in range(1, i + 1)),
                   sp.S.Zero)).xreplace(qd_to_u) for i in range(N + 1)]
    u_ind = [u[0], u[2]]                       # x', th0'
    u_dep = [u[1]] + u[3:]                     # y', th1'..thN'
    kd = [qi.diff(t) - ui for qi, ui in zip(q, u)]
    tic = time.perf_counter()
    km = KanesMethod(Nf, q_ind=q, u_ind=u_ind, u_dependent=u_dep, kd_eqs=kd,
                     velocity_constraints=cons)
    km.kanes_equations(bodies, [])
    rhs = km.rhs()
    out = {"seconds": time.perf_counter() - tic, "outputs": rhs.rows}
    if sizes:
        out["cse_count_ops"] = cse_size(rhs[len(q):])
    return out


WORKERS = {"jetnh": lambda s: work_jetnh(s["N"], s["principle"], s["sizes"]),
           "lagranges_method": lambda s: work_lagranges(s["N"], s["sizes"]),
           "kanes_method": lambda s: work_kane(s["N"], s["sizes"])}


def measure(spec: dict, timeout: float, sizes: bool) -> dict:
    """The timing run, then (separately, so that a slow ``cse`` cannot hide the timing)
    the size run."""
    r = run_worker(__file__, {**spec, "sizes": False}, timeout)
    if sizes and "seconds" in r:
        s = run_worker(__file__, {**spec, "sizes": True}, timeout)
        r["cse_count_ops"] = s.get("cse_count_ops")
    return r


def seconds(r) -> float | None:
    if not r:
        return None
    return r.get("seconds", r.get("seconds_lower_bound"))


def main(argv=None) -> int:
    ap = parser(__doc__, "derive_ntrailer")
    ap.add_argument("--ns", default=None, help="comma-separated N (default 1..12,16,20,24,32)")
    ap.add_argument("--budget", type=float, default=120.0,
                    help="stop a tool after a run longer than this (seconds)")
    ap.add_argument("--timeout", type=float, default=600.0, help="per run (seconds)")
    ap.add_argument("--no-sizes", action="store_true")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        spec = json.loads(args.worker)
        print(json.dumps(WORKERS[spec["kind"]](spec)))
        return 0
    if args.ns:
        ns = [int(v) for v in args.ns.split(",")]
    else:
        ns = [1, 2, 4] if args.quick else [*range(1, 13), 16, 20, 24, 32]
    budget = 20.0 if args.quick else args.budget
    sizes = not args.no_sizes
    stopped = set()
    rows = []
    print(f"{'N':>3} | " + " ".join(f"{p:>9}" for p in PRINCIPLES)
          + " | " + " ".join(f"{b[:9]:>9}" for b in BASELINES) + " | LM/chetaev", flush=True)
    for N in ns:
        row = {"N": N, "n": N + 3, "k": N + 1, "jetnh": {}}
        for p in PRINCIPLES:
            if ("jetnh", p) not in stopped:
                r = row["jetnh"][p] = measure({"kind": "jetnh", "N": N, "principle": p},
                                              args.timeout, sizes)
                if r.get("timeout") or "error" in r or r["seconds"] > budget:
                    stopped.add(("jetnh", p))
        for b in BASELINES:
            if b not in stopped or N == 8:
                r = row[b] = measure({"kind": b, "N": N}, args.timeout, sizes)
                if r.get("timeout") or "error" in r or r["seconds"] > budget:
                    stopped.add(b)
        ch = seconds(row["jetnh"].get("chetaev"))
        for b in BASELINES:
            if ch and seconds(row.get(b)) and "error" not in row[b]:
                row[f"{b}_over_chetaev"] = seconds(row[b]) / ch
                row[f"{b}_ratio_is_lower_bound"] = bool(row[b].get("timeout"))
        rows.append(row)
        ratio = row.get("lagranges_method_over_chetaev")
        print(f"{N:>3} | " + " ".join(f"{fmt_seconds(row['jetnh'].get(p)):>9}" for p in PRINCIPLES)
              + " | " + " ".join(f"{fmt_seconds(row.get(b)):>9}" for b in BASELINES)
              + " | " + (f"{ratio:.1f}x" if ratio else "-"), flush=True)
        write("derive_ntrailer", {
            "model": "car with N on-axle trailers (Murray-Sastry 1993), m=1, I=1/3, d=1; "
                     "dependent y, th1..thN",
            "budget_s": budget, "timeout_s": args.timeout, "rows": rows},
            args.out, args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
