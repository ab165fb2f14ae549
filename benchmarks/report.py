"""Assemble BENCHMARKS.md from the JSON results in benchmarks/results/.

    .venv/bin/python benchmarks/report.py [--results DIR] [--out BENCHMARKS.md]

Re-run a benchmark (its JSON and PNG files land in benchmarks/results/), then this script:
BENCHMARKS.md is generated, never edited by hand.  ``jetnh bench --all [--quick]`` runs
every benchmark and then this.  Files this report knows render as their own section
(workprecision, numeric_skip, numeric_speed, numeric_ensemble, forms_vs_galgebra,
derive_ntrailer); every other results/*.json renders through the generic format below
(overhead_fixed also gives a row of the summary table).

The generic format (stress_*.json, sweep_dask.json, anything new).  Write it with
``_common.write(name, data, out, quick)``, which adds benchmark, profile, date, command,
commit and machine; ``data`` may hold:

    "title":   str            section heading (default: the first docstring line of
                              benchmarks/<benchmark>.py)
    "summary": [str, ...]     the findings, one short sentence each (or one str)
    "limits":  [str, ...]     where the numerics stop being trustworthy, one line each;
                              also listed in the summary table that opens BENCHMARKS.md
    "columns": [str, ...]     which keys of "rows" to show, in order (default: every key
                              whose values are numbers, strings or booleans)
    "rows":    [{...}, ...]   one dict per case: a table (nested dicts flatten to "a.b")
    "tables":  [{"title": str, "columns": [str, ...], "rows": [[...], ...],
                 "note": str}, ...]          further tables, already laid out
    "figures": [str, ...]     PNG file names next to the JSON

Anything else stays in the JSON.  A file with neither "rows" nor "tables" falls back to a
table for every top-level list of dicts and a line for every top-level dict.
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import os
import re
from pathlib import Path

from _common import RESULTS, ROOT

TITLES = {"workprecision": "Work-precision: error against run time",
          "numeric_skip": "Cold and warm start; what skipping work saves",
          "numeric_speed": "Where the numerical speed comes from",
          "numeric_ensemble": "Ensembles",
          "derive_ntrailer": "Derivation scaling: N-trailer against sympy.physics.mechanics",
          "forms_vs_galgebra": "Differential forms: jetnh.geometry.forms against galgebra"}
#: files whose section is generic but which give a row of the summary table (a method
#: of ``Report`` of the same name)
SUMMARY_ONLY = ("overhead_fixed",)


# ---------------------------------------------------------------------- formatting
def num(x) -> str:
    """A number in 3 significant digits ('-' for none); anything else as text."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return str(x)
    return str(x) if isinstance(x, int) else f"{x:.3g}"


def secs(s) -> str:
    """Seconds in a readable unit."""
    if s is None:
        return "-"
    for unit, f in (("s", 1.0), ("ms", 1e3), ("µs", 1e6)):
        if s * f >= 1.0 or unit == "µs":
            return f"{s * f:.3g} {unit}"


def ratio(x) -> str:
    return "-" if x is None else f"{x:.2g}×" if x < 10 else f"{x:.0f}×"


