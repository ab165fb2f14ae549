"""The ``jetnh`` command: derive, compare, simulate and sweep constrained systems; list the
catalogue; run the benchmarks and the seed paper's reproduction.

MODEL is a catalogue name (``jetnh models`` lists them; options as in ``n_trailer:N=4``)
or the path of a model file (TOML; see ``jetnh.modelfile`` and ``examples/*.toml``).

Exit codes: 0 ok, 2 usage, 1 model or numerical error.  Errors print a message on
stderr, never a traceback (``--debug`` shows one for errors that are jetnh's own bugs).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp

from .mechanics import principles
from .errors import ArgumentError, JetnhError, ModelFileError, PrincipleError
from .mechanics.principles import PRINCIPLES

EPILOG_MODEL = ("MODEL: a catalogue name (see `jetnh models`; scalable ones take options, "
                "e.g. n_trailer:N=4) or a model file (TOML, e.g. examples/rolling_disk.toml).")


class UsageError(Exception):
    """Bad command-line syntax (exit code 2)."""


#: Scene.run's argument names -> the options of simulate and sweep that set them
OPTION_NAMES = {"n_steps": "--steps", "rtol": "--rtol", "atol": "--atol",
                "timeout": "--timeout"}
_ARG_NAME = re.compile(r"(?<![\w-])(" + "|".join(OPTION_NAMES) + r")(?:=(?=\s|$))?(?!\w)")


def option_message(message: str) -> str:
    """An ``ArgumentError`` message with Scene.run's argument names as the CLI options."""
    return _ARG_NAME.sub(lambda m: OPTION_NAMES[m.group(1)], message)


# ---------------------------------------------------------------------- progress
#: seconds a step runs before a terminal shows its elapsed time (a sign of life)
SIGN_OF_LIFE = 1.0


class Progress:
    """Step-by-step progress on stderr: ``jetnh: deriving chetaev ... 0.31 s``.  On a
    terminal a step that takes longer than ``SIGN_OF_LIFE`` seconds shows its elapsed
    time while it runs (a tqdm status line), and sweeps show a tqdm bar; elsewhere
    (a pipe, a log) each step is a line.  ``quiet``: nothing."""

    def __init__(self, quiet=False, stream=None):
        self.quiet = quiet
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def note(self, message: str):
        """A line on stderr, unless quiet (errors are not notes)."""
        if not self.quiet:
            print(message, file=self.stream, flush=True)

    @contextmanager
    def step(self, what: str):
        if self.quiet:
            yield
            return
        t0 = time.perf_counter()
        if not self.tty:
            self.stream.write(f"jetnh: {what} ...\n")
            self.stream.flush()
        ticker = _Ticker(self.stream, f"jetnh: {what} ...") if self.tty else None
        ok = False
        try:
            yield
            ok = True
        finally:
            dt = time.perf_counter() - t0
            if ticker is not None:
                ticker.close()
                self.stream.write(f"jetnh: {what} ... {'done' if ok else 'failed'} "
                                  f"({dt:.2f} s)\n")
            elif dt >= 0.5 or not ok:
                self.stream.write(f"jetnh: {what}: {'done' if ok else 'failed'} ({dt:.2f} s)\n")
            self.stream.flush()

    def bar(self, what: str, unit: str):
        """A ``progress(done, total)`` callback and a function that ends it: a tqdm bar
        on a terminal, else one line per tenth (None when quiet)."""
        if self.quiet:
            return None, lambda: None
        from tqdm import tqdm

        if self.tty:
            bars = []

            def show(done, total):
                if not bars:
                    bars.append(tqdm(total=total, desc=f"jetnh: {what}", unit=unit,
                                     file=self.stream))
                bars[0].update(done - bars[0].n)
            return show, lambda: bars and bars[0].close()
        shown, t0 = [-1], time.perf_counter()

        def line(done, total):
            if 10 * done // total > shown[0]:
                shown[0] = 10 * done // total
                text = tqdm.format_meter(
                    done, total, time.perf_counter() - t0, prefix=f"jetnh: {what}",
                    bar_format="{desc}: {n_fmt}/{total_fmt} " + unit + "s [{elapsed}<"
                               "{remaining}]")
                self.stream.write(text + "\n")
                self.stream.flush()
        return line, lambda: None


class _Ticker:
    """A tqdm status line with the elapsed time of a running step, refreshed from a
    thread, shown once the step has run ``SIGN_OF_LIFE`` seconds; cleared on close."""

    def __init__(self, stream, what):
        import threading

        from tqdm import tqdm

        self.bar = tqdm(total=None, desc=what, file=stream, leave=False,
                        delay=SIGN_OF_LIFE, mininterval=0.2, bar_format="{desc} {elapsed}")
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop.wait(0.25):
            self.bar.update(0)

    def close(self):
        self.stop.set()
        self.thread.join()
        self.bar.close()


# ---------------------------------------------------------------------- models
@dataclass
class Loaded:
    """A model from the catalogue or a file, with its defaults for simulation."""

    system: object
    label: str
    initial: dict = field(default_factory=dict)
    principle: str | None = None
    convention: str | None = None
    integrals: dict = field(default_factory=dict)
    simulation: dict = field(default_factory=dict)


_SPEC = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?::(.*))?$")


def _catalogue_options(text: str, model: str) -> dict:
    opts = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        k, sep, v = item.partition("=")
        if not sep:
            raise UsageError(f"model options are KEY=VALUE, got {item!r} in {model!r} "
                             "(e.g. n_trailer:N=4)")
        try:
            opts[k.strip()] = int(v)
        except ValueError:
            raise UsageError(f"model option {k.strip()} must be an integer, got {v!r}") from None
    return opts


