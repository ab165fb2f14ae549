"""The overhead of a run: the first run on a fresh machine, the fixed cost of a short run
and the cost per right-hand-side evaluation, on this tree and on earlier ones.

    .venv/bin/python benchmarks/overhead.py --tree before=PATH [--tree NAME=PATH ...]
                                            [--rounds 3] [--quick] [--fixed] [--out PATH]

(default output: benchmarks/results/overhead.json, with ``--fixed``
benchmarks/results/overhead_fixed.json; a tree is a git worktree, e.g.
``git worktree add /tmp/before a6430f6``; this tree is "after").  Every figure comes from
fresh processes with empty numba and kernel caches, the trees alternating within each of
``--rounds`` rounds; each figure is the best over the rounds.  On the rolling disk:

1. First run: the time of the first ``run`` of dop853, dopri5 and rk4 (the kernels
   generated before the clock starts), i.e. the compilation of its loop from nothing:
   each method in a process of its own, and the three one after the other in one process;
   wall-clock and CPU seconds of the process (CPU time is the steadier figure on a loaded
   machine).
2. Fixed cost: a run to T = 1e-6 with ``save="final"`` (best of many calls).  On this
   tree also the compiled loop called directly with the same arguments (its entry point,
   no argument checks, no Trajectory): the floor a run's Python side adds to.
3. Per evaluation: (a run to T = 100 minus the fixed cost) / the extra rhs evaluations
   (rk4: 2000 steps against 1).
4. Fixed cost against the bare call, in one process (the caches as they are), the calls
   interleaved in a random order each round (each figure the 5th percentile of single
   calls, so that the machine's load and the caches hit every one alike):
   the compiled dop853 loop called directly (its entry point, the arguments made once),
   ``scene.run()``, ``scene.run`` with the keywords of a benchmark or a parameter loop
   (``method``, ``rtol``, ``atol``, ``save``; and those of the work-precision
   benchmark: ``split``, ``singular``, ``t_span`` too), ``scene.run(y0=...)`` (the same
   array each call, and a new state each call: the states of the ``replace`` row below),
   ``scene.run(t_eval=...)`` (five times), ``scene.run`` on a new time span each call
   (a loop over the final time), ``scene.replace(initial=...).run()`` (a new initial
   state each call, as a shooting loop does), ``scene.replace(params=...).run()`` of a
   run-time parameter beside ``scene.run(params=...)`` and an ensemble of one run, each with one
   step (T = 1e-6, ``save="final"``), and ensembles of eight such runs on two threads and
   serially (a small ensemble's fixed cost); the ratios to the bare call.  Also the bare
   call of ``run(t_eval=...)``'s own loop (which evaluates the dense output there) and the
   bare call of a run of three steps and its arithmetic: its rhs evaluations at the cost
   of one in a long run (T = 100: the difference of the long and the one-step call over
   their difference in evaluations).  And the parts of a run's Python side, each alone:
   the ``set_wakeup_fd`` that confirms the wakeup fd, a halt flag, ``interrupt.call`` of
   nothing, the Trajectory of the loop's result, ``solve.run`` (a run without
   ``Scene.run``'s option handling), the timing itself (in every figure), and the floor
   of a run with its guarantees: a halt flag, the ``set_wakeup_fd`` confirming the wakeup
   fd, the bare call and a Trajectory of its result, in a row; and each tree's own
   floor: the ``set_wakeup_fd`` only where its runs confirm the fd each time (trees that
   know the fd is still the watchdog's skip it), the Trajectory its runs make.
   ``--fixed`` measures this alone (seconds), and 5.
5. A run interleaved with other work (as the work-precision benchmark's panels run it):
   a dop853 run of isokinetic_particle (Chetaev, T = 2, rtol 1e-8, ``save="final"``) and
   the bare call of its compiled loop, each hot (5th percentile of calls in a row), right
   after a scipy RK45 run of the same problem (median) and after a pause of 1.2 s
   (median), asleep or busy-waiting: what caches that other work emptied cost a single
   call.  A control (``sum(range(300))``, no part of a run) shows what any Python code
   pays; the page faults during the calls after a pause are counted, and the run after
   a pause is timed again without the wakeup fd's confirmation after
   ``interrupt.CONFIRM`` seconds.
"""

