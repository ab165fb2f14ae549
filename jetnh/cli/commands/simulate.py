"""``jetnh simulate``: integrate a model under one principle and print diagnostics."""

from __future__ import annotations

import sys
from pathlib import Path

from ...errors import JetnhError
from ..loading import load_model, settings, with_split
from .. import outputs
from ..parser import (EPILOG_MODEL, FALLBACK, count, jetnh_default, model_args,
                      shown_default, subcommand)
from ..running import (METHOD_HELP, assignments, initial_values, monitored_integrals,
                       step_options, stop_text)
from ..usage import UsageError


def add_parser(sub):
    s = subcommand(
        sub, "simulate", run=True,
        help="integrate a model under one principle (compiled) and print diagnostics",
        description="Simulate MODEL with a compiled jetnh Scene.  Parameters default to the "
                    "model's values and the initial state to the model's [initial] (states "
                    "not given start at 0; dependent velocities follow from the "
                    "constraints; the multipliers of vakonomic, holder and suslov are "
                    "named lambda_<dependent>).  Prints the final state and the "
                    "diagnostics: constraint residual, energy drift, first integrals "
                    "([integrals] of a model file), steps.",
        epilog=EPILOG_MODEL + "\n\nexample:\n  jetnh simulate examples/rolling_disk.toml "
                              "--t-end 10 --init psi_t=0.3 --csv disk.csv --plot disk.png")
    model_args(s)
    s.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value (repeatable, or comma-separated)")
    s.add_argument("--init", action="append", metavar="NAME=VALUE",
                   help="an initial value of a coordinate, velocity (x_t) or multiplier "
                        "(repeatable, or comma-separated)")
    s.add_argument("--method", default=None, help=METHOD_HELP)
    s.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="wall-clock budget: the run stops there and reports "
                        "what it has (default: none)")
    shown_default(s.add_argument(
        "--points", type=count, default=None, metavar="N",
        help=f"output points of the adaptive methods (default: the model's, else "
             f"{FALLBACK}; 0: every step)"), jetnh_default("points"))
    s.add_argument("--project", action="store_true",
                   help="replace initial dependent velocities that contradict the "
                        "constraints by the values the constraints give")
    s.add_argument("--complete", action="store_true",
                   help="solve holonomic constraints g(q) = 0 for the dependent coordinates "
                        "of an initial configuration off them (else it is refused)")
    s.add_argument("--csv", metavar="PATH", help="write t and every column to a CSV file")
    s.add_argument("--plot", metavar="PATH", help="save a plot (png, pdf, svg) of the run")
    s.add_argument("--path", metavar="X,Y",
                   help="with --plot: a panel of the path in the plane of these two series "
                        "(default: x,y when the model has coordinates x and y; 'none': no "
                        "path panel)")
    s.add_argument("--format", choices=("text", "json"), default="text",
                   help="text (default) or json")
    s.set_defaults(func=run)


def run(args, progress) -> int:
    import numpy as np

    from ...numeric import Scene, arguments

    model = with_split(load_model(args.model), args.split)
    system = model.system
    opts = settings(args, model)
    principle, method = opts.principle, opts.method
    # the run's options, checked before the kernels are derived and compiled
    arguments.tolerances(opts.rtol, opts.atol, 1)
    t0, t1 = arguments.time_span(opts.t_span)
    kw = step_options(args, method, (t0, t1), "--points N for N output points")
    params = assignments(args.set, "--set")

    # the initial state: the model's, then --init; missing states start at 0.  The model's
    # values of dependent velocities are checked against the constraints, unless --split
    # changed which velocities are dependent (then they follow from them)
    initial, zeros = initial_values(model, principle, assignments(args.init, "--init"),
                                    dependent_velocities=not args.split)
    integrals, skipped = monitored_integrals(model, principle)
    for k in skipped:
        progress.note(f"jetnh: the integral {k!r} uses multipliers, which the {principle} "
                      "state does not have; skipped")

    if args.path is not None and not args.plot:
        raise UsageError("--path chooses a panel of the plot: give --plot PATH too")
    path_names = _path_names(args.path, system)
    for out, kinds, what in ((args.csv, outputs.TEXT, "--csv"),
                             (args.plot, outputs.FIGURE, "--plot")):
        if out:
            outputs.check(out, kinds, what)
    try:
        scene = Scene(system, principle, params=params, initial=initial, t_span=(t0, t1),
                      convention=opts.convention, integrals=integrals,
                      project=args.project, complete=args.complete)
    except JetnhError as exc:
        msg = (str(exc).replace("pass project=True", "pass --project")
               .replace("pass complete=True", "pass --complete")
               .replace(" (complete=[...] names other coordinates)", ""))
        raise type(exc)(msg) from None
    if path_names:
        _check_series(path_names, scene)
    with progress.step(f"deriving and compiling the {principle} kernels "
                       "(cached for later runs)"):
        scene.compile()
    if "n_steps" not in kw and opts.points >= 2:
        kw["t_eval"] = np.linspace(t0, t1, opts.points)
    with progress.step(f"integrating with {method} over [{t0:g}, {t1:g}]"):
        traj = scene.run(rtol=opts.rtol, atol=opts.atol, method=method, timeout=args.timeout,
                         **kw)
    d = traj.diagnostics
    # where the run ended: with output times (t_eval) a run stopped early went on past
    # its last row, to the state it keeps, unless that state is not finite (a singular
    # stop where the values overflowed: then final is the last row, before the stop)
    final = traj.final
    t_final = traj.t_final if len(traj) else t0
    last_state = ("t_eval" not in kw or traj.singularity is None
                  or traj.singularity["t"] == t_final)
    if args.format == "json":
        print(outputs.as_json({"model": model.label, "principle": principle,
                          "params": scene.params, "initial": scene.initial,
                          "final": final, "final_t": t_final, "final_is_last_state":
                          last_state, "diagnostics": d.as_dict(),
                          "zero_initial": zeros}, indent=2))
    else:
        print(f"{system.name or model.label}: {principle}, t in [{t0:g}, {t1:g}]")
        if scene.params:
            print("parameters: " + ", ".join(f"{k} = {v:g}" for k, v in scene.params.items()))
        print("initial:    " + ", ".join(f"{k} = {v:.10g}" for k, v in scene.initial.items()))
        if zeros:
            print(f"            (not given, set to 0: {', '.join(zeros)})")
        if scene.projected:
            print("projected:  " + ", ".join(f"{k}: {g:g} -> {v:.10g}"
                                             for k, (g, v) in scene.projected.items()))
        values = ", ".join(f"{k} = {v:.10g}" for k, v in final.items())
        if last_state:
            print("final:      " + values)
            if not traj.success:
                print(f"stopped:    at t = {t_final:.10g}: {stop_text(traj, args, False)}")
        else:
            print(f"last row:   t = {t_final:.10g}: " + values)
            print(f"stopped:    after the last row: {stop_text(traj, args)}; its state "
                  "there is not finite")
        print(d)
    if args.csv:
        outputs.write(args.csv, lambda tmp: _write_csv(traj, tmp))
        progress.note(f"wrote {args.csv}")
    if args.plot:
        with progress.step(f"plotting to {args.plot}"):
            outputs.write(args.plot, lambda tmp: _plot(
                traj, system, tmp, f"{system.name or model.label} ({principle})",
                path_names, Path(args.plot).suffix[1:]))
    if not traj.success:
        print(f"jetnh: error: the integration stopped early: {stop_text(traj, args)}",
              file=sys.stderr)
        return 1
    return 0


