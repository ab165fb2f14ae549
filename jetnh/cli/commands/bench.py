"""``jetnh bench``: list or run the benchmarks of benchmarks/ and regenerate
BENCHMARKS.md."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ...errors import JetnhError
from ..parser import subcommand
from ..usage import UsageError


def add_parser(sub):
    b = subcommand(
        sub, "bench",
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
    b.add_argument("name", nargs="?", metavar="NAME",
                   help="a benchmark script of benchmarks/, without .py")
    b.add_argument("args", nargs=argparse.REMAINDER, metavar="ARGS",
                   help="the script's own options")
    b.set_defaults(func=run)


def repo_root() -> Path:
    """The checkout jetnh runs from (benchmarks/ and papers/ live there)."""
    return Path(__file__).resolve().parents[3]


def run(args, progress) -> int:
    """List the benchmark scripts (benchmarks/*.py with a ``__main__`` block; helpers
    such as ``_common.py`` are not listed), run one, or run them all and then
    ``report.py``, which regenerates BENCHMARKS.md."""
    import ast
    import subprocess

    bench_dir = repo_root() / "benchmarks"
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
            if subprocess.call(cmd, cwd=str(repo_root())):
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
    return subprocess.call(cmd, cwd=str(repo_root()))