import json
import os
import subprocess
import sys
import tempfile

from _common import RESULTS, ROOT, parser, write

METHODS = ("dop853", "dopri5", "rk4")

SETUP = r"""
import json, time
import numpy as np
import jetnh.models as models
from jetnh.numeric import Scene
sc = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
           t_span=(0.0, 10.0)).compile()
def best(f, n):
    b = 1e9
    for _ in range(n):
        tic = time.perf_counter(); f(); b = min(b, time.perf_counter() - tic)
    return b
"""

FIRST = SETUP + r"""
out = {}
for m in METHODS:
    tic, cpu = time.perf_counter(), time.process_time()
    sc.run(method=m, save="final", **({"n_steps": 100} if m == "rk4" else {}))
    out[m] = time.perf_counter() - tic
    out[m + "_cpu"] = time.process_time() - cpu
print(json.dumps(out))
"""

COST = SETUP + r"""
out = {}
for m in ("dop853", "dopri5", "rk4"):
    sc.run(method=m, save="final", **({"n_steps": 100} if m == "rk4" else {}))
for m in ("dop853", "dopri5", "rk4"):
    kw = dict(rtol=1e-9, atol=1e-12) if m != "rk4" else {}
    short = lambda: sc.run(method=m, t_span=(0.0, 1e-6), save="final",
                           **(kw or {"n_steps": 1}))
    long = lambda: sc.run(method=m, t_span=(0.0, 100.0), save="final",
                          **(kw or {"n_steps": 2000}))
    n0 = short().diagnostics.rhs_evaluations
    n1 = long().diagnostics.rhs_evaluations
    fs, gs = [], []
    for _ in range(3):
        fs.append(best(short, REPS_SHORT))
        gs.append(best(long, REPS_LONG))
    out["fixed_s_" + m] = min(fs)
    out["per_eval_s_" + m] = (min(gs) - min(fs)) / (n1 - n0)
try:            # the compiled loop alone (this tree's API)
    from jetnh.numeric import interrupt, loops, methods
    from jetnh.numeric.methods.loop import Control, watch_of
    kern = sc.kernels
    ctl = Control(1e-9, np.full(len(sc.y0), 1e-12), 0.0, np.inf, 10**7, 0)
    # (newer trees also return the callbacks behind the addresses: kept alive in `got`)
    got = loops.entry(sc, methods.method("dop853"), kern, None, None, ctl, np.zeros(0), 2,
                      watch_of(kern, None, True, 1e-10), None)
    entry, prefix, suffix = got[:3]
    args = (*prefix, 0.0, 1e-6, sc.y0.copy(), sc.p, *suffix, interrupt.flag())
    out["call_s_dop853"] = min(best(lambda: entry(*args), REPS_SHORT) for _ in range(3))
except ImportError:
    pass
print(json.dumps(out))
"""


