"""The expression language of model files: text -> sympy by walking the syntax tree, and
sympy -> text (see ``jetnh.modelfile`` for the language and its limits).

Nothing is evaluated: ``ast.parse`` gives the syntax tree, which is turned into sympy
objects node by node, with every constant subexpression shadowed in double precision
(overflow and domain errors are refused before sympy sees them).
"""

from __future__ import annotations

import ast
import math
import random
import re
import sys

import sympy as sp

from ..errors import JetnhError, ModelFileError
from . import limits
from .text import char_column, line_col, refuse_non_ascii, shorten

FUNCTIONS = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1), "cot": (sp.cot, 1),
    "sec": (sp.sec, 1), "csc": (sp.csc, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1), "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "asinh": (sp.asinh, 1), "acosh": (sp.acosh, 1), "atanh": (sp.atanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "sqrt": (sp.sqrt, 1),
    "Abs": (sp.Abs, 1), "abs": (sp.Abs, 1), "sign": (sp.sign, 1),
}
CONSTANTS = {"pi": sp.pi}
_NONSMOOTH = {"floor", "ceiling", "ceil", "frac", "round", "Heaviside", "heaviside",
              "DiracDelta", "Min", "Max", "min", "max", "Piecewise", "piecewise", "Mod",
              "mod", "re", "im", "arg", "conjugate", "step", "clip"}
HYPERBOLIC = frozenset({"sinh", "cosh", "tanh"})

_REFUSED = {
    ast.Attribute: "attribute access is", ast.Subscript: "subscripts are",
    ast.Lambda: "lambdas are", ast.ListComp: "comprehensions are",
    ast.SetComp: "comprehensions are", ast.DictComp: "comprehensions are",
    ast.GeneratorExp: "comprehensions are", ast.JoinedStr: "f-strings are",
    ast.FormattedValue: "f-strings are", ast.Starred: "starred arguments are",
    ast.Compare: "comparisons are", ast.BoolOp: "boolean operators ('and', 'or') are",
    ast.IfExp: "conditional expressions are", ast.List: "lists are", ast.Tuple: "tuples are",
    ast.Set: "sets are", ast.Dict: "dictionaries are",
    ast.NamedExpr: "assignment expressions are", ast.Await: "await is",
    ast.Yield: "yield is", ast.YieldFrom: "yield is", ast.Slice: "slices are",
}
_OPS = {ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<",
        ast.RShift: ">>", ast.BitOr: "|", ast.BitXor: "^", ast.BitAnd: "&"}


def _sign(x):
    return math.copysign(1.0, x) if x else 0.0


# double-precision shadows of the functions: every symbol-free subexpression is also
# evaluated in floats, so that overflow and domain errors are refused before sympy sees
# them (sympy's own evaluation of exp(exp(exp(100))) does not return)
_FLOAT = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "cot": lambda x: 1 / math.tan(x),
    "sec": lambda x: 1 / math.cos(x), "csc": lambda x: 1 / math.sin(x),
    "asin": math.asin, "acos": math.acos, "atan": math.atan, "atan2": math.atan2,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "asinh": math.asinh,
    "acosh": math.acosh, "atanh": math.atanh, "exp": math.exp, "log": math.log,
    "sqrt": math.sqrt, "Abs": abs, "abs": abs, "sign": _sign,
}
_BAD = (sp.zoo, sp.nan, sp.oo, -sp.oo)


class _Unknown(Exception):
    """An expression the double-precision evaluation does not know."""