def load_model(spec: str) -> Loaded:
    """A catalogue name (``name`` or ``name:K=V,...``) or a path to a model file."""
    from . import models
    from .modelfile import load

    path = Path(spec)
    match = _SPEC.match(spec)
    looks_like_file = spec.endswith(".toml") or os.sep in spec or "/" in spec
    in_catalogue = bool(match) and match.group(1) in models.CATALOGUE
    if looks_like_file or (not in_catalogue and path.exists()):
        m = load(path)
        return Loaded(m.system, m.name or path.stem, dict(m.initial), m.principle,
                      m.convention, dict(m.integrals), dict(m.simulation))
    if not in_catalogue:
        raise ModelFileError(
            f"no model named {spec!r} in the catalogue, and no model file of that name; "
            f"the catalogue has {', '.join(models.CATALOGUE)} (see `jetnh models`)")
    name, rest = match.group(1), match.group(2)
    opts = _catalogue_options(rest or "", spec)
    info = models.info(name)
    system = info.system(**opts)
    return Loaded(system, spec, info.initial(**opts), None, None, {},
                  {"t_end": info.t_end})


def _with_split(loaded: Loaded, split: str | None) -> Loaded:
    if split:
        names = [s.strip() for s in split.split(",") if s.strip()]
        loaded.system = loaded.system.with_split(names)
    return loaded


# ---------------------------------------------------------------------- derive
#: characters of a result printed on the screen; --out FILE writes the full form
SCREEN_BUDGET = 20_000


def _label(expr) -> str:
    """A short input expression (L, a force) in full, a large one summarized."""
    from .algebra.singular import label

    return label(sp.sympify(expr, strict=True))


def _write(args, progress, text: str, form) -> None:
    """The result: to --out in full, else on stdout (``text`` is the short form)."""
    if args.out:
        path = Path(args.out)
        if not path.resolve().parent.is_dir():
            raise JetnhError(f"cannot write {path}: the directory {path.resolve().parent} "
                             "does not exist")
        path.write_text(text + "\n", encoding="utf-8")
        progress.note(f"jetnh: wrote {path} ({len(form.where)} named quantities)")
    else:
        print(text)


def _render(args, form, header: list, data: dict, J, keys=None) -> str:
    """``form`` (``jetnh.algebra.shared``) after ``header`` lines (text and LaTeX) or inside
    ``data`` (JSON, its headings renamed by ``keys``): in full with --out, else within
    the screen budget."""
    from .algebra.shared import SharedForm

    budget = None if args.out else SCREEN_BUDGET
    more = " (write them all with --out FILE)"
    if args.format == "json":
        keys = keys or {}
        form = SharedForm([keys.get(r, r) if isinstance(r, str) else r for r in form.rows],
                          form.where)
        data.update(form.as_dict(budget))
        return json.dumps(data, indent=2)
    if args.format == "latex":
        return form.latex(J, budget, more)
    return "\n".join(header + [form.text(budget, more)])


def _simplified(form, seconds, progress):
    """``form`` with its small expressions (rows and named quantities: ``Simplifier``)
    trigsimp'd within ``seconds`` each, 10 x ``seconds`` in all, the others kept (the
    rows refer to the named quantities by name).  ``seconds`` None: 0.5 s for a result
    small enough to be shown without names, else none."""
    from .algebra.shared import SharedForm

    if seconds is None:
        seconds = 0.0 if form.where else 0.5
    simp = Simplifier(per=seconds, total=10 * seconds)
    if not simp.ok:
        return form
    with progress.step(f"simplifying for display ({seconds:g} s each)"):
        rows = [r if isinstance(r, str) else (r[0], simp(r[1])) for r in form.rows]
        where = [(name, simp(e)) for name, e in form.where]
    progress.note(f"jetnh: simplified {simp.done} of {len(form.expressions()) + len(where)} expressions ("
                  f"{simp.large} too large, {simp.timed_out} out of time, "
                  f"{simp.unstarted} "
                  f"past the {simp.total:g} s budget: shown as derived)")
    return SharedForm(rows, where)


class _Budget(Exception):
    pass


class Simplifier:
    """trigsimp for display (never on a hot path): each expression of at most ``nodes``
    tree nodes within ``per`` seconds, at most ``total`` seconds in all (SIGALRM; where
    that is unavailable, or with ``per = 0``, expressions are shown as derived)."""

    def __init__(self, per: float = 0.5, total: float = 5.0, nodes: int = 60):
        import signal
        import threading

        self.per, self.left, self.total, self.nodes = per, total, total, nodes
        self.done = self.timed_out = self.unstarted = self.large = 0
        self.ok = (per > 0 and hasattr(signal, "setitimer")
                   and threading.current_thread() is threading.main_thread())

    def __call__(self, expr):
        from .algebra.shared import tree_size

        if tree_size([expr], self.nodes) > self.nodes:
            self.large += 1
            return expr
        if not self.ok or self.left <= 0:
            self.unstarted += 1
            return expr
        import signal

        def alarm(signum, frame):
            raise _Budget
        budget = min(self.per, self.left)
        old = signal.signal(signal.SIGALRM, alarm)
        t0 = time.perf_counter()
        try:
            signal.setitimer(signal.ITIMER_REAL, budget)
            try:
                out = sp.trigsimp(expr)
                self.done += 1
                return out
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
        except _Budget:
            self.timed_out += 1
            return expr
        finally:
            signal.signal(signal.SIGALRM, old)
            self.left -= time.perf_counter() - t0


def cmd_derive(args, progress) -> int:
    from .algebra.shared import shared_form

    loaded = _with_split(load_model(args.model), args.split)
    system = loaded.system
    principle = args.principle or loaded.principle or "chetaev"
    convention = args.convention or loaded.convention or "paper"
    with progress.step(f"deriving the {principle} equations"):
        eom = system.equations(principle, form=args.form, convention=convention)
        exprs = eom.expressions
    with progress.step("solving for the accelerations"):
        acc = eom.accelerations()
    heads = [f"{eom.principle} equations, {eom.form} form {eom.paper}".rstrip(),
             "accelerations (on the constraint manifold)", "the constraint manifold"]
    with progress.step("writing in shared form"):
        form = shared_form([heads[0]] + [(None, e) for e in exprs] + [heads[1]]
                           + list(acc.items()) + ([heads[2]] if system.phi else [])
                           + list(system.phi.items()))
    form = _simplified(form, args.simplify, progress)
    name = system.name or loaded.label
    header = [f"{name}: dependent {', '.join(q.name for q in system.dependent) or 'none'}"]
    if system.dissipation != 0:
        header.append(f"  dissipation D = {_label(system.dissipation)} "
                      "(Q_s = forces - dD/dqdot^s)")
    header += [f"  force Q_{k} = {v}" for k, v in _forces(system).items()]
    data = {"model": loaded.label, "name": system.name, "principle": eom.principle,
            "form": eom.form, "convention": eom.convention, "paper": eom.paper,
            "coordinates": [q.name for q in system.J.q],
            "dependent": [q.name for q in system.dependent],
            "parameters": {s.name: v for s, v in system.defaults.items()},
            "forces": _forces(system), "dissipation": _label(system.dissipation),
            "multipliers": [str(m) for m in eom.multipliers]}
    keys = dict(zip(heads, ("expressions", "accelerations", "dependent_velocities")))
    _write(args, progress, _render(args, form, header, data, eom.J, keys), form)
    return 0


def _forces(system) -> dict:
    """The nonzero generalized forces Q_s (forces and -dD/dqdot^s), by coordinate name."""
    return {q.name: _label(Q) for q, Q in zip(system.J.q, system.Q) if Q != 0}


# ---------------------------------------------------------------------- compare
#: tree nodes of phi up to which compare shows the forms on L~ and T (they
#: differentiate phi as a tree: exponential in a chain of constraints)
PHI_TREE_MAX = 2_000
_COMPARE_FORMS = {"chetaev": "voronets", "vakonomic": "embedded", "holder": "embedded",
                  "suslov": "embedded"}


def cmd_compare(args, progress) -> int:
    from .mechanics.equivalence import comparisons
    from .algebra.shared import shared_form, tree_size

    loaded = _with_split(load_model(args.model), args.split)
    system = loaded.system
    J = system.J
    small = tree_size(list(system.phi.values()), PHI_TREE_MAX) <= PHI_TREE_MAX
    with progress.step("classifying"):
        cls = system.classify()
    header = [f"{system.name or loaded.label}",
              f"  coordinates: {' '.join(q.name for q in J.q)}; dependent: "
              f"{' '.join(q.name for q in system.dependent)}",
              f"  L = {_label(system.L)}"]
    header += [f"  constraint: {_label(f)} = 0" for f in system.constraints]
    header += [f"  force Q_{k} = {v}" for k, v in _forces(system).items()]
    header.append(f"  classification: {cls}")
    rows: list = ["the constraint manifold and the embedded Lagrangian"]
    rows += list(system.phi.items()) + [("L~", system.L_tilde)]
    if small:
        with progress.step("computing T"):
            T = system.T()
        rows += [(f"T^{system.dependent[a].name}_{system.independent[m].name}", T[a, m])
                 for a in range(T.rows) for m in range(T.cols)]
    else:
        header.append(f"  (phi is a nested expression of over {PHI_TREE_MAX} tree nodes: T "
                      "and the forms on L~, which differentiate it, are not shown; the "
                      "accelerations are)")
    solved = {}
    for principle in PRINCIPLES:
        form = _COMPARE_FORMS[principle] if small else None
        with progress.step(f"deriving {principle}"):
            eom = system.equations(principle, form=form)
            solved[principle] = eom
            if small:
                rows.append(f"{principle} ({eom.form} form {eom.paper})".replace(" )", ")"))
                rows += [(None, e) for e in eom.expressions]
            rows.append(f"{principle} accelerations")
            rows += list(eom.accelerations().items())
    with progress.step("writing in shared form"):
        form = shared_form(rows)
    form = _simplified(form, args.simplify, progress)
    verdicts = []
    with progress.step("comparing every pair of principles"):
        for c in comparisons(system, solved):
            verdicts.append(f"  {c}")
    if args.format == "json":
        data = {"model": loaded.label, "name": system.name,
                "coordinates": [q.name for q in J.q],
                "dependent": [q.name for q in system.dependent],
                "classification": str(cls),
                "equivalence": [v.strip() for v in verdicts]}
        text = _render(args, form, [], data, J)
    else:
        text = "\n".join([_render(args, form, header, {}, J), "", "equivalence:"] + verdicts)
    _write(args, progress, text, form)
    return 0


# ---------------------------------------------------------------------- simulate
def _assignments(items, what) -> dict:
    out = {}
    for item in items or ():
        for part in filter(None, (p.strip() for p in item.split(","))):
            k, sep, v = part.partition("=")
            if not sep or not k.strip():
                raise UsageError(f"{what} takes NAME=VALUE, got {part!r}")
            try:
                out[k.strip()] = float(v)
            except ValueError:
                raise UsageError(f"{what} {k.strip()}: {v!r} is not a number") from None
    return out


