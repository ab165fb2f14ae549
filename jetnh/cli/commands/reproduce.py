"""``jetnh reproduce``: the machine-checked reproduction of the seed paper."""

from __future__ import annotations

import sys

from ...errors import JetnhError
from ..parser import subcommand
from .bench import repo_root


def add_parser(sub):
    r = subcommand(
        sub, "reproduce",
        help="the machine-checked reproduction of the seed paper "
             "(writes papers/zhao2008/results.json and report.md)",
        description="Check every numbered equation and claim of the seed paper (Zhao, "
                    "Guo, Liu, Liu, Acta Physica Sinica 57 (2008)) against jetnh's own "
                    "derivation, prove the general identities for generic systems, "
                    "simulate the two examples, print the summary and the errata, and "
                    "write papers/zhao2008/report.md and results.json (what `make run` "
                    "does).  Runs from a checkout of the repository.")
    r.add_argument("--fast", action="store_true", help="proofs for n <= 3, short simulations")
    r.add_argument("--no-figures", action="store_true", help="skip the simulations and figures")
    r.set_defaults(func=run)


def run(args, progress) -> int:
    root = repo_root()
    if not (root / "papers" / "zhao2008" / "reproduce.py").exists():
        raise JetnhError("the reproduction lives in the repository's papers/ directory; run "
                         "`jetnh reproduce` from a checkout installed with `pip install -e .`")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    from papers.zhao2008.reproduce import main as reproduce

    argv = (["--fast"] if args.fast else []) + (["--no-figures"] if args.no_figures else [])
    return reproduce(argv)
