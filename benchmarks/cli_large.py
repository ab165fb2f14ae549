"""The command line on large systems: `jetnh derive` and `jetnh compare` on the N-trailer.

    .venv/bin/python benchmarks/cli_large.py [--quick] [--ns 3,5,8,16] [--timeout 300]
        [--baseline DIR] [--baseline-ns 3,5,8] [--out PATH]

(default output: benchmarks/results/cli_large.json)

Each command runs in a fresh process, ``python -m jetnh derive n_trailer:N=N -p P`` for
every principle P and ``python -m jetnh compare n_trailer:N=N``,
with an empty kernel cache (``JETNH_CACHE`` a new directory) and ``PYTHONPATH`` the tree
measured, once printing to the screen and once with ``--out FILE``.  Recorded: the wall
time of each process (interpreter start-up and imports included), the bytes printed
(stdout: the short form on screen, bounded) and the bytes of ``FILE`` (the full result
in shared form), or the time-out.

The baseline (``--baseline DIR``) is another source tree run the same way in the same
run, commands interleaved, e.g. the tree before the derivatives on the shared graph:
``git archive 1a618e7 | tar -x -C /tmp/base-1a6``; the ratio is baseline time over this
tree's time (a lower bound where the baseline timed out).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import ROOT, parser, write  # noqa: E402

PRINCIPLES = ("chetaev", "vakonomic", "holder", "suslov")


def run(tree: Path, args: list, timeout: float, to_file: bool = False) -> dict:
    """One CLI command in a fresh process on ``tree``: seconds and the bytes printed
    (``to_file``: the bytes written to ``--out FILE`` instead)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.txt"
        env = dict(os.environ, PYTHONPATH=str(tree), JETNH_CACHE=str(Path(tmp) / "cache"))
        extra = ["--out", str(out)] if to_file else []
        tic = time.perf_counter()
        try:
            p = subprocess.run([sys.executable, "-m", "jetnh", *args, *extra], env=env,
                               capture_output=True, timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return {"seconds": None, "status": f"timeout {timeout:g} s"}
        dt = time.perf_counter() - tic
        size = out.stat().st_size if to_file and out.exists() else len(p.stdout)
        return {"seconds": round(dt, 2), "bytes": size,
                "status": "ok" if p.returncode == 0 else f"exit {p.returncode}"}


def commands(N: int) -> list:
    return ([(f"derive {p}", ["derive", f"n_trailer:N={N}", "-p", p]) for p in PRINCIPLES]
            + [("compare", ["compare", f"n_trailer:N={N}"])])


def main(argv=None):
    ap = parser(__doc__, "cli_large")
    ap.add_argument("--ns", default="3,5,8,16")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--baseline", type=Path, default=None, help="a source tree to compare")
    ap.add_argument("--baseline-ns", default="3,5,8")
    args = ap.parse_args(argv)
    ns = [3] if args.quick else [int(n) for n in args.ns.split(",")]
    base_ns = {int(n) for n in args.baseline_ns.split(",")} if args.baseline else set()
    rows, slow = [], set()
    for N in ns:
        for name, cmd in commands(N):
            row = {"N": N, "command": name}
            if name in slow:                  # timed out at a smaller N: not tried again
                row.update(status="skipped")
            else:
                screen = run(ROOT, cmd, args.timeout)
                row.update(seconds=screen["seconds"], stdout_bytes=screen.get("bytes"),
                           status=screen["status"])
                if row["seconds"] is None:
                    slow.add(name)
                else:
                    full = run(ROOT, cmd, args.timeout, to_file=True)
                    row.update(out_seconds=full["seconds"], out_bytes=full.get("bytes"))
            if N in base_ns:
                b = run(args.baseline, cmd, args.timeout)
                row.update(baseline_seconds=b["seconds"], baseline_stdout_bytes=b.get("bytes"),
                           baseline_status=b["status"])
                if row.get("seconds"):
                    bt = b["seconds"] if b["seconds"] is not None else args.timeout
                    row["ratio"] = ("> " if b["seconds"] is None else "") + \
                        f"{bt / row['seconds']:.3g}"
            print(row, flush=True)
            rows.append(row)
    done = [r for r in rows if r.get("seconds")]
    at8 = [r for r in done if r["N"] == 8]
    summary = [f"N = 8: every command in {max(r['seconds'] for r in at8):.3g} s or less "
               f"(process wall time), stdout at most "
               f"{max(r['stdout_bytes'] for r in at8)} bytes"] if at8 else []
    if args.baseline:
        summary.append(f"baseline: the tree at {args.baseline}, same run, interleaved")
    columns = ["N", "command", "seconds", "stdout_bytes", "out_seconds", "out_bytes", "status"]
    if args.baseline:
        columns += ["baseline_seconds", "baseline_stdout_bytes", "baseline_status", "ratio"]
    write("cli_large", {"title": "The command line on large systems (N-trailer)",
                        "summary": summary, "columns": columns, "rows": rows,
                        "timeout": args.timeout,
                        "baseline": str(args.baseline) if args.baseline else None},
          args.out, args.quick)


if __name__ == "__main__":
    main()