def table(columns, rows) -> str:
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    out += ["| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def flatten(row: dict, prefix="") -> dict:
    """Scalars of a nested dict as "a.b" keys.  A measurement {"seconds": s, ...} becomes
    "a" = s (and "a ops" = its "cse_count_ops", if any); a time-out
    ({"lower_bound" | "seconds_lower_bound": s}) becomes "a" = ">s"."""
    out = {}
    for k, v in row.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            if "seconds" in v:
                out[key] = v["seconds"]
                if "cse_count_ops" in v:
                    out[f"{key} ops"] = v["cse_count_ops"]
            elif "lower_bound" in v or "seconds_lower_bound" in v:
                out[key] = f">{num(v.get('lower_bound', v.get('seconds_lower_bound')))}"
            elif "error" in v:
                out[key] = "error"
            else:
                out.update(flatten(v, key + "."))
        elif v is None or isinstance(v, (int, float, str, bool)):
            out[key] = v
    return out


def row_table(flat, columns=None) -> str:
    """A table of flattened rows; strings longer than 40 characters go below it as
    numbered notes."""
    cols = columns or list(dict.fromkeys(k for f in flat for k in f))
    notes, rows = [], []
    for f in flat:
        row = []
        for c in cols:
            v = f.get(c)
            if isinstance(v, str) and len(v) > 40:
                notes.append(v)
                v = f"[{len(notes)}]"
            row.append(num(v))
        rows.append(row)
    return table(cols, rows) + "".join(f"\n[{i}] {n}\n" for i, n in enumerate(notes, 1))


class Report:
    def __init__(self, results: Path, out: Path):
        self.results, self.out = results, out
        self.docs = {}
        for path in sorted(results.glob("*.json")):
            try:
                self.docs[path.stem] = json.loads(path.read_text())
            except (OSError, ValueError) as exc:
                print(f"report: skipping {path.name}: {exc}")
        self.titles = dict(TITLES)
        self.summary = []          # (question, answer, section name)
        self.limits = []           # (line, section name)

    def ref(self, name: str) -> str:
        """A markdown link to a section."""
        return f"[{self.titles[name]}](#{anchor_of(self.titles[name])})"

    def link(self, name: str) -> str:
        return os.path.relpath(self.results / name, self.out.parent).replace(os.sep, "/")

    def figures(self, names) -> str:
        return "".join(f"![{n}]({self.link(n)})\n\n" for n in names or ()
                       if (self.results / n).exists())

    def header(self, name, title=None) -> str:
        d = self.docs[name]
        title = title or TITLES[name]
        m = d.get("machine", {})
        prof = d.get("profile")
        lines = [f"## {title}\n",
                 f"*{d.get('date', '?')}, commit {d.get('commit') or '?'}"
                 + (f", **{prof} profile**" if prof == "quick" else "")
                 + f"; {m.get('platform', '?')}, {m.get('cpus', m.get('cpu_count', '?'))} "
                 f"CPUs, load {num_list(m.get('loadavg', m.get('loadavg_start')))}.*\n",
                 f"Regenerate: `{d.get('command', '?')}`\n"]
        return "\n".join(lines) + "\n"

    # ------------------------------------------------------------------ sections
    def workprecision(self, d) -> str:
        s = d["summary"]
        targets = [str(t) for t in s["targets"]]
        out = [self.header("workprecision"),
               doc_body("workprecision"), self.figures(d.get("figures")),
               self.wp_findings(d) + "\n"]
        methods = ["jetnh dop853", "jetnh dopri5", "scipy DOP853", "scipy RK45",
                   "scipy LSODA", "scipy Radau", "scipy DOP853 (jetnh rhs)", "jetnh rk4",
                   "jetnh dla", "jetnh dvi"]
        for t in (targets[0], targets[2]):
            rows = []
            for p in d["panels"]:
                tte = p["time_to_error"]
                base = min((tte[m][t] for m in ("jetnh dop853", "jetnh dopri5")
                            if tte.get(m, {}).get(t)), default=None)
                rows.append([p["label"]] + [
                    "" if m not in tte else
                    "-" if not tte[m][t] else
                    f"{secs(tte[m][t])}" + (f" ({ratio(tte[m][t] / base)})" if base else "")
                    for m in methods])
            out.append(f"**Time to reach an error of {t}** (cheapest run at or below it; "
                       "in brackets: ratio to jetnh's fastest adaptive method; - never "
                       "reached, blank: not applicable)\n\n")
            out.append(table(["system / principle"] + methods, rows) + "\n")
        rows = []
        for m, by in s["time_ratio_to_jetnh"].items():
            if m.startswith("scipy") or m in ("jetnh rk4", "jetnh dla", "jetnh dvi"):
                rows.append([m] + [f"{ratio(by[t]['geomean'])} ({ratio(by[t]['min'])}–"
                                   f"{ratio(by[t]['max'])}, n={by[t]['n']})" if by.get(t)
                                   else "-" for t in targets])
        best = s["best_scipy_over_jetnh"]
        rows.append(["**fastest scipy method**"] + [
            f"**{ratio(best[t]['geomean'])}** ({ratio(best[t]['min'])}–"
            f"{ratio(best[t]['max'])}, n={best[t]['n']})" if best.get(t) else "-"
            for t in targets])
        cold = s.get("best_scipy_over_jetnh_cold")
        if cold:
            rows.append(["fastest scipy method, first calls of the rounds (cold caches)"] + [
                f"{ratio(cold[t]['geomean'])} ({ratio(cold[t]['min'])}–"
                f"{ratio(cold[t]['max'])}, n={cold[t]['n']})" if cold.get(t) else "-"
                for t in targets])
        out.append("**Time over jetnh's time at equal error**, geometric mean (min–max, "
                   "number of panels) over the system × principle panels:\n\n")
        out.append(table(["method"] + [f"error {t}" for t in targets], rows) + "\n")
        out.append(self.wp_floor(d))
        rows = [[m, num(a["median"]), num(a["max"]), f"{a['over_1']}/{a['n']}",
                 f"{a['over_10']}/{a['n']}"] for m, a in s["achieved_over_requested"].items()]
        out.append("**Achieved error / requested rtol** (adaptive methods, every run whose "
                   "error the reference resolves):\n\n")
        out.append(table(["method", "median", "max", "runs over 1", "runs over 10"], rows))
        out.append("\n" + s["note"] + ".\n\n")
        rows = [[p["label"], num(p["t_end"]), len(p["states"]), p["reference"]["kind"],
                 num(p["reference"]["uncertainty"]),
                 num(p["reference"].get("tight_run_error")),
                 ", ".join(f"{m.split()[-1]} {num(o)}" for m, o in p.get("orders", {}).items())]
                for p in d["panels"]]
        out.append("**The panels**: span, states, reference and its uncertainty (for exact "
                   "cases, the error of the tight-run procedure against the closed form, "
                   "which validates it), and the observed order of the fixed-step "
                   "methods:\n\n")
        out.append(table(["system / principle", "T", "states", "reference", "uncertainty",
                          "tight run vs exact", "observed order"], rows) + "\n")
        self.wp_summary(d)
        return "".join(out)

    @staticmethod
    def wp_floor(d) -> str:
        """The floor of each panel at error 1e-8 and, at every error, the panels where even
        the floor is below the goal (a file without them: nothing)."""
        s = d["summary"]
        floor = s.get("fastest_scipy_over_floor")
        if not floor:
            return ""
        t = str(s["targets"][2])
        goal = s["goal"]
        rows = []
        for p in d["panels"]:
            f = p["floor"]
            b = f["by_target"].get(t)
            if b:
                rows.append([p["label"], b["nfev"], f"{f['per_evaluation_s'] * 1e9:.3g} ns",
                             secs(f["fixed_s"]), secs(b["floor_s"]), secs(b["loop_s"]),
                             secs(b["jetnh_s"]),
                             f"{secs(b['scipy_s'])} ({b['scipy_method'].split()[-1]})",
                             ratio(b["scipy_over_jetnh"]), ratio(b["scipy_over_loop"]),
                             ratio(b["scipy_over_floor"]),
                             ratio(b["scipy_over_run_floor"]) if b.get("scipy_over_run_floor")
                             else "-"])
        out = [f"**The floor at error {t}**: what any implementation making jetnh's rhs "
               "evaluations must pay — evaluations (the fewest of a jetnh adaptive run at "
               "this error) × one evaluation in a bare compiled loop + the fixed cost of the "
               "bare compiled call; between it and jetnh's time, jetnh's compiled loop "
               "called directly (the run without its Python side); all measured on each "
               "panel in this run.  The fastest scipy method over the floor is the largest "
               "ratio such an implementation could reach; the run floor adds what a run "
               "from Python cannot skip while Ctrl-C stops it within a step (a halt flag, "
               "`set_wakeup_fd` where runs confirm the wakeup fd each time, the Trajectory):\n\n",
               table(["system / principle", "evaluations", "per evaluation", "fixed", "floor",
                      "compiled loop", "jetnh", "fastest scipy", "scipy / jetnh",
                      "scipy / loop", "scipy / floor", "scipy / run floor"], rows),
               f"\nPanels below {ratio(goal)} the fastest scipy method, at each error, even at "
               "the floor; and with jetnh's compiled loop: "]
        out.append("; ".join(f"error {k}: " + (", ".join(v["below_goal"]) or "none")
                             + f" (scipy / floor {ratio(v['min'])}–{ratio(v['max'])}); "
                             + (", ".join(v["loop_below_goal"]) or "none")
                             + f" (scipy / loop {ratio(v['scipy_over_loop']['min'])}–"
                             f"{ratio(v['scipy_over_loop']['max'])})"
                             + ("; at the run floor: "
                                + (", ".join(v["run_floor_below_goal"]) or "none")
                                + f" (scipy / run floor {ratio(v['run_floor']['min'])}–"
                                f"{ratio(v['run_floor']['max'])})" if v.get("run_floor")
                                else "")
                             for k, v in floor.items()) + ".\n\n")
        return "".join(out)

    def wp_summary(self, d):
        """The work-precision rows of the summary table and its limit of validity."""
        s = d["summary"]
        targets = [str(t) for t in s["targets"]]
        best = s["best_scipy_over_jetnh"]
        t = targets[2]
        if best.get(t):
            self.summary.append((
                "Run time against lambdify + scipy `solve_ivp`, at equal error",
                f"{ratio(best[t]['geomean'])} faster than the fastest of RK45, DOP853, "
                f"LSODA, Radau (geometric mean over {best[t]['n']} system × principle "
                f"panels; {ratio(best[t]['min'])}–{ratio(best[t]['max'])}) at error {t}; "
                f"{ratio(best[targets[0]]['geomean'])} at {targets[0]}"
                + (f"; first calls of the rounds, cold caches: "
                   f"{ratio(s['best_scipy_over_jetnh_cold'][t]['geomean'])}"
                   if (s.get("best_scipy_over_jetnh_cold") or {}).get(t) else ""),
                "workprecision"))
        floor = s.get("fastest_scipy_over_floor", {}).get(t)
        if floor:
            below = floor["below_goal"]
            self.summary.append((
                "… the most any implementation making jetnh's rhs evaluations could reach "
                "(the floor: evaluations × a bare evaluation + the bare call's fixed cost)",
                f"{ratio(floor['geomean'])} ({ratio(floor['min'])}–{ratio(floor['max'])}) "
                f"at error {t}; below {ratio(s['goal'])} on "
                + (f"{len(below)} of {floor['n']} panels ({', '.join(below)})" if below
                   else f"none of {floor['n']} panels")
                + (f"; with a run's Python floor (Ctrl-C guarantee) below it on "
                   + (f"{len(floor['run_floor_below_goal'])} ("
                      f"{', '.join(floor['run_floor_below_goal'])}; scipy / run floor "
                      f"{ratio(floor['run_floor']['min'])}–{ratio(floor['run_floor']['max'])})"
                      if floor["run_floor_below_goal"] else "none")
                   if floor.get("run_floor") else "")
                + f"; jetnh takes {ratio(floor['jetnh_over_floor']['geomean'])} its floor "
                f"({ratio(floor['jetnh_over_floor']['min'])}–"
                f"{ratio(floor['jetnh_over_floor']['max'])}); fastest scipy over jetnh's "
                f"compiled loop called directly {ratio(floor['scipy_over_loop']['geomean'])} "
                f"({ratio(floor['scipy_over_loop']['min'])}–"
                f"{ratio(floor['scipy_over_loop']['max'])})", "workprecision"))
        same = s["time_ratio_to_jetnh"].get("scipy DOP853 (jetnh rhs)", {}).get(t)
        if same:
            self.summary.append((
                "… scipy's DOP853 given jetnh's compiled rhs (the share of the integrator "
                "loop)", f"{ratio(same['geomean'])} slower than jetnh ({ratio(same['min'])}–"
                f"{ratio(same['max'])}) at error {t}",
                "workprecision"))
        times = sorted(min(x for x in (p["time_to_error"][m][t] for m in ("jetnh dop853",
                                                                             "jetnh dopri5"))
                           if x) for p in d["panels"]
                       if p["time_to_error"]["jetnh dop853"][t]
                       or p["time_to_error"]["jetnh dopri5"][t])
        a = s["achieved_over_requested"].get("jetnh dop853")
        if a and times:
            self.summary.append((
                "Accuracy for the time it takes",
                f"error {t} at T in {secs(times[len(times) // 2])} (median over "
                f"{len(times)} panels; {secs(times[0])}–{secs(times[-1])}); dop853's achieved "
                f"error / requested rtol: median {num(a['median'])}, max {num(a['max'])}, "
                f"over 1 in {a['over_1']} of {a['n']} runs (the global error grows where the "
                "dynamics amplify it, as for scipy's DOP853)", "workprecision"))
        worst = max(((r["achieved_over_requested"], p["label"], p["t_end"])
                     for p in d["panels"] for r in p["runs"] if r["method"] == "jetnh dop853"
                     and r.get("achieved_over_requested")
                     and r["error"] > 10 * p["reference"]["uncertainty"]), default=None)
        if worst:
            self.limits.append((f"rtol bounds the error of each step, not the error at T: "
                                f"on {worst[1]} (T = {num(worst[2])}) the error at T is up to "
                                f"{num(worst[0])} × rtol, for every method alike",
                                "workprecision"))
        floors = [p["reference"]["uncertainty"] for p in d["panels"]]
        self.limits.append((f"errors below {num(min(floors))}–{num(max(floors))} (depending "
                            "on the run) are not resolved: double precision over the run; "
                            "rtol < 1e-12 buys nothing", "workprecision"))

    @staticmethod
    def wp_findings(d) -> str:
        """What the work-precision numbers say, in words."""
        s = d["summary"]
        t = str(s["targets"][2])
        r = s["time_ratio_to_jetnh"]
        out = ["**Findings**\n"]
        same = s.get("same_error_as_scipy", {})
        if same:
            out.append("- jetnh's dop853 and dopri5 take scipy's DOP853 and RK45 steps: the "
                       "errors at T agree within 1 % in " + ", ".join(
                           f"{v['agree']}/{v['runs']} ({k})" for k, v in same.items())
                       + " of the runs at equal rtol; the time ratios are the cost of the "
                       "implementations, a compiled loop and rhs against Python ones.")
        loop = r.get("scipy DOP853 (jetnh rhs)", {}).get(t)
        if loop:
            out.append(f"- scipy's DOP853 on jetnh's compiled rhs is still {ratio(loop['geomean'])}"
                       " slower than jetnh at equal error: most of the gap is solve_ivp's "
                       "Python step loop, not the right-hand side.")
        fastest = s.get("fastest_scipy_method", {}).get(t, {})
        if fastest:
            out.append(f"- The fastest scipy method at error {t}: " + ", ".join(
                f"{m} in {n} panel{'s' * (n > 1)}" for m, n in sorted(
                    fastest.items(), key=lambda x: -x[1])) + ". jetnh's advantage is "
                       "smallest on the short runs (a few hundred rhs evaluations), where "
                       "every route's fixed cost per call dominates (see the run-cost table "
                       "below), and largest on the long and large ones.")
        a = s["achieved_over_requested"]
        if "scipy LSODA" in a:
            out.append(f"- LSODA's error exceeds the requested rtol in "
                       f"{a['scipy LSODA']['over_1']}/{a['scipy LSODA']['n']} runs (median "
                       f"achieved/requested {num(a['scipy LSODA']['median'])}): part of its "
                       "speed at loose tolerance is accuracy it does not deliver. Radau "
                       "(implicit, finite-difference Jacobian) is the slowest: these problems "
                       "are not stiff.")
        rk4 = r.get("jetnh rk4", {}).get(t)
        if rk4:
            out.append(f"- Fixed-step rk4 at its best step count takes {ratio(rk4['geomean'])}"
                       f" ({ratio(rk4['min'])}–{ratio(rk4['max'])}) the time of the adaptive "
                       "methods: it wins on smooth short runs (no error estimate), loses where "
                       "the solution needs small steps somewhere, and its step count is only "
                       "known after the fact, from the reference.")
        dla = [r.get(m, {}).get(t) for m in ("jetnh dla", "jetnh dvi")]
        if any(dla):
            out.append("- The discrete Lagrange-d'Alembert and vakonomic integrators are "
                       "second order (observed orders in the table below) and cost "
                       + " and ".join(f"{ratio(x['geomean'])}" for x in dla if x)
                       + " the adaptive time for the same error: they are for structure "
                       "(long-time behaviour of the invariants, see the stress tests), not "
                       "for accuracy per second.")
        return "\n".join(out) + "\n"

    def numeric_skip(self, d) -> str:
        out = [self.header("numeric_skip"),
               doc_body("numeric_skip")]
        for c in d.get("cold_warm", []):
            rows = [[k, secs(v.get("work_s")), secs(v["prepare_s"]), secs(v["first_run_s"]),
                     secs(v["next_run_s"]), secs(v["import_s"])] for k, v in c["runs"].items()]
            out.append(f"**{c['problem']}**, T = {num(c['t_end'])}, each start in a new "
                       "process (best of its repetitions):\n\n")
            out.append(table(["start", "to the first trajectory", "derive + generate + "
                              "compile (or load) / derive + lambdify", "first run",
                              "next run", "imports (the same modules)"], rows))
            pay = c.get("runs_to_pay_off_cold")
            out.append(f"\ncold / warm {ratio(c['cold_over_warm'])}; lambdify route / warm "
                       f"{ratio(c['lambdify_over_warm'])}; lambdify route / cold "
                       f"{ratio(c['lambdify_over_cold'])}; every further run is "
                       f"{ratio(c['run_speedup'])} faster with jetnh, so a cold start has "
                       + (f"paid for itself after {pay:.2g} further runs" if pay else
                          "paid for itself by the first run") + ".\n\n")
        for c in d.get("cold_warm", []):
            work = {k: v.get("work_s") for k, v in c["runs"].items()}
            self.summary.append((
                f"Time to the first trajectory after the imports, {c['problem']}",
                f"jetnh cold (derive, generate, compile) {secs(work['kernels cold'])}, "
                f"warm (disk cache) {secs(work['warm'])}; lambdify + solve_ivp "
                f"{secs(work['lambdify + solve_ivp'])}"
                + (f"; first use on a machine (integrator loops compiled too) "
                   f"{secs(work['machine cold'])}" if "machine cold" in work else ""),
                "numeric_skip"))
        rows = [[r["system"], secs(r["chetaev_only_s"]), secs(r["all_four_s"]),
                 ratio(r["ratio"])] for r in d.get("derive_one_vs_all", [])]
        out.append("**Derive only the principle asked for** (fresh System, sympy cache "
                   "cleared):\n\n" + table(["system", "chetaev only", "all four", "ratio"],
                                           rows) + "\n")
        rows = [[f"{r['system']} / {r['principle']}", f"{num(r['compiled']['rhs_ns'])} ns",
                 f"{num(r['runtime']['rhs_ns'])} ns", ratio(r["rhs_ratio"]),
                 secs(r["compiled"]["run_s"]), secs(r["runtime"]["run_s"]),
                 ratio(r["run_ratio"]), r["same_result"]]
                for r in d.get("params_compiled_vs_runtime", [])]
        out.append("**Parameters compiled in, against read at run time** (`runtime_params`, "
                   "what ensembles over parameters use):\n\n"
                   + table(["scene", "rhs compiled", "rhs runtime", "ratio", "run compiled",
                            "run runtime", "ratio", "same result"], rows) + "\n")
        o = d.get("output_modes")
        if o:
            rows = [[r["mode"], secs(r["run_s"]), ratio(r["ratio_to_final"]), r["rows"],
                     f"{r['bytes'] / 1024:.1f} KiB", r["nfev"]] for r in o["rows"]]
            out.append(f"**Output** ({o['problem']}):\n\n" + table(
                ["save", "run", "ratio to final", "rows", "memory", "rhs evaluations"],
                rows) + "\n")
        rows = [[r["problem"], secs(r["checks_s"]), secs(r["no_checks_s"]), ratio(r["ratio"]),
                 secs(r.get("event_s")), ratio(r.get("event_ratio")), r["same_result"]]
                for r in d.get("checks", [])]
        out.append("**Singularity checks and a user event** (`singular='stop'` against "
                   "`'ignore'`; an event sin ψ = 0):\n\n" + table(
                       ["scene", "with checks", "without", "ratio", "with event",
                        "event / checks", "same result"], rows) + "\n")
        return "".join(out)

    def numeric_speed(self, d) -> str:
        out = [self.header("numeric_speed"),
               doc_body("numeric_speed")]
        rows = []
        for r in d.get("rhs_call", []):
            for k, v in r["ns_per_call"].items():
                rows.append([r["problem"], r["states"], k, f"{num(v)} ns",
                             ratio(r["ratio_to_generated"][k])])
        out.append("**One right-hand-side call**:\n\n" + table(
            ["scene", "states", "implementation", "per call", "ratio to generated"], rows))
        rows = []
        for r in d.get("run_cost", []):
            for k, v in r["summary"].items():
                rows.append([r["problem"], k, f"{num(v['fixed_us'])} µs",
                             ratio(v["fixed_ratio"]), f"{num(v['per_evaluation_ns'])} ns",
                             ratio(v["per_evaluation_ratio"])])
        out.append("\n**One run** (rtol 1e-9): fixed cost (a run of one step) and cost per "
                   "rhs evaluation (from the longest span):\n\n" + table(
                       ["scene", "route", "fixed", "ratio", "per evaluation", "ratio"], rows))
        calls = d.get("rhs_call", [])
        if calls:
            self.summary.append((
                "One rhs evaluation: generated numba kernel against the lambdified function",
                "; ".join(f"{c['problem']}: {num(c['ns_per_call']['generated'])} ns, the "
                          "lambdified function "
                          f"{ratio(c['ratio_to_generated']['lambdify (math) + numpy array'])}"
                          " slower" for c in calls), "numeric_speed"))
        runs = d.get("run_cost", [])
        if runs:
            s = runs[0]["summary"]
            self.summary.append((
                "Fixed cost of one run (where short runs spend their time)",
                f"jetnh {num(s['jetnh dop853']['fixed_us'])} µs, solve_ivp on the lambdified "
                f"rhs {num(s['scipy DOP853 (lambdify)']['fixed_us'])} µs: for runs of a few "
                "hundred evaluations the ratio is this, not the per-evaluation one",
                "numeric_speed"))
        return "".join(out) + "\n"

    def numeric_ensemble(self, d) -> str:
        out = [self.header("numeric_ensemble"), doc_body("numeric_ensemble")]
        rows = []
        for p in d.get("problems", []):
            for r in p["rows"]:
                for m, v in r["modes"].items():
                    per = v.get("per_eval_vs_single_run")
                    rows.append([p["problem"], r["n_runs"], m, secs(v["wall_s"]),
                                 f"{v['rhs_per_s'] / 1e6:.3g} M", ratio(v["speedup_vs_serial"]),
                                 "-" if per is None else f"{per:.2f}",
                                 v["bitwise_equal_to_serial"]])
        out.append(table(["scene", "runs", "mode", "wall", "rhs/s", "speed-up vs serial",
                          "CPU per evaluation / single run", "bitwise = serial"],
                         rows))
        if d.get("problems"):
            p = d["problems"][0]
            r = p["rows"][-1]
            modes = r["modes"]
            fastest = max(modes, key=lambda m: modes[m]["speedup_vs_serial"])
            self.summary.append((
                "Ensembles (many initial conditions, one compiled loop)",
                f"{p['problem']}, {r['n_runs']} runs: "
                f"{modes['serial']['rhs_per_s'] / 1e6:.3g} M rhs evaluations/s serial; "
                f"{fastest} {ratio(modes[fastest]['speedup_vs_serial'])} on "
                f"{d.get('machine', {}).get('cpus', '?')} CPUs; bitwise equal to single "
                f"runs: {all(v['bitwise_equal_to_serial'] for v in modes.values())}",
                "numeric_ensemble"))
        return "".join(out) + "\n"

    def forms_vs_galgebra(self, d) -> str:
        out = [self.header("forms_vs_galgebra"), doc_body("forms_vs_galgebra")]
        rows = []
        for r in d.get("results", []):
            for op, v in r["ops"].items():
                rows.append([r["n"], r["dim"], op, secs(v["jetnh_s"]), secs(v["jetnh_expand_s"]),
                             secs(v["galgebra_s"]), ratio(v["ratio_galgebra_over_jetnh"]),
                             ratio(v["ratio_galgebra_over_jetnh_expand"]), v["results_agree"]])
        out.append(table(["n", "dim", "op", "jetnh", "jetnh + expand", "galgebra",
                          "galgebra / jetnh", "galgebra / (jetnh + expand)", "agree"], rows))
        if rows:
            r = d["results"][-1]
            self.summary.append((
                "Exterior algebra on J¹ (wedge, d) against galgebra",
                f"n = {r['n']} (dim {r['dim']}): galgebra / (jetnh + expand) "
                + ", ".join(f"{op} {ratio(v['ratio_galgebra_over_jetnh_expand'])}"
                            for op, v in r["ops"].items()),
                "forms_vs_galgebra"))
        return "".join(out) + "\n"

    def derive_ntrailer(self, d) -> str:
        out = [self.header("derive_ntrailer"), doc_body("derive_ntrailer")]
        for key in ("model", "targets", "verdict", "note"):
            if key in d:
                v = d[key]
                v = "; ".join(f"{k}: {x}" for k, x in v.items()) if isinstance(v, dict) else v
                out.append(f"- **{key}**: {v}\n")
        rows = pick_rows(d)
        if rows:
            flat = [flatten(r) for r in rows]
            for f in flat:                      # a ratio to a time-out is a lower bound
                for k, v in list(f.items()):
                    if k.endswith("_ratio_is_lower_bound") and v:
                        r = k.replace("_ratio_is_lower_bound", "_over_chetaev")
                        f[r] = f">{num(f[r])}"
            cols = [c for c in dict.fromkeys(k for f in flat for k in f)
                    if not c.endswith(("_is_lower_bound", ".outputs", "cse_seconds"))]
            times = [c for c in cols if not c.endswith(" ops")]
            ops = ["N"] + [c for c in cols if c.endswith(" ops")]
            out.append("\nTime to the accelerations [s] and ratios to jetnh's Chetaev "
                       "time:\n\n" + row_table(flat, times))
            if len(ops) > 1:
                out.append("\nExpression size: operations after `cse` (count_ops):\n\n"
                           + row_table(flat, ops))
            ratios = derive_ratios(flat)
            if ratios:
                self.summary.append((
                    "Derivation (equations solved for the accelerations), N-trailer",
                    "; ".join(f"{camel(b)} / jetnh Chetaev: {ratio(pairs[-1][1])} at N = "
                              f"{pairs[-1][0]} (largest N both finished; "
                              + ", ".join(f"N={n}: {ratio(r)}" for n, r in pairs[:-1]) + ")"
                              for b, pairs in ratios.items()), "derive_ntrailer"))
        out.append(self.figures(d.get("figures")))
        return "".join(out) + "\n"

    def overhead_fixed(self, d):
        """The summary row of overhead_fixed.json (its section is generic)."""
        a = d.get("fixed", {}).get("after")
        if a:
            bare = a["bare call"]
            self.summary.append((
                "Fixed cost of a short run (one dop853 step, rolling disk) against the bare "
                "call of its compiled loop",
                f"run() {secs(a['run()'])}, {ratio(a['run()'] / bare)} the bare call "
                f"({secs(bare)}); run(y0=...) {ratio(a['run(y0=...)'] / bare)}, "
                f"replace(initial=...).run() {ratio(a['replace(initial=...).run()'] / bare)}"
                f", an ensemble of one {ratio(a['ensemble of one'] / bare)}", "overhead_fixed"))

    def generic(self, name, d) -> str:
        title = d.get("title") or doc_first_line(name) or name
        self.titles[name] = title
        if name in SUMMARY_ONLY:
            getattr(self, name)(d)
        out = [self.header(name, title)]
        summary = d.get("summary")
        if isinstance(summary, str):
            summary = [summary]
        if isinstance(summary, list):
            out += [f"- {s}\n" for s in summary if isinstance(s, str)]
        limits = d.get("limits") or []
        if limits:
            out.append("\n**Limits of validity**:\n\n" + "".join(f"- {s}\n" for s in limits))
        self.limits += [(s, name) for s in limits]
        out.append("\n" + self.figures(d.get("figures") or find_pngs(d)))
        rows = d.get("rows")
        if is_rows(rows):
            out.append(row_table([flatten(r) for r in rows], d.get("columns")) + "\n")
        elif not d.get("tables"):                 # not in the format: show what there is
            for key, v in d.items():
                if key in ("machine", "summary", "limits", "figures"):
                    continue
                if is_rows(v):
                    out.append(f"**{key}**\n\n" + row_table([flatten(r) for r in v]) + "\n")
                elif isinstance(v, dict) and flatten(v):
                    out.append(f"**{key}**: " + "; ".join(
                        f"{k} {num(x)}" for k, x in flatten(v).items()) + "\n\n")
        for t in d.get("tables") or []:
            out.append(f"**{t.get('title', '')}**\n\n" + table(
                t["columns"], [[num(c) for c in r] for r in t["rows"]]))
            if t.get("note"):
                out.append(f"\n{t['note']}\n")
            out.append("\n")
        return "".join(out)

    # ------------------------------------------------------------------ document
    def render(self) -> str:
        body = []
        for name in TITLES:
            if name in self.docs:
                body.append(getattr(self, name)(self.docs[name]))
        for name in sorted(self.docs):
            if name not in TITLES:
                body.append(self.generic(name, self.docs[name]))
        missing = [n for n in TITLES if n not in self.docs]
        head = ["# Benchmarks\n\n",
                "Generated by `benchmarks/report.py` from the JSON files in "
                "`benchmarks/results/`; do not edit by hand. Re-run a benchmark, then "
                "`.venv/bin/python benchmarks/report.py`; or `jetnh bench --all [--quick]` "
                "for every benchmark and this report. Every figure is a ratio against a "
                "baseline measured in the same run, the best of several repetitions (the "
                "machine is shared and noisy); each section gives its date, commit, machine "
                "load and the command that regenerates it.\n\n",
                machine_line(self.docs), "\n"]
        if self.summary or self.limits:
            head.append("## Summary\n\n")
            rows = [[q, a, self.ref(n)] for q, a, n in self.summary]
            if self.limits:
                rows.append(["Where the numerics stop being trustworthy",
                             "<br>".join(f"{x} ({self.ref(n)})" for x, n in self.limits), ""])
            head.append(table(["question", "answer", "section"], rows) + "\n")
        if missing:
            head.append("Not run yet: " + ", ".join(f"`benchmarks/{m}.py`" for m in missing)
                        + ".\n\n")
        return "".join(head) + "\n".join(body)


# ---------------------------------------------------------------------- helpers
def num_list(v) -> str:
    return "?" if not v else " ".join(f"{x:.2g}" for x in v)


def anchor_of(title: str) -> str:
    """GitHub's heading anchor."""
    keep = "".join(c for c in title.lower() if c.isalnum() or c in " -_")
    return keep.replace(" ", "-")


def _docstring(name: str) -> str:
    path = ROOT / "benchmarks" / f"{name}.py"
    try:
        return ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    except (OSError, SyntaxError):
        return ""


def doc_first_line(name: str) -> str:
    doc = _docstring(name).split("\n\n")[0]
    return " ".join(doc.split()).rstrip(".")


def doc_body(name: str) -> str:
    """A script's docstring without the usage and default-output paragraphs, as
    markdown: indented blocks as code, "- ", "* " and "1. " items as lists (their
    indented continuation lines joined), the rest as running text."""
    out = []
    for para in _docstring(name).split("\n\n"):
        if para.lstrip().startswith((".venv", "(default output")):
            continue
        lines = para.splitlines()
        if all(line.startswith("    ") for line in lines):
            out.append("```\n" + "\n".join(line[4:] for line in lines) + "\n```")
            continue
        blocks = []                                # [kind ("item"|"text"), text]
        for line in lines:
            item = re.match(r"(- |\* |\d+\. )", line)
            if item or not blocks or (blocks[-1][0] == "item" and not line.startswith(" ")):
                blocks.append(["item" if item else "text", line.strip()])
            else:
                blocks[-1][1] += " " + line.strip()
        md = blocks[0][1]
        for (k0, _), (k1, text) in zip(blocks, blocks[1:]):
            md += ("\n" if k0 == k1 == "item" else "\n\n") + text
        out.append(md)
    return "\n\n".join(o.strip() for o in out) + "\n\n"


def machine_line(docs) -> str:
    for name in ("workprecision", *sorted(docs)):
        m = docs.get(name, {}).get("machine")
        if m and "versions" in m:
            v = ", ".join(f"{k} {x}" for k, x in m["versions"].items())
            return (f"Machine: {m['platform']}, {m['processor']}, {m['cpus']} CPUs, Python "
                    f"{m['python']}; {v}.\n")
    return ""


def camel(name: str) -> str:
    """lagranges_method -> LagrangesMethod."""
    return "".join(w.capitalize() for w in name.split("_"))


def is_rows(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(r, dict) for r in v)


def find_pngs(obj) -> list:
    """File names of every "*.png" string in a JSON document."""
    if isinstance(obj, str):
        return [os.path.basename(obj)] if obj.endswith(".png") else []
    items = obj.values() if isinstance(obj, dict) else obj if isinstance(obj, list) else ()
    return [p for v in items for p in find_pngs(v)]


def pick_rows(d):
    """The per-N rows of derive_ntrailer.json: ``rows``, else ``summary``."""
    for key in ("rows", "summary"):
        v = d.get(key)
        if isinstance(v, list) and v and all(isinstance(r, dict) and "N" in r for r in v):
            return v
    return []


def derive_ratios(flat) -> dict:
    """{baseline: [(N, baseline seconds / jetnh Chetaev seconds)]}: the rows' own
    "<baseline>_over_chetaev" ratios, else LagrangesMethod over the first jetnh Chetaev
    time (the older schema)."""
    out = {}
    for f in flat:
        own = {k[:-len("_over_chetaev")]: v for k, v in f.items()
               if k.endswith("_over_chetaev") and isinstance(v, (int, float))}
        if not own:
            lm = next((v for k, v in f.items() if "lagranges" in k.lower()
                       and isinstance(v, (int, float)) and not k.endswith("ops")), None)
            jn = next((v for k, v in f.items() if k.startswith("jetnh") and "chetaev" in k
                       and "patched" not in k and isinstance(v, (int, float))
                       and not k.endswith("ops")), None)
            own = {"lagranges_method": lm / jn} if lm and jn else {}
        for b, r in own.items():
            out.setdefault(b, []).append((f["N"], r))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=RESULTS)
    ap.add_argument("--out", type=Path, default=ROOT / "BENCHMARKS.md")
    args = ap.parse_args(argv)
    args.out.write_text(Report(args.results, args.out).render())
    print("wrote", os.path.relpath(args.out))


if __name__ == "__main__":
    main()
