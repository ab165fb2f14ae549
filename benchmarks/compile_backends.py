"""Compiling one huge kernel: LLVM optimisation levels, split into functions, or the
system C compiler -- compile CPU seconds against the cost of a call.

    .venv/bin/python benchmarks/compile_backends.py [--quick] [--ns 8,16,32]
        [--principle vakonomic] [--modes 3/3,1/0,0/0,split300,gcc-O0,gcc-O1]
        [--gcc-timeout 120] [--out PATH]

(default output: benchmarks/results/compile_backends.json)

The kernel is the rhs of the N-trailer (``models.get("n_trailer", N=N)``, default
parameters) as jetnh generates it: a straight-line program (``codegen.llvm.program``).
Each mode compiles the program, in this process, into a C function
``void kern(double t, double *y, double *p, double *out)``:

- ``I/C``: LLVM IR emitted as ``codegen.llvm.straight_line`` emits it, the ``-O<I>``
  pass pipeline, then code generation at ``-O<C>`` (MCJIT); ``3/3`` is what numba does for
  every function, ``1/0`` the quick route (``codegen.quick``);
- ``splitK``: the program cut into functions of K instructions (never inlined), the
  values that cross a cut passed through a scratch array; ``-O3``/``-O3``;
- ``gcc-O<k>``: the program printed as C (one ``const double`` per instruction) and
  compiled by ``gcc -O<k> -shared -fno-math-errno -ffp-contract=off`` (CPU seconds of the
  child), given up after ``--gcc-timeout`` seconds.

Recorded: CPU seconds of each phase (parse, IR passes, code generation; for LLVM at
-O3 also the greedy register allocator's share, from LLVM's pass timers), the cost of a
call (best of rounds of ctypes calls, minus nothing: ctypes adds ~1 us), and whether
the outputs equal those of ``3/3`` bit for bit.
"""

from __future__ import annotations

import ctypes
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import parser, write  # noqa: E402

_UNARY = {"sin": "llvm.sin.f64", "cos": "llvm.cos.f64", "exp": "llvm.exp.f64",
          "log": "llvm.log.f64", "abs": "llvm.fabs.f64", "sqrt": "llvm.sqrt.f64"}


def rhs_program(N: int, principle: str) -> tuple:
    from jetnh import models
    from jetnh.numeric.codegen import kernel_expressions
    from jetnh.numeric.codegen.continuous import _used_phi
    from jetnh.numeric.codegen.llvm import program
    from jetnh.numeric.codegen.text import Emitter

    system = models.get("n_trailer", N=N)
    params = {getattr(k, "name", k): float(v) for k, v in system.defaults.items()}
    phi, rhs = kernel_expressions(system, principle, params)
    pre = _used_phi(phi, rhs)
    em = Emitter([e for _, e in pre] + list(rhs))
    return program(em, pre, list(enumerate(rhs)))


def _operands(op) -> tuple:
    kind = op[0]
    if kind in ("add", "mul"):
        return op[1:]
    if kind in ("div", "pow"):
        return op[1:3]
    if kind == "powi":
        return (op[1],)
    if kind == "fn":
        return op[2:]
    if kind == "out":
        return (op[2],)
    return ()


def _emit(ir, b, mod, ops, lo, hi, t, ptr, value, keep):
    """Instructions lo..hi-1 of ``ops`` into builder ``b`` (as ``straight_line``)."""
    dbl, i64 = ir.DoubleType(), ir.IntType(64)

    def fn(name, n=1):
        name = _UNARY.get(name, name)
        f = mod.globals.get(name)
        return f or ir.Function(mod, ir.FunctionType(dbl, [dbl] * n), name)

    def prod(xs):
        acc = xs[0]
        for x in xs[1:]:
            acc = b.fmul(acc, x)
        return acc

    for i in range(lo, hi):
        op, kind = ops[i], ops[i][0]
        if kind in ("y", "p"):
            v = b.load(b.gep(ptr[kind], [ir.Constant(i64, op[1])]))
        elif kind == "t":
            v = t
        elif kind == "c":
            v = ir.Constant(dbl, op[1])
        elif kind == "add":
            v = value(op[1])
            for a in op[2:]:
                v = b.fadd(v, value(a))
        elif kind == "mul":
            v = prod([value(a) for a in op[1:]])
        elif kind == "div":
            v = b.fdiv(value(op[1]), value(op[2]))
        elif kind == "powi":
            v = (prod([value(op[1])] * op[2]) if op[2] <= 4 else
                 b.call(fn("llvm.pow.f64", 2), [value(op[1]), ir.Constant(dbl, float(op[2]))]))
        elif kind == "pow":
            v = b.call(fn("llvm.pow.f64", 2), [value(op[1]), value(op[2])])
        elif kind == "fn":
            v = b.call(fn(op[1], len(op) - 2), [value(a) for a in op[2:]])
        else:
            b.store(value(op[2]), b.gep(ptr["o"], [ir.Constant(i64, op[1])]))
            continue
        keep(i, v)


