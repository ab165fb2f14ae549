"""What ``jn.connect`` finds on the catalogue: every model x principle, from the model's
catalogue start to where its Chetaev motion is after ``T`` (1 s, or the catalogue's
span where that is shorter).

    PYTHONPATH=. python benchmarks/connect_survey.py [--quick] [--models a,b] [--out PATH]
        [--update]

(default output: benchmarks/results/connect_survey.json; ``--update`` replaces only the
rows run in that file, keeping the others)

For each model: the Chetaev run of ``T`` from the catalogue initial state gives ``start``
(its configuration at 0) and ``end`` (every coordinate at T); then ``jn.connect(model, P,
start, end, (0, T))`` from the default guess for P in vakonomic, Hoelder, Chetaev,
Suslov.  The end is reachable under Chetaev by construction; under the other principles
it may not be (Suslov's motions with zero multipliers are another family; a vakonomic
end may lie where the endpoint map is singular).  Vakonomic and Hoelder take
``restarts=RESTARTS``: where the first answer has a conjugate time inside the span (no
minimizer of the action), the restarts look for a cheaper extremal without one.  Where the
answer is still no minimizer, an independent route bounds the least action from above
(``direct``): the action minimised over paths that meet the constraints (the independent
coordinates a line plus ``MODES`` sine modes each, the dependent ones integrated from
the constraints by the trapezoid rule -- where they do not depend on the dependent
coordinates --, the dependent ends as equality constraints; scipy's SLSQP), and
where L and the constraints do not depend on the dependent coordinates (so P_a = dL/dqdot^a
+ lambda_a is constant along an extremal and equals the SLSQP multiplier of that end),
connect from its initial velocities and multipliers lambda_a(t0) = P_a - dL/dqdot^a(t0),
on ``SEGMENTS`` segments.  Each case runs in a fresh interpreter with a time-out.  The
table gives the cost, the verdicts (normal, conjugate times, minimizer), the residual and
the wall time; or the failure's class and message.  ``--quick``: the four smallest
models.
"""

from __future__ import annotations

import json
import sys
import time

try:
    from _common import parser, run_worker, write
except ImportError:          # run from the repository root
    from benchmarks._common import parser, run_worker, write

T = 1.0
PRINCIPLES = ("vakonomic", "holder", "chetaev", "suslov")
MODELS = ("heisenberg", "nonholonomic_particle", "chaplygin_sleigh", "knife_edge",
          "rolling_disk", "appell_hamel", "rolling_coin", "isokinetic_particle",
          "rheonomic_knife_edge", "bead_on_parabola", "radial_line", "rolling_ball",
          "ball_on_turntable", "suslov_rigid_body", "n_trailer", "particle_chain",
          "damped_knife_edge", "damped_chaplygin_sleigh")
QUICK = ("heisenberg", "nonholonomic_particle", "chaplygin_sleigh", "knife_edge")
TIMEOUT = 600.0
#: restarts of the least-action search (``connect(restarts=)``, vakonomic and Hoelder)
RESTARTS = 8
#: sine modes per independent coordinate and quadrature steps of the direct route
MODES, STEPS = 10, 400
#: multiple shooting segments for connect from the direct route's answer
SEGMENTS = 4


def span(name) -> float:
    import jetnh.models

    return min(T, jetnh.models.info(name).t_end)


def endpoints(name):
    """(start, end): the catalogue start and the Chetaev motion's configuration at
    ``span(name)``."""
    import jetnh as jn
    import jetnh.models

    system = jn.models.get(name)
    tr = jn.Scene(system, "chetaev", initial=jn.models.initial(name),
                  t_span=(0.0, span(name))).run(rtol=1e-12, atol=1e-13)
    coords = [q.name for q in system.J.q]
    return ({c: float(tr[c][0]) for c in coords}, {c: float(tr[c][-1]) for c in coords},
            tr.status)


