"""Python text of a shared expression graph: the scalar printer and the ``Emitter``.

Numbers are printed with ``repr(float)``, which round-trips exactly.  Nothing is
simplified, and no expression is flattened: ``Emitter`` prints each distinct node once,
in topological order, as an assignment or inline in its only parent, so that the text is
linear in the shared size; ``Emitter.jacobian`` differentiates the same graph node by node.
"""

from __future__ import annotations

import sympy as sp
from sympy.functions.elementary.piecewise import ExprCondPair
from sympy.printing.pycode import PythonCodePrinter

from ...algebra import dag


class _Printer(PythonCodePrinter):
    """Scalar Python/numba printer: exact floats, small integer powers as products."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_Integer(self, expr):
        return repr(float(expr))

    def _print_Half(self, expr):
        return "0.5"

    def _print_Pow(self, expr, rational=False):
        b, e = expr.as_base_exp()
        base = self.parenthesize(b, 60)  # tighter than * so products stay grouped
        if e.is_Integer:
            k = int(e)
            if 1 <= abs(k) <= 4:
                prod = "*".join([base] * abs(k))
                prod = prod if abs(k) == 1 else f"({prod})"
                return prod if k > 0 else f"(1.0/{prod})"
        if e == sp.S.Half:
            return f"math.sqrt({self._print(b)})"
        if e == -sp.S.Half:
            return f"(1.0/math.sqrt({self._print(b)}))"
        return f"{base}**{self.parenthesize(e, 60)}"


_PRINTER = _Printer()


def print_expr(expr) -> str:
    return _PRINTER.doprint(expr)


# ---------------------------------------------------------------------- the emitter
_ADD, _MUL, _POW, _ATOM = 10, 20, 30, 40        # Python precedence of a printed node
#: the functions of the math module printed (and compiled) as themselves
MATH = frozenset({"sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh",
                   "tanh", "asinh", "acosh", "atanh", "exp", "log"})
_STRUCTURAL = (sp.Tuple, ExprCondPair)           # parts of a node, never printed alone


def _fast(e) -> bool:
    """Printed by the emitter itself (else: rebuilt on named children, sympy's printer)."""
    return (e.is_Add or e.is_Mul or e.is_Pow or isinstance(e, sp.Abs)
            or (isinstance(e, sp.Function) and type(e).__name__ in MATH))


def _parts(e):
    """The nodes the value of ``e`` depends on: its arguments, through structural ones
    (a Piecewise's pairs)."""
    for a in e.args:
        if isinstance(a, _STRUCTURAL):
            yield from _parts(a)
        else:
            yield a


class Emitter:
    """Straight-line code for a shared graph (``roots``: every expression the code will
    assign, so that uses are counted once for all).

    Equal subexpressions are merged bottom-up (by their head and their children's
    indices, so equal copies cost no tree comparison); each distinct node is printed once,
    in terms of its children's text.  A node used more than once, or whose text is
    longer than ``inline`` characters, is assigned to a name ``<prefix><i>``; a node used
    once is written inline into its parent.  Time and text are linear in the number of
    distinct nodes: no tree is ever walked (``emit`` writes the assignments).
    """

    def __init__(self, roots, prefix: str = "c", inline: int = 160):
        self.roots = [sp.sympify(r, strict=True) for r in roots]   # keeps the ids below alive
        self.prefix, self.inline = prefix, inline
        self.index: dict = {}       # id(node) -> canonical index
        self.rep: list = []         # canonical index -> node
        seen: dict = {}
        for e in dag.nodes(self.roots):
            key = (e.func, tuple(self.index[id(a)] for a in e.args)) if e.args else e
            i = seen.get(key)
            if i is None:
                i = seen[key] = len(self.rep)
                self.rep.append(e)
            self.index[id(e)] = i
        self.uses = [0] * len(self.rep)
        for e in self.rep:
            bump = 1 if _fast(e) and not (
                e.is_Pow and e.exp.is_Integer and abs(e.exp) > 1) else 2
            for a in e.args:
                self.uses[self.index[id(a)]] += bump
        for r in self.roots:
            self.uses[self.index[id(r)]] += 1
        self.text: dict = {}        # canonical index -> (text, precedence)
        self.den: dict = {}         # index of an inline negative power -> its denominator
        self.count = 0

    def __len__(self) -> int:
        return len(self.rep)

    def of(self, e) -> int:
        return self.index[id(e)]

    def name(self, prefix=None) -> str:
        self.count += 1
        return f"{prefix or self.prefix}{self.count - 1}"

    def emit(self, outputs) -> list[str]:
        """Lines computing ``outputs`` (``[(target, expr), ...]``, expressions among the
        roots): the nodes not yet computed, children first, then ``target = ...``."""
        lines = []
        for e in dag.nodes([expr for _, expr in outputs]):
            i = self.index[id(e)]
            if i in self.text:
                continue
            if isinstance(e, _STRUCTURAL):
                self.text[i] = (None, _ATOM)
                continue
            text, prec = self._format(e)
            if e.args and (self.uses[i] > 1 or len(text) > self.inline):
                name = self.name()
                lines.append(f"{name} = {text}")
                self.den.pop(i, None)
                text, prec = name, _ATOM
            self.text[i] = (text, prec)
        for target, expr in outputs:
            if target is not None:
                lines.append(f"{target} = {self.text[self.index[id(sp.sympify(expr, strict=True))]][0]}")
        return lines

    # ------------------------------------------------------------------ printing
    def _arg(self, a, prec: int) -> str:
        text, p = self.text[self.index[id(a)]]
        return text if p >= prec else f"({text})"

    def _format(self, e) -> tuple[str, int]:
        if not e.args:
            if e.is_Symbol:
                return e.name, _ATOM
            if e.is_Number or e.is_NumberSymbol:
                v = float(e)
                return repr(v), _ATOM if v >= 0 else _MUL
            return f"({_PRINTER.doprint(e)})", _ATOM
        if e.is_Add:
            out = []
            for a in e.args:
                text, p = self.text[self.index[id(a)]]
                if not out:
                    out.append(text)
                elif text.startswith("-") and p >= _MUL:
                    out.append(f" - {text[1:]}")
                else:
                    out.append(f" + {text}")
            return "".join(out), _ADD
        if e.is_Mul:
            args = list(e.args)
            coeff = args.pop(0) if args[0].is_Number else None
            num, den = [], []
            for a in args:
                i = self.index[id(a)]
                if i in self.den:
                    den.append(self.den[i])
                else:
                    num.append(self._arg(a, _MUL))
            text = "*".join(num) or "1.0"
            if coeff is not None:
                if coeff == -1:
                    text = "-" + text
                else:
                    text = f"{float(coeff)!r}*{text}"
            if den:
                text += "/" + (den[0] if len(den) == 1 else "(" + "*".join(den) + ")")
            return text, _MUL
        if e.is_Pow:
            b, x = e.args
            base = self._arg(b, _ATOM)
            i = self.index[id(e)]
            if x.is_Integer and 1 <= abs(int(x)) <= 4:
                k = abs(int(x))
                prod = "*".join([base] * k)
                d = prod if k == 1 else f"({prod})"
                if x > 0:
                    return d, _ATOM
                self.den[i] = d
                return f"(1.0/{d})", _ATOM
            if x == sp.S.Half:
                return f"math.sqrt({self.text[self.index[id(b)]][0]})", _ATOM
            if x == -sp.S.Half:
                d = f"math.sqrt({self.text[self.index[id(b)]][0]})"
                self.den[i] = d
                return f"(1.0/{d})", _ATOM
            return f"{base}**{self._arg(x, _ATOM)}", _POW
        if isinstance(e, sp.Abs):
            return f"abs({self.text[self.index[id(e.args[0])]][0]})", _ATOM
        if isinstance(e, sp.Function) and type(e).__name__ in MATH:
            args = ", ".join(self.text[self.index[id(a)]][0] for a in e.args)
            return f"math.{type(e).__name__}({args})", _ATOM
        return f"({_PRINTER.doprint(self.local(e))})", _ATOM

    def local(self, e, real: bool = False):
        """``e`` rebuilt on its children's names (as Symbols; structural parts rebuilt)."""
        args = []
        for a in e.args:
            if isinstance(a, _STRUCTURAL):
                args.append(self.local(a, real))
            elif a.args or a.is_Symbol:
                text = self.text[self.index[id(a)]][0]
                args.append(sp.Symbol(text, real=True) if real else sp.Symbol(text))
            else:
                args.append(a)
        return e.func(*args)

    # ------------------------------------------------------------------ derivatives
    def jacobian(self, outputs, states, chains=None) -> list[str]:
        """Lines writing ``target = d expr / d state`` (forward mode over the nodes:
        each node's derivatives from its children's, by the chain rule on the node's own
        head, never on a flattened expression), after ``emit`` computed every root.

        ``outputs``: ``[(row, expr), ...]``; ``states``: Symbol -> column; ``chains``:
        Symbol -> expression (a root) the symbol stands for (e.g. a dependent velocity
        v<a> = phi^a).  Writes ``J[row, column] = ...`` for the nonzero entries only.
        """
        col = {self.index[id(s)]: j for s, j in states.items() if id(s) in self.index}
        chain = {self.index[id(s)]: self.index[id(sp.sympify(e, strict=True))]
                 for s, e in (chains or {}).items() if id(s) in self.index}
        lines, D = [], {}

        def deriv(i):
            e = self.rep[i]
            if not e.args:
                if i in col:
                    return {col[i]: "1.0"}
                return D.get(chain[i], {}) if i in chain else {}
            if isinstance(e, _STRUCTURAL) or not isinstance(e, sp.Expr):
                return {}
            kids = [self.index[id(a)] for a in _parts(e)]
            live = [k for k in range(len(kids)) if D.get(kids[k])]
            if not live:
                return {}
            partial = self._partials(e, live)
            acc: dict = {}
            for k in live:
                p = partial[k]
                for j, d in D[kids[k]].items():
                    term = d if p == "1.0" else (f"{p}*{d}" if d != "1.0" else p)
                    acc.setdefault(j, []).append(term)
            out = {}
            for j, terms in acc.items():
                text = " + ".join(terms)
                if len(terms) == 1 and (text.isidentifier() or text.startswith("(")):
                    pass
                elif self.uses[i] > 1 or len(text) > self.inline:
                    name = self.name("d")
                    lines.append(f"{name} = {text}")
                    text = name
                elif len(terms) > 1:
                    text = f"({text})"
                out[j] = text
            return out

        for e in dag.nodes(list((chains or {}).values()) + [expr for _, expr in outputs]):
            i = self.index[id(e)]
            if i not in D:
                D[i] = deriv(i)
        for row, expr in outputs:
            for j, d in sorted(D[self.index[id(sp.sympify(expr, strict=True))]].items()):
                lines.append(f"J[{row}, {j}] = {d}")
        return lines

    def _partials(self, e, live) -> dict:
        """Text of d e / d (child k) for the children ``live``, in the names of the
        node and its children (every compound node is named in a Jacobian kernel)."""
        val = self.text[self.index[id(e)]][0]
        parts = list(_parts(e))
        names = [self.text[self.index[id(a)]][0] for a in parts]
        paren = [n if self.text[self.index[id(a)]][1] >= _ATOM else f"({n})"
                 for n, a in zip(names, parts)]
        out = {}
        if e.is_Add:
            return {k: "1.0" for k in live}
        if e.is_Mul:
            for k in live:
                out[k] = "*".join(paren[:k] + paren[k + 1:]) or "1.0"
            return out
        if e.is_Pow:
            b, x = e.args
            if 0 in live:
                if x.is_number:
                    xv = float(x)
                    if x == sp.S.Half:
                        out[0] = f"(0.5/{val})"
                    elif x == 1:
                        out[0] = "1.0"
                    elif x == 2:
                        out[0] = f"(2.0*{paren[0]})"
                    else:
                        out[0] = f"({xv!r}*{paren[0]}**{xv - 1.0!r})"
                else:
                    out[0] = f"({paren[1]}*{paren[0]}**({paren[1]} - 1.0))"
            if 1 in live:
                out[1] = f"({val}*math.log({names[0]}))"
            return out
        local = self.local(e, real=True)
        for k in live:
            d = local.diff(sp.Symbol(names[k], real=True))
            out[k] = f"({_PRINTER.doprint(d)})"
        return out