def llvm_module(ops, split: int = 0):
    """The program as an LLVM module with ``kern``; ``split``: cut into functions."""
    from llvmlite import binding as llvm
    from llvmlite import ir

    dbl, i64 = ir.DoubleType(), ir.IntType(64)
    dptr = dbl.as_pointer()
    mod = ir.Module("k")
    mod.triple = llvm.get_process_triple()
    kern = ir.Function(mod, ir.FunctionType(ir.VoidType(), [dbl, dptr, dptr, dptr]), "kern")
    if not split:
        b = ir.IRBuilder(kern.append_basic_block())
        t, y, p, o = kern.args
        vals = {}
        _emit(ir, b, mod, ops, 0, len(ops), t, {"y": y, "p": p, "o": o}, vals.__getitem__,
              vals.__setitem__)
        b.ret_void()
        return mod
    chunk = [i // split for i in range(len(ops))]
    crossing = sorted({a for i, op in enumerate(ops) for a in _operands(op)
                       if chunk[a] != chunk[i] and ops[a][0] != "c"})
    slot = {j: k for k, j in enumerate(crossing)}
    cty = ir.FunctionType(ir.VoidType(), [dbl, dptr, dptr, dptr, dptr])
    parts = []
    for c in range(chunk[-1] + 1):
        f = ir.Function(mod, cty, f"part{c}")
        f.attributes.add("noinline")
        f.linkage = "internal"
        b = ir.IRBuilder(f.append_basic_block())
        t, y, p, o, w = f.args
        vals = {}

        def value(j, vals=vals, b=b, w=w):
            if j not in vals:
                vals[j] = (ir.Constant(dbl, ops[j][1]) if ops[j][0] == "c" else
                           b.load(b.gep(w, [ir.Constant(i64, slot[j])])))
            return vals[j]

        def keep(i, v, vals=vals, b=b, w=w):
            vals[i] = v
            if i in slot:
                b.store(v, b.gep(w, [ir.Constant(i64, slot[i])]))

        _emit(ir, b, mod, ops, c * split, min(len(ops), (c + 1) * split), t,
              {"y": y, "p": p, "o": o}, value, keep)
        b.ret_void()
        parts.append(f)
    b = ir.IRBuilder(kern.append_basic_block())
    w = b.alloca(dbl, ir.Constant(i64, max(1, len(slot))))
    for f in parts:
        b.call(f, [*kern.args, w])
    b.ret_void()
    return mod


def compile_llvm(mod, ir_opt: int, cg_opt: int):
    """CPU seconds of each phase, the register allocator's share, the address, the
    engine (keep it alive)."""
    from llvmlite import binding as llvm

    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    phases = {}
    tic = time.process_time()
    m = llvm.parse_assembly(str(mod))
    phases["parse"] = time.process_time() - tic
    tm = llvm.Target.from_triple(llvm.get_process_triple()).create_target_machine(
        cpu=llvm.get_host_cpu_name(), features=llvm.get_host_cpu_features().flatten(),
        opt=cg_opt, jit=True)
    llvm.set_time_passes(True)
    tic = time.process_time()
    if ir_opt:
        pb = llvm.create_pass_builder(tm, llvm.create_pipeline_tuning_options(speed_level=ir_opt))
        pb.getModulePassManager().run(m, pb)
    phases["ir_passes"] = time.process_time() - tic
    tic = time.process_time()
    engine = llvm.create_mcjit_compiler(m, tm)
    engine.finalize_object()
    phases["codegen"] = time.process_time() - tic
    report = llvm.report_and_reset_timings()
    llvm.set_time_passes(False)
    ra = re.search(r"^\s*([\d.]+)\s+\(\s*([\d.]+)%\)\s.*Greedy Register Allocator", report, re.M)
    phases["regalloc_share_of_timed"] = float(ra.group(2)) / 100 if ra else 0.0
    return phases, engine.get_function_address("kern"), engine


def c_source(ops) -> str:
    names = {"sin": "sin", "cos": "cos", "exp": "exp", "log": "log", "abs": "fabs",
             "sqrt": "sqrt"}
    lines = ["#include <math.h>",
             "void kern(double t, const double *y, const double *p, double *out) {"]
    for i, op in enumerate(ops):
        kind = op[0]
        if kind in ("y", "p"):
            e = f"{kind}[{op[1]}]"
        elif kind == "t":
            e = "t"
        elif kind == "c":
            e = repr(float(op[1]))
        elif kind in ("add", "mul"):
            e = (" + " if kind == "add" else " * ").join(f"v{a}" for a in op[1:])
        elif kind == "div":
            e = f"v{op[1]} / v{op[2]}"
        elif kind == "powi":
            e = (" * ".join([f"v{op[1]}"] * op[2]) if op[2] <= 4 else
                 f"pow(v{op[1]}, {float(op[2])!r})")
        elif kind == "pow":
            e = f"pow(v{op[1]}, v{op[2]})"
        elif kind == "fn":
            e = f"{names[op[1]]}(" + ", ".join(f"v{a}" for a in op[2:]) + ")"
        else:
            lines.append(f"  out[{op[1]}] = v{op[2]};")
            continue
        lines.append(f"  const double v{i} = {e};")
    return "\n".join(lines + ["}"]) + "\n"


def compile_gcc(ops, level: str, tmp: str, timeout: float):
    src, so = os.path.join(tmp, "k.c"), os.path.join(tmp, f"k{level}.so")
    with open(src, "w") as fh:
        fh.write(c_source(ops))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        subprocess.run(["gcc", "-shared", "-fPIC", f"-O{level}", "-fno-math-errno",
                        "-ffp-contract=off", src, "-o", so, "-lm"], check=True,
                       timeout=timeout, capture_output=True)
    except subprocess.TimeoutExpired:
        return {"timeout": timeout}, None, None
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    lib = ctypes.CDLL(so)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return {"codegen": cpu}, ctypes.cast(lib.kern, ctypes.c_void_p).value, lib


def call_cost(address, n_state, n_out, reps) -> tuple[float, object]:
    import numpy as np

    f = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
                         ctypes.c_void_p)(address)
    y = np.random.default_rng(0).uniform(-0.5, 0.5, n_state)
    p, out = np.zeros(1), np.zeros(n_out)
    best = float("inf")
    for _ in range(5):
        tic = time.perf_counter()
        for _ in range(reps):
            f(0.25, y.ctypes.data, p.ctypes.data, out.ctypes.data)
        best = min(best, (time.perf_counter() - tic) / reps)
    return best, out.copy()


