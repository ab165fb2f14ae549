"""Straight-line programs: a shared graph as a flat list of instructions, emitted as LLVM
instructions by one numba intrinsic (``straight_line``), and their forward-mode
derivatives (the Jacobian, the variational equations of sensitivities).

Generated kernel modules import ``straight_line`` from here by path: moving it changes
the format of those modules (``layout.CODEGEN_VERSION``).
"""

from __future__ import annotations

import json

import sympy as sp

from .text import MATH, Emitter

_LLVM_UNARY = {"sin": "llvm.sin.f64", "cos": "llvm.cos.f64", "exp": "llvm.exp.f64",
               "log": "llvm.log.f64", "abs": "llvm.fabs.f64", "sqrt": "llvm.sqrt.f64"}


class Unsupported(Exception):
    """A head the straight-line program has no instruction for (printed as text instead)."""


def program(em: Emitter, phi, outputs) -> tuple:
    """The graph of ``phi`` (``[(v<a>, expr)]``) and ``outputs`` (``[(slot, expr)]``) as
    straight-line instructions ``(op, operands...)``, operands being indices of earlier
    instructions: ``("y", i)``, ``("p", i)``, ``("t",)``, ``("c", x)``, ``("add", ...)``,
    ``("mul", ...)``, ``("div", a, b)``, ``("powi", a, k)``, ``("pow", a, b)``,
    ``("fn", name, ...)``, ``("out", slot, a)``.  Each distinct node is one instruction."""
    ops, at = [], {}            # canonical index -> instruction index
    symbol = {}

    def add(op):
        ops.append(op)
        return len(ops) - 1

    def node(e):
        i = em.index[id(e)]
        if i in at:
            return at[i]
        if not e.args:
            if e.is_Symbol:
                name = e.name
                if name in symbol:
                    at[i] = symbol[name]
                elif name == "t":
                    at[i] = add(("t",))
                elif name[0] in "sp" and name[1:].isdigit():
                    at[i] = add(("y" if name[0] == "s" else "p", int(name[1:])))
                else:
                    raise Unsupported(name)
            elif e.is_Number or e.is_NumberSymbol:
                at[i] = add(("c", float(e)))
            else:
                raise Unsupported(type(e).__name__)
            return at[i]
        if e.is_Add:
            at[i] = add(("add", *[node(a) for a in e.args]))
        elif e.is_Mul:
            num, den = [], []
            for a in e.args:           # a reciprocal used elsewhere too: computed once
                if a.is_Pow and a.exp.is_Integer and a.exp < 0 and em.uses[em.of(a)] == 1:
                    k = -int(a.exp)
                    b = node(a.base)
                    den.append(b if k == 1 else add(("powi", b, k)))
                else:
                    num.append(node(a))
            top = num[0] if len(num) == 1 else add(("mul", *num)) if num else add(("c", 1.0))
            if den:
                bottom = den[0] if len(den) == 1 else add(("mul", *den))
                top = add(("div", top, bottom))
            at[i] = top
        elif e.is_Pow:
            b, x = e.args
            if x.is_Integer:
                k = int(x)
                pos = add(("powi", node(b), abs(k)))
                at[i] = pos if k > 0 else add(("div", add(("c", 1.0)), pos))
            elif x == sp.S.Half:
                at[i] = add(("fn", "sqrt", node(b)))
            elif x == -sp.S.Half:
                at[i] = add(("div", add(("c", 1.0)), add(("fn", "sqrt", node(b)))))
            else:
                at[i] = add(("pow", node(b), node(x)))
        elif isinstance(e, sp.Abs):
            at[i] = add(("fn", "abs", node(e.args[0])))
        elif isinstance(e, sp.Function) and type(e).__name__ in MATH:
            at[i] = add(("fn", type(e).__name__, *[node(a) for a in e.args]))
        else:
            raise Unsupported(type(e).__name__)
        return at[i]

    for name, e in phi:
        symbol[name] = node(e)
    for slot, e in outputs:
        add(("out", slot, node(e)))
    return tuple(ops)


