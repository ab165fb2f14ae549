"""The bare call of radau's compiled loop: one step (T = 1e-6, save="final") on the rolling
disk, called at its machine-code entry with the arguments made once, for this tree's
``methods/radau.py`` and for the one of an earlier commit (``--before``), both compiled in
this process and their calls interleaved (each figure the best of its calls).

    .venv/bin/python benchmarks/radau_call.py [--before REF] [--reps N] [--quick] [--out PATH]

(default output: benchmarks/results/radau_call.json; ``REF`` a git revision, default
``HEAD~1``.)  The loop of this tree takes its five callbacks as integer addresses
(``_common.function_at``, ``radau.jacobian_at``); the earlier one, if it takes them as
first-class functions, gets their ``FunctionAddress`` objects, which numba unboxes on every
call.  The two runs' results are checked equal to the bit.  The earlier loop is compiled
into the signed store under its own name (``radau_before._solve_*``).
"""

import importlib.util
import os
import subprocess
import sys
import tempfile

import numpy as np

from _common import ROOT, best_of, parser, write


def before_module(ref: str):
    """``jetnh.numeric.methods.radau`` as it was at ``ref``, as the module
    ``jetnh.numeric.methods.radau_before``."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{ref}:jetnh/numeric/methods/"
                             "radau.py"], check=True, capture_output=True).stdout
    path = os.path.join(tempfile.mkdtemp(prefix="radau_before."), "radau_before.py")
    with open(path, "wb") as f:
        f.write(source)
    name = "jetnh.numeric.methods.radau_before"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def main():
    ap = parser(__doc__, "radau_call")
    ap.add_argument("--before", default="HEAD~1")
    ap.add_argument("--reps", type=int, default=3000)
    args = ap.parse_args()
    reps = 300 if args.quick else args.reps

    import jetnh.models as models
    from jetnh.numeric import Scene, interrupt, solve
    from jetnh.numeric.methods import _common, radau
    from jetnh.numeric.methods.loop import features

    sc = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
               t_span=(0.0, 10.0)).compile()
    plan = solve.plan(sc, "radau", t_span=(0.0, 1e-6), save="final")
    parts = features(*(plan.suffix[i] for i in (0, 3, 4)))     # ctl, mode, watch
    kern = sc.kernels
    objects = (kern.rhs_fp, sc.jacobian.address, kern.sing_fp, kern.sing_fp,
               kern.hol_or_none)
    old = before_module(args.before)
    old_takes_addresses = old.ARGS[0] == _common.i8
    calls = {}
    for name, module in (("before", old), ("after", radau)):
        entry = _common.entry_point(module.solver(parts))
        prefix = tuple(o.address for o in objects) if (
            module is radau or old_takes_addresses) else objects
        call_args = (*prefix, 0.0, 1e-6, sc.y0.copy(), sc.p, *plan.suffix, interrupt.flag())
        calls[name] = (lambda e=entry, a=call_args: e(*a))
    (t_before, r_before), (t_after, r_after) = best_of([calls["before"], calls["after"]],
                                                       reps)
    assert all(np.array_equal(np.asarray(a), np.asarray(b))
               for a, b in zip(r_before, r_after)), "the two loops' results differ"
    load = os.getloadavg()
    data = {"before": args.before, "reps": reps, "load": list(load),
            "call_s_before": t_before, "call_s_after": t_after,
            "ratio_before_over_after": t_before / t_after}
    print(f"one-step radau bare call: before ({args.before}) {t_before * 1e6:.2f} us, "
          f"after {t_after * 1e6:.2f} us, ratio {t_before / t_after:.2f} "
          f"(load {load[0]:.2f})")
    write("radau_call", data, args.out, args.quick)


if __name__ == "__main__":
    main()
