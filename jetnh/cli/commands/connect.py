"""``jetnh connect``: the motion of a principle joining two configurations."""

from __future__ import annotations

import sys

from ...errors import JetnhError
from .. import outputs
from ..declared import declared
from ..loading import load_model, with_split
from ..parser import (EPILOG_MODEL, PRINCIPLES, canonical_principle, model_args,
                      principle_option, span_options, subcommand,
                      tolerance_options)
from ..running import assignments
from ..usage import UsageError


def add_parser(sub):
    s = subcommand(
        sub, "connect",
        help="the motion of a principle joining two configurations (two-point problem)",
        description="Find a motion of MODEL under --principle (default: the model's, "
                    "else vakonomic: the stationary action with fixed endpoints) from the "
                    "configuration --from at T0 to --to at --t-end, by shooting with the exact "
                    "sensitivities (jetnh.connect).  Prints the initial state found, the "
                    "action int L dt, the endpoint residual, whether the extremal is "
                    "normal, and its conjugate times.  --from defaults to the model's "
                    "initial configuration (coordinates not given start at 0); --to may "
                    "name only some coordinates (chetaev and suslov reach at most as "
                    "many as there are independent velocities).",
        epilog=EPILOG_MODEL + "\n\nexamples:\n  jetnh connect heisenberg --to x=1,y=0.5,z=0.2 "
                              "--t-end 1 --plot geodesic.png\n  jetnh connect "
                              "rolling_disk -p chetaev --to x=0.5,y=0.3 --t-end 1 "
                              "--compare vakonomic")
    model_args(s)
    principle_option(s, "the model's, else vakonomic")
    span_options(s)
    tolerance_options(s, "jetnh.connect's, ", lambda: _connect_default("rtol"),
                      lambda: _connect_default("atol"), of="the shooting runs")
    s.add_argument("--from", dest="start", action="append", metavar="NAME=VALUE",
                   help="a coordinate at T0 (repeatable, or comma-separated); the "
                        "others: the model's initial values, else 0 (the output says "
                        "which)")
    s.add_argument("--to", dest="end", action="append", metavar="NAME=VALUE",
                   help="a coordinate at T (repeatable, or comma-separated); required")
    s.add_argument("--guess", action="append", metavar="NAME=VALUE",
                   help="initial velocities and multipliers to start the search from "
                        "(default: the straight line, zero multipliers)")
    s.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value (repeatable, or comma-separated)")
    s.add_argument("--compare", metavar="PRINCIPLE", type=canonical_principle,
                   choices=PRINCIPLES,
                   help="also connect under PRINCIPLE to the configuration the first "
                        "motion reached (every coordinate, when PRINCIPLE's unknowns "
                        "allow it; else --to), and print the two side by side: cost, "
                        "residual, verdicts, initial velocities and multipliers.  If "
                        "PRINCIPLE cannot connect, the first motion is printed and "
                        "PRINCIPLE's error goes to stderr (exit code 1)")
    s.add_argument("--segments", type=int, metavar="K",
                   help="multiple shooting on K segments of the span (default: chosen "
                        "from the growth of the guess's sensitivities; 1: single "
                        "shooting)")
    s.add_argument("--restarts", type=int, metavar="K",
                   help="vakonomic, holder: where the motion found has a conjugate time "
                        "inside the span (no minimizer of the action), look for a cheaper "
                        "one from K restarts (default 0)")
    s.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="wall-clock budget for each search: it stops there "
                        "and says how close it came (default: none)")
    s.add_argument("--complete", action="store_true",
                   help="with holonomic constraints: solve the start's dependent "
                        "coordinates from g = 0 instead of refusing a start off it")
    s.add_argument("--plot", metavar="PATH",
                   help="save a plot (png, pdf, svg) of the coordinates against t")
    s.add_argument("--format", choices=("text", "json"), default="text",
                   help="text (default) or json")
    s.set_defaults(func=run)


def _connect_default(name):
    """The default of ``jetnh.connect``'s keyword ``name`` (read from its source)."""
    return declared("connect", "connect", name)


