"""What the commands that run a model share: NAME=VALUE lists, the names of a scene's
state and the others it may use, the integration methods."""

from __future__ import annotations

from .usage import UsageError


def assignments(items, what) -> dict:
    """``NAME=VALUE`` items of a repeatable option (each may be comma-separated) as
    numbers by name."""
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


def method_of(name: str):
    """The integration method called ``name`` (a ``jetnh.numeric.methods.Method``: --steps
    sets the number of steps of the fixed-step ones, --times needs dense output)."""
    from ..numeric.methods import method

    return method(name)


METHOD_HELP = ("dop853 (default), dopri5, rk4, radau (implicit, for stiff problems), dla "
               "(discrete Lagrange-d'Alembert, chetaev only), dvi (discrete vakonomic) or "
               "scipy-<RK45|DOP853|Radau|BDF|LSODA>")


def state_names(system, principle) -> list:
    """The names of a scene's state: coordinates, independent velocities, multipliers."""
    from ..numeric.codegen import multiplier_names

    return ([q.name for q in system.J.q] + [v.name for v in system.independent_velocities]
            + list(multiplier_names(system, principle)))


def scene_names(system) -> set:
    """Names an expression of a scene may use besides the states: time, dependent
    velocities and parameters."""
    return ({system.J.t.name} | {v.name for v in system.dependent_velocities}
            | {p.name for p in system.parameters})