def program_text(ops: tuple) -> str:
    """A straight-line program as compact JSON text (``program_of`` reads it back): a
    generated module holds its programs as string literals, which Python compiles at once,
    where a literal tuple of a huge kernel's instructions took seconds (every element a
    constant of the code object).  Floats round-trip exactly (``repr``)."""
    return json.dumps(ops, separators=(",", ":"))


def program_of(text: str) -> tuple:
    """The program ``program_text`` wrote: a tuple of instruction tuples."""
    return tuple(tuple(op) for op in json.loads(text))


def straight_line(ops: tuple):
    """A numba intrinsic ``body(t, y, p, out)`` that emits ``ops`` (``program``) as LLVM
    instructions: numba types one call instead of every operation (its type inference
    costs about a millisecond per operation), and LLVM compiles the block.  A program
    compiled quickly (``quick.quick_cfunc``), or above the ``rhs`` threshold
    (``quick.quick_ops``), is written as LLVM assembly text and parsed by LLVM
    (``ir_text``: the same instructions in the same order, a function the intrinsic
    calls), skipping llvmlite's instruction objects and their printing, most of the
    compile time left at ``-O0``."""
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    from .quick import quick_ops

    dbl = ir.DoubleType()
    i64 = ir.IntType(64)
    above_rhs_threshold = len(ops) > quick_ops()

    @intrinsic
    def body(typingctx, t, y, p, out):
        def codegen(context, builder, signature, args):
            mod = builder.module
            ptr = {name: context.make_array(ty)(context, builder, v).data
                   for name, ty, v in zip("ypo", signature.args[1:], args[1:])}
            if above_rhs_threshold or getattr(context, "jetnh_quick", False):
                import llvmlite.binding as llvm

                name, text = ir_text(ops)
                module = llvm.parse_assembly(text)
                module.triple, module.data_layout = mod.triple, str(mod.data_layout)
                _link(context.active_code_library, module)
                fn = cgutils.get_or_insert_function(
                    mod, ir.FunctionType(ir.VoidType(), [dbl] + [ptr["y"].type] * 3), name)
                builder.call(fn, [args[0], ptr["y"], ptr["p"], ptr["o"]])
                return context.get_dummy_value()

            def fn(name, n=1):
                return cgutils.get_or_insert_function(
                    mod, ir.FunctionType(dbl, [dbl] * n), _LLVM_UNARY.get(name, name))

            def prod(xs):
                acc = xs[0]
                for x in xs[1:]:
                    acc = builder.fmul(acc, x)
                return acc

            vals = []
            for op in ops:
                kind = op[0]
                if kind == "y" or kind == "p":
                    v = builder.load(builder.gep(ptr[kind], [ir.Constant(i64, op[1])]))
                elif kind == "t":
                    v = args[0]
                elif kind == "c":
                    v = ir.Constant(dbl, op[1])
                elif kind == "add":
                    v = vals[op[1]]
                    for a in op[2:]:
                        v = builder.fadd(v, vals[a])
                elif kind == "mul":
                    v = prod([vals[a] for a in op[1:]])
                elif kind == "div":
                    v = builder.fdiv(vals[op[1]], vals[op[2]])
                elif kind == "powi":
                    k = op[2]
                    if k <= 4:
                        v = prod([vals[op[1]]] * k)
                    else:
                        v = builder.call(fn("llvm.pow.f64", 2),
                                         [vals[op[1]], ir.Constant(dbl, float(k))])
                elif kind == "pow":
                    v = builder.call(fn("llvm.pow.f64", 2), [vals[op[1]], vals[op[2]]])
                elif kind == "fn":
                    v = builder.call(fn(op[1], len(op) - 2), [vals[a] for a in op[2:]])
                else:       # "out"
                    builder.store(vals[op[2]], builder.gep(ptr["o"], [ir.Constant(i64, op[1])]))
                    v = None
                vals.append(v)
            return context.get_dummy_value()

        return types.void(t, y, p, out), codegen

    return body


