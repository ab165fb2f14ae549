"""Model files: the safe expression parser, reading, writing and the round trip."""

import ast
import builtins
import os
import pathlib
import subprocess
import sys
import time

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh.strategies as jst
from jetnh import JetSpace, System, models
from jetnh import modelfile as mf
from jetnh.mechanics.system import PRINCIPLES
from jetnh.errors import JetnhError, ModelFileError
from jetnh.algebra.zero import vanishes
from deadline import deadline

EXAMPLES = sorted((pathlib.Path(__file__).resolve().parents[1] / "examples").glob("*.toml"))

DESIGN_EXAMPLE = '''
name = "vertical rolling disk"
coordinates = ["x", "y", "phi", "psi"]
dependent = ["x", "y"]
lagrangian = "(x_t**2 + y_t**2)/2 + (I1*phi_t**2 + I2*psi_t**2)/2"
constraints = ["x_t - R*cos(psi)*phi_t", "y_t - R*sin(psi)*phi_t"]
[parameters]
R = 1.0
I1 = 0.5
I2 = 0.25
[initial]
phi_t = 1.0
psi_t = 0.7
'''

x, x_t, y, t, a = sp.symbols("x x_t y t a")
NAMES = {"x": x, "x_t": x_t, "y": y, "t": t, "a": a}


def parse(text):
    return mf.parse_expression(text, NAMES)


# ---------------------------------------------------------------------- the language
@pytest.mark.parametrize("text, expected", [
    ("x_t**2/2 - a*sin(x)", x_t**2 / 2 - a * sp.sin(x)),
    ("-x + +y", -x + y),
    ("(x + 1)**2 * 3 / 4", sp.Rational(3, 4) * (x + 1)**2),
    ("x**-2", x**-2),
    ("2**0.5 * x", sp.Float(2**0.5) * x),
    ("atan2(y, x) + Abs(x) + abs(y) + sign(x)",
     sp.atan2(y, x) + sp.Abs(x) + sp.Abs(y) + sp.sign(x)),
    ("sqrt(1 + x**2) + exp(-t) + log(2 + cos(x))",
     sp.sqrt(1 + x**2) + sp.exp(-t) + sp.log(2 + sp.cos(x))),
    ("pi*x", sp.pi * x),
    ("x\n  + y", x + y),                        # line breaks are white space
    ("1/3", sp.Rational(1, 3)),                 # exact
    ("sinh(x)*cosh(y)*tanh(t)*asinh(x)*atan(y)*tan(x)*sec(x)*csc(y)*cot(t)",
     sp.sinh(x) * sp.cosh(y) * sp.tanh(t) * sp.asinh(x) * sp.atan(y) * sp.tan(x) * sp.sec(x)
     * sp.csc(y) * sp.cot(t)),
    (" + ".join(f"{k}*x" for k in range(1, 400)), sum(range(1, 400)) * x),   # long chains
])
def test_accepted(text, expected):
    assert parse(text) == expected


HOSTILE = [
    # (text, words the message must contain, quoted offending text)
    ("__import__('os').system('touch /tmp/jetnh_pwned')", "attribute access", "__import__"),
    ("__import__('os')", "double underscores", "__import__"),
    ("open('/tmp/jetnh_pwned', 'w')", "not an allowed function", "open("),
    ("eval('1')", "not an allowed function", "eval("),
    ("exec('import os')", "not an allowed function", "exec("),
    ("x.__class__", "attribute access", "x.__class__"),
    ("sin.__globals__", "attribute access", "sin.__globals__"),
    ("x[0]", "subscripts", "x[0]"),
    ("lambda: 1", "lambdas", "lambda"),
    ("[c for c in ()]", "comprehensions", "[c for c"),
    ("(c for c in ())", "comprehensions", "c for c"),
    ("'text'", "strings", "'text'"),
    ("b'x'", "strings", "b'x'"),
    ("f'{x}'", "f-strings", "f'{x}'"),
    ("sin(x=1)", "keyword arguments", "sin(x=1)"),
    ("sin(*x)", "starred", "*x"),
    ("x if y else t", "conditional", "x if y"),
    ("x < y", "comparisons", "x < y"),
    ("x and y", "boolean", "x and y"),
    ("not x", "not", "not x"),
    ("~x", "~", "~x"),
    ("x // 2", "//", "x // 2"),
    ("x % 2", "%", "x % 2"),
    ("x @ y", "@", "x @ y"),
    ("x ^ y", "^", "x ^ y"),
    ("(x := 1)", "assignment", "x := 1"),
    ("[x, y]", "lists", "[x, y]"),
    ("(x, y)", "tuples", "x, y"),
    ("{x: y}", "dictionaries", "{x: y}"),
    ("foo + x", "unknown name", "foo"),
    ("x(1)", "not a function", "x(1)"),
    ("sin", "is a function", "sin"),
    ("sin(x)(y)", "calls of expressions", "sin(x)(y)"),
    ("atan2(x)", "takes 2 arguments", "atan2(x)"),
    ("1j * x", "complex", "1j"),
    ("None", "not a number", "None"),
    ("True + x", "not a number", "True"),
    ("9**9**9", "exponents", "9**9**9"),
    ("2**(-65)", "exponents", "2**(-65)"),
    ("(x + 1)**64 * (x + 1)", "exponent 65", "(x + 1)**64"),
    ("((x_t + 1)**64 + 1)**64", "10000 terms", "((x_t + 1)**64 + 1)**64"),
    ("sin((x + y + t + a)**64)", "10000 terms", "(x + y + t + a)**64"),
    ("(10**40)**6", "digits", "(10**40)**6"),
    ("1" * 41, "digits", "1111"),
    ("exp(exp(exp(100)))", "overflows", "exp(exp(100))"),
    ("1e308 * 10", "finite", "1e308 * 10"),
    ("1e400", "finite", "1e400"),
    ("1/0", "division by zero", "1/0"),
    ("x/(1 - 1)", "division by zero", "x/(1 - 1)"),
    ("log(0)", "domain of log", "log(0)"),
    ("sqrt(-1)", "domain of sqrt", "sqrt(-1)"),
    ("acos(2) * x", "domain of acos", "acos(2)"),
    ("tan(pi/2)", "infinite or undefined", "tan(pi/2)"),
    ("0**-1", "undefined", "0**-1"),
    ("x +", "not a valid expression", "x +"),
    ("import os", "not a valid expression", "import os"),
    ("x; y", "not a valid expression", "x; y"),
]


