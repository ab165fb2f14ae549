"""``jetnh derive``: the equations of motion of a model under one principle."""

from __future__ import annotations

from ..loading import load_model, settings, with_split
from ..parser import EPILOG_MODEL, model_args, shown_args, subcommand
from ..render import forces, label, render, simplified, write


def add_parser(sub):
    d = subcommand(
        sub, "derive", principle=True,
        help="equations of motion of a model under one principle",
        description="Derive the equations of motion of MODEL under one principle, and the "
                    "accelerations (and multiplier rates) on the constraint manifold.",
        epilog=EPILOG_MODEL + "\n\nexample:\n  jetnh derive appell_hamel --principle suslov "
                              "--format json")
    model_args(d)
    d.add_argument("--form", default=None,
                   help="form of the equations: chetaev maggi|multiplier|voronets; "
                        "vakonomic and holder multiplier|explicit|reduced|embedded; suslov "
                        "multiplier|reduced|embedded (default: the first)")
    shown_args(d)
    d.set_defaults(func=run)


def run(args, progress) -> int:
    from ...algebra import dag
    from ...algebra.shared import shared_form

    model = with_split(load_model(args.model), args.split)
    system = model.system
    opts = settings(args, model)
    with progress.step(f"deriving the {opts.principle} equations"):
        eom = system.equations(opts.principle, form=args.form, convention=opts.convention)
        exprs = eom.expressions
    with progress.step("solving for the accelerations"):
        acc = eom.accelerations()
    dependent = ", ".join(v.name for v in system.phi)
    if system.phi:                   # on the manifold: the dependent velocities are phi
        acc = dict(zip(acc, dag.xreplace(list(acc.values()), system.phi)))
    heads = [f"{eom.principle} equations, {eom.form} form {eom.paper}".rstrip(),
             "accelerations on the constraint manifold" + (
                 f" (in the independent velocities: {dependent} replaced by their values "
                 "below)" if system.phi else ""),
             "the constraint manifold"]
    with progress.step("writing in shared form"):
        form = shared_form([heads[0]] + [(None, e) for e in exprs] + [heads[1]]
                           + list(acc.items()) + ([heads[2]] if system.phi else [])
                           + list(system.phi.items()))
    form = simplified(form, args.simplify, progress)
    name = system.name or model.label
    header = [f"{name}: dependent {', '.join(q.name for q in system.dependent) or 'none'}"]
    if system.dissipation != 0:
        header.append(f"  dissipation D = {label(system.dissipation)} "
                      "(Q_s = forces - dD/dqdot^s)")
    header += [f"  force Q_{k} = {v}" for k, v in forces(system).items()]
    data = {"model": model.label, "name": system.name, "principle": eom.principle,
            "form": eom.form, "convention": eom.convention, "paper": eom.paper,
            "coordinates": [q.name for q in system.J.q],
            "dependent": [q.name for q in system.dependent],
            "parameters": {s.name: v for s, v in system.defaults.items()},
            "forces": forces(system), "dissipation": label(system.dissipation),
            "multipliers": [str(m) for m in eom.multipliers]}
    keys = dict(zip(heads, ("expressions", "accelerations", "dependent_velocities")))
    write(args, progress, render(args, form, header, data, eom.J, keys), form)
    return 0