def _write_csv(traj, path):
    import numpy as np

    cols = traj.as_dict()
    names = list(cols)
    data = np.column_stack([cols[n] for n in names])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(names) + "\n")
        for row in data:
            fh.write(",".join(repr(float(x)) for x in row) + "\n")


def _path_names(text, system) -> tuple | None:
    """The two series of the path panel: ``--path X,Y``, or x and y when the model has
    such coordinates; None for no panel."""
    coords = {q.name for q in system.J.q}
    if text is None:
        return ("x", "y") if {"x", "y"} <= coords else None
    if text.strip().lower() == "none":
        return None
    names = [n.strip() for n in text.split(",")]
    if len(names) != 2 or not all(names):
        raise UsageError(f"--path takes two series names separated by a comma (e.g. "
                         f"--path x,y), not {text!r}")
    return tuple(names)


def _check_series(names, scene):
    """The ``--path`` names, before the run: each must be a series of its trajectory
    (time, a coordinate, a velocity, a multiplier, a first integral, the energy or a
    constraint residual); every unknown one is named."""
    system = scene.system
    known = (["t"] + [q.name for q in system.J.q] + [v.name for v in system.J.qd]
             + list(scene.multipliers) + list(scene.integrals) + ["energy"]
             + [f"residual[{a}]" for a in range(system.k)])
    unknown = [n for n in names if n not in known]
    if unknown:
        raise UsageError(f"--path: {', '.join(map(repr, unknown))} "
                         + ("is not a series" if len(unknown) == 1 else "are not series")
                         + f" of this run; choose from {', '.join(known)}")


def _plot(traj, system, path, title, path_names=None, form=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = _figure(traj, system, title, path_names)
    fig.savefig(path, format=form)
    plt.close(fig)


def _figure(traj, system, title, path_names=None):
    """The series of the run against t (coordinates, velocities, multipliers, then the
    constraint residual and the energy drift) and, with ``path_names``, the path in
    their plane beside them."""
    import numpy as np
    from matplotlib.figure import Figure

    coords = [q.name for q in system.J.q]
    vels = [v.name for v in system.J.qd]
    lams = [n for n in traj.names if n.startswith("lambda_")]
    groups = [("coordinates", coords), ("velocities", vels)] + ([("multipliers", lams)]
                                                                 if lams else [])
    rows = len(groups) + 1
    fig = Figure(figsize=(8 + 4.5 * bool(path_names), 2.6 * rows), layout="constrained")
    grid = fig.add_gridspec(rows, 2 if path_names else 1,
                            width_ratios=[8, 4.5] if path_names else None)
    axes = [fig.add_subplot(grid[0, 0])]
    axes += [fig.add_subplot(grid[i, 0], sharex=axes[0]) for i in range(1, rows)]
    for ax, (label, names) in zip(axes, groups):
        for n in names:
            ax.plot(traj.t, traj[n], label=n)
        ax.set_ylabel(label)
        ax.legend(fontsize="small", ncol=min(len(names), 4))
    ax = axes[-1]
    floor = 1e-17                        # exact zeros would squash the log scale
    res = traj.residual
    if res.size:
        ax.semilogy(traj.t, np.maximum(abs(res).max(axis=1), floor), label="max |f|")
    E = traj.energy
    ax.semilogy(traj.t, np.maximum(abs(E - E[0]), floor), label="|E - E(t0)|")
    ax.set_ylabel(f"diagnostics (floor {floor:g})")
    ax.legend(fontsize="small")
    axes[-1].set_xlabel("t")
    if path_names:
        plane = fig.add_subplot(grid[:, 1])
        traj.plot_path(*path_names, ax=plane)
        plane.set_title(f"path in the ({path_names[0]}, {path_names[1]}) plane "
                        "(dot: the start)")
    fig.suptitle(title)
    return fig
