"""The ``jetnh`` command: derive and compare equations of motion of a model.

Exit codes: 0 ok, 2 usage, 1 model or numerical error.  User errors print a message on
stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from itertools import combinations

import sympy as sp

from .constraints import PRINCIPLES
from .errors import JetnhError


def _load(model: str):
    from . import models

    return models.get(model)


def _display(system, expr) -> str:
    """A readable form for people (trigsimp here is display only, never on a hot path)."""
    return str(sp.trigsimp(system.on_constraints(expr)))


def cmd_derive(args) -> int:
    system = _load(args.model)
    eom = system.equations(args.principle, form=args.form, convention=args.convention)
    if args.format == "latex":
        print(eom.latex())
    elif args.format == "json":
        acc = eom.accelerations()
        print(json.dumps({
            "model": args.model, "principle": eom.principle, "form": eom.form,
            "convention": eom.convention, "paper": eom.paper,
            "expressions": [str(e) for e in eom.expressions],
            "multipliers": [str(m) for m in eom.multipliers],
            "accelerations": {str(k): str(v) for k, v in acc.items()},
        }, indent=2))
    else:
        print(eom)
        print("accelerations (on the constraint manifold):")
        for k, v in eom.accelerations().items():
            print(f"  {k} = {_display(system, v)}")
    return 0


def cmd_compare(args) -> int:
    from .equivalence import compare

    system = _load(args.model)
    J = system.J
    print(f"{system.name or args.model}")
    print(f"  coordinates: {' '.join(q.name for q in J.q)}; dependent: "
          f"{' '.join(q.name for q in system.dependent)}")
    print(f"  L = {system.L}")
    for f in system.constraints:
        print(f"  constraint: {f} = 0")
    print(f"  classification: {system.classify()}")
    print(f"  L~ = {_display(system, system.L_tilde)}")
    print(f"  T = {system.T().applyfunc(lambda e: sp.trigsimp(e)).tolist()}")
    for principle in PRINCIPLES:
        form = {"chetaev": "voronets", "holder": "embedded"}.get(principle, "embedded")
        eom = system.equations(principle, form=form)
        print()
        print(f"{principle} ({form} form {eom.paper})".replace(" )", ")"))
        for e in eom.expressions:
            print(f"  {_display(system, e)} = 0")
        acc = eom.accelerations()
        print("  accelerations:")
        for k, v in acc.items():
            print(f"    {k} = {_display(system, v)}")
    print()
    print("equivalence:")
    for a, b in combinations(PRINCIPLES, 2):
        print(f"  {compare(system, a, b)}")
    return 0


def cmd_reproduce(args) -> int:
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[1]
    if not (root / "papers" / "zhao2008" / "reproduce.py").exists():
        raise JetnhError("the reproduction lives in the repository's papers/ directory; run "
                         "`jetnh reproduce` from a checkout installed with `pip install -e .`")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    from papers.zhao2008.reproduce import main as reproduce

    argv = (["--fast"] if args.fast else []) + (["--no-figures"] if args.no_figures else [])
    return reproduce(argv)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="jetnh", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("derive", help="equations of motion of a model under one principle")
    d.add_argument("model", help="a catalogue name (e.g. rolling_disk, appell_hamel)")
    d.add_argument("--principle", "-p", choices=PRINCIPLES, default="chetaev")
    d.add_argument("--form", default=None, help="form of the equations (default: the principle's first)")
    d.add_argument("--convention", choices=("paper", "imposed"), default="paper")
    d.add_argument("--format", choices=("text", "latex", "json"), default="text")
    d.set_defaults(func=cmd_derive)
    c = sub.add_parser("compare", help="every principle side by side, with T and equivalences")
    c.add_argument("model", help="a catalogue name (e.g. rolling_disk)")
    c.set_defaults(func=cmd_compare)
    r = sub.add_parser("reproduce", help="the machine-checked reproduction of the seed paper "
                       "(writes papers/zhao2008/results.json and report.md)")
    r.add_argument("--fast", action="store_true", help="proofs for n <= 3, short simulations")
    r.add_argument("--no-figures", action="store_true", help="skip the simulations and figures")
    r.set_defaults(func=cmd_reproduce)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except JetnhError as exc:
        print(f"jetnh: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
