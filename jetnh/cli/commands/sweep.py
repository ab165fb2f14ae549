"""``jetnh sweep``: run a model over a grid of parameters and initial values."""

from __future__ import annotations

import math
from pathlib import Path

from ..loading import load_model, settings, with_split
from .. import outputs
from ..parser import (EPILOG_MODEL, evenly_spaced, model_args, positive_count, seconds,
                      subcommand)
from ..running import (METHOD_HELP, assignments, initial_values, method_of,
                       monitored_integrals, step_options)
from ..usage import UsageError


def add_parser(sub):
    w = subcommand(
        sub, "sweep", run=True,
        help="run a model over a grid of parameters and initial values (here or on Dask)",
        description="Run MODEL at every point of the grid (the Cartesian product of the "
                    "--grid axes) and write one row per point: the grid values (initial "
                    "values as NAME(t0)), the final values of the states (or their values "
                    "at --times as NAME(t=T)) and the diagnostics: status, stop_reason, "
                    "steps (NaN for scipy-* methods, which do not count them), "
                    "constraint residual, energy and first-integral drift over the rows a "
                    "run stores (dop853, dopri5, rk4, radau: t0 and the final time or "
                    "--times, not every step; dla, dvi, scipy-*: every step).  A point "
                    "that fails keeps its row with its stop_reason.  The other values "
                    "are as for `jetnh simulate`.  With --scheduler the points run as "
                    "chunks on a Dask cluster (the result is the same to the last bit).",
        epilog=EPILOG_MODEL + "\n\nexamples:\n"
               "  jetnh sweep rolling_disk --grid R=0.5:2:16 --grid phi_t=0.1:1:16 "
               "--out disk.parquet\n"
               "  jetnh sweep appell_hamel --grid x_t=0:3:31 --times 0.1,0.5 --scheduler "
               "tcp://127.0.0.1:8786 --out ah.csv\n"
               "  jetnh sweep rolling_disk --grid R=0.5:2:40 --grid psi_t=-1:1:40 --plot "
               "map.png --value x --out map.csv")
    model_args(w)
    w.add_argument("--grid", action="append", required=True, metavar="NAME=A:B:N",
                   help="an axis: N evenly spaced values from A to B (N >= 1), or "
                        "NAME=V1,V2,... (repeatable; NAME a parameter or a state)")
    w.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value for every point (repeatable, or comma-separated)")
    w.add_argument("--init", action="append", metavar="NAME=VALUE",
                   help="an initial value for every point (repeatable, or comma-separated)")
    w.add_argument("--times", metavar="T1,T2,...|A:B:N",
                   help="output times (default: the final time only)")
    w.add_argument("--outputs", metavar="NAME,...",
                   help="output columns (default: every state, dependent velocity and "
                        "integral)")
    w.add_argument("--method", default=None,
                   help=METHOD_HELP + "; dla, dvi and scipy run point by point")
    w.add_argument("--scheduler", metavar="ADDRESS",
                   help="a Dask scheduler, e.g. tcp://10.0.0.5:8786 (needs pip install "
                        "'jetnh[cluster]'; default: this machine, every core, no Dask)")
    w.add_argument("--chunk-size", type=positive_count, default=None, metavar="N",
                   help="points per Dask task (default: 4 tasks per worker thread)")
    w.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="give up on the sweep after this long (default: no limit)")
    w.add_argument("--connect-timeout", type=seconds, default=10.0, metavar="SECONDS",
                   help="time to reach the scheduler (default 10)")
    w.add_argument("--out", metavar="PATH",
                   help="write the table to PATH (.parquet or .csv); default: CSV on stdout")
    w.add_argument("--plot", metavar="PATH",
                   help="save the map of --value over the two --grid axes (PNG)")
    w.add_argument("--value", metavar="COLUMN", help="the column --plot shows")
    w.set_defaults(func=run)


