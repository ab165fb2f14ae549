"""``jetnh linearize``: the linearization of a model about an operating point, its
eigenvalues and stability verdict; optionally along a parameter (crossings of
Re lambda = 0, a stability diagram)."""

from __future__ import annotations


from ..loading import load_model, settings, with_split
from .. import outputs
from ..parser import EPILOG_MODEL, evenly_spaced, model_args, subcommand
from ..running import assignments, initial_values
from ..usage import UsageError


def add_parser(sub):
    s = subcommand(
        sub, "linearize", principle=True,
        help="linearize a model about an operating point: A, eigenvalues, stability",
        description="Linearize MODEL's equations under one principle on the constraint "
                    "manifold about the operating point --at (states not given take the "
                    "model's initial values, else 0; dependent velocities follow from the "
                    "constraints).  Prints the state, A, the eigenvalues, the residual "
                    "|x'| (0: a steady motion) and the verdict.  --steady solves for some "
                    "states so that the point is a steady motion; --param scans a "
                    "parameter or a state and locates where Re lambda crosses 0.",
        epilog=EPILOG_MODEL + "\n\nexample:\n  jetnh linearize rolling_coin --at theta=0,"
                              "psi_t=0,theta_t=0,phi_t=3 --param phi_t=0.2:4:39 "
                              "--plot coin.png")
    model_args(s)
    s.add_argument("--at", action="append", metavar="NAME=VALUE",
                   help="a value of the operating point: coordinate, velocity (x_t) or "
                        "multiplier (repeatable, or comma-separated)")
    s.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value (repeatable, or comma-separated)")
    s.add_argument("--drop", default="cyclic", metavar="cyclic|none|Q1,Q2",
                   help="coordinates left out of the state (default: cyclic, those the "
                        "equations do not use)")
    s.add_argument("--steady", metavar="NAME,...",
                   help="states to solve for so that the point is a steady motion")
    s.add_argument("--param", action="append", metavar="NAME=A:B:N",
                   help="scan NAME (a parameter or a state) over N evenly spaced values "
                        "from A to B (N >= 2); one scan: give it once")
    s.add_argument("--plot", metavar="PATH", help="with --param: save the stability "
                                                  "diagram (png, pdf, svg)")
    s.add_argument("--format", choices=("text", "json"), default="text",
                   help="text (default) or json")
    s.set_defaults(func=run)


def _scan(items):
    """The one scan of ``--param`` (None without it): a scan is along one name, so a
    second --param is refused rather than dropped."""
    if not items:
        return None
    if len(items) > 1:
        raise UsageError("--param scans one name, got " + " and ".join(
            repr(i) for i in items) + ": give --param once, and the other names a value "
            "with --at or --set")
    return _scan_spec(items[0])


def _scan_spec(text: str):
    name, sep, rng = (text or "").partition("=")
    name = name.strip()
    if not sep or not name:
        raise UsageError(f"--param takes NAME=A:B:N, got {text!r} (e.g. phi_t=0.5:4:50)")
    return (name, *evenly_spaced(rng, f"--param {name}", least=2,
                                 one=f"--at {name}={{a}} or --set {name}={{a}} to linearize "
                                     "at that one value"))


def run(args, progress) -> int:
    import numpy as np

    from ...numeric.linearize import linearize

    model = with_split(load_model(args.model), args.split)
    system = model.system
    opts = settings(args, model)
    principle = opts.principle
    params = assignments(args.set, "--set")
    scan = _scan(args.param)
    if args.plot and not scan:
        raise UsageError("--plot draws the stability diagram of a scan: give --param too")
    if args.plot:
        outputs.check(args.plot, outputs.FIGURE, "--plot")
    at, zeros = initial_values(model, principle, assignments(args.at, "--at"))
    drop = {"cyclic": "cyclic", "none": None}.get(args.drop)
    if args.drop not in ("cyclic", "none"):
        drop = [d.strip() for d in args.drop.split(",") if d.strip()]
    with progress.step(f"deriving and compiling the {principle} Jacobian "
                       "(cached for later runs)"):
        lin = linearize(system, principle, at=at, params=params, drop=drop,
                        convention=opts.convention)
    if args.steady:
        lin = lin.steady([n.strip() for n in args.steady.split(",") if n.strip()])
    result = None
    if scan:
        name, a, b, n = scan
        result = lin.along(name, np.linspace(a, b, n))
    if args.format == "json":
        out = {"model": model.label, "principle": principle, "params": dict(lin.params),
               "at": dict(lin.at), "state": list(lin.state_names),
               "dropped": list(lin.dropped), "eliminated": list(lin.eliminated),
               "A": lin.A.tolist(),
               "eigenvalues": [[z.real, z.imag] for z in lin.eigenvalues.tolist()],
               "residual": lin.residual, "steady_motion": lin.steady_motion,
               "verdict": lin.verdict, "zero_at": zeros}
        if result is not None:
            out["scan"] = {"name": result.name, "crossings": list(result.crossings),
                           "values": result.values.tolist(),
                           "steady_motion": result.steady_motion.tolist(),
                           "stable": result.stable.tolist()}
        print(outputs.as_json(out, indent=2))
    else:
        print(f"{system.name or model.label}: {principle}")
        if lin.params:
            print("parameters: " + ", ".join(f"{k} = {v:g}" for k, v in lin.params.items()))
        print("at:         " + ", ".join(f"{k} = {v:.10g}" for k, v in lin.at.items()))
        if zeros:
            print(f"            (not given, set to 0: {', '.join(zeros)})")
        print(f"state:      {', '.join(lin.state_names)}"
              + (f" (dropped: {', '.join(lin.dropped)})" if lin.dropped else "")
              + (f" (from g = 0: {', '.join(lin.eliminated)})" if lin.eliminated else ""))
        with np.printoptions(precision=6, suppress=True, linewidth=100):
            print("A =")
            print(lin.A)
            print(f"eigenvalues: {lin.eigenvalues}")
        print(f"residual |x'| = {lin.residual:.3g}"
              + ("  (a steady motion)" if lin.steady_motion else
                 "  (not a steady motion: no stability verdict; --steady NAME,... solves "
                 "for one)"))
        print(f"verdict: {lin.verdict}")
        if result is not None:
            stable, off = result.stable, int((~result.steady_motion).sum())
            print(f"scan of {result.name} over [{scan[1]:g}, {scan[2]:g}] ({scan[3]} values): "
                  f"stable at {int(stable.sum())} of them"
                  + (f" ({off} not steady motions)" if off else ""))
            print("crossings of Re lambda = 0: "
                  + (", ".join(f"{c:.12g}" for c in result.crossings) or "none"))
    if args.plot:
        _plot(result, args.plot, f"{system.name or model.label} ({principle})", progress)
    return 0


def _plot(result, path, title, progress):
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with progress.step(f"plotting to {path}"):
        ax = result.plot()
        ax.set_title(title)
        ax.figure.tight_layout()
        outputs.write(path, lambda tmp: ax.figure.savefig(tmp, format=Path(path).suffix[1:]))
        plt.close(ax.figure)