FIXED = SETUP + r"""
from jetnh.numeric import interrupt, loops, methods
from jetnh.numeric.methods.loop import Control, watch_of
short = sc.replace(t_span=(0.0, 1e-6))
kern = short.kernels
y0 = short.y0.copy()
ctl = Control(1e-9, np.full(len(y0), 1e-12), 0.0, np.inf, 10**7, 0)
watch = watch_of(kern, None, True, 1e-10)


def bare(t1, ctl):      # the compiled dop853 loop called directly on (0, t1)
    got = loops.entry(short, methods.method("dop853"), kern, None, None, ctl, np.zeros(0),
                      2, watch, None)           # newer trees: and the callbacks, kept
    entry, prefix, suffix = got[:3]
    args = (*prefix, 0.0, t1, y0, short.p, *suffix, interrupt.flag())
    return lambda i, keep=got: entry(*args)


h3 = float(np.nextafter(1e-3, np.inf))      # three steps of 1e-3 exactly
three = bare(3e-3, Control(1e-3, np.full(len(y0), 1e-3), h3, h3, 10**7, 0))
long = bare(100.0, ctl)
nfev = {"3-step call": int(three(0)[4][2]), "long call": int(long(0)[4][2])}
states = {n: short.initial[n] for n in short.state_names}
inis = [dict(states, phi_t=states["phi_t"] + 1e-3 * k) for k in range(16)]
y0s = [np.array([ini[n] for n in short.state_names]) for ini in inis]     # (the same states)
y8 = np.repeat(y0[None, :], 8, axis=0)
tuned = Scene(short.system, "chetaev", initial=states, t_span=short.t_span,
              runtime_params=["R"]).compile()
prms = [dict(tuned.params, R=tuned.params["R"] * (1.0 + 1e-3 * k)) for k in range(16)]
te5 = np.linspace(0.0, 1e-6, 5)
calls = {
    "bare call": bare(1e-6, ctl),
    "3-step call": three,
    "run()": lambda i: short.run(save="final"),
    # the keywords every benchmark and parameter loop gives (the bare call's tolerances)
    "run(method=, rtol=, atol=, save=)": lambda i: short.run(
        method="dop853", rtol=1e-9, atol=1e-12, save="final"),
    "run(work-precision keywords)": lambda i: short.run(
        method="dop853", save="final", rtol=1e-9, atol=1e-12, split="fixed",
        singular="ignore", t_span=(0, 1e-6)),
    "run(y0=...)": lambda i: short.run(y0=y0, save="final"),
    # replace(initial=...)'s new states as arrays: what a shooting loop's run(y0=) gets
    "run(y0=...), a new state each call": lambda i: short.run(y0=y0s[i % 16], save="final"),
    "run(t_eval=...)": lambda i: short.run(t_eval=te5),
    # a loop over final times (each call a span of its own)
    "run(t_span=...), a new span each call": lambda i: short.run(
        t_span=(0.0, 1e-6 * (1.0 + i * 1e-4)), save="final"),
    "replace(initial=...).run()": lambda i: short.replace(initial=inis[i % 16]).run(
        save="final"),
    # a loop over a run-time parameter: a copy of the scene, and run(params=) beside it
    "replace(params=...).run()": lambda i: tuned.replace(params=prms[i % 16]).run(
        save="final"),
    "run(params=...)": lambda i: tuned.run(params={"R": prms[i % 16]["R"]}, save="final"),
    "ensemble of one": lambda i: short.ensemble(y0[None, :], save="final"),
    # eight runs: the fixed cost of a small ensemble, on two threads and serially
    "ensemble of 8 (threads)": lambda i: short.ensemble(y8, save="final", workers=2),
    "ensemble of 8 (serial)": lambda i: short.ensemble(y8, save="final", parallel="serial"),
}
nfev["bare call"] = int(calls["bare call"](0)[4][2])
for f in calls.values():
    f(0)
try:        # the bare call of run(t_eval=...)'s own loop (its dense output at the times)
    timed_plan = next(v for k, v in short._memo["quick"].items()
                      if v.te is not None and len(v.te) == 5 and v.direct)
    calls["bare call of run(t_eval=...)'s loop"] = lambda i, pl=timed_plan: pl.entry(
        *pl.head, y0, short.p, *pl.suffix, interrupt.flag())
except (AttributeError, KeyError, StopIteration):
    pass
try:        # the parts of a run's Python side, each timed alone (the names of this tree)
    import _signal
    from jetnh.numeric import solve
    plan = next(v for v in short._memo["plans"].values() if v.save == "final"
                and v.method.name == "dop853" and v.checked and v.t1 == 1e-6
                and v.rtol == 1e-9 and v.entry is not None)
    own, p, y = interrupt._WATCHDOG.own, short._p, short.y0.copy()
    out = plan.entry(*plan.prefix, plan.t0, plan.t1, y, p, *plan.suffix, interrupt.flag())
    noop = lambda: None
    from jetnh.numeric.trajectory import Trajectory

    confirm = _signal.set_wakeup_fd
    confirm = getattr(confirm, "__wrapped__", confirm)      # (CPython's own)

    def floor(i):       # what no run could skip: a halt flag, the wakeup fd confirmed (its
        halt = np.zeros(1, np.int64)        # set_wakeup_fd), the call, a Trajectory
        confirm(own, warn_on_full_buffer=False)
        got = plan.entry(*plan.prefix, plan.t0, plan.t1, y, p, *plan.suffix, halt)
        return Trajectory._finished(short, (got[1], got[2], got[3]), p, "dop853", "",
                                    (got[4], 0.0, {}), plan.kern, None)

    # this tree's floor: the wakeup fd confirmed only where a run confirms it (trees that
    # know it is still the watchdog's do not), and the Trajectory its runs make
    known = hasattr(interrupt, "_KNOWN")
    lean = getattr(Trajectory, "_of_loop", None)

    def tree_floor(i):
        halt = np.zeros(1, np.int64)
        if not known:
            confirm(own, warn_on_full_buffer=False)
        got = plan.entry(*plan.prefix, plan.t0, plan.t1, y, p, *plan.suffix, halt)
        if lean is not None:
            return lean(short, got, p, "dop853", "", 0.0, plan.kern, None)
        return Trajectory._finished(short, (got[1], got[2], got[3]), p, "dop853", "",
                                    (got[4], 0.0, {}), plan.kern, None)
    calls.update({
        "part: the floor (halt flag, set_wakeup_fd, call, Trajectory)": floor,
        "part: this tree's floor (halt flag, set_wakeup_fd where a run confirms the "
        "wakeup fd, call, its runs' Trajectory)": tree_floor,
        "part: set_wakeup_fd": lambda i: confirm(own, warn_on_full_buffer=False),
        "part: halt flag": lambda i: np.zeros(1, np.int64),
        "part: interrupt.call of nothing": lambda i: interrupt.call(noop, interrupt.flag()),
        "part: Trajectory": lambda i: solve.trajectory(short, "dop853", out, 0.0, plan.kern,
                                                       None, p, 0.0, y, 1e-10, True),
        "part: solve.run": lambda i: solve.run(short, plan, short.y0.copy(), p, True),
        "part: the timing itself": lambda i: None,
    })
except (AttributeError, KeyError, ImportError, TypeError, StopIteration):
    pass
times = {k: [] for k in calls}
times["long call"] = []
order = np.random.default_rng(0)
for i in range(REPS_FIXED):
    for k in order.permutation(list(calls)):    # no call always after the same one
        f = calls[k]
        tic = time.perf_counter(); f(i); times[k].append(time.perf_counter() - tic)
    if i % 20 == 0:
        tic = time.perf_counter(); long(i); times["long call"].append(time.perf_counter() - tic)
out = {k: float(np.percentile(v, 5)) for k, v in times.items()}
# the arithmetic of a call: its evaluations at the cost of one in a long run (the long
# and the one-step call's difference over their difference in evaluations)
per = (out["long call"] - out["bare call"]) / (nfev["long call"] - nfev["bare call"])
out["3-step arithmetic"] = nfev["3-step call"] * per
print(json.dumps(out))
"""