def run(args, progress) -> int:
    from ...numeric.connect import VARIATIONAL, connect

    loaded = with_split(load_model(args.model), args.split)
    system = loaded.system
    sim = loaded.simulation
    principle = args.principle or loaded.principle or "vakonomic"
    end = assignments(args.end, "--to")
    if not end:
        raise UsageError("give the end configuration: --to NAME=VALUE[,NAME=VALUE...]")
    coords = [q.name for q in system.J.q]
    given = assignments(args.start, "--from")
    zeros = [c for c in coords if c not in given and c not in loaded.initial]
    from_model = [c for c in coords if c not in given and c in loaded.initial]
    start = {c: float(loaded.initial.get(c, 0.0)) for c in coords}
    start.update(given)
    t0 = args.t_start if args.t_start is not None else float(sim.get("t_start", 0.0))
    t1 = args.t_end if args.t_end is not None else sim.get("t_end")
    if t1 is None:
        raise UsageError("give --t-end (the model file has no [simulation] t_end)")
    guess = assignments(args.guess, "--guess") or None
    if args.plot:
        outputs.check(args.plot, outputs.FIGURE, "--plot")
    kw = {"rtol": args.rtol} if args.rtol is not None else {}
    if args.atol is not None:
        kw["atol"] = args.atol
    if args.segments is not None:
        kw["segments"] = args.segments
    if args.restarts is not None:
        kw["restarts"] = args.restarts
    if args.timeout is not None:
        kw["timeout"] = args.timeout
    if args.complete:
        kw["complete"] = True
    params = assignments(args.set, "--set") or None
    with progress.step(f"connecting under {principle} over [{t0:g}, {float(t1):g}] "
                       "(kernels compiled once, then cached)"):
        c = connect(system, principle, start, end, (t0, float(t1)), params=params,
                    guess=guess, **kw)
    found, failed = [c], None
    if args.compare:
        other = args.compare
        reached = {n: float(c.trajectory[n][-1]) for n in coords}
        full = other in VARIATIONAL
        try:
            with progress.step(f"connecting under {other} to the configuration reached"):
                found.append(connect(system, other, start, reached if full else end,
                                     (t0, float(t1)), params=params, **kw))
        except JetnhError as exc:       # the first motion stands: print it, then the error
            failed = f"--compare {other}: {exc}"
    if args.format == "json":
        rows = [_record(x) for x in found]
        compared = ({"compared": rows[1]} if len(rows) > 1 else
                    {"compared": {"principle": args.compare, "error": failed}} if failed
                    else {})
        print(outputs.as_json({"model": loaded.label, "start": start, "zero_start": zeros,
                          "model_start": from_model,
                          "end": end, "t_span": [t0, float(t1)], **rows[0],
                          **compared}, indent=2))
    else:
        print(f"{system.name or loaded.label}: t in [{t0:g}, {float(t1):g}]")
        print("from:      " + ", ".join(f"{k} = {v:.10g}" for k, v in start.items()))
        if from_model:
            print(f"           (not given, the model's initial values: "
                  f"{', '.join(from_model)})")
        if zeros:
            print(f"           (not given, set to 0: {', '.join(zeros)})")
        for x in found:
            _print(x, end)
        if failed:
            print(f"-- {args.compare}\nnot connected (the error is on stderr)")
        if len(found) > 1:
            a, b = found
            print(f"{b.principle} against {a.principle}: cost {b.cost:.12g} against "
                  f"{a.cost:.12g} (difference {b.cost - a.cost:.6g}); largest distance "
                  f"between the paths {_distance(a, b, coords):.6g}")
    if args.plot:
        with progress.step(f"plotting to {args.plot}"):
            _plot(found, coords, args.plot, system.name or loaded.label)
    if failed:
        sys.stdout.flush()
        print(f"jetnh: error: {failed}", file=sys.stderr)
        return 1
    return 0