def _link(library, module):
    """Link the parsed ``module`` into numba's code ``library`` as it is: the library's
    module passes optimise it (numba's ``add_llvm_module`` would first run the function
    passes on it, a second round of the same passes over the whole program).  That goes
    through numba's private ``_final_module``; where a numba release has none, through
    ``add_llvm_module`` (slower to compile, the same code)."""
    final = getattr(library, "_final_module", None)
    if final is None:
        library.add_llvm_module(module)
    else:
        final.link_in(module)


def ir_text(ops: tuple) -> tuple[str, str]:
    """``(name, module)``: LLVM assembly of ``void name(double t, ptr y, ptr p, ptr out)``
    computing ``ops`` with the instructions ``straight_line`` builds, in its order (the
    same arithmetic: bit-for-bit the same results); ``name`` is new in every call (each
    compilation defines its own external function, also beside a cached one)."""
    import struct
    import uuid

    def const(x):
        return "0x%016X" % struct.unpack("<Q", struct.pack("<d", float(x)))[0]

    lines, declared = [], {}
    val: list = []
    tmp = [0]

    def fresh():
        tmp[0] += 1
        return f"%u{tmp[0]}"

    def chain(opcode, xs):
        acc = xs[0]
        for x in xs[1:]:
            r = fresh()
            lines.append(f"  {r} = {opcode} double {acc}, {x}")
            acc = r
        return acc

    def call(name, xs):
        callee = _LLVM_UNARY.get(name, name)
        declared[callee] = len(xs)
        r = fresh()
        lines.append(f"  {r} = call double @{callee}("
                     + ", ".join(f"double {x}" for x in xs) + ")")
        return r

    for op in ops:
        kind = op[0]
        if kind == "y" or kind == "p":
            g, r = fresh(), fresh()
            lines.append(f"  {g} = getelementptr double, ptr %{kind}, i64 {op[1]}")
            lines.append(f"  {r} = load double, ptr {g}")
            v = r
        elif kind == "t":
            v = "%t"
        elif kind == "c":
            v = const(op[1])
        elif kind == "add":
            v = chain("fadd", [val[a] for a in op[1:]])
        elif kind == "mul":
            v = chain("fmul", [val[a] for a in op[1:]])
        elif kind == "div":
            v = fresh()
            lines.append(f"  {v} = fdiv double {val[op[1]]}, {val[op[2]]}")
        elif kind == "powi":
            k = op[2]
            v = (chain("fmul", [val[op[1]]] * k) if k <= 4
                 else call("llvm.pow.f64", [val[op[1]], const(k)]))
        elif kind == "pow":
            v = call("llvm.pow.f64", [val[op[1]], val[op[2]]])
        elif kind == "fn":
            v = call(op[1], [val[a] for a in op[2:]])
        else:       # "out"
            g = fresh()
            lines.append(f"  {g} = getelementptr double, ptr %o, i64 {op[1]}")
            lines.append(f"  store double {val[op[2]]}, ptr {g}")
            v = None
        val.append(v)
    body = "\n".join(lines)
    name = "jetnh_straight_line_" + uuid.uuid4().hex
    decls = "".join(f"declare double @{f}({', '.join(['double'] * n)})\n"
                    for f, n in sorted(declared.items()))
    return name, (f"{decls}\ndefine void @{name}(double %t, ptr %y, ptr %p, "
                  f"ptr %o) {{\nentry:\n{body}\n  ret void\n}}\n")