def case(name, principle):
    """One connect: a JSON-able dict (its answer or its failure)."""
    import jetnh as jn
    import jetnh.models

    system = jn.models.get(name)
    start, end, status = endpoints(name)
    if status != 0:
        return {"failure": "the Chetaev run fails before T"}
    tic = time.perf_counter()
    variational = principle in ("vakonomic", "holder")
    try:
        c = jn.connect(system, principle, start, end, (0.0, span(name)),
                       restarts=RESTARTS if variational else 0)
    except jn.ConnectError as e:
        best = e.best
        return {"seconds": time.perf_counter() - tic, "failure": "ConnectError",
                "message": str(e), "best_residual": None if best is None else best.residual}
    except jn.JetnhError as e:
        return {"seconds": time.perf_counter() - tic, "failure": type(e).__name__,
                "message": str(e)}
    seconds = time.perf_counter() - tic
    out = {"seconds": seconds, "T": span(name), "cost": c.cost, "normal": c.normal,
           "conjugate_times": list(c.conjugate_times), "minimizer": c.minimizer,
           "residual": c.residual, "rank": c.rank, "iterations": c.iterations,
           "route": c.route, "search": c.search, "initial": dict(c.initial)}
    if c.minimizer is False:
        out["direct"] = direct(system, principle, start, end, span(name))
    return out


def direct(system, principle, start, end, T):
    """The independent route (module docstring): the least action over the path family
    by SLSQP, and connect from it where the multipliers follow from its end
    multipliers."""
    import numpy as np
    import sympy as sp
    from scipy.optimize import approx_fprime, minimize

    import jetnh as jn
    from jetnh.algebra import dag

    J = system.J
    par = {s: float(system.defaults[s]) for s in system.parameters}
    ind = [J.split(v)[0] for v in system.independent_velocities]
    dep = list(system.dependent)
    phi = [system.phi[v] for v in system.dependent_velocities]
    if any(q in e.free_symbols for q in dep for e in phi):
        return {"failure": "not attempted: the constraints depend on the dependent "
                           "coordinates"}
    t = np.linspace(0.0, T, STEPS + 1)
    k = np.arange(1, MODES + 1)
    sine = np.sin(np.pi * np.outer(t / T, k))
    dsine = np.pi / T * k * np.cos(np.pi * np.outer(t / T, k))

    def path(z):
        Z = z.reshape(len(ind), MODES)
        point = {J.t: t, **par}
        for j, q in enumerate(ind):
            a, b = start[q.name], end[q.name]
            point[q] = a + (b - a) * t / T + sine @ Z[j]
            point[J.jet(q, 1)] = (b - a) / T + dsine @ Z[j]
        for q, v, e in zip(dep, system.dependent_velocities,
                           dag.evaluate_numpy(phi, point)):
            e = np.broadcast_to(e, t.shape)
            point[v] = e                            # the trapezoid rule's integral
            point[q] = start[q.name] + np.concatenate(
                [[0.0], np.cumsum(0.5 * (e[1:] + e[:-1]) * np.diff(t))])
        return point

    w = np.full(STEPS + 1, 2.0)
    w[1::2], w[0], w[-1] = 4.0, 1.0, 1.0
    w *= T / STEPS / 3.0                             # Simpson on the nodes

    def action(z):
        (L,) = dag.evaluate_numpy([system.L], path(z))
        return float(w @ np.broadcast_to(L, w.shape))

    def ends(z):
        p = path(z)
        return np.array([p[q][-1] - end[q.name] for q in dep])

    tic = time.perf_counter()
    r = minimize(action, np.zeros(len(ind) * MODES), method="SLSQP",
                 constraints=[{"type": "eq", "fun": ends}],
                 options={"maxiter": 300, "ftol": 1e-12})
    out = {"cost": float(r.fun), "success": bool(r.success), "iterations": int(r.nit),
           "end_error": float(np.max(np.abs(ends(r.x)))),
           "seconds": time.perf_counter() - tic}
    cyclic = not any(q in e.free_symbols for q in dep
                     for e in [system.L, *system.constraints])
    if not cyclic:
        return out
    # the end multipliers mu (grad action = mu . grad ends) are P_a
    grad = approx_fprime(r.x, action, 1e-7)
    G = np.array([approx_fprime(r.x, lambda z, i=i: ends(z)[i], 1e-7)
                  for i in range(len(dep))])
    mu = np.linalg.lstsq(G.T, grad, rcond=None)[0]
    p0 = path(r.x)
    p0 = {s: (v[0] if np.ndim(v) else v) for s, v in p0.items()}
    dL = dag.evaluate_numpy([sp.diff(system.L, J.jet(q, 1)) for q in dep], p0)
    guess = [float(p0[v]) for v in system.independent_velocities] + [
        float(m - d) for m, d in zip(mu, dL)]
    try:
        c = jn.connect(system, principle, start, end, (0.0, T), guess=guess,
                       segments=SEGMENTS)
    except jn.JetnhError as e:
        out["connect"] = {"failure": type(e).__name__, "message": str(e)[:300]}
        return out
    out["connect"] = {"cost": c.cost, "minimizer": c.minimizer,
                      "conjugate_times": list(c.conjugate_times), "residual": c.residual,
                      "route": c.route, "initial": dict(c.initial)}
    return out


def row(name, principle, r):
    if "failure" in r and "message" not in r and "seconds" not in r:
        return f"| {name} | {principle} | {r.get('failure', r.get('error'))} |"
    if r.get("timeout"):
        return f"| {name} | {principle} | time-out (> {r['seconds_lower_bound']:.0f} s) |"
    if "error" in r:
        return f"| {name} | {principle} | crash: {r['error']} |"
    if "failure" in r:
        msg = r["message"].replace("|", "/")
        return f"| {name} | {principle} | {r['failure']} ({r['seconds']:.1f} s): {msg} |"
    ct = ", ".join(f"{t:.4g}" for t in r["conjugate_times"]) or "none"
    text = (f"| {name} | {principle} | cost {r['cost']:.6g}, "
            f"{'normal' if r['normal'] else 'ABNORMAL'}, conjugate times {ct}"
            + (", NOT A MINIMIZER" if r.get("minimizer") is False else "")
            + f", residual {r['residual']:.1e}, rank {r['rank']}, {r['iterations']} it, "
            f"{r['seconds']:.1f} s, by {r['route']}")
    d = r.get("direct")
    if d and "cost" in d:
        text += f"; direct route: action <= {d['cost']:.6g}"
        got = d.get("connect", {})
        if "cost" in got:
            text += (f", connect from it: cost {got['cost']:.6g}, "
                     f"{'minimizer' if got['minimizer'] else 'no minimizer'}")
    return text + " |"


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        spec = json.loads(sys.argv[2])
        print(json.dumps(case(spec["model"], spec["principle"])))
        return
    ap = parser(__doc__, "connect_survey")
    ap.add_argument("--models", help="comma-separated catalogue names (default: all)")
    ap.add_argument("--principles", default=",".join(PRINCIPLES))
    ap.add_argument("--update", action="store_true",
                    help="replace only these rows in the results file, keep the others")
    args = ap.parse_args()
    names = args.models.split(",") if args.models else (QUICK if args.quick else MODELS)
    results = {}
    print("| model | principle | answer |\n|---|---|---|")
    for name in names:
        for p in args.principles.split(","):
            r = run_worker(__file__, {"model": name, "principle": p}, TIMEOUT)
            results[f"{name}/{p}"] = r
            print(row(name, p, r), flush=True)
    if args.update and args.out.exists():
        results = {**json.loads(args.out.read_text())["results"], **results}
    write("connect_survey", {"T": T, "results": results}, args.out, args.quick)


if __name__ == "__main__":
    main()
