"""Model files: the safe expression parser, reading, writing and the round trip."""

import builtins
import pathlib
import time

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh.strategies as jst
from jetnh import JetSpace, System, models
from jetnh import modelfile as mf
from jetnh.constraints import PRINCIPLES
from jetnh.errors import JetnhError, ModelFileError
from jetnh.testing import vanishes

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
    assert (s2.L, s2.constraints, s2.dependent, s2.defaults, s2.name) == \
        (s.L, s.constraints, s.dependent, s.defaults, s.name)
    assert m.initial == init and m.principle == "suslov"
    assert m.simulation == {"t_end": 2.0, "method": "rk4", "points": 11}


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
@given(jst.constrained_systems(max_n=3))
def test_random_systems_round_trip(case):
    J, L, cons, dep = case
    s = System(J, L, cons, dep)
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
    (dict(constraints='["y"]'), "holonomic"),
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