def derivative_program(ops: tuple, n: int) -> tuple:
    """The forward-mode derivative of a straight-line program: every instruction's
    derivatives in the states ``y[j]`` (only the nonzero ones) by the chain rule on the
    instruction itself; each ``("out", i, a)`` becomes ``("out", i*n + j, da/dy_j)``
    (row-major slots of an n-column matrix).  Raises ``Unsupported`` for ``abs``."""
    out, D = _forward(ops)
    # the value stores become placeholders (indices unchanged); the matrix's stores follow
    result = [op if op[0] != "out" else ("c", 0.0) for op in out]
    for op in ops:
        if op[0] == "out":
            for j, x in sorted(D[op[2]].items()):
                result.append(("out", op[1] * n + j, x))
    return tuple(result)


def sensitivity_program(ops: tuple, n: int, n_p: int) -> tuple:
    """The variational equations of a straight-line right-hand side ``y' = f(t, y, p)``
    (``ops``, stores ``out[0..n-1]``) for the state augmented by ``S = dy/d(y0, p)``, an
    n x m matrix (m = n + n_p) stored row-major after the state (``y[n + i*m + k]``):
    the stores of f unchanged, then ``S'[i, k] = sum_j df_i/dy_j S[j, k] (+ df_i/dp_l for
    the column k = n + l)``, the partial derivatives by forward mode on the program
    (``_forward``: the runtime parameters are the columns n..m-1)."""
    out, D = _forward(ops, n)
    m = n + n_p
    load: dict = {}

    def add(op):
        out.append(op)
        return len(out) - 1

    def s(j, k):
        if (j, k) not in load:
            load[(j, k)] = add(("y", n + j * m + k))
        return load[(j, k)]

    zero = add(("c", 0.0))
    for op in ops:
        if op[0] != "out":
            continue
        i, d = op[1], D[op[2]]
        for k in range(m):
            terms = [add(("mul", x, s(j, k))) for j, x in sorted(d.items()) if j < n]
            if k >= n and k in d:
                terms.append(d[k])
            value = zero if not terms else terms[0] if len(terms) == 1 else add(("add", *terms))
            out.append(("out", n + i * m + k, value))
    return tuple(out)


def sensitivity_jacobian_program(ops: tuple, n: int, n_p: int) -> tuple:
    """The Jacobian radau's Newton iteration uses for the augmented state of
    ``sensitivity_program``: df/dy on the diagonal block of the state and of every
    column of S (block-diagonal; the coupling d(df/dy S)/dy is left out, as a simplified
    Newton iteration may: it changes the iteration's convergence rate, not its solution).
    Row-major slots of an N x N matrix, N = n (1 + m)."""
    out, D = _forward(ops)
    m = n + n_p
    size = n * (1 + m)
    result = [op if op[0] != "out" else ("c", 0.0) for op in out]
    for op in ops:
        if op[0] != "out":
            continue
        i = op[1]
        for j, x in sorted(D[op[2]].items()):
            result.append(("out", i * size + j, x))
            for k in range(m):
                result.append(("out", (n + i * m + k) * size + n + j * m + k, x))
    return tuple(result)


