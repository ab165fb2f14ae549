"""``jetnh compare``: every principle side by side, with integrability, T and the
equivalences."""

from __future__ import annotations

from ...mechanics.principles import PRINCIPLES
from ..loading import load_model, with_split
from ..parser import EPILOG_MODEL, model_args, shown_args, subcommand
from ..render import forces, label, render, simplified, write

#: tree nodes of phi up to which compare shows the forms on L~ and T (they
#: differentiate phi as a tree: exponential in a chain of constraints)
PHI_TREE_MAX = 2_000
_COMPARE_FORMS = {"chetaev": "voronets", "vakonomic": "embedded", "holder": "embedded",
                  "suslov": "embedded"}


def add_parser(sub):
    c = subcommand(
        sub, "compare",
        help="every principle side by side, with integrability, T and the equivalences",
        description="Classify MODEL (affine, integrable by Frobenius, Chaplygin, regular, "
                    "rheonomic), print L~ and T^alpha_mu, the equations and accelerations "
                    "under every principle, and which principles share solutions "
                    "(identically, or on the branch lambda = -p of (32)).",
        epilog=EPILOG_MODEL)
    model_args(c)
    shown_args(c)
    c.set_defaults(func=run)


def run(args, progress) -> int:
    from ...mechanics.equivalence import comparisons
    from ...algebra.shared import shared_form, tree_size

    model = with_split(load_model(args.model), args.split)
    system = model.system
    J = system.J
    small = tree_size(list(system.phi.values()), PHI_TREE_MAX) <= PHI_TREE_MAX
    with progress.step("classifying"):
        cls = system.classify()
    header = [f"{system.name or model.label}",
              f"  coordinates: {' '.join(q.name for q in J.q)}; dependent: "
              f"{' '.join(q.name for q in system.dependent)}",
              f"  L = {label(system.L)}"]
    header += [f"  constraint: {label(f)} = 0"
               + (" (holonomic)" if i in system.holonomic_rows else "")
               for i, f in enumerate(system.given_constraints)]
    header += [f"  force Q_{k} = {v}" for k, v in forces(system).items()]
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
    form = simplified(form, args.simplify, progress)
    verdicts = []
    with progress.step("comparing every pair of principles"):
        for c in comparisons(system, solved):
            verdicts.append(f"  {c}")
    if args.format == "json":
        data = {"model": model.label, "name": system.name,
                "coordinates": [q.name for q in J.q],
                "dependent": [q.name for q in system.dependent],
                "classification": str(cls),
                "equivalence": [v.strip() for v in verdicts]}
        text = render(args, form, [], data, J)
    else:
        text = "\n".join([render(args, form, header, {}, J), "", "equivalence:"] + verdicts)
    write(args, progress, text, form)
    return 0