#: the fixed-step methods (and their aliases): --steps sets their number of steps
FIXED_STEP = ("rk4", "dla", "lda", "nh-midpoint", "dvi", "vakonomic-midpoint")
METHOD_HELP = ("dop853 (default), dopri5, rk4, radau (implicit, for stiff problems), dla "
               "(discrete Lagrange-d'Alembert, chetaev only), dvi (discrete vakonomic) or "
               "scipy-<RK45|DOP853|Radau|BDF|LSODA>")


def scene_names(system) -> set:
    """Names an expression of a scene may use besides the states: time, dependent
    velocities and parameters."""
    return ({system.J.t.name} | {v.name for v in system.dependent_velocities}
            | {p.name for p in system.parameters})


def cmd_simulate(args, progress) -> int:
    import numpy as np

    from .numeric import Scene
    from .numeric import arguments
    from .numeric.codegen import multiplier_names

    loaded = _with_split(load_model(args.model), args.split)
    system = loaded.system
    sim = loaded.simulation
    principle = args.principle or loaded.principle or "chetaev"
    convention = args.convention or loaded.convention or "paper"
    params = _assignments(args.set, "--set")
    init_override = _assignments(args.init, "--init")
    t0 = args.t_start if args.t_start is not None else float(sim.get("t_start", 0.0))
    t1 = args.t_end if args.t_end is not None else sim.get("t_end")
    if t1 is None:
        raise UsageError("give --t-end (the model file has no [simulation] t_end)")
    method = args.method or sim.get("method", "dop853")
    rtol = args.rtol if args.rtol is not None else sim.get("rtol", 1e-9)
    atol = args.atol if args.atol is not None else sim.get("atol", 1e-12)
    points = (args.points if args.points is not None else
              arguments.count(sim.get("points", 201), "[simulation] points", limit=10**7))

    # the initial state: the model's, then --init; missing states start at 0
    lams = multiplier_names(system, principle)
    states = ([q.name for q in system.J.q] + [v.name for v in system.independent_velocities]
              + list(lams))
    # the model's values of dependent velocities are checked against the constraints,
    # unless --split changed which velocities are dependent (then they follow from them)
    dep_vel = {v.name for v in system.dependent_velocities}
    initial = {k: v for k, v in loaded.initial.items()
               if k in states or (k in dep_vel and not args.split)}
    initial.update(init_override)
    zeros = [s for s in states if s not in initial]
    initial.update({s: 0.0 for s in zeros})
    integrals = {}
    for k, v in loaded.integrals.items():
        if {s.name for s in v.free_symbols} - set(states) - set(scene_names(system)):
            progress.note(f"jetnh: the integral {k!r} uses multipliers, which the "
                          f"{principle} state does not have; skipped")
        else:
            integrals[k] = v

    for out in (args.csv, args.plot):
        if out and not Path(out).resolve().parent.is_dir():
            raise JetnhError(f"cannot write {out}: the directory "
                             f"{Path(out).resolve().parent} does not exist")
    try:
        scene = Scene(system, principle, params=params, initial=initial,
                      t_span=(t0, float(t1)), convention=convention, integrals=integrals,
                      project=args.project)
    except JetnhError as exc:
        msg = str(exc).replace("pass project=True", "pass --project")
        raise type(exc)(msg) from None
    with progress.step(f"deriving and compiling the {principle} kernels "
                       "(cached for later runs)"):
        scene.compile()
    kw = {}
    if method.lower() in FIXED_STEP:
        kw["n_steps"] = args.steps
    elif points >= 2:
        kw["t_eval"] = np.linspace(t0, float(t1), points)
    with progress.step(f"integrating with {method} over [{t0:g}, {float(t1):g}]"):
        traj = scene.run(rtol=rtol, atol=atol, method=method, timeout=args.timeout, **kw)
    d = traj.diagnostics
    final = traj.final
    if args.format == "json":
        print(json.dumps({"model": loaded.label, "principle": principle,
                          "params": scene.params, "initial": scene.initial,
                          "final": final, "diagnostics": d.as_dict(),
                          "zero_initial": zeros}, indent=2, default=float))
    else:
        print(f"{system.name or loaded.label}: {principle}, t in [{t0:g}, {float(t1):g}]")
        if scene.params:
            print("parameters: " + ", ".join(f"{k} = {v:g}" for k, v in scene.params.items()))
        print("initial:    " + ", ".join(f"{k} = {v:.10g}" for k, v in scene.initial.items()))
        if zeros:
            print(f"            (not given, set to 0: {', '.join(zeros)})")
        if scene.projected:
            print("projected:  " + ", ".join(f"{k}: {g:g} -> {v:.10g}"
                                             for k, (g, v) in scene.projected.items()))
        print("final:      " + ", ".join(f"{k} = {v:.10g}" for k, v in final.items()))
        print(d)
    if args.csv:
        _write_csv(traj, args.csv)
        progress.note(f"wrote {args.csv}")
    if args.plot:
        with progress.step(f"plotting to {args.plot}"):
            _plot(traj, system, args.plot, f"{system.name or loaded.label} ({principle})")
    if not traj.success:
        print(f"jetnh: error: the integration stopped early: {traj.stop_reason}",
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


def _plot(traj, system, path, title):
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    coords = [q.name for q in system.J.q]
    vels = [v.name for v in system.J.qd]
    lams = [n for n in traj.names if n.startswith("lambda_")]
    groups = [("coordinates", coords), ("velocities", vels)] + ([("multipliers", lams)]
                                                                 if lams else [])
    fig, axes = plt.subplots(len(groups) + 1, 1, figsize=(8, 2.6 * (len(groups) + 1)),
                             sharex=True)
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
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


# ---------------------------------------------------------------------- sweep
def _values(text: str, what: str) -> list:
    """``A:B:N`` (N evenly spaced values from A to B) or ``V1,V2,...``: numbers, parsed
    by float() (never evaluated)."""
    import numpy as np

    try:
        if ":" in text:
            a, b, n = text.split(":")
            if int(n) < 1:
                raise ValueError
            return list(np.linspace(float(a), float(b), int(n)))
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise UsageError(f"{what}: {text!r} is neither START:STOP:N (N an integer >= 1) nor "
                         "a comma-separated list of numbers") from None


def _grid(items) -> dict:
    grid = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"--grid takes NAME=START:STOP:N or NAME=V1,V2,..., got {item!r}")
        if name in grid:
            raise UsageError(f"--grid gives {name} twice; give each name once")
        grid[name] = _values(text, f"--grid {name}")
    return grid


def _write_table(df, path: Path):
    if path.suffix == ".csv":
        df.to_csv(path, index=False)
        return
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise JetnhError("writing parquet needs pyarrow: pip install 'jetnh[parquet]' (or "
                         "write a .csv)") from None
    df.to_parquet(path, index=False)


def cmd_sweep(args, progress) -> int:
    from .numeric import Scene
    from .numeric.codegen import multiplier_names
    from .sweep import plot_map, sweep

    grid = _grid(args.grid)
    times = _values(args.times, "--times") if args.times else None
    if args.plot and (len(grid) != 2 or not args.value):
        raise UsageError("--plot draws a map over two --grid axes of the column --value; "
                         "give exactly two --grid and a --value")
    for out, kinds in ((args.out, (".csv", ".parquet")), (args.plot, None)):
        if not out:
            continue
        if not Path(out).resolve().parent.is_dir():
            raise JetnhError(f"cannot write {out}: the directory "
                             f"{Path(out).resolve().parent} does not exist")
        if kinds and Path(out).suffix not in kinds:
            raise JetnhError(f"cannot write {out}: give a .csv or .parquet path")
    loaded = _with_split(load_model(args.model), args.split)
    system = loaded.system
    sim = loaded.simulation
    principle = args.principle or loaded.principle or "chetaev"
    t0 = args.t_start if args.t_start is not None else float(sim.get("t_start", 0.0))
    t1 = args.t_end if args.t_end is not None else sim.get("t_end")
    if t1 is None:
        raise UsageError("give --t-end (the model file has no [simulation] t_end)")
    method = args.method or sim.get("method", "dop853")
    if times is not None and method.lower() in FIXED_STEP:
        raise UsageError(f"--times needs dense output, which {method} does not have; use "
                         "--method dop853, dopri5, radau or scipy-<M>, or omit --times (final "
                         "values)")
    states = ([q.name for q in system.J.q] + [v.name for v in system.independent_velocities]
              + list(multiplier_names(system, principle)))
    initial = {s: 0.0 for s in states}
    initial.update({k: v for k, v in loaded.initial.items() if k in states})
    initial.update(_assignments(args.init, "--init"))
    known = set(states) | set(scene_names(system))
    integrals = {k: v for k, v in loaded.integrals.items()
                 if not {s.name for s in v.free_symbols} - known}
    params = _assignments(args.set, "--set")
    scene = Scene(system, principle, params=params, initial=initial, t_span=(t0, float(t1)),
                  convention=args.convention or loaded.convention or "paper",
                  integrals=integrals,
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
                   connect_timeout=args.connect_timeout, method=method,
                   rtol=args.rtol if args.rtol is not None else sim.get("rtol", 1e-9),
                   atol=args.atol if args.atol is not None else sim.get("atol", 1e-12),
                   **({"n_steps": args.steps} if method.lower() in FIXED_STEP else {}))
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
        plot_map(df, x, y, args.value, args.plot,
                 title=f"{system.name or loaded.label} ({principle}): {args.value}")
        progress.note(f"wrote {args.plot}")
    return 0


# ---------------------------------------------------------------------- models
def cmd_models(args, progress) -> int:
    from . import models
    from .modelfile import dumps

    if not args.name:
        width = max(map(len, models.CATALOGUE))
        for name in models.CATALOGUE:
            info = models.info(name)
            opts = "".join(f" [{k}={v}]" for k, v in info.options.items())
            print(f"{name:<{width}}  {info.summary}{opts}")
        print(f"\n{len(models.CATALOGUE)} models; `jetnh models NAME` shows one, "
              "`jetnh models NAME --toml` prints it as a model file.")
        return 0
    loaded = load_model(args.name)
    if args.toml:
        print(dumps(loaded.system, loaded.initial,
                    simulation={"t_end": loaded.simulation["t_end"]}
                    if "t_end" in loaded.simulation else None), end="")
        return 0
    name = args.name.split(":")[0]
    doc = models.CATALOGUE[name].__doc__ if name in models.CATALOGUE else ""
    s = loaded.system
    print(f"{name}: {s.name}")
    print(f"  coordinates {', '.join(q.name for q in s.J.q)}; dependent "
          f"{', '.join(q.name for q in s.dependent)}")
    print(f"  parameters {', '.join(f'{k.name} = {v:g}' for k, v in s.defaults.items())}")
    print(f"  initial {', '.join(f'{k} = {v:g}' for k, v in loaded.initial.items())}")
    if doc:
        import textwrap
        print()
        print(textwrap.dedent("    " + doc.strip()))
    return 0


# ---------------------------------------------------------------------- bench
def _repo_root() -> Path:
    return Path(__file__).resolve().parents[1]


def cmd_bench(args, progress) -> int:
    """List the benchmark scripts (benchmarks/*.py with a ``__main__`` block; helpers
    such as ``_common.py`` are not listed), run one, or run them all and then
    ``report.py``, which regenerates BENCHMARKS.md."""
    import ast
    import subprocess

    bench_dir = _repo_root() / "benchmarks"
    scripts = [p for p in sorted(bench_dir.glob("*.py")) if bench_dir.is_dir()
               and "__main__" in p.read_text(encoding="utf-8", errors="replace")]
    if not scripts:
        raise JetnhError("no benchmarks found: they live in the repository's benchmarks/ "
                         "directory; run `jetnh bench` from a checkout installed with "
                         "`pip install -e .`")
    by_name = {p.stem: p for p in scripts}
    if args.all:
        if args.name:
            raise UsageError("--all runs every benchmark; give no NAME with it")
        failed = []
        for p in [p for p in scripts if p.stem != "report"] + [by_name["report"]]:
            cmd = [sys.executable, str(p)] + (["--quick"] if args.quick and
                                               p.stem != "report" else [])
            progress.note(f"jetnh: running {' '.join(cmd[1:])}")
            if subprocess.call(cmd, cwd=str(_repo_root())):
                failed.append(p.stem)
        if failed:
            raise JetnhError(f"these benchmarks failed (their output is above): "
                             f"{', '.join(failed)}")
        return 0
    if args.quick:
        raise UsageError("--quick goes with --all; for one benchmark write "
                         "`jetnh bench NAME --quick`")
    if not args.name:
        print(f"benchmarks in {bench_dir}:")
        for p in scripts:
            try:
                doc = ast.get_docstring(ast.parse(p.read_text(encoding="utf-8"))) or ""
            except (SyntaxError, OSError, UnicodeDecodeError):
                doc = ""
            first = " ".join(doc.strip().split("\n\n")[0].split()) if doc else ""
            print(f"  {p.stem}: {first[:150]}")
        print("\nrun one with `jetnh bench NAME [ARGS...]` (ARGS go to the script, e.g. "
              "--quick, --help); every one and then the report with `jetnh bench --all "
              "[--quick]`; results are written under benchmarks/results/, the report to "
              "BENCHMARKS.md.")
        return 0
    if args.name not in by_name:
        raise JetnhError(f"no benchmark named {args.name!r}; the benchmarks are "
                         f"{', '.join(by_name)}")
    cmd = [sys.executable, str(by_name[args.name]), *args.args]
    progress.note(f"jetnh: running {' '.join(cmd[1:])}")
    return subprocess.call(cmd, cwd=str(_repo_root()))


# ---------------------------------------------------------------------- reproduce
def cmd_reproduce(args, progress) -> int:
    root = _repo_root()
    if not (root / "papers" / "zhao2008" / "reproduce.py").exists():
        raise JetnhError("the reproduction lives in the repository's papers/ directory; run "
                         "`jetnh reproduce` from a checkout installed with `pip install -e .`")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    from papers.zhao2008.reproduce import main as reproduce

    argv = (["--fast"] if args.fast else []) + (["--no-figures"] if args.no_figures else [])
    return reproduce(argv)


# ---------------------------------------------------------------------- cache
def _bytes(n: int) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024


def cmd_cache(args, progress) -> int:
    """Where the kernel cache lives and what it holds; or empty it."""
    from .numeric import cache

    if args.action == "clear":
        root = cache.cache_root()
        n = cache.clear()
        print(f"removed {n} cached {'entry' if n == 1 else 'entries'} from {root}")
        return 0
    i = cache.info()
    print(f"kernel cache: {i['root']}"
          + (" (from JETNH_CACHE)" if i["env"] else " (the user cache directory)"))
    print(f"entries:      {i['entries']} ({_bytes(i['bytes'])})")
    if i["old_versions"]:
        print(f"older jetnh:  {_bytes(i['old_versions'])} of kernels of other versions "
              "(jetnh cache clear removes them)")
    if i["fallback"]:
        print(f"not usable:   {i['fallback']}")
        print("              runs use a private temporary cache, removed at exit")
    else:
        print("usable:       yes (runs keep their kernels here)")
    return 0


# ---------------------------------------------------------------------- parser
class _Formatter(argparse.RawDescriptionHelpFormatter):
    pass


_ALIASES = "aliases: " + "; ".join(f"{', '.join(p.aliases)} (= {p.name})"
                                   for p in principles.REGISTRY if p.aliases)


def _principle(name: str) -> str:
    """--principle: an alias is read as its canonical name (argparse checks the choice)."""
    try:
        return principles.canonical(name)
    except PrincipleError:
        return name


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    p = argparse.ArgumentParser(
        prog="jetnh", formatter_class=_Formatter,
        description=__doc__.replace("``", ""),
        epilog="examples:\n"
               "  jetnh models\n"
               "  jetnh derive rolling_disk --principle suslov --format latex\n"
               "  jetnh compare examples/rolling_disk.toml\n"
               "  jetnh simulate knife_edge --t-end 5 --set alpha=0.5 --init phi_t=2 "
               "--plot knife.png\n"
               "  jetnh models chaplygin_sleigh --toml > sleigh.toml")
    p.add_argument("--version", action="version", version=f"jetnh {__version__}")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="only errors on stderr: no progress or other messages (also after "
                        "COMMAND)")
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                        help="only errors on stderr: no progress or other messages")
    common.add_argument("--debug", action="store_true",
                        help="show a traceback for unexpected (internal) errors")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def model_args(sp_, split=True):
        sp_.add_argument("model", metavar="MODEL", help="catalogue name or model file")
        if split:
            sp_.add_argument("--split", metavar="Q1,Q2",
                             help="dependent coordinates, comma-separated (overrides the "
                                  "model's; e.g. --split x,y)")

    def shown_args(sp_):
        sp_.add_argument("--format", choices=("text", "latex", "json"), default="text",
                         help="text (default), latex (an aligned block) or json; each "
                              "in the same shared form")
        sp_.add_argument("--out", metavar="FILE",
                         help="write the full result to FILE (on the screen large results "
                              f"are cut to about {SCREEN_BUDGET // 1000} kB)")
        sp_.add_argument("--simplify", type=float, default=None, metavar="SECONDS",
                         help="trigsimp each small expression shown (at most 60 tree "
                              "nodes) within SECONDS, 10 x SECONDS in all; larger ones are "
                              "shown as derived, and a note says how many were simplified "
                              "(default: 0.5 for results shown without named quantities, "
                              "else 0; 0: none)")

    d = sub.add_parser(
        "derive", parents=[common], formatter_class=_Formatter,
        help="equations of motion of a model under one principle",
        description="Derive the equations of motion of MODEL under one principle, and the "
                    "accelerations (and multiplier rates) on the constraint manifold.",
        epilog=EPILOG_MODEL + "\n\nexample: jetnh derive appell_hamel --principle suslov "
                              "--format json")
    model_args(d)
    d.add_argument("--principle", "-p", choices=PRINCIPLES, type=_principle, default=None,
                   help="chetaev (Lagrange-d'Alembert), vakonomic, holder or suslov "
                        "(default: the model file's, else chetaev); " + _ALIASES)
    d.add_argument("--form", default=None,
                   help="form of the equations: chetaev maggi|multiplier|voronets; "
                        "vakonomic and holder multiplier|explicit|reduced|embedded; suslov "
                        "multiplier|reduced|embedded (default: the first)")
    d.add_argument("--convention", choices=("paper", "imposed"), default=None,
                   help="paper: every variation is independent after the commutator (as "
                        "the paper); imposed: the variation's own condition is imposed")
    shown_args(d)
    d.set_defaults(func=cmd_derive)

    c = sub.add_parser(
        "compare", parents=[common], formatter_class=_Formatter,
        help="every principle side by side, with integrability, T and the equivalences",
        description="Classify MODEL (affine, integrable by Frobenius, Chaplygin, regular, "
                    "rheonomic), print L~ and T^alpha_mu, the equations and accelerations "
                    "under every principle, and which principles share solutions "
                    "(identically, or on the branch lambda = -p of (32)).",
        epilog=EPILOG_MODEL)
    model_args(c)
    shown_args(c)
    c.set_defaults(func=cmd_compare)

    s = sub.add_parser(
        "simulate", parents=[common], formatter_class=_Formatter,
        help="integrate a model under one principle (compiled) and print diagnostics",
        description="Simulate MODEL with a compiled jetnh Scene.  Parameters default to the "
                    "model's values and the initial state to the model's [initial] (states "
                    "not given start at 0; dependent velocities follow from the "
                    "constraints; the multipliers of vakonomic, holder and suslov are "
                    "named lambda_<dependent>).  Prints the final state and the "
                    "diagnostics: constraint residual, energy drift, first integrals "
                    "([integrals] of a model file), steps.",
        epilog=EPILOG_MODEL + "\n\nexample: jetnh simulate examples/rolling_disk.toml "
                              "--t-end 10 --init psi_t=0.3 --csv disk.csv --plot disk.png")
    model_args(s)
    s.add_argument("--principle", "-p", choices=PRINCIPLES, type=_principle, default=None,
                   help="default: the model file's, else chetaev; " + _ALIASES)
    s.add_argument("--convention", choices=("paper", "imposed"), default=None)
    s.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value (repeatable, or comma-separated)")
    s.add_argument("--init", action="append", metavar="NAME=VALUE",
                   help="an initial value of a coordinate, velocity (x_t) or multiplier "
                        "(repeatable, or comma-separated)")
    s.add_argument("--t-start", type=float, default=None, metavar="T0", help="default 0")
    s.add_argument("--t-end", type=float, default=None, metavar="T",
                   help="end time (default: the model's [simulation] t_end or the "
                        "catalogue's)")
    s.add_argument("--method", default=None, help=METHOD_HELP)
    s.add_argument("--timeout", type=float, default=None,
                   help="wall-clock budget in seconds: the run stops there and reports "
                        "what it has (default: none)")
    s.add_argument("--rtol", type=float, default=None, help="default 1e-9")
    s.add_argument("--atol", type=float, default=None, help="default 1e-12")
    s.add_argument("--points", type=int, default=None,
                   help="output points of the adaptive methods (default 201; 0: every step)")
    s.add_argument("--steps", type=int, default=1000,
                   help="steps of the fixed-step methods rk4, dla and dvi (default 1000)")
    s.add_argument("--project", action="store_true",
                   help="replace initial dependent velocities that contradict the "
                        "constraints by the values the constraints give")
    s.add_argument("--csv", metavar="PATH", help="write t and every column to a CSV file")
    s.add_argument("--plot", metavar="PATH", help="save a plot (png, pdf, svg) of the run")
    s.add_argument("--format", choices=("text", "json"), default="text")
    s.set_defaults(func=cmd_simulate)

    w = sub.add_parser(
        "sweep", parents=[common], formatter_class=_Formatter,
        help="run a model over a grid of parameters and initial values (here or on Dask)",
        description="Run MODEL at every point of the grid (the Cartesian product of the "
                    "--grid axes) and write one row per point: the grid values (initial "
                    "values as NAME(t0)), the final values of the states (or their values "
                    "at --times as NAME(t=T)) and the diagnostics: status, stop_reason, "
                    "steps, constraint residual, energy and first-integral drift.  A point "
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
                   help="an axis: N values from A to B, or NAME=V1,V2,... (repeatable; "
                        "NAME a parameter or a state)")
    w.add_argument("--principle", "-p", choices=PRINCIPLES, type=_principle, default=None,
                   help="default: the model file's, else chetaev; " + _ALIASES)
    w.add_argument("--convention", choices=("paper", "imposed"), default=None)
    w.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="a parameter value for every point (repeatable, or comma-separated)")
    w.add_argument("--init", action="append", metavar="NAME=VALUE",
                   help="an initial value for every point (repeatable, or comma-separated)")
    w.add_argument("--t-start", type=float, default=None, metavar="T0", help="default 0")
    w.add_argument("--t-end", type=float, default=None, metavar="T",
                   help="end time (default: the model's [simulation] t_end or the "
                        "catalogue's)")
    w.add_argument("--times", metavar="T1,T2,...|A:B:N",
                   help="output times (default: the final time only)")
    w.add_argument("--outputs", metavar="NAME,...",
                   help="output columns (default: every state, dependent velocity and "
                        "integral)")
    w.add_argument("--method", default=None,
                   help=METHOD_HELP.replace("(default)", "(default: the model file's, else "
                                                         "dop853)")
                        + "; dla, dvi and scipy run point by point")
    w.add_argument("--rtol", type=float, default=None, help="default 1e-9")
    w.add_argument("--atol", type=float, default=None, help="default 1e-12")
    w.add_argument("--steps", type=int, default=1000,
                   help="steps of the fixed-step methods rk4, dla and dvi (default 1000)")
    w.add_argument("--scheduler", metavar="ADDRESS",
                   help="a Dask scheduler, e.g. tcp://10.0.0.5:8786 (needs pip install "
                        "'jetnh[cluster]'; default: this machine, every core, no Dask)")
    w.add_argument("--chunk-size", type=int, default=None, metavar="N",
                   help="points per Dask task (default: 4 tasks per worker thread)")
    w.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="give up on a Dask sweep after this long (default: no limit)")
    w.add_argument("--connect-timeout", type=float, default=10.0, metavar="SECONDS",
                   help="time to reach the scheduler (default 10)")
    w.add_argument("--out", metavar="PATH",
                   help="write the table to PATH (.parquet or .csv); default: CSV on stdout")
    w.add_argument("--plot", metavar="PATH",
                   help="save the map of --value over the two --grid axes (PNG)")
    w.add_argument("--value", metavar="COLUMN", help="the column --plot shows")
    w.set_defaults(func=cmd_sweep)

    m = sub.add_parser(
        "models", parents=[common], formatter_class=_Formatter,
        help="list the catalogue, show a model, or print it as a model file",
        description="Without NAME: list the catalogue.  With NAME: its coordinates, "
                    "parameters, default initial state and docstring (source, closed forms, "
                    "first integrals); with --toml: the model as a model file to edit.")
    m.add_argument("name", nargs="?", metavar="NAME")
    m.add_argument("--toml", action="store_true", help="print NAME as a model file")
    m.set_defaults(func=cmd_models)

    b = sub.add_parser(
        "bench", parents=[common], formatter_class=_Formatter,
        help="list or run the benchmarks of benchmarks/ and regenerate BENCHMARKS.md",
        description="Without NAME: list the benchmark scripts in the repository's "
                    "benchmarks/ directory.  With NAME: run benchmarks/NAME.py with ARGS "
                    "(each script documents its options, try --help; every one takes "
                    "--quick and --out).  With --all: run every benchmark, then "
                    "benchmarks/report.py, which writes BENCHMARKS.md from the results; "
                    "--all --quick runs each one's quick profile (minutes, not tens of "
                    "minutes).  `jetnh bench report` regenerates BENCHMARKS.md alone.")
    b.add_argument("--all", action="store_true",
                   help="run every benchmark, then the report")
    b.add_argument("--quick", action="store_true", help="with --all: the quick profiles")
    b.add_argument("name", nargs="?", metavar="NAME")
    b.add_argument("args", nargs=argparse.REMAINDER, metavar="ARGS")
    b.set_defaults(func=cmd_bench)

    k = sub.add_parser(
        "cache", parents=[common], formatter_class=_Formatter,
        help="show where the compiled-kernel cache lives and what it holds, or empty it",
        description="info: the cache directory (JETNH_CACHE, else the platform's user "
                    "cache directory), its entries and their size, and whether runs can "
                    "use it or fall back to a private temporary cache.  clear: remove "
                    "every cached kernel (they are compiled again when needed).")
    k.add_argument("action", choices=("info", "clear"), nargs="?", default="info",
                   help="default: info")
    k.set_defaults(func=cmd_cache)

    r = sub.add_parser(
        "reproduce", parents=[common], formatter_class=_Formatter,
        help="the machine-checked reproduction of the seed paper "
             "(writes papers/zhao2008/results.json and report.md)")
    r.add_argument("--fast", action="store_true", help="proofs for n <= 3, short simulations")
    r.add_argument("--no-figures", action="store_true", help="skip the simulations and figures")
    r.set_defaults(func=cmd_reproduce)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    progress = Progress(quiet=getattr(args, "quiet", False))
    try:
        return args.func(args, progress)
    except UsageError as exc:
        print(f"jetnh {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except JetnhError as exc:
        msg = str(exc)
        if isinstance(exc, ArgumentError) and args.command in ("simulate", "sweep"):
            msg = option_message(msg)
        print(f"jetnh: error: {msg}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("jetnh: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"jetnh: error:{where}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    except (MemoryError, RecursionError) as exc:
        print(f"jetnh: error: the model is too large for this computation "
              f"({type(exc).__name__})", file=sys.stderr)
        return 1
    except Exception as exc:                                     # jetnh's own bugs
        if getattr(args, "debug", False):
            raise
        print(f"jetnh: internal error: {type(exc).__name__}: {exc}\n"
              "jetnh: this is a bug in jetnh; rerun with --debug for the traceback and "
              "report it", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