def _record(c) -> dict:
    return {"principle": c.principle, "initial": dict(c.initial), "cost": c.cost,
            "residual": c.residual, "normal": c.normal,
            "conjugate_times": (None if c.conjugate_times is None
                                else list(c.conjugate_times)),
            "legendre": c.legendre, "minimizer": c.minimizer,
            "search": c.search, "rank": c.rank, "iterations": c.iterations}


def _print(c, end):
    from ...numeric.connect.verdicts import LEGENDRE_ZERO

    print(f"-- {c.principle}")
    print("initial:   " + ", ".join(f"{k} = {v:.10g}" for k, v in c.initial.items()))
    print(f"cost:      {c.cost:.12g} (the action int L dt)")
    print(f"residual:  {c.residual:.3e} (max |q(t1) - end|)")
    print(f"normal:    {'yes' if c.normal else 'no: an abnormal extremal'}")
    times, variational = c.conjugate_times, c.legendre is not None
    print("conjugate: " + ("not checked" if times is None else
                           ", ".join(f"t = {t:.10g}" for t in times) or "none in (t0, t1]")
          + ("" if variational else " (where the endpoint map to the named coordinates "
             "is singular)"))
    if variational:
        sign = ("positive definite all along" if c.legendre > LEGENDRE_ZERO else
                "not positive semidefinite somewhere" if c.legendre < -LEGENDRE_ZERO else
                "singular somewhere: zero within its resolution")
        print(f"legendre:  {c.legendre:.6g} (the Hessian of L + lambda f on the admissible "
              f"velocities, in the independent ones scaled to a unit diagonal: its "
              f"smallest eigenvalue at the worst time: {sign})")
    if c.minimizer is False:
        print("minimizer: no (" + ("Legendre's condition fails: L + lambda f is not "
                                   "positive on the admissible velocities"
                                   if c.legendre < -LEGENDRE_ZERO else "a conjugate time "
                                   "inside the span; --restarts looks for a cheaper motion")
              + ")")
    elif c.minimizer is None and variational:
        print("minimizer: not checked (a singular Hessian of L + lambda f, or conjugate "
              "times not checked)")
    if c.search:
        print(f"search:    {c.search}")
    if c.rank < len(c.unknowns) and c.rank < len(end):
        print(f"note:      the endpoint is degenerate (shooting Jacobian of rank "
              f"{c.rank}): a family of motions arrives, this is one of them")


def _distance(a, b, coords) -> float:
    import numpy as np

    t = np.linspace(a.trajectory.t[0], a.trajectory.t[-1], 400)
    qa, qb = a.trajectory.at(t), b.trajectory.at(t)
    return float(max(np.max(np.abs(qa[n] - qb[n])) for n in coords))


def _plot(found, coords, path, title):
    """The coordinates of the motions ``found`` against t, written to ``path`` at once
    or not at all (``outputs.write``)."""
    from pathlib import Path

    import numpy as np
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4), layout="tight")
    ax = fig.add_subplot()
    for k, c in enumerate(found):
        tr = c.trajectory
        t = np.linspace(tr.t[0], tr.t[-1], 400)
        q = tr.at(t)
        for i, name in enumerate(coords):
            ax.plot(t, q[name], color=f"C{i}", ls=("-", "--")[k % 2],
                    label=f"{name} ({c.principle})")
        for tc in c.conjugate_times or ():
            ax.axvline(tc, color="k", ls=":", lw=1)
    ax.set_xlabel("t")
    ax.set_ylabel("coordinates")
    ax.legend(fontsize="small", ncol=len(found), loc="center left", bbox_to_anchor=(1, 0.5))
    c = found[0]
    ax.set_title(f"{title} ({', '.join(x.principle for x in found)}): cost "
                 + ", ".join(f"{x.cost:.6g}" for x in found)
                 + ("" if c.normal else ", abnormal")
                 + (f", conjugate at {', '.join(f'{x:.4g}' for x in c.conjugate_times)}"
                    if c.conjugate_times else ""))
    outputs.write(path, lambda tmp: fig.savefig(tmp, format=Path(path).suffix[1:]))