def _float_value(expr, point: dict, memo: dict):
    """``expr`` in double precision at ``point`` (Symbol -> float); None when it (or a
    part of it) is not a finite real number.  Iterative: the tree may be deep."""
    stack = [(expr, False)]
    while stack:
        e, done = stack.pop()
        if id(e) in memo:
            continue
        if not done:
            if e.is_Symbol:
                memo[id(e)] = point[e]
            elif e.is_Number or e is sp.pi or e is sp.E:
                memo[id(e)] = float(e)
            else:
                stack.append((e, True))
                stack.extend((a, False) for a in e.args)
            continue
        vals = [memo[id(a)] for a in e.args]
        if any(v is None for v in vals):
            memo[id(e)] = None
            continue
        try:
            if e.is_Add:
                v = math.fsum(vals)
            elif e.is_Mul:
                v = math.prod(vals)
            elif e.is_Pow:
                v = math.pow(*vals)
            elif type(e).__name__ in _FLOAT:
                v = _FLOAT[type(e).__name__](*vals)
            else:
                raise _Unknown(type(e).__name__)
        except (ValueError, ZeroDivisionError, OverflowError):
            v = None
        memo[id(e)] = v if v is not None and math.isfinite(v) else None
    return memo[id(expr)]


def real_somewhere(exprs, symbols) -> bool:
    """Whether the expressions are all finite and real at one of ``SAMPLE_POINTS`` random
    points (every symbol in [0.31, 1.37], as jetnh samples to decide ranks)."""
    rng = random.Random(0)
    symbols = sorted(symbols, key=lambda s: s.name)
    for _ in range(limits.SAMPLE_POINTS):
        point = {s: rng.uniform(0.31, 1.37) for s in symbols}
        memo = {}
        try:
            if all(_float_value(e, point, memo) is not None for e in exprs):
                return True
        except _Unknown:
            return True                      # cannot tell: leave it to jetnh
    return False


#: the numbers of the language: digits, with a decimal point and an exponent or not
_LITERAL = re.compile(r"(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def literal(text, value, fail, form=True) -> None:
    """Refuse (``fail(what)``) a number ``text`` (read as ``value``) written outside the
    language (with ``form``: hexadecimal, binary, octal, digits grouped by "_"), or one
    whose nonzero digits fall below double precision's normal range (read as 0 or a
    subnormal: the term would vanish or lose digits)."""
    if text is None:
        return
    if form and not _LITERAL.fullmatch(text):
        fail("numbers are integers and decimals (digits, a decimal point, an exponent "
             "e.g. 1.5e-3); write this one so:")
    digits = text.lower().split("e")[0]
    if isinstance(value, float) and abs(value) < sys.float_info.min \
            and any(c in "123456789" for c in digits):
        read = "0" if value == 0 else f"{value!r}, digits lost"
        fail(f"the number is below double precision's normal range (about "
             f"{sys.float_info.min:.3g}) and would be read as {read}; rescale the units "
             "(write the model in other units of length, time or mass):")


class _Parser:
    """Builds one sympy expression from one syntax tree (the language: ``jetnh.modelfile``).

    Every ``build`` returns ``(expr, value, size)``: the sympy expression; when it
    contains no symbol, its value in double precision (else None); and an upper bound of
    the number of terms of its expansion (sums add, products multiply, an integer power
    n of s terms has at most C(s + n - 1, n)), since jetnh and sympy expand expressions
    (``expand`` of ((x_t + 1)**64 + 1)**64 would not return).
    """

    def __init__(self, text: str, names: dict, where: str, hint: dict | None = None,
                 offset_map=None):
        self.text = text
        self.names = names
        self.where = where
        self.hint = hint or {}
        self.offset_map = offset_map

    # ------------------------------------------------------------------ errors
    def fail(self, node, what: str):
        seg = None
        line, col = getattr(node, "lineno", None), getattr(node, "col_offset", None)
        if line is not None:
            try:
                seg = ast.get_source_segment(self.text, node)
            except Exception:                          # pragma: no cover - defensive
                seg = None
            col = char_column(self.text, line, col)
            if self.offset_map is not None:
                line, col = self.offset_map(col)
        quote = f" {shorten(seg)!r}" if seg else ""
        at = f" at line {line}, column {col + 1}" if line is not None else ""
        raise ModelFileError(f"{self.where}: {what}{quote}{at}")

    _lines = None

    def segment(self, node):
        """The source text of a one-line ``node`` (``ast.get_source_segment`` splits the
        whole text at every call)."""
        if node.lineno != node.end_lineno:
            return ast.get_source_segment(self.text, node)
        if self._lines is None:
            self._lines = [line.encode() for line in self.text.splitlines(keepends=True)]
        return self._lines[node.lineno - 1][node.col_offset:node.end_col_offset].decode()

    # ------------------------------------------------------------------ building
    def build(self, node, depth=0):
        if depth > limits.MAX_DEPTH:
            self.fail(node, f"nesting deeper than {limits.MAX_DEPTH} levels is refused:")
        kind = type(node)
        if kind is ast.Expression:
            return self.build(node.body, depth)
        if kind is ast.Constant:
            return self.constant(node)
        if kind is ast.Name:
            return self.name(node)
        if kind is ast.UnaryOp:
            if isinstance(node.op, (ast.USub, ast.UAdd)):
                e, v, n = self.build(node.operand, depth + 1)
                if isinstance(node.op, ast.UAdd):
                    return e, v, n
                return -e, (None if v is None else -v), n
            self.fail(node, f"the operator {'not' if isinstance(node.op, ast.Not) else '~'} "
                      "is not allowed:")
        if kind is ast.BinOp:
            return self.binop(node, depth)
        if kind is ast.Call:
            return self.call(node, depth)
        what = _REFUSED.get(kind, f"{kind.__name__} syntax is")
        self.fail(node, f"{what} not allowed:")

    def constant(self, node):
        v = node.value
        if isinstance(v, bool) or v is None or v is Ellipsis:
            self.fail(node, f"the constant {v!r} is not a number:")
        if isinstance(v, (int, float)):
            literal(self.segment(node), v, lambda what: self.fail(node, what))
        if isinstance(v, int):
            if abs(v).bit_length() > 3.33 * limits.MAX_INT_DIGITS:
                self.fail(node, f"integers of more than {limits.MAX_INT_DIGITS} digits are "
                          "refused:")
            return sp.Integer(v), float(v), 1
        if isinstance(v, float):
            if not math.isfinite(v):
                self.fail(node, "the number is not finite:")
            return sp.Float(v), v, 1
        if isinstance(v, complex):
            self.fail(node, "complex numbers are not allowed:")
        if isinstance(v, (str, bytes)):
            self.fail(node, "strings are not allowed:")
        self.fail(node, f"the constant {type(v).__name__} is not allowed:")

    def name(self, node):
        n = node.id
        if "__" in n:
            self.fail(node, "names with double underscores are not allowed:")
        if n in self.names:
            return self.names[n], None, 1
        if n in CONSTANTS:
            return CONSTANTS[n], float(CONSTANTS[n]), 1
        if n in FUNCTIONS:
            self.fail(node, f"{n} is a function; call it, e.g. {n}(x):")
        if n in self.hint:
            self.fail(node, self.hint[n])
        known = ", ".join(sorted(self.names)) or "none"
        self.fail(node, f"unknown name (declared names: {known}; declare parameters "
                  "under [parameters]):")

    def number(self, node, value, what="the value"):
        """A double-precision shadow value, or a refusal if it is not a finite real."""
        if isinstance(value, complex) or not math.isfinite(value):
            self.fail(node, f"{what} is not a finite real number:")
        return value

    def binop(self, node, depth):
        op = type(node.op)
        if op in _OPS:
            self.fail(node, f"the operator {_OPS[op]} is not allowed:")
        if op in (ast.Add, ast.Sub):
            first, parts = self._chain(node, (ast.Add, ast.Sub))
            e, v, n = self.build(first, depth + 1)
            terms, total, size = [e], v, n
            for o, right in parts:
                e, v, n = self.build(right, depth + 1)
                terms.append(e if o is ast.Add else -e)
                if total is not None and v is not None:
                    total = self.number(node, total + v if o is ast.Add else total - v)
                else:
                    total = None
                size = self.size(node, size + n)
            return self.check(node, sp.Add(*terms)), total, size
        if op in (ast.Mult, ast.Div):
            first, parts = self._chain(node, (ast.Mult, ast.Div))
            e, v, n = self.build(first, depth + 1)
            factors, total, size = [e], v, n
            for o, right in parts:
                e, v, n = self.build(right, depth + 1)
                size = self.size(node, size * n)
                if o is ast.Div and (e == 0 or v == 0.0):
                    self.fail(node, "division by zero:")
                if total is not None and v is not None:
                    total = self.number(node, total * v if o is ast.Mult else total / v)
                else:
                    total = None
                factors.append(e if o is ast.Mult else self.check(node, sp.Pow(e, -1)))
            # one product of all factors: multiplying one factor at a time re-flattens the
            # partial product each time (quadratic: a chain of 1000 factors took seconds)
            return self.check(node, sp.Mul(*factors)), total, size
        if op is ast.Pow:
            base, bv, bn = self.build(node.left, depth + 1)
            exp_, ev, en = self.build(node.right, depth + 1)
            return self.power(node, base, bv, bn, exp_, ev, en)
        self.fail(node, f"the operator {op.__name__} is not allowed:")  # pragma: no cover

    @staticmethod
    def _chain(node, ops):
        """Flatten a left-nested chain a op b op c ... iteratively: (a, [(op, b), ...])."""
        parts = []
        while isinstance(node, ast.BinOp) and type(node.op) in ops:
            parts.append((type(node.op), node.right))
            node = node.left
        return node, list(reversed(parts))

    def size(self, node, n):
        if n > limits.MAX_TERMS:
            self.fail(node, f"the expansion of this expression would have more than "
                      f"{limits.MAX_TERMS} terms; refused:")
        return n

    def power(self, node, base, bv, bn, exp_, ev, en):
        if exp_.is_Integer and abs(int(exp_)) > limits.MAX_EXPONENT:
            self.fail(node, f"integer exponents beyond +-{limits.MAX_EXPONENT} are refused:")
        value = None
        if bv is not None and ev is not None:
            if bv == 0.0 and ev <= 0:
                self.fail(node, "0 to a non-positive power is undefined:")
            try:
                value = math.pow(bv, ev)
            except OverflowError:
                self.fail(node, "the value overflows double precision:")
            except ValueError:
                self.fail(node, "the value is not real:")
            self.number(node, value)
            if base.is_Number and exp_.is_Rational:
                est = _digits(base) * abs(int(exp_.p)) / int(exp_.q)
                if est > limits.MAX_NUMBER_DIGITS:
                    self.fail(node, f"exact numbers of more than {limits.MAX_NUMBER_DIGITS} digits "
                              "are refused:")
        if exp_.is_Integer:
            k = abs(int(exp_))
            size = math.comb(bn + k - 1, k) if k else 1
        else:
            size = bn * en               # not expanded by sympy: opaque, but both parts count
        size = self.size(node, size)
        return self.check(node, sp.Pow(base, exp_)), value, size

    def call(self, node, depth):
        f = node.func
        if not isinstance(f, ast.Name):
            if isinstance(f, ast.Attribute):
                self.fail(node, "attribute access is not allowed:")
            self.fail(node, f"calls of expressions are not allowed (only the functions "
                      f"{_fnames()}):")
        n = f.id
        if "__" in n:
            self.fail(f, "names with double underscores are not allowed:")
        if n not in FUNCTIONS:
            if n in _NONSMOOTH:
                self.fail(node, f"{n}() is not allowed: it is not smooth, and the equations "
                          "of motion need derivatives; write the model smoothly (e.g. "
                          "tanh(u/eps) for a step, Abs(u) for |u|, whose kink the "
                          "integrators stop at):")
            if n in self.names or n in CONSTANTS:
                self.fail(node, f"{n} is not a function; only {_fnames()} can be called:")
            self.fail(node, f"{n}() is not an allowed function; the functions are "
                      f"{_fnames()}:")
        if node.keywords:
            self.fail(node, "keyword arguments are not allowed:")
        for a in node.args:
            if isinstance(a, ast.Starred):
                self.fail(a, "starred arguments are not allowed:")
        func, arity = FUNCTIONS[n]
        if len(node.args) != arity:
            self.fail(node, f"{n} takes {arity} argument{'s' if arity > 1 else ''}, "
                      f"got {len(node.args)}:")
        built = [self.build(a, depth + 1) for a in node.args]
        value = None
        if all(v is not None for _, v, _ in built):
            try:
                value = _FLOAT[n](*(v for _, v, _ in built))
            except OverflowError:
                self.fail(node, "the value overflows double precision:")
            except (ValueError, ZeroDivisionError):
                self.fail(node, f"the argument is outside the domain of {n}:")
            self.number(node, value)
        size = self.size(node, sum(k for _, _, k in built))
        return self.check(node, func(*(e for e, _, _ in built))), value, size

    # ------------------------------------------------------------------ checks
    def check(self, node, e):
        """Local checks of a freshly built node (cheap: e and its top-level args)."""
        parts = (e,) + (e.args if e.is_Mul or e.is_Pow else ())
        for p in parts:
            if p in _BAD:
                self.fail(node, "the expression is infinite or undefined:")
            if p.is_Number and _digits(p) > limits.MAX_NUMBER_DIGITS:
                self.fail(node, f"exact numbers of more than {limits.MAX_NUMBER_DIGITS} digits are "
                          "refused:")
            if p.is_Pow and p.exp.is_Integer and abs(int(p.exp)) > limits.MAX_EXPONENT:
                self.fail(node, f"the integer exponent {p.exp} (after combining equal bases) "
                          f"is beyond +-{limits.MAX_EXPONENT}:")
        if e.is_Add and any(a in _BAD for a in e.args):
            self.fail(node, "the expression is infinite or undefined:")
        return e


def _fnames() -> str:
    return ", ".join(sorted(FUNCTIONS))


def _digits(n) -> int:
    """Decimal digits of an exact number (the larger of numerator and denominator)."""
    if n.is_Rational:
        bits = max(abs(int(n.p)).bit_length(), int(n.q).bit_length())
        return int(bits * 0.30103) + 1
    return 0


class Budget:
    """What the expressions of one model file may cost together (``MAX_FILE_NODES``
    syntax nodes and ``MAX_CALL_COST`` units of function calls)."""

    def __init__(self, nodes: int | None = None, calls: int | None = None):
        self.nodes = limits.MAX_FILE_NODES if nodes is None else nodes
        self.calls = limits.MAX_CALL_COST if calls is None else calls
        self.used_nodes = 0
        self.used_calls = 0


def _is_int_literal(node) -> bool:
    while isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return (isinstance(node, ast.Constant) and isinstance(node.value, int)
            and not isinstance(node.value, bool))


def _call_like(node) -> bool:
    """Function calls and powers with other than integer-literal exponents: the nodes whose
    construction makes sympy query the assumptions of their argument (for nested
    hyperbolic functions those queries expand real and imaginary parts, exponentially
    in the nesting)."""
    if isinstance(node, ast.Call):
        return True
    return (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow)
            and not _is_int_literal(node.right))


def _measure(tree, where: str):
    """(syntax nodes, deepest nesting of calls, call cost) of a syntax tree, by one
    iterative walk (no recursion: the tree may be deep); stops at ``MAX_NODES`` nodes.

    A call-like node (``_call_like``) with ``k`` calls nested inside it (on its deepest
    path) costs ``CALL_COST_BASE**k`` units.  The hyperbolic functions (``HYPERBOLIC``)
    cost ``HYPERBOLIC_COST`` units each and their argument must hold no call-like node
    and at most ``MAX_HYPERBOLIC_ARG`` syntax nodes (the first offence is returned):
    sympy decides whether sinh, cosh, tanh of an expression are real by expanding the
    real and imaginary parts of the expression, at a cost exponential in the nesting
    and steep in the size (building the derivative of tanh(a sum of 100 terms) does not
    return within minutes).
    """
    count = 0
    level = {}          # id(node) -> deepest nesting of call-like nodes in its subtree
    size = {}           # id(node) -> syntax nodes in its subtree
    cost = 0
    deepest = 0
    bad = None
    stack = [(tree, False)]
    while stack:
        node, done = stack.pop()
        if not done:
            count += 1
            if count > limits.MAX_NODES:
                raise ModelFileError(f"{where}: the expression has more than {limits.MAX_NODES} "
                                     "syntax nodes; split the model into shorter "
                                     "expressions or raise jetnh.modelfile.MAX_NODES")
            stack.append((node, True))
            stack.extend((c, False) for c in ast.iter_child_nodes(node))
            continue
        below, n = 0, 1
        for c in ast.iter_child_nodes(node):
            below = max(below, level.pop(id(c), 0))
            n += size.pop(id(c), 0)
        if _call_like(node):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in HYPERBOLIC):
                f = node.func.id
                if below and bad is None:
                    bad = (node, f"{f} of an expression holding function calls (or non-integer "
                         "powers) is refused (sympy's cost of it explodes); write it with "
                         f"exp, e.g. {_EXP_FORM[f]}:")
                if n - 2 > limits.MAX_HYPERBOLIC_ARG and bad is None:
                    bad = (node, f"the argument of {f} has {n - 2} syntax nodes, more than "
                         f"{limits.MAX_HYPERBOLIC_ARG} (sympy's cost of it explodes); write it "
                         f"with exp, e.g. {_EXP_FORM[f]}:")
                cost += limits.HYPERBOLIC_COST
            else:
                cost += limits.CALL_COST_BASE ** min(below, 40)
            below += 1
            deepest = max(deepest, below)
        level[id(node)] = below
        size[id(node)] = n
    return count, deepest, cost, bad


_EXP_FORM = {"sinh": "sinh(u) = (exp(u) - exp(-u))/2", "cosh": "cosh(u) = (exp(u) + exp(-u))/2",
             "tanh": "tanh(u) = (exp(2*u) - 1)/(exp(2*u) + 1)"}


def parse_expression(text, names: dict, where: str = "expression", hint: dict | None = None,
                     budget: Budget | None = None):
    """The sympy expression written in ``text``, with ``names`` (str -> Symbol) declared.

    Raises ``ModelFileError`` for anything outside the language (``jetnh.modelfile``).
    ``hint`` maps names to a specific refusal message (e.g. accelerations).  Line breaks
    count as spaces (multi-line TOML strings), positions refer to the text as given.
    ``budget`` is shared by the expressions of one file (``MAX_FILE_NODES``,
    ``MAX_CALL_COST``); without it, the expression has a budget of its own.
    """
    if not isinstance(text, str):
        raise ModelFileError(f"{where}: expected an expression in a string, got "
                             f"{type(text).__name__} ({shorten(repr(text))})")
    if len(text) > limits.MAX_CHARS:
        raise ModelFileError(f"{where}: the expression has {len(text)} characters; the limit "
                             f"is {limits.MAX_CHARS}; split the model into shorter expressions")
    if "\x00" in text:
        raise ModelFileError(f"{where}: the expression contains a NUL character; remove it")
    # before ast.parse, which normalises identifiers (NFKC)
    refuse_non_ascii(text, where, lambda i: line_col(text, i))
    if not text.strip():
        raise ModelFileError(f"{where}: the expression is empty; write an expression such as "
                             "'x_t**2/2'")
    budget = budget if budget is not None else Budget()
    # one line, same offsets: a line break is white space in an expression
    flat = text.replace("\r", " ").replace("\n", " ").replace("\t", " ").replace("\f", " ")
    lead = len(flat) - len(flat.lstrip())
    body = flat.strip()
    try:
        tree = ast.parse(body, mode="eval")
    except SyntaxError as exc:
        # offset 0: the expression ended too early; point just past its end
        offset = min(exc.offset or len(body) + 1, len(body) + 1)
        line, col = line_col(text, lead + offset - 1)
        at = f" at line {line}, column {col + 1}"
        raise ModelFileError(f"{where}: not a valid expression ({exc.msg}){at}: "
                             f"{shorten(text)!r}") from None
    except (RecursionError, MemoryError, ValueError, OverflowError) as exc:
        raise ModelFileError(f"{where}: the expression is too deeply nested or too large "
                             f"to parse ({type(exc).__name__}); simplify it") from None
    parser = _Parser(body, names, where, hint, lambda col: line_col(text, lead + col))
    count, deepest, cost, bad = _measure(tree, where)
    if deepest > limits.MAX_CALL_DEPTH:
        raise ModelFileError(
            f"{where}: function calls (or non-integer powers) are nested {deepest} deep, "
            f"e.g. tanh(tanh(...)); the limit is {limits.MAX_CALL_DEPTH} (sympy's cost of building "
            "and differentiating them grows exponentially with the nesting); introduce a "
            "coordinate or rewrite the expression flatter")
    if bad is not None:
        parser.fail(*bad)
    budget.used_nodes += count
    if budget.used_nodes > budget.nodes:
        raise ModelFileError(
            f"{where}: the expressions of this model have more than {budget.nodes} syntax "
            "nodes together; simplify the model or raise jetnh.modelfile.MAX_FILE_NODES")
    budget.used_calls += cost
    if budget.used_calls > budget.calls:
        raise ModelFileError(
            f"{where}: the function calls of this model cost {budget.used_calls} units, "
            f"more than the limit {budget.calls} (a call with k calls nested inside it costs "
            f"{limits.CALL_COST_BASE}**k units, since building nested functions costs sympy about "
            "that much); use fewer or less deeply nested functions, or raise "
            "jetnh.modelfile.MAX_CALL_COST")
    try:
        expr, _, _ = parser.build(tree)
        if expr.has(*_BAD):
            raise ModelFileError(f"{where}: the expression is infinite or undefined")
        if expr.has(sp.I):
            raise ModelFileError(f"{where}: the expression is complex (jetnh works with real "
                                 "expressions); write it with real functions")
    except JetnhError:
        raise
    except RecursionError:
        raise ModelFileError(f"{where}: the expression is too deeply nested; simplify "
                             "it") from None
    except (OverflowError, MemoryError, ValueError, ArithmeticError) as exc:
        raise ModelFileError(f"{where}: sympy cannot build the expression "
                             f"({type(exc).__name__}: {shorten(str(exc))}); simplify "
                             "it") from None
    except Exception as exc:
        raise ModelFileError(f"{where}: sympy cannot build the expression (internal: "
                             f"{type(exc).__name__}: {shorten(str(exc))})") from exc
    return expr


class _Printer(sp.printing.str.StrPrinter):
    """sympy's str printer, restricted to what ``parse_expression`` reads back."""

    def _print_Float(self, expr):
        v = float(expr)
        if not math.isfinite(v):
            raise ModelFileError(f"the number {expr} cannot be written to a model file")
        return repr(v)

    def _print_Exp1(self, expr):
        return "exp(1)"

    def _print_ImaginaryUnit(self, expr):
        raise ModelFileError("complex numbers cannot be written to a model file")

    def _print_Function(self, expr):
        name = expr.func.__name__
        if name not in FUNCTIONS:
            raise ModelFileError(f"the function {name} is not in the model-file language "
                                 f"({_fnames()}); it cannot be written")
        return super()._print_Function(expr)


def expression_text(expr) -> str:
    """``expr`` as model-file text (refuses what the reader would refuse)."""
    return _Printer({"order": None}).doprint(expr)