COLD = r"""
import json, resource, time
import numpy as np
import jetnh.models as models
from jetnh.numeric import Scene, interrupt
sc = Scene(models.get("isokinetic_particle"), "chetaev",
           initial=models.initial("isokinetic_particle"), t_span=(0.0, 2.0)).compile()
kw = dict(method="dop853", save="final", rtol=1e-8, atol=1e-11)
run = lambda: sc.run(**kw)
other = lambda: sc.run(method="scipy-RK45", save="final", rtol=1e-8, atol=1e-11)
run(); other()
plan = [v for v in sc._memo["plans"].values() if v.rtol == 1e-8 and v.entry is not None][0]
p = sc._p


def bare():
    halt = interrupt.flag()
    return plan.entry(*plan.prefix, plan.t0, plan.t1, sc.y0.copy(), p, *plan.suffix, halt)


def timed(f):
    tic = time.perf_counter(); f(); return time.perf_counter() - tic


def python():       # a control: Python work that is none of a run's
    return sum(range(300))


def busy(seconds):  # a pause that keeps the process on the CPU (unless preempted)
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


out, faults = {}, 0
for name, f in (("run", run), ("bare call", bare), ("Python control", python)):
    out[name + ", hot"] = float(np.percentile([timed(f) for _ in range(REPS_HOT)], 5))
    after = []
    for _ in range(REPS_OTHER):
        other(); after.append(timed(f))
    out[name + ", after a scipy run"] = float(np.median(after))
    paused, busied = [], []
    for _ in range(REPS_PAUSE):
        time.sleep(1.2)
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        paused.append(timed(f))
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        faults += r1.ru_minflt + r1.ru_majflt - r0.ru_minflt - r0.ru_majflt
        busy(1.2); busied.append(timed(f))
    out[name + ", after a pause"] = float(np.median(paused))
    out[name + ", after a busy pause"] = float(np.median(busied))
# what the pause is not: the wakeup fd confirmed again (after CONFIRM seconds)
if hasattr(interrupt, "CONFIRM"):
    interrupt.CONFIRM = float("inf")
    paused = []
    for _ in range(REPS_PAUSE):
        time.sleep(1.2); paused.append(timed(run))
    out["run, after a pause, the wakeup fd not confirmed again"] = float(np.median(paused))
out["page faults during the calls after a pause (count)"] = faults
print(json.dumps(out))
"""