@pytest.mark.parametrize("text, words, quoted", HOSTILE)
def test_refused_with_quote_and_position(text, words, quoted):
    with pytest.raises(ModelFileError) as info:
        parse(text)
    msg = str(info.value)
    assert words in msg, msg
    assert quoted in msg, msg
    assert "line 1, column" in msg, msg


def test_position_in_multiline_expression():
    with pytest.raises(ModelFileError, match=r"'y\.real' at line 3, column 5"):
        parse("x +\n  1 +\n    y.real")
    with pytest.raises(ModelFileError, match=r"'foo' at line 2, column 5"):
        parse("x\n  + foo")


def test_limits():
    with pytest.raises(ModelFileError, match="characters"):
        parse("x + " * (mf.MAX_CHARS // 4) + "x")
    with pytest.raises(ModelFileError, match="syntax nodes"):
        parse("+".join(["sin(x)"] * (mf.MAX_NODES // 3)))
    with pytest.raises(ModelFileError, match="nest"):
        parse("sin(" * (mf.MAX_DEPTH + 5) + "x" + ")" * (mf.MAX_DEPTH + 5))
    with pytest.raises(ModelFileError, match="nest"):
        parse("-" * 3000 + "x")
    with pytest.raises(ModelFileError):
        parse("(" * 300 + "x" + ")" * 300)
    for bad in ("", "   ", 3, None, "x\x00"):
        with pytest.raises(ModelFileError):
            parse(bad)


def test_towers_are_refused_fast():
    for text in ("9**9**9**9", "2**2**2**2**2**2", "((x*10**3)**64)**64",
                 "exp(exp(exp(exp(9))))", "10.0**10**10", "exp(100)**exp(100)",
                 "sqrt(" + "*".join(["123456789"] * 30) + ")",
                 "((x_t + 1)**64 + 1)**64", "(" + "+".join(["x"] * 99) + "+y)**64"):
        t0 = time.perf_counter()
        with pytest.raises(ModelFileError):
            parse(text)
        assert time.perf_counter() - t0 < 2.0, text


CANARY = "/tmp/jetnh_modelfile_canary"
PAYLOADS = [
    f"__import__('os').system('touch {CANARY}')",
    f"open('{CANARY}', 'w')",
    f"eval(\"open('{CANARY}', 'w')\")",
    f"exec(\"open('{CANARY}', 'w')\")",
    f"(lambda: open('{CANARY}', 'w'))()",
    f"[open('{CANARY}', 'w') for _ in (1,)]",
    f"sin.__globals__['__builtins__']['open']('{CANARY}', 'w')",
    f"x.__class__.__mro__[-1].__subclasses__()",
    f"Symbol('x').__reduce__()",
    f"sympify(\"open('{CANARY}', 'w')\")",
    f"parse_expr(\"open('{CANARY}', 'w')\")",
    f"getattr(x, 'evalf')()",
    f"globals()['__builtins__']",
]


@pytest.fixture
def no_execution(monkeypatch):
    """Make eval, exec, sympify, parse_expr and compile-to-code explode while the parser
    runs (compiling to a syntax tree only, as ast.parse does, stays allowed)."""
    import ast

    import sympy.parsing.sympy_parser as sps

    def boom(*a, **k):
        raise AssertionError("the model-file parser must not evaluate strings")
    real_compile = builtins.compile

    def ast_only(source, filename, mode, flags=0, *a, **k):
        if not flags & ast.PyCF_ONLY_AST:
            boom()
        return real_compile(source, filename, mode, flags, *a, **k)
    for mod, name in ((builtins, "eval"), (builtins, "exec"), (sp, "sympify"),
                      (sps, "parse_expr")):
        monkeypatch.setattr(mod, name, boom)
    monkeypatch.setattr(builtins, "compile", ast_only)
    pathlib.Path(CANARY).unlink(missing_ok=True)
    yield
    assert not pathlib.Path(CANARY).exists(), "a payload was executed"


@pytest.mark.parametrize("payload", PAYLOADS)
def test_payloads_are_not_executed(payload, no_execution):
    with pytest.raises(ModelFileError):
        parse(payload)


def test_valid_expressions_parse_without_eval(no_execution):
    expected = x_t**2 / 2 - a * sp.cos(x) + sp.sqrt(1 + y**2)
    assert parse("x_t**2/2 - a*cos(x) + sqrt(1 + y**2)") == expected


# hostile fragments for the random expressions: some allowed, some not
_ATOMS = ["x", "y", "x_t", "t", "a", "pi", "1", "2", "0", "0.5", "1e308", "9", "64", "65",
          "foo", "__import__", "open", "'s'", "None", "x.y", "x[0]", "1j", "lambda: 0",
          f"open('{CANARY}','w')", f"__import__('os').system('touch {CANARY}')"]
_FUNCS = ["sin", "cos", "exp", "log", "sqrt", "atan2", "Abs", "eval", "exec", "getattr",
          "__import__", "open", "sympify", "x", "(lambda v: v)"]
_OPS = ["+", "-", "*", "/", "**", "//", "%", "@", "<", "and", "|", ".", ","]


@st.composite
def hostile_expressions(draw, depth=4):
    if depth == 0 or draw(st.integers(0, 3)) == 0:
        return draw(st.sampled_from(_ATOMS))
    kind = draw(st.integers(0, 4))
    if kind == 0:
        return f"{draw(hostile_expressions(depth - 1))} {draw(st.sampled_from(_OPS))} " \
               f"{draw(hostile_expressions(depth - 1))}"
    if kind == 1:
        args = draw(st.lists(hostile_expressions(depth - 1), min_size=0, max_size=3))
        return f"{draw(st.sampled_from(_FUNCS))}({', '.join(args)})"
    if kind == 2:
        return f"({draw(hostile_expressions(depth - 1))})"
    if kind == 3:
        op = draw(st.sampled_from(["-", "+", "not ", "~"]))
        return f"{op}{draw(hostile_expressions(depth - 1))}"
    return f"{draw(hostile_expressions(depth - 1))}**{draw(hostile_expressions(depth - 1))}"


def _only_documented_errors(text):
    try:
        out = parse(text)
    except ModelFileError:
        return
    assert isinstance(out, sp.Basic)
    assert out.free_symbols <= set(NAMES.values())


@settings(max_examples=200)
@given(hostile_expressions())
def test_random_hostile_expressions(text):
    pathlib.Path(CANARY).unlink(missing_ok=True)
    _only_documented_errors(text)
    assert not pathlib.Path(CANARY).exists()


_CHARS = list("xyat_0123456789.+-*/()e ,'\"[]:=lambd\\\n%^&|<>~!@#")


@settings(max_examples=200)
@given(st.text(alphabet=st.sampled_from(_CHARS), max_size=60))
def test_random_text(text):
    _only_documented_errors(text)


@settings(max_examples=100)
@given(st.text(max_size=40))
def test_random_unicode(text):
    _only_documented_errors(text)


# ---------------------------------------------------------------------- model files
def test_design_example():
    m = mf.loads(DESIGN_EXAMPLE)
    disk = models.rolling_disk()
    assert m.name == "vertical rolling disk"
    assert m.system.L == disk.L and m.system.constraints == disk.constraints
    assert m.system.dependent == disk.dependent and m.system.defaults == disk.defaults
    assert m.initial == {"phi_t": 1.0, "psi_t": 0.7}
    assert m.parameters == {"R": 1.0, "I1": 0.5, "I2": 0.25}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_examples_load_and_derive(path):
    m = mf.load(path)
    assert m.system.equations(m.principle or "chetaev").accelerations()
    assert "t_end" in m.simulation


@pytest.mark.parametrize("name", list(models.CATALOGUE))
def test_catalogue_round_trip(name):
    opts = {"n_trailer": {"N": 1}}.get(name, {})
    s = models.get(name, **opts)
    init = models.initial(name, **opts)
    text = mf.dumps(s, init, principle="suslov", simulation={"t_end": 2.0, "method": "rk4",
                                                             "points": 11})
    m = mf.loads(text)
    s2 = m.system
    assert (s2.L, s2.constraints, s2.dependent, s2.defaults, s2.name, s2.forces,
            s2.dissipation) == (s.L, s.constraints, s.dependent, s.defaults, s.name,
                                s.forces, s.dissipation)
    assert m.initial == init and m.principle == "suslov"
    assert m.simulation == {"t_end": 2.0, "method": "rk4", "points": 11}


def test_the_model_record_is_frozen_and_written_whole():
    """A Model (the record of the catalogue and of model files) is immutable and equal by
    content; dumps(model) writes it with its defaults, and reading that gives it back."""
    import dataclasses

    from jetnh.errors import FrozenError

    m = mf.loads(_file(**{"[initial]": "y = 0.2\nx_t = 1.0", "[integrals]": 'p = "x_t*y"',
                          "[simulation]": 't_end = 3.0\nmethod = "dopri5"'}), "m.toml")
    back = mf.loads(mf.dumps(m, principle="suslov"), "m.toml")
    assert back == dataclasses.replace(m, principle="suslov") and back != m
    assert hash(back) == hash(dataclasses.replace(m, principle="suslov"))
    assert mf.loads(mf.dumps(back), "m.toml") == back
    with pytest.raises(FrozenError):
        m.initial["y"] = 0.0
    with pytest.raises(FrozenError):
        m.simulation.update(t_end=1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.principle = "vakonomic"
    other = m.with_split(["x"])
    assert [q.name for q in other.system.dependent] == ["x"] and other.initial == m.initial
    assert [q.name for q in m.system.dependent] != ["x"]


@pytest.mark.parametrize("name", ["rolling_disk", "appell_hamel", "suslov_rigid_body"])
def test_round_trip_gives_the_same_equations(name, tmp_path):
    s = models.get(name)
    path = mf.dump(s, tmp_path / "m.toml", models.initial(name))
    s2 = mf.load(path).system
    for principle in PRINCIPLES:
        e1, e2 = s.equations(principle), s2.equations(principle)
        assert e1.expressions == e2.expressions, principle
    a1 = s.equations("vakonomic").accelerations()
    a2 = s2.equations("vakonomic").accelerations()
    assert a1 == a2


def same(a, b):
    """Equal as expressions: the parser builds with sympy's automatic evaluation, so a
    product such as 2*(t**2 + 1) that was built unevaluated comes back distributed."""
    return a == b or sp.expand(a - b) == 0 or vanishes(a - b)


@settings(max_examples=15)
@given(jst.systems(max_n=3))
def test_random_systems_round_trip(s):
    s2 = mf.loads(mf.dumps(s)).system
    assert s2.dependent == s.dependent and same(s2.L, s.L)
    assert all(same(f2, f) for f2, f in zip(s2.constraints, s.constraints, strict=True))
    e1, e2 = s.equations("chetaev").expressions, s2.equations("chetaev").expressions
    assert all(same(a, b) for a, b in zip(e1, e2, strict=True))


@settings(max_examples=50)
@given(jst.jet_spaces(max_n=3).flatmap(lambda J: st.tuples(st.just(J), jst.jet_expressions(J))))
def test_random_expressions_round_trip(case):
    J, e = case
    names = {s.name: s for s in (J.t,) + J.q + J.qd}
    assert same(mf.parse_expression(mf.expression_text(e), names), e)


def test_floats_round_trip_exactly():
    J = JetSpace("x")
    s = System(J, J.qd[0]**2 * sp.Float(0.1 + 0.2) / 2, [], None)
    assert mf.loads(mf.dumps(s)).system.L == s.L


def test_writer_refuses_what_the_reader_refuses():
    J = JetSpace("x")
    f = sp.Function("f")
    with pytest.raises(ModelFileError, match="not in the model-file language"):
        mf.dumps(System(J, J.qd[0]**2 / 2 + f(J.q[0]), [], None))
    k = sp.Symbol("k")
    with pytest.raises(ModelFileError, match="no values"):
        mf.dumps(System(J, J.qd[0]**2 / 2 - k * J.q[0]**2, [], None))
    assert "k = 2.0" in mf.dumps(System(J, J.qd[0]**2 / 2 - k * J.q[0]**2, [], None),
                                 params={"k": 2})


def _file(**over):
    base = {"coordinates": '["x", "y", "z"]', "lagrangian": '"(x_t**2 + y_t**2 + z_t**2)/2"',
            "constraints": '["z_t - y*x_t"]'}
    base.update(over)
    tables = {k: v for k, v in base.items() if k.startswith("[")}
    lines = [f"{k} = {v}" for k, v in base.items() if v is not None and not k.startswith("[")]
    for k, v in tables.items():
        lines.append(f"{k}\n{v}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("over, words", [
    (dict(coordinates=None), "missing key 'coordinates'"),
    (dict(lagrangian=None), "missing key 'lagrangian'"),
    (dict(lagrangain='"x"'), "unknown key 'lagrangain'"),
    (dict(coordinates='"x y"'), "'coordinates' must be a list of strings"),
    (dict(coordinates="[]"), "'coordinates' is empty"),
    (dict(coordinates='["x", "x", "z"]'), "x given twice"),
    (dict(coordinates='["x", "y", "z_t"]'), "ends in '_t'"),
    (dict(coordinates='["x", "y", "t"]'), "reserved (time)"),
    (dict(coordinates='["x", "y", "sin"]'), "reserved (a function)"),
    (dict(coordinates='["x", "y", "__z"]'), "not a usable name"),
    (dict(coordinates='["x", "y", "lambda"]'), "not a usable name"),
    (dict(lagrangian="3"), "expected an expression in a string"),
    (dict(lagrangian='"x_tt"'), "accelerations"),
    (dict(lagrangian='"k*x_t**2"'), "unknown name"),
    (dict(constraints='"z_t"'), "must be a list of strings"),
    (dict(constraints='["z_t - y*x_t", 1]'), "must be a list of strings"),
    (dict(constraints='["t - 1"]'), "time only"),
    (dict(dependent='["w"]'), "'w' is not one of the coordinates"),
    (dict(dependent='["x", "y"]'), "dependent coordinates given for 1 constraints"),
    (dict(branch="-1"), "'branch' must be >= 0"),
    (dict(branch='"0"'), "'branch' must be an integer"),
    (dict(principle='"lagrange"'), "'principle' must be one of"),
    (dict(convention='"mine"'), "'convention' must be"),
    (dict(name="1"), "'name' must be a string"),
    ({"[parameters]": "k = 1.0"}, "k is used neither"),
    ({"[parameters]": 'k = "one"'}, "must be a number"),
    ({"[parameters]": "k = true"}, "must be a number"),
    ({"[parameters]": "k = nan"}, "must be finite"),
    ({"[parameters]": "x_t = 1.0"}, "reserved"),
    ({"[parameters]": "cos = 1.0"}, "reserved"),
    ({"[initial]": "w = 1.0"}, "'w' is not one of the coordinates, velocities"),
    ({"[initial]": 'x = "0"'}, "must be a number"),
    ({"[multipliers]": "lambda_x = 1.0"}, "'lambda_x' is not one of the multipliers"),
    ({"[integrals]": 'E = "x_t*lambda_q"'}, "unknown name"),
    ({"[simulation]": "t_stop = 1.0"}, "unknown key 't_stop'"),
    ({"[simulation]": 't_end = "1"'}, "must be a number"),
    ({"[simulation]": "rtol = -1.0"}, "must be positive"),
    ({"[simulation]": "points = 1"}, "points must be between"),
])
def test_file_errors(over, words):
    with pytest.raises(ModelFileError) as info:
        mf.loads(_file(**over), "m.toml")
    assert words in str(info.value) and "m.toml" in str(info.value), str(info.value)


def test_expansion_bomb_in_a_file_is_refused_fast():
    t0 = time.perf_counter()
    with pytest.raises(ModelFileError, match="terms"):
        mf.loads('coordinates = ["x", "z"]\nlagrangian = "(x_t**2 + z_t**2)/2"\n'
                 'constraints = ["z_t - ((x_t + 1)**64 + 1)**64"]\n')
    assert time.perf_counter() - t0 < 2.0
    many = ", ".join(f'"q{i}"' for i in range(mf.MAX_COORDINATES + 1))
    with pytest.raises(ModelFileError, match="coordinates; the limit"):
        mf.loads(f'coordinates = [{many}]\nlagrangian = "q0_t**2"\n')


def test_file_level_errors(tmp_path):
    with pytest.raises(ModelFileError, match="not valid TOML"):
        mf.loads('coordinates = ["x"\n')
    with pytest.raises(ModelFileError, match="no such file"):
        mf.load(tmp_path / "missing.toml")
    with pytest.raises(ModelFileError, match="is a directory"):
        mf.load(tmp_path)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * mf.MAX_FILE_BYTES)
    with pytest.raises(ModelFileError, match="limit"):
        mf.load(big)
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"name = \"\xff\"\n")
    with pytest.raises(ModelFileError, match="UTF-8"):
        mf.load(bad)
    assert issubclass(ModelFileError, JetnhError)


def test_multipliers_integrals_and_simulation():
    m = mf.loads(_file(**{"[multipliers]": "lambda_z = 0.5",
                          "[initial]": "y = 0.2\nx_t = 1.0",
                          "[integrals]": 'p = "x_t - lambda_z*y"',
                          "[simulation]": 't_end = 3.0\nmethod = "dopri5"'}))
    assert m.initial == {"y": 0.2, "x_t": 1.0, "lambda_z": 0.5}
    lam = sp.Symbol("lambda_z")
    assert m.integrals["p"] == sp.Symbol("x_t") - lam * sp.Symbol("y")
    assert m.simulation == {"t_end": 3.0, "method": "dopri5"}
    with pytest.raises(ModelFileError, match="given in \\[initial\\] and in \\[multipliers\\]"):
        mf.loads(_file(**{"[multipliers]": "lambda_z = 0.5", "[initial]": "lambda_z = 0.1"}))


# ---------------------------------------------------------------------- the trust boundary
# One test per class of hostile input: the file itself, the cost of building expressions,
# identifiers that change meaning, and functions that cannot go through the derivation.

SMALL = 'coordinates = ["x", "y"]\nlagrangian = "(x_t**2 + y_t**2)/2"\n' \
        'constraints = ["y_t - x*x_t"]\n'


def test_only_regular_files_are_read(tmp_path):
    """Class 1: file type and size. A FIFO blocked forever and a symlink to /dev/zero
    read gigabytes (stat says size 0); now both are refused at once."""
    fifo = tmp_path / "model.toml"
    os.mkfifo(fifo)
    with deadline(5, "load(FIFO)"), pytest.raises(ModelFileError) as info:
        mf.load(fifo)
    assert "FIFO" in str(info.value) and "regular file" in str(info.value)
    zero = tmp_path / "zero.toml"
    zero.symlink_to("/dev/zero")
    with deadline(5, "load(-> /dev/zero)"), pytest.raises(ModelFileError,
                                                          match="character device, not a "
                                                                "regular file"):
        mf.load(zero)
    with pytest.raises(ModelFileError, match="is a directory, not a regular file"):
        mf.load(tmp_path)
    with pytest.raises(ModelFileError, match="no such file; check the path"):
        mf.load(tmp_path / "missing.toml")
    dangling = tmp_path / "dangling.toml"
    dangling.symlink_to(tmp_path / "nowhere")
    with pytest.raises(ModelFileError, match="no such file"):
        mf.load(dangling)
    link = tmp_path / "link.toml"                   # a symlink to a regular file is fine
    (tmp_path / "real.toml").write_text(SMALL)
    link.symlink_to(tmp_path / "real.toml")
    assert mf.load(link).system.J.n == 2
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b'name = "ok"\nlagrangian = "\xff"\n')
    with pytest.raises(ModelFileError, match=r"byte 0xFF at line 2, column 15 .* save the file "
                                             "as UTF-8"):
        mf.load(bad)
    nul = tmp_path / "nul.toml"
    nul.write_bytes(SMALL.encode() + b"# \x00\n")
    with pytest.raises(ModelFileError, match=r"NUL byte at line 4, column 3"):
        mf.load(nul)
    with pytest.raises(ModelFileError, match="NUL character at line 1"):
        mf.loads("x = 1\x00")
    with pytest.raises(ModelFileError, match="a str or a Path"):
        mf.load(3)
    with pytest.raises(ModelFileError, match="cannot open"):
        mf.load("bad\x00path.toml")
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + SMALL.encode())
    assert mf.load(bom).system.J.n == 2


def test_read_is_bounded_whatever_the_size_claims(tmp_path, monkeypatch):
    """Class 1: at most MAX_FILE_BYTES + 1 bytes are read, even when stat lies (files
    of /proc report size 0)."""
    f = tmp_path / "m.toml"
    f.write_text(SMALL + "# " + "x" * 5000 + "\n")
    monkeypatch.setattr(mf, "MAX_FILE_BYTES", 4096)
    real_fstat = os.fstat

    class Lying:
        def __init__(self, st):
            self.st_mode, self.st_size = st.st_mode, 0
    monkeypatch.setattr(os, "fstat", lambda fd: Lying(real_fstat(fd)))
    reads = []
    real_read = os.read
    monkeypatch.setattr(os, "read", lambda fd, n: reads.append(n) or real_read(fd, n))
    with pytest.raises(ModelFileError, match="more than 4096 bytes"):
        mf.load(f)
    assert sum(reads) <= 4097


def test_expression_cost_is_bounded():
    """Class 2: twelve nested tanh took minutes inside the parser (sympy's real-part test
    of tanh expands real and imaginary parts); the derivative of tanh of a 100-term sum
    does not return; a product of 1000 factors took seconds (built one factor at a time)."""
    names = {"x": x, "x_t": x_t, "y": y, "t": t, "a": a}
    cases = [
        ("tanh(" * 12 + "x" + ")" * 12, "nested 12 deep"),
        ("sin(" * 6 + "x" + ")" * 6, "nested 6 deep"),
        ("tanh(sin(x))", "tanh of an expression holding function calls"),
        ("cosh(x**0.5)", "cosh of an expression holding function calls"),
        ("tanh(" + " + ".join(["a*x_t"] * 20) + ")", "the argument of tanh has"),
        (" + ".join(f"sin(cos(atan({k}*x)))" for k in range(1, 200)), "MAX_CALL_COST"),
        ("exp(exp(exp(exp(10))))", "overflows"),
        ("10**10**10", "exponents"),
        ("10.0**10.0**10.0", "overflows"),
    ]
    for text, words in cases:
        with deadline(3, text[:40]), pytest.raises(ModelFileError) as info:
            mf.parse_expression(text, names)
        assert words in str(info.value), str(info.value)
    ps = sp.symbols("p0:1000")
    with deadline(3, "a product of 1000 factors"):
        big = mf.parse_expression("*".join(p.name for p in ps) + "/x",
                                  {**names, **{p.name: p for p in ps}})
    assert big == sp.Mul(*ps) / x
    with deadline(3, "five nested calls"):
        mf.parse_expression("sin(cos(atan(exp(sqrt(1 + x**2)))))", names)


def test_expression_build_errors_become_model_file_errors(monkeypatch):
    """Class 2: whatever sympy raises while building (OverflowError, RecursionError,
    MemoryError, ValueError, ...) is a ModelFileError."""
    for exc in (OverflowError("big"), RecursionError(), MemoryError(), ValueError("v"),
                KeyError("internal")):
        def boom(*a, exc=exc):
            raise exc
        monkeypatch.setattr(sp, "Mul", boom)
        with pytest.raises(ModelFileError, match="sympy cannot build the expression|too "
                                                 "deeply nested"):
            mf.parse_expression("x*y", NAMES)
        monkeypatch.undo()


def _model(n, cons, L=None, extra=""):
    coords = ", ".join(f'"q{i}"' for i in range(n))
    L = L or " + ".join(f"q{i}_t**2" for i in range(n))
    c = ", ".join(f'"{f}"' for f in cons)
    return f'coordinates = [{coords}]\nlagrangian = "{L}"\nconstraints = [{c}]\n{extra}'


def test_model_limits_are_honest():
    """Class 2: what the limits allow reads in seconds (100 coordinates with 16
    constraints took 0.8 s before the rank test became exact; 30 with 29 took 22 s; the
    constraints complex everywhere sent the rank test to symbolic algebra: 4 of them took
    13 s); beyond the limits, a refusal at once."""
    n, k = mf.MAX_SPLIT_COST // mf.MAX_CONSTRAINTS, mf.MAX_CONSTRAINTS
    per = mf.MAX_JACOBIAN_COST // n // k
    cons = []
    for i in range(k):
        c, j = f"q{i}_t", 0
        while True:
            more = c + f" - sin(q{(i + j) % n})*q{(i + j + 1) % n}_t"
            if sum(1 for _ in ast.walk(ast.parse(more, mode="eval"))) > per:
                break
            c, j = more, j + 1
        cons.append(c)
    t0 = time.monotonic()
    with deadline(20, "the largest allowed split"):
        m = mf.loads(_model(n, cons))
    assert len(m.system.dependent) == k
    print(f"largest split: {time.monotonic() - t0:.2f} s")
    refusals = [
        (_model(mf.MAX_COORDINATES + 1, []), "the limit is"),
        (_model(mf.MAX_CONSTRAINTS + 2, [f"q{i}_t - q0_t" for i in range(1, mf.MAX_CONSTRAINTS + 2)]),
         "constraints; the limit"),
        (_model(60, [f"q{i}_t - q0_t" for i in range(1, 10)]), "MAX_SPLIT_COST"),
        (_model(30, [" + ".join(f"q{i}_t*q{j}" for i in range(30) for j in range(4))]),
         "MAX_JACOBIAN_COST"),
        (_model(6, [f"q{i}_t - acos(3 + q{i + 1}**2)*q0_t" for i in range(1, 5)]),
         "not all finite and real"),
    ]
    for text, words in refusals:
        with deadline(3, words), pytest.raises(ModelFileError) as info:
            mf.loads(text)
        assert words in str(info.value), str(info.value)


def test_reading_never_solves_the_constraints():
    """Class 2: with a branch, System solved the constraints at construction; a general
    quartic (or two coupled quadratics) did not return within minutes."""
    quartic = _model(3, ["q1_t**4 + q0*q1_t**3 + q0_t*q1_t**2 + q2*q1_t + 1"],
                     extra='dependent = ["q1"]\nbranch = 0\n')
    with deadline(5, "reading a quartic with a branch"):
        m = mf.loads(quartic)
    assert m.system.branch == 0


def test_file_node_and_call_budgets_are_shared():
    """Class 2: the expressions of a file share one budget (a file of many expressions
    each under the per-expression limits cannot multiply the cost)."""
    towers = " + ".join(f"sin(cos(atan(exp(q0*{k}))))" for k in range(1, 60))
    extra = "[integrals]\n" + "".join(f'I{i} = "{towers}"\n' for i in range(3))
    with deadline(5, "shared budget"), pytest.raises(ModelFileError, match="MAX_CALL_COST"):
        mf.loads(_model(2, [], extra=extra))
    polys = " + ".join(f"q0_t*q1*{k}" for k in range(1, 400))
    extra = "[integrals]\n" + "".join(f'I{i} = "{polys}"\n' for i in range(5))
    with deadline(5, "shared nodes"), pytest.raises(ModelFileError, match="MAX_FILE_NODES"):
        mf.loads(_model(2, [], extra=extra))


@pytest.mark.parametrize("text, where, char", [
    ('lagrangian = "\uff58_t**2/2"', "lagrangian", "U+FF58"),            # fullwidth x
    ('lagrangian = "x_t**2/2 + \U0001d465"', "lagrangian", "U+1D465"),   # math italic x
    ('lagrangian = "x_t**2/2 + x\u2002"', "lagrangian", "U+2002"),        # en space
    ('coordinates = ["x", "\uff59"]', "coordinates", "U+FF59"),
    ('dependent = ["\uff59"]', "dependent", "U+FF59"),
    ('[parameters]\n"\uff4b" = 1.0', "parameters", "U+FF4B"),
    ('[initial]\n"\uff58" = 1.0', "initial", "U+FF58"),
    ('[integrals]\n"\uff25" = "x_t"', "integrals", "U+FF25"),
    ('"n\u0430me" = "cyrillic a"', "n\u0430me", "U+0430"),
])
def test_non_ascii_identifiers_are_refused(text, where, char):
    """Class 3: Python's parser folds U+FF58 into 'x' (NFKC), so 'ｘ_t' silently meant x_t;
    every name and expression must be ASCII, and the refusal names the character."""
    base = {"coordinates": 'coordinates = ["x", "y"]', "lagrangian":
            'lagrangian = "(x_t**2 + y_t**2)/2"', "constraints": 'constraints = ["y_t - x*x_t"]'}
    key = text.split(" =")[0] if not text.startswith("[") else None
    lines = [v for k, v in base.items() if k != key] + [text]
    tables = [ln for ln in lines if ln.startswith("[")]
    src = "\n".join([ln for ln in lines if not ln.startswith("[")] + tables) + "\n"
    with pytest.raises(ModelFileError) as info:
        mf.loads(src, "m.toml")
    msg = str(info.value)
    assert char in msg and "ASCII" in msg and "m.toml" in msg, msg
    if char in ("U+FF58", "U+1D465"):
        assert "read it as 'x'" in msg, msg


def test_names_match_exactly_and_text_has_no_controls():
    """Class 3: a name with a trailing line break matched the name pattern ($ matches
    before a final newline); control characters in the name reached the terminal."""
    with pytest.raises(ModelFileError, match="not a usable name"):
        mf.loads('coordinates = ["x\\n", "y"]\nlagrangian = "y_t**2"\n')
    with pytest.raises(ModelFileError, match="control character U\\+001B"):
        mf.loads(SMALL + 'name = "\\u001b[2Jowned"\n')
    with pytest.raises(ModelFileError, match="control character U\\+202E"):
        mf.loads(SMALL + 'description = "abc\\u202Efed"\n')
    assert mf.loads(SMALL + 'description = "two\\nlines"\n').description == "two\nlines"


@pytest.mark.parametrize("fname", sorted(mf.FUNCTIONS))
def test_every_function_goes_through_the_derivation(fname):
    """Class 4: every whitelisted function either derives or is refused at load time.
    (Abs, abs and sign are derived: System keeps them as sqrt(u**2), u/sqrt(u**2).)"""
    arg = {"acosh": "2 + sin(x)", "log": "2 + sin(x)", "sqrt": "2 + sin(x)",
           "cot": "2 + sin(x)", "csc": "2 + sin(x)", "atan2": "x, 2 + cos(x)",
           "asin": "0.5*sin(x)", "acos": "0.5*sin(x)", "atanh": "0.5*sin(x)",
           "Abs": "x - 3", "abs": "x - 3", "sign": "x - 5"}.get(fname, "x")
    F = f"{fname}({arg})"
    m = mf.loads(f'coordinates = ["x", "y"]\nlagrangian = "(x_t**2 + y_t**2)/2 - {F}"\n'
                 f'constraints = ["y_t - (1 + {F}/10)*x_t"]\n')
    acc = m.system.equations("chetaev").accelerations()
    assert acc


@pytest.mark.parametrize("fname", ["floor", "ceiling", "Heaviside", "Min", "Max",
                                   "Piecewise", "Mod", "re", "im"])
def test_non_smooth_functions_are_refused_with_a_reason(fname):
    """Class 4: functions that cannot be differentiated are refused with the reason."""
    with pytest.raises(ModelFileError, match="not smooth.*need derivatives"):
        parse(f"{fname}(x) + x_t")


def test_cli_derives_and_simulates_every_function(tmp_path):
    """Class 4, end to end: one model using every whitelisted function, through
    `jetnh derive` and `jetnh simulate`."""
    terms = " + ".join(
        f"{f}({ {'acosh': '2 + sin(x)', 'log': '2 + sin(x)', 'sqrt': '2 + sin(x)', 'cot': '2 + sin(x)', 'csc': '2 + sin(x)', 'atan2': 'x, 2 + cos(x)', 'asin': '0.5*sin(x)', 'acos': '0.5*sin(x)', 'atanh': '0.5*sin(x)', 'tan': '0.3*sin(x)', 'sec': '0.3*sin(x)', 'Abs': 'x - 3', 'abs': 'x + 3', 'sign': 'x - 5', 'exp': '0.1*x'}.get(f, 'x') })"
        for f in sorted(mf.FUNCTIONS))
    path = tmp_path / "all.toml"
    path.write_text(f'coordinates = ["x", "y"]\nlagrangian = "(x_t**2 + y_t**2)/2 - k*({terms})"\n'
                    'constraints = ["y_t - (1 + 0.1*sin(x) + 0.01*tanh(x) + 0.01*Abs(x - 3))*x_t"]\n'
                    "[parameters]\nk = 0.1\n[initial]\nx_t = 1.0\n")
    jetnh = [sys.executable, "-m", "jetnh"]
    for args in (["derive", str(path), "--principle", "chetaev"],
                 ["simulate", str(path), "--t-end", "1"]):
        out = subprocess.run(jetnh + args, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr


def test_forces_and_dissipation_in_model_files():
    """[forces] and dissipation give the accelerations of the same System built in
    Python; a force on a non-coordinate is refused."""
    text = """
coordinates = ["x", "y"]
lagrangian = "(x_t**2 + y_t**2)/2"
constraints = ["y_t - x*x_t"]
dissipation = "c*y_t**2/2"
[forces]
x = "-k*x + sin(t)"
[parameters]
c = 0.5
k = 2.0
"""
    s = mf.loads(text).system
    J = s.J
    x, xd, yd = J.q[0], J.qd[0], J.qd[1]
    c, k = sp.symbols("c k")
    ref = System(J, (xd**2 + yd**2) / 2, [yd - x * xd], forces={x: -k * x + sp.sin(J.t)},
                    dissipation=c * yd**2 / 2)
    assert s.Q == ref.Q == (-k * x + sp.sin(J.t), -c * yd)
    for p in ("chetaev", "vakonomic"):
        a, b = s.equations(p).accelerations(), ref.equations(p).accelerations()
        assert all(sp.simplify(a[v] - b[v]) == 0 for v in b)
    with pytest.raises(ModelFileError, match=r"\[forces\]: 'z' is not one of the coordinates"):
        mf.loads(text.replace('x = "-k*x', 'z = "-k*x'))
    with pytest.raises(ModelFileError, match="used neither"):
        mf.loads(text.replace('dissipation = "c*y_t**2/2"\n', ""))