def _values(text: str, what: str, one: str = "") -> list:
    """``A:B:N`` (``parser.evenly_spaced``: one value or more) or ``V1,V2,...``: finite
    numbers, read by float() (never evaluated)."""
    import numpy as np

    listed = "a comma-separated list of finite numbers"
    if ":" in text:
        return list(np.linspace(*evenly_spaced(text, what, least=1, one=one,
                                               otherwise=listed)))
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = [math.nan]
    if not all(map(math.isfinite, values)):
        raise UsageError(f"{what}: {text!r} is neither A:B:N nor {listed}")
    return values


def _grid(items) -> dict:
    grid = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"--grid takes NAME=A:B:N or NAME=V1,V2,..., got {item!r}")
        if name in grid:
            raise UsageError(f"--grid gives {name} twice; give each name once")
        grid[name] = _values(text, f"--grid {name}", one=f"--grid {name}={{a}}")
    return grid


def _write_table(df, path: Path):
    if path.suffix.lower() == ".csv":
        outputs.write(path, lambda tmp: df.to_csv(tmp, index=False))
    else:
        outputs.write(path, lambda tmp: df.to_parquet(tmp, index=False))


def run(args, progress) -> int:
    from ...numeric import Scene
    from ...sweep import plot_map, sweep

    grid = _grid(args.grid)
    times = _values(args.times, "--times", one="--times {a}") if args.times else None
    if args.plot and (len(grid) != 2 or not args.value):
        raise UsageError("--plot draws a map over two --grid axes of the column --value; "
                         "give exactly two --grid and a --value")
    for out, kinds, what in ((args.out, outputs.TABLE, "--out"),
                             (args.plot, outputs.FIGURE, "--plot")):
        if out:
            outputs.check(out, kinds, what)
    model = with_split(load_model(args.model), args.split)
    system = model.system
    opts = settings(args, model)
    principle, method = opts.principle, opts.method
    t_span = opts.t_span
    steps = step_options(args, method, t_span, "--times for output times")
    if times is not None and not method_of(method).dense:
        raise UsageError(f"--times needs dense output, which {method} does not have; use "
                         "--method dop853, dopri5, radau or scipy-<M>, or omit --times (final "
                         "values)")
    initial, _ = initial_values(model, principle, assignments(args.init, "--init"))
    integrals, _ = monitored_integrals(model, principle)
    params = assignments(args.set, "--set")
    scene = Scene(system, principle, params=params, initial=initial, t_span=t_span,
                  convention=opts.convention, integrals=integrals,
                  runtime_params=[k for k in grid if k in {p.name for p in system.parameters}])
    with progress.step(f"deriving and compiling the {principle} kernels "
                       "(cached for later runs)"):
        scene.compile()
    where = f"on the Dask cluster at {args.scheduler}" if args.scheduler else "on this machine"
    show, close = progress.bar(f"sweeping {where}", "point")
    try:
        df = sweep(scene, grid, client=args.scheduler, times=times,
                   outputs=args.outputs.split(",") if args.outputs else None,
                   chunk_size=args.chunk_size, progress=show, timeout=args.timeout,
                   connect_timeout=args.connect_timeout, method=method, rtol=opts.rtol,
                   atol=opts.atol, **steps)
    finally:
        close()
    failed = int((~df["success"]).sum())
    progress.note(f"jetnh: {len(df)} points, {len(df) - failed} succeeded"
                  + (f", {failed} stopped early (see stop_reason)" if failed else ""))
    if args.out:
        _write_table(df, Path(args.out))
        progress.note(f"wrote {args.out}")
    else:
        print(df.to_csv(index=False), end="")
    if args.plot:
        x, y = df.attrs["grid"]
        title = f"{system.name or model.label} ({principle}): {args.value}"
        outputs.write(args.plot, lambda tmp: plot_map(df, x, y, args.value, tmp, title=title))
        progress.note(f"wrote {args.plot}")
    return 0
