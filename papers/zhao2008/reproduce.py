"""Run the reproduction: checks of (1)-(44) and of the claims, proofs, examples, report.

    python -m papers.zhao2008 [--fast] [--no-figures]

writes ``results.json`` (DESIGN.md section 4 format) and ``report.md`` beside this file,
and prints the summary: counts per status, the errata, and where the report is.
``--fast`` proves the general identities for n <= 3 only and shortens the simulations.
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


def check_items(log=print) -> list[dict]:
    printed = load_printed()
    ctx = Context()
    items = []
    for label, kind, text, fn in REGISTRY:
        t0 = time.perf_counter()
        out = fn(ctx)
        items.append({
            "label": label, "kind": kind, "status": out.status,
            "printed": text if text is not None else printed.get(label, ""),
            "derived": out.derived, "note": out.note, "evidence": out.evidence,
            "seconds": round(time.perf_counter() - t0, 2)})
        log(f"  {label:<48} {out.status}")
    return items


def summary(items) -> dict:
    counts = {}
    for it in items:
        counts[it["status"]] = counts.get(it["status"], 0) + 1
    return counts


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
    items = check_items()
    print("Proofs for generic systems:")
    from .proofs import run as run_proofs
    proofs = run_proofs(max_n=3 if args.fast else 4)
    simulations = {}
    if not args.no_figures:
        print("Examples, simulated:")
        from .examples import run as run_examples
        simulations = run_examples(out, fast=args.fast)

    results = {
        "paper": PAPER,
        "generated": {"date": datetime.date.today().isoformat(), "machine": platform.node(),
                      "python": platform.python_version(),
                      "command": "python -m papers.zhao2008" + (" --fast" if args.fast else ""),
                      "seconds": round(time.perf_counter() - t0, 1)},
        "summary": summary(items),
        "items": items,
        "proofs": proofs,
        "simulations": simulations,
    }
    (out / "results.json").write_text(json.dumps(results, indent=1, ensure_ascii=False) + "\n")
    from .report import write as write_report
    report = write_report(results, out / "report.md")

    counts = results["summary"]
    print()
    print(f"{len(items)} items: " + ", ".join(f"{counts.get(k, 0)} {k}"
                                              for k in ("verified", "erratum", "not-checkable")))
    print(f"proofs: {sum(p['holds'] for p in proofs)}/{len(proofs)} hold")
    print("errata:")
    for it in items:
        if it["status"] == "erratum":
            print(f"  {it['label']}: {it['note'].split('. ')[0].rstrip('.')}.")
    print(f"report: {report}")
    print(f"results: {out / 'results.json'}")
    ok = all(p["holds"] for p in proofs) and all(
        s.get("ok", True) for s in simulations.values())
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