def measure(N: int, principle: str, modes, gcc_timeout: float) -> list:
    tic = time.process_time()
    ops = rhs_program(N, principle)
    derive = time.process_time() - tic
    n_state = max(o[1] for o in ops if o[0] == "y") + 1
    n_out = max(o[1] for o in ops if o[0] == "out") + 1
    reps = max(20, int(1e6 / len(ops)))
    rows, ref = [], None
    with tempfile.TemporaryDirectory(prefix="jetnh-backends-") as tmp:
        for mode in modes:
            keep = None
            if mode.startswith("gcc-O"):
                phases, address, keep = compile_gcc(ops, mode[5:], tmp, gcc_timeout)
            else:
                split = int(mode[5:]) if mode.startswith("split") else 0
                ir_opt, cg_opt = (3, 3) if split else map(int, mode.split("/"))
                phases, address, keep = compile_llvm(llvm_module(ops, split), ir_opt, cg_opt)
            row = {"N": N, "principle": principle, "ops": len(ops), "mode": mode,
                   "derive_cpu": derive, "load": round(os.getloadavg()[0], 1), **phases}
            if address:
                cost, out = call_cost(address, n_state, n_out, reps)
                ref = out if ref is None else ref
                row.update(compile_cpu=sum(v for k, v in phases.items() if k != "regalloc_"
                                           "share_of_timed"),
                           call_us=1e6 * cost, bitwise_equal_to_first=bool((out == ref).all()))
            rows.append(row)
            print(json.dumps(row), flush=True)
            del keep
    return rows


def main(argv=None) -> int:
    ap = parser(__doc__, "compile_backends")
    ap.add_argument("--ns", default="8,16,32")
    ap.add_argument("--principle", default="vakonomic")
    ap.add_argument("--modes", default="3/3,1/0,0/0,split300,gcc-O0,gcc-O1")
    ap.add_argument("--gcc-timeout", type=float, default=120.0)
    args = ap.parse_args(argv)
    ns = [4] if args.quick else [int(n) for n in args.ns.split(",")]
    rows = []
    for N in ns:
        rows += measure(N, args.principle, args.modes.split(","), args.gcc_timeout)
    full = {r["N"]: r for r in rows if r["mode"] == "3/3" and "compile_cpu" in r}
    summary = []
    for r in rows:
        base = full.get(r["N"])
        if base and r is not base and "compile_cpu" in r:
            summary.append(
                f"N = {r['N']} ({r['ops']} instructions), {r['mode']}: compile "
                f"{r['compile_cpu']:.2f} CPU s against {base['compile_cpu']:.2f} at 3/3 "
                f"({base['compile_cpu'] / r['compile_cpu']:.1f}x less), a call "
                f"{r['call_us'] / base['call_us']:.2f}x as long")
        elif base is r:
            summary.append(f"N = {r['N']} ({r['ops']} instructions), 3/3: compile "
                           f"{r['compile_cpu']:.2f} CPU s (greedy register allocation "
                           f"{100 * r['regalloc_share_of_timed']:.0f} % of LLVM's timed "
                           f"passes), a call {r['call_us']:.1f} us")
        elif "timeout" in r:
            summary.append(f"N = {r['N']}, {r['mode']}: more than {r['timeout']:.0f} s")
    write("compile_backends", {
        "title": "Compiling one huge kernel (the N-trailer's rhs): LLVM levels, split "
                 "functions, gcc",
        "summary": summary,
        "columns": ["N", "ops", "mode", "load", "parse", "ir_passes", "codegen",
                    "compile_cpu", "regalloc_share_of_timed", "call_us",
                    "bitwise_equal_to_first", "timeout"],
        "rows": rows}, args.out, args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