def _forward(ops: tuple, params_at=None):
    """Forward mode over a straight-line program: ``(ops extended by the derivative
    instructions, D)`` with ``D[i]`` = {column: instruction of d op_i / d column}, the
    columns being the states ``y[j]`` and, with ``params_at`` = c, the runtime parameters
    ``p[l]`` as columns c + l.  Raises ``Unsupported`` for ``abs``."""
    out = list(ops)
    const: dict = {}

    def add(op):
        out.append(op)
        return len(out) - 1

    def c(x):
        if x not in const:
            const[x] = add(("c", float(x)))
        return const[x]

    def total(terms):
        return terms[0] if len(terms) == 1 else add(("add", *terms))

    def fprime(name, i, args):
        a = args[0]
        if name == "sin":
            return add(("fn", "cos", a))
        if name == "cos":
            return add(("mul", c(-1), add(("fn", "sin", a))))
        if name == "exp":
            return i
        if name == "log":
            return add(("div", c(1), a))
        if name == "sqrt":
            return add(("div", c(0.5), i))
        if name in ("tan", "tanh"):
            sq = add(("powi", i, 2))
            return add(("add", c(1), sq)) if name == "tan" else add(
                ("add", c(1), add(("mul", c(-1), sq))))
        if name == "sinh":
            return add(("fn", "cosh", a))
        if name == "cosh":
            return add(("fn", "sinh", a))
        sq = add(("powi", a, 2))
        if name == "atan":
            return add(("div", c(1), add(("add", c(1), sq))))
        if name in ("asin", "acos"):
            r = add(("div", c(1 if name == "asin" else -1),
                     add(("fn", "sqrt", add(("add", c(1), add(("mul", c(-1), sq))))))))
            return r
        if name == "asinh":
            return add(("div", c(1), add(("fn", "sqrt", add(("add", sq, c(1)))))))
        if name == "acosh":
            return add(("div", c(1), add(("fn", "sqrt", add(("add", sq, c(-1)))))))
        if name == "atanh":
            return add(("div", c(1), add(("add", c(1), add(("mul", c(-1), sq))))))
        raise Unsupported(name)

    D: list = []
    for i, op in enumerate(ops):
        kind, d = op[0], {}
        if kind == "y":
            d = {op[1]: c(1)}
        elif kind == "p" and params_at is not None:
            d = {params_at + op[1]: c(1)}
        elif kind == "add":
            acc: dict = {}
            for a in op[1:]:
                for j, x in D[a].items():
                    acc.setdefault(j, []).append(x)
            d = {j: total(t) for j, t in acc.items()}
        elif kind == "mul":
            acc = {}
            args = list(op[1:])
            for k, a in enumerate(args):
                others = args[:k] + args[k + 1:]
                for j, x in D[a].items():
                    acc.setdefault(j, []).append(add(("mul", *others, x)) if others else x)
            d = {j: total(t) for j, t in acc.items()}
        elif kind == "div":
            a, b = op[1], op[2]
            acc = {}
            for j, x in D[a].items():
                acc.setdefault(j, []).append(add(("div", x, b)))
            for j, x in D[b].items():
                acc.setdefault(j, []).append(add(("div", add(("mul", c(-1), i, x)), b)))
            d = {j: total(t) for j, t in acc.items()}
        elif kind == "powi":
            a, k = op[1], op[2]
            if D[a]:
                f = c(k) if k == 1 else add(("mul", c(k), a if k == 2 else add(("powi", a, k - 1))))
                d = {j: add(("mul", f, x)) for j, x in D[a].items()}
        elif kind == "pow":
            a, b = op[1], op[2]
            acc = {}
            if D[a]:
                f = add(("mul", b, add(("pow", a, add(("add", b, c(-1)))))))
                for j, x in D[a].items():
                    acc.setdefault(j, []).append(add(("mul", f, x)))
            if D[b]:
                g = add(("mul", i, add(("fn", "log", a))))
                for j, x in D[b].items():
                    acc.setdefault(j, []).append(add(("mul", g, x)))
            d = {j: total(t) for j, t in acc.items()}
        elif kind == "fn":
            args = list(op[2:])
            acc = {}
            if op[1] == "atan2":            # atan2(u, w): (w du - u dw) / (u^2 + w^2)
                u, w = args
                r2 = add(("add", add(("powi", u, 2)), add(("powi", w, 2))))
                for j, x in D[u].items():
                    acc.setdefault(j, []).append(add(("div", add(("mul", w, x)), r2)))
                for j, x in D[w].items():
                    acc.setdefault(j, []).append(
                        add(("div", add(("mul", c(-1), u, x)), r2)))
            elif D[args[0]]:
                f = fprime(op[1], i, args)
                for j, x in D[args[0]].items():
                    acc.setdefault(j, []).append(add(("mul", f, x)))
            d = {j: total(t) for j, t in acc.items()}
        D.append(d)
    return out, D