"""What the commands that run a model share: NAME=VALUE lists, a scene's state (its
names, its initial values from the model and the options), the first integrals it can
monitor, the other names it may use, the integration methods."""

from __future__ import annotations

from .usage import UsageError


def assignments(items, what) -> dict:
    """``NAME=VALUE`` items of a repeatable option (each may be comma-separated) as
    numbers by name; a name given twice is refused (which value was meant?)."""
    out = {}
    for item in items or ():
        for part in filter(None, (p.strip() for p in item.split(","))):
            k, sep, v = part.partition("=")
            if not sep or not k.strip():
                raise UsageError(f"{what} takes NAME=VALUE, got {part!r}")
            if k.strip() in out:
                raise UsageError(f"{what} gives {k.strip()} twice; give each name once")
            try:
                out[k.strip()] = float(v)
            except ValueError:
                raise UsageError(f"{what} {k.strip()}: {v!r} is not a number") from None
    return out


def method_of(name: str):
    """The integration method called ``name`` (a ``jetnh.numeric.methods.Method``: --steps
    sets the number of steps of the fixed-step ones, --times needs dense output)."""
    from ..numeric.methods import method

    return method(name)


METHOD_HELP = ("dop853, dopri5, rk4, radau (implicit, for stiff problems), dla "
               "(discrete Lagrange-d'Alembert, chetaev only), dvi (discrete vakonomic) or "
               "scipy-<RK45|DOP853|Radau|BDF|LSODA> (default: the model's, else dop853)")


def state_names(system, principle) -> list:
    """The names of a scene's state: coordinates, independent velocities, multipliers."""
    from ..numeric.codegen import multiplier_names

    return ([q.name for q in system.J.q] + [v.name for v in system.independent_velocities]
            + list(multiplier_names(system, principle)))


def initial_values(model, principle, given: dict,
                   dependent_velocities: bool = False) -> tuple[dict, list]:
    """The model's initial values of the states (and of the dependent velocities, which
    are checked against the constraints, if ``dependent_velocities``) updated by
    ``given``; the states neither gives start at 0, and are returned too."""
    system = model.system
    states = state_names(system, principle)
    keep = set(states) | ({v.name for v in system.dependent_velocities}
                          if dependent_velocities else set())
    values = {k: v for k, v in model.initial.items() if k in keep}
    values.update(given)
    zeros = [s for s in states if s not in values]
    return {**values, **dict.fromkeys(zeros, 0.0)}, zeros


def monitored_integrals(model, principle) -> tuple[dict, list]:
    """The model's first integrals that a scene of ``principle`` can monitor, and the
    names of the others (they use multipliers its state does not have)."""
    known = set(state_names(model.system, principle)) | scene_names(model.system)
    kept = {k: v for k, v in model.integrals.items()
            if not {s.name for s in v.free_symbols} - known}
    return kept, [k for k in model.integrals if k not in kept]


def scene_names(system) -> set:
    """Names an expression of a scene may use besides the states: time, dependent
    velocities and parameters."""
    return ({system.J.t.name} | {v.name for v in system.dependent_velocities}
            | {p.name for p in system.parameters})


def step_options(args, method: str, t_span, outputs: str) -> dict:
    """The step options of a run from --steps and --max-steps, checked before anything
    is derived: ``n_steps`` of a fixed-step method (--steps, default ``FIXED_STEPS``,
    within the budget), ``max_steps`` where --max-steps is given.  --steps with an
    adaptive method is refused (its steps are its own); the message names ``outputs``,
    the command's option of output times."""
    from ..numeric import arguments
    from ..numeric.options import StepControl
    from .parser import FIXED_STEPS

    kw = {}
    if args.max_steps is not None:
        kw["max_steps"] = arguments.count(args.max_steps, "max_steps")
    if not method_of(method).fixed_step:
        if args.steps is not None:
            raise UsageError(f"--steps sets the steps of the fixed-step methods rk4, dla and "
                             f"dvi; {method} chooses its own: give {outputs}, --max-steps N "
                             "for a step budget, or --method rk4 --steps N for fixed steps")
        return kw
    steps = FIXED_STEPS if args.steps is None else args.steps
    budget = kw.get("max_steps", StepControl.max_steps)
    if steps > budget:
        raise UsageError(f"--max-steps {budget} is below the {steps} steps of {method} "
                         f"(--steps{'' if args.steps is not None else ', default'} {steps}); "
                         "raise --max-steps or lower --steps")
    kw["n_steps"] = arguments.fixed_steps(steps, None, *t_span, method, budget)
    return kw


def stop_text(traj, args, when: bool = True) -> str:
    """Why ``traj`` stopped early; a stop by the step budget named by its option
    (--max-steps), its size and (``when``) the time it came at."""
    from ..numeric import MAX_STEPS
    from ..numeric.options import StepControl

    if traj.status != MAX_STEPS:
        return traj.stop_reason
    given = args.max_steps is not None
    budget = args.max_steps if given else StepControl.max_steps
    return (f"the step budget of {budget} steps (--max-steps{'' if given else ', default'}) "
            f"ran out{f' at t = {traj.t_final:.10g}' if when else ''}; raise --max-steps "
            "to go further")
