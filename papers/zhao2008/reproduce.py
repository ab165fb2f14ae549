"""Run the reproduction: checks of (1)-(44) and of the claims, proofs, examples, report.

    python -m papers.zhao2008 [--fast] [--no-figures]

writes ``results.json`` (one item per equation and claim), ``report.md`` and the figures
beside this file, and prints the summary: counts per status, the errata, and where the
report is.
``--fast`` proves the general identities for n <= 3 only and shortens the simulations.

The committed outputs hold results only, so two runs give the same bytes and a checkout
stays clean: the facts of one run (date, machine, versions, timings) go to the terminal
and to ``run.json`` (untracked, listed in .gitignore).
"""

from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import platform
import sys
import time

from . import claims  # noqa: F401  (registers the claim checks)
from .items import REGISTRY, Context
from .printed import load as load_printed

HERE = pathlib.Path(__file__).resolve().parent
PAPER = ("Zhao Zhe, Guo Yong-Xin, Liu Chang, Liu Shi-Xing, Differential equations of motion "
         "for constrained systems with respect to three kinds of nonholonomic variations, "
         "Acta Physica Sinica 57 (2008)")


def check_items(log=print, timings: dict | None = None) -> list[dict]:
    """Every registered item checked; its time goes to ``timings`` (label -> s), not the item."""
    printed = load_printed()
    ctx = Context()
    items = []
    for label, kind, text, fn in REGISTRY:
        t0 = time.perf_counter()
        out = fn(ctx)
        items.append({
            "label": label, "kind": kind, "status": out.status,
            "printed": text if text is not None else printed.get(label, ""),
            "derived": out.derived, "note": out.note, "evidence": out.evidence})
        if timings is not None:
            timings[label] = round(time.perf_counter() - t0, 2)
        log(f"  {label:<48} {out.status}")
    return items


def write_results(data: dict, path: pathlib.Path) -> pathlib.Path:
    """JSON with a fixed layout (key order as built, indent 1, UTF-8, final newline)."""
    path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8",
                    newline="\n")
    return path


def summary(items) -> dict:
    counts = {}
    for it in items:
        counts[it["status"]] = counts.get(it["status"], 0) + 1
    return counts


def run_facts(command: str, seconds: float, items: dict, proofs: list[dict]) -> dict:
    """What is particular to this run (never written to the committed outputs)."""
    import importlib.metadata as md

    versions = {}
    for pkg in ("jetnh", "sympy", "numpy", "scipy", "numba", "matplotlib"):
        try:
            versions[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            versions[pkg] = None
    return {"command": command,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": platform.node(), "platform": platform.platform(),
            "python": platform.python_version(), "versions": versions,
            "seconds": round(seconds, 1),
            "item_seconds": items,
            "proof_seconds": [{k: p[k] for k in ("statement", "n", "k", "seconds")} for p in proofs]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m papers.zhao2008", description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="proofs for n <= 3, short simulations")
    ap.add_argument("--no-figures", action="store_true", help="skip simulations and figures")
    ap.add_argument("--out", default=str(HERE), help="directory for results.json and report.md")
    args = ap.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()

    print(f"Reproducing: {PAPER}")
    print("Equations and claims:")
    item_seconds: dict = {}
    items = check_items(timings=item_seconds)
    print("Proofs for generic systems:")
    from .proofs import run as run_proofs
    proofs = run_proofs(max_n=3 if args.fast else 4)
    proof_seconds = [dict(p) for p in proofs]
    for p in proofs:
        del p["seconds"]
    simulations = {}
    if not args.no_figures:
        print("Examples, simulated:")
        from .examples import run as run_examples
        simulations = run_examples(out, fast=args.fast)

    command = "python -m papers.zhao2008" + (" --fast" if args.fast else "")
    results = {
        "paper": PAPER,
        "generated": {"command": command},
        "summary": summary(items),
        "items": items,
        "proofs": proofs,
        "simulations": simulations,
    }
    write_results(results, out / "results.json")
    from .report import write as write_report
    report = write_report(results, out / "report.md")
    facts = run_facts(command, time.perf_counter() - t0, item_seconds, proof_seconds)
    write_results(facts, out / "run.json")

    counts = results["summary"]
    print()
    print(f"{len(items)} items: " + ", ".join(f"{counts.get(k, 0)} {k}"
                                              for k in ("verified", "erratum", "not-checkable")))
    print(f"proofs: {sum(p['holds'] is True for p in proofs)}/{len(proofs)} hold")
    print("errata:")
    for it in items:
        if it["status"] == "erratum":
            print(f"  {it['label']}: {it['note'].split('. ')[0].rstrip('.')}.")
    print(f"report: {report}")
    print(f"results: {out / 'results.json'}")
    print(f"this run: {facts['seconds']} s, {facts['date']}, {facts['machine']}, Python "
          f"{facts['python']}; timings in {out / 'run.json'} (untracked)")
    ok = all(p["holds"] is True for p in proofs) and all(
        s.get("ok", True) for s in simulations.values())
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