def fresh(root, code, cold=True):
    """``code`` in a fresh process on the tree ``root`` (``cold``: with empty caches):
    its JSON line."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PYTHONPATH=str(root))
        if cold:
            env.update(JETNH_CACHE=os.path.join(tmp, "jc"),
                       NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
        res = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp,
                             capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def commit(root) -> str:
    r = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                       capture_output=True, text=True)
    return r.stdout.strip() or "?"


FLOOR = ("part: this tree's floor (halt flag, set_wakeup_fd where a run confirms the "
         "wakeup fd, call, its runs' Trajectory)")


TEVAL = "bare call of run(t_eval=...)'s loop"
NEW_Y0 = "run(y0=...), a new state each call"


def fixed(root, reps) -> dict:
    """The fixed costs against the bare call (section 4) of one tree."""
    return fresh(root, FIXED.replace("REPS_FIXED", str(reps)), cold=False)


def interleaved(root, quick) -> dict:
    """A single run among other work (section 5) on one tree."""
    reps = (50, 5, 3) if quick else (1000, 60, 8)
    code = COLD
    for name, n in zip(("REPS_HOT", "REPS_OTHER", "REPS_PAUSE"), reps):
        code = code.replace(name, str(n))
    return fresh(root, code, cold=False)


def measure(root, reps_short, reps_long) -> dict:
    """Every figure of one tree in one round."""
    out = {}
    for m in METHODS:
        alone = fresh(root, FIRST.replace("METHODS", repr((m,))))
        out[f"first_{m}_alone"] = alone[m]
        out[f"first_{m}_alone_cpu"] = alone[m + "_cpu"]
    three = fresh(root, FIRST.replace("METHODS", repr(METHODS)))
    out["first_three"] = sum(three[m] for m in METHODS)
    out["first_three_cpu"] = sum(three[m + "_cpu"] for m in METHODS)
    out.update(fresh(root, COST.replace("REPS_SHORT", str(reps_short))
                     .replace("REPS_LONG", str(reps_long))))
    return out


ROWS = ([(f"first_{m}_alone{c}", f"first run of {m} alone ({w})") for m in METHODS
         for c, w in (("", "s"), ("_cpu", "CPU s"))]
        + [(f"first_three{c}", f"first runs of the three in one process ({w})")
           for c, w in (("", "s"), ("_cpu", "CPU s"))]
        + [(f"fixed_s_{m}", f"fixed cost of a {m} run (us)") for m in METHODS]
        + [("call_s_dop853", "the compiled dop853 loop called directly (us)")]
        + [(f"per_eval_s_{m}", f"{m}: cost per rhs evaluation (ns)") for m in METHODS])


def main(argv=None):
    ap = parser(__doc__, "overhead")
    ap.add_argument("--tree", action="append", default=[], metavar="NAME=PATH",
                    help="an earlier tree to measure too (a git worktree)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--fixed", action="store_true",
                    help="only the fixed costs against the bare call (section 4)")
    args = ap.parse_args(argv)
    trees = dict(t.split("=", 1) for t in args.tree)
    trees["after"] = str(ROOT)
    reps_short, reps_long = (50, 2) if args.quick else (2000, 5)
    rounds = 1 if args.quick else args.rounds
    reps_fixed = 200 if args.quick else 3000
    cost = {name: fixed(root, reps_fixed) for name, root in trees.items()}
    for name, c in cost.items():
        print(f"{name}: " + ", ".join(f"{k} {v * 1e6:.1f} us ({v / c['bare call']:.2f}x)"
                                      for k, v in c.items()), flush=True)
    fixed_table = dict(
        title="Fixed cost of a one-step dop853 run against the bare call of its compiled "
              "loop (rolling disk; one process per tree, calls interleaved, 5th "
              "percentile of single calls)",
        columns=["", *(f"{n} (us)" for n in trees), *(f"{n} / bare call" for n in trees)],
        rows=[[k, *(f"{cost[n][k] * 1e6:.3g}" if k in cost[n] else "-" for n in trees),
               *(f"{cost[n][k] / cost[n]['bare call']:.2f}" if k in cost[n] else "-"
                 for n in trees)]
              for k in cost["after"]],
        note="trees (commits): " + ", ".join(f"{n} = {commit(p)}" for n, p in trees.items()))
    a = cost["after"]
    fixed_summary = (
        f"the bare call of a 3-step dop853 run costs {a['3-step call'] * 1e6:.3g} us, "
        f"{(a['3-step call'] - a['3-step arithmetic']) * 1e6:.2f} us more than its "
        f"arithmetic ({a['3-step arithmetic'] * 1e6:.2f} us); "
        f"a one-step dop853 run costs {a['run()'] / a['bare call']:.2f}x the bare call of its "
        f"compiled loop ({a['run()'] * 1e6:.3g} us against {a['bare call'] * 1e6:.3g} us); "
        f"with keywords {a['run(method=, rtol=, atol=, save=)'] / a['bare call']:.2f}x "
        f"(the work-precision benchmark's "
        f"{a['run(work-precision keywords)'] / a['bare call']:.2f}x), "
        f"run(y0=...) {a['run(y0=...)'] / a['bare call']:.2f}x, "
        f"run(t_eval=...) {a['run(t_eval=...)'] / a['bare call']:.2f}x"
        + (f" ({a['run(t_eval=...)'] / a[TEVAL]:.2f}x the bare call of its own loop)"
           if TEVAL in a else "")
        + f", on a new time span "
        f"each call {a['run(t_span=...), a new span each call'] / a['bare call']:.2f}x, "
        f"replace(initial=...).run() {a['replace(initial=...).run()'] / a['bare call']:.2f}x "
        f"({a['replace(initial=...).run()'] / a[NEW_Y0]:.2f}x run(y0=...) on a new state each "
        f"call, which costs {a[NEW_Y0] / a['bare call']:.2f}x),"
        + (f" replace(params=...).run() {a['replace(params=...).run()'] / a['run(params=...)']:.2f}x"
           f" run(params=...)," if "run(params=...)" in a else "") +
        f" an ensemble of one {a['ensemble of one'] / a['bare call']:.2f}x"
        + (f"; the floor of a run on this tree {a[FLOOR] / a['bare call']:.2f}x" if FLOOR in a
           else "")
        + f"; an ensemble of 8"
        f" {a['ensemble of 8 (threads)'] * 1e6:.3g} us on two threads, "
        f"{a['ensemble of 8 (serial)'] * 1e6:.3g} us serially")
    print(fixed_summary)
    among = {name: interleaved(root, args.quick) for name, root in trees.items()}
    def shown(k, v):        # (microseconds, or a count)
        return f"{v:.0f}" if k.endswith("(count)") else f"{v * 1e6:.3g}"
    for name, c in among.items():
        print(f"{name}: " + ", ".join(f"{k} {shown(k, v)}" for k, v in c.items()), flush=True)
    cold_table = dict(
        title="A dop853 run of isokinetic_particle (rtol 1e-8) among other work: hot, right "
              "after a scipy run, after a pause of 1.2 s asleep or busy (one process per "
              "tree; a Python control)",
        columns=["", *(f"{n} (us)" for n in trees)],
        rows=[[k, *(shown(k, among[n][k]) if k in among[n] else "-" for n in trees)]
              for k in among["after"]],
        note="trees (commits): " + ", ".join(f"{n} = {commit(p)}" for n, p in trees.items()))
    c = among["after"]
    cold_summary = (
        f"a single dop853 run of isokinetic_particle at rtol 1e-8 costs "
        f"{c['run, hot'] * 1e6:.3g} us hot, {c['run, after a scipy run'] * 1e6:.3g} us right "
        f"after a scipy run and {c['run, after a pause'] * 1e6:.3g} us after a pause of 1.2 s "
        f"(its bare compiled call {c['bare call, hot'] * 1e6:.3g}, "
        f"{c['bare call, after a scipy run'] * 1e6:.3g} and "
        f"{c['bare call, after a pause'] * 1e6:.3g} us)")
    print(cold_summary)
    if args.fixed:
        out = args.out if args.out != RESULTS / "overhead.json" else None
        write("overhead_fixed", dict(title="Overhead of a run: the fixed cost against the bare "
                                     "call", summary=[fixed_summary, cold_summary],
                                     tables=[fixed_table, cold_table], fixed=cost,
                                     interleaved=among,
                                     trees={n: commit(p) for n, p in trees.items()}),
              out, args.quick)
        return
    runs = {name: [] for name in trees}
    for r in range(rounds):
        for name, root in trees.items():
            runs[name].append(measure(root, reps_short, reps_long))
            print(f"round {r + 1}, {name}: {json.dumps(runs[name][-1])}", flush=True)
    best = {name: {k: min(x[k] for x in rs) for k in rs[0]} for name, rs in runs.items()}
    names = list(trees)

    def scale(key):
        return 1.0 if key.startswith("first") else 1e9 if "per_eval" in key else 1e6
    rows = []
    for key, label in ROWS:
        vals = [best[n].get(key) for n in names]
        after = best["after"].get(key)
        rows.append([label] + [("-" if v is None else f"{v * scale(key):.4g}") for v in vals]
                    + [("-" if v is None or after is None else f"{after / v:.2f}")
                       for v in vals[:-1]])
    a = best["after"]
    summary = []
    for name in names[:-1]:
        b = best[name]
        summary.append(
            f"after / {name}: first runs (loops compiled from nothing; CPU seconds) "
            + ", ".join(f"{m} {a[f'first_{m}_alone_cpu']:.1f} s vs "
                        f"{b[f'first_{m}_alone_cpu']:.1f} s" for m in METHODS)
            + f"; the three in one process {a['first_three_cpu']:.1f} s vs "
              f"{b['first_three_cpu']:.1f} s; fixed cost "
            + ", ".join(f"{m} {a[f'fixed_s_{m}'] / b[f'fixed_s_{m}']:.2f}" for m in METHODS)
            + "; per evaluation "
            + ", ".join(f"{m} {a[f'per_eval_s_{m}'] / b[f'per_eval_s_{m}']:.2f}"
                        for m in METHODS))
    if "call_s_dop853" in a:
        summary.append(f"a dop853 run to T = 1e-6 costs {a['fixed_s_dop853'] * 1e6:.1f} us, "
                       f"of which the compiled loop {a['call_s_dop853'] * 1e6:.1f} us")
    for s in summary:
        print(s)
    summary += [fixed_summary, cold_summary]
    tables = [fixed_table, cold_table,
              dict(title="First run, fixed cost, cost per evaluation (rolling disk; fresh "
                         "processes, empty caches; best of the rounds)",
                   columns=[""] + names + [f"after / {n}" for n in names[:-1]], rows=rows,
                   note="trees (commits): " + ", ".join(f"{n} = {commit(p)}"
                                                        for n, p in trees.items()))]
    write("overhead", dict(title="Overhead of a run: first run, fixed cost, cost per "
                                 "evaluation", summary=summary, tables=tables, runs=runs,
                           fixed=cost, interleaved=among, trees={n: commit(p) for n, p in trees.items()}),
          args.out, args.quick)


if __name__ == "__main__":
    main()
