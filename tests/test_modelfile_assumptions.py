"""Assumptions on parameters in model files (``[assumptions]``): written by ``dumps``,
read back as the same symbols, so that ``jetnh.compare``'s singular sets survive the round
trip; read from booleans only; files without them read as before."""

import builtins

import pytest
import sympy as sp
from hypothesis import assume, given, strategies as st

import jetnh as jn
from jetnh import modelfile as mf
from jetnh.errors import ModelFileError
from jetnh.modelfile.assumptions import ASSUMPTIONS

J = jn.JetSpace("x y th")
th = J.q[2]
xd, yd, thd = J.qd
VALUES = (-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0)


@st.composite
def parameters(draw, name):
    """A parameter with random facts among ASSUMPTIONS (consistent ones) and a value
    that satisfies them."""
    facts = draw(st.dictionaries(st.sampled_from(ASSUMPTIONS), st.booleans(), max_size=3))
    try:
        sym = sp.Symbol(name, **facts)
    except ValueError:                                   # contradicting facts
        assume(False)
    fits = [v for v in VALUES
            if all(getattr(sp.Integer(int(v)) if v.is_integer() else sp.Float(v),
                           f"is_{f}") is want for f in ASSUMPTIONS
                   if (want := getattr(sym, f"is_{f}")) is not None)]
    assume(fits)
    return sym, draw(st.sampled_from(fits))


def sleigh(m, I, a):
    """A sleigh whose mass m, inertia I and offset a are parameters: its singular sets
    hold m = 0 and I + a**2 m = 0 unless the assumptions rule them out."""
    (m, vm), (I, vI), (a, va) = m, I, a
    L = m * (xd**2 + yd**2) / 2 + I * thd**2 / 2
    return jn.System(J, L, [sp.sin(th) * xd - sp.cos(th) * yd + a * thd], dependent=[J.q[1]],
                     defaults={m: vm, I: vI, a: va})


@given(parameters("m"), parameters("I"), parameters("a"))
def test_round_trip_keeps_every_parameters_assumptions(m, I, a):
    system = sleigh(m, I, a)
    text = mf.dumps(system)
    back = mf.loads(text).system
    assert back == system
    for p in system.parameters:
        q, = [q for q in back.parameters if q.name == p.name]
        assert q == p and q.assumptions0 == p.assumptions0
    # the file states the fewest facts: each one written is needed
    table = [line for line in text.split("[assumptions]\n")[-1].splitlines()
             if " = { " in line]
    for line in table:
        name, facts = line.split(" = { ")
        stated = dict(f.split(" = ") for f in facts.rstrip(" }").split(", "))
        stated = {f: v == "true" for f, v in stated.items()}
        p, = [p for p in system.parameters if p.name == name]
        assert sp.Symbol(name, **stated) == p
        for f in stated:
            assert sp.Symbol(name, **{k: v for k, v in stated.items() if k != f}) != p


@given(parameters("m"), parameters("a"))
def test_compares_singular_sets_survive_the_round_trip(m, a):
    system = sleigh(m, (sp.Symbol("I", positive=True), 0.5), a)
    back = mf.loads(mf.dumps(system)).system
    for pair in (("vakonomic", "chetaev"), ("suslov", "chetaev")):
        before, after = jn.compare(system, *pair).singular, jn.compare(back, *pair).singular
        assert set(before) == set(after)


def test_singular_sets_in_closed_form():
    """m and I positive: only cos(th) = 0 is singular (I + a**2 m > 0); a plain m adds
    m = 0 and I + a**2 m = 0 — before and after the round trip alike."""
    m, I, a = sp.symbols("m I a", positive=True)
    positive = sleigh((m, 1.0), (I, 0.5), (a, 0.2))
    plain = sleigh((sp.Symbol("m"), 1.0), (sp.Symbol("I"), 0.5), (sp.Symbol("a"), 0.2))
    for system in (positive, mf.loads(mf.dumps(positive)).system):
        assert jn.compare(system, "vakonomic", "chetaev").singular == [sp.cos(th)]
    m0, I0, a0 = sp.symbols("m I a")
    for system in (plain, mf.loads(mf.dumps(plain)).system):
        assert set(jn.compare(system, "vakonomic", "chetaev").singular) == {
            sp.cos(th), m0, I0 + a0**2 * m0}


FILE = """coordinates = ["x"]
lagrangian = "m*x_t**2/2 - k*x**2/2"
[parameters]
m = 2.0
k = 3.0
"""


@pytest.fixture
def no_strings_evaluated(monkeypatch):
    """eval and exec explode, and so does sympify given a string (building the System
    sympifies sympy objects, which is allowed)."""
    def boom(*a, **k):
        raise AssertionError("the model-file reader must not evaluate strings")
    sympify = sp.sympify

    def objects_only(a, *args, **kw):
        if isinstance(a, str):
            boom()
        return sympify(a, *args, **kw)
    for mod, name, fake in ((builtins, "eval", boom), (builtins, "exec", boom),
                            (sp, "sympify", objects_only)):
        monkeypatch.setattr(mod, name, fake)


def test_the_file_states_them_and_reading_evaluates_nothing(no_strings_evaluated):
    model = mf.loads(FILE + '[assumptions]\nm = { positive = true }\n'
                            'k = { integer = true, nonnegative = true }\n')
    got = {p.name: p for p in model.system.parameters}
    assert got["m"] == sp.Symbol("m", positive=True)
    assert got["k"] == sp.Symbol("k", integer=True, nonnegative=True)
    assert model.system.defaults[got["k"]] == 3.0


def test_files_without_assumptions_read_as_before():
    model = mf.loads(FILE)
    assert set(model.system.parameters) == {sp.Symbol("m"), sp.Symbol("k")}
    assert "[assumptions]" not in mf.dumps(model)


@pytest.mark.parametrize("table, words", [
    ("m = { prime = true }", "'prime' is not an assumption a model file holds"),
    ("m = { positive = 1 }", "[assumptions] m: positive must be a boolean"),
    ("m = { positive = \"true\" }", "must be a boolean"),
    ("m = \"positive\"", "[assumptions] m must be a table"),
    ("x = { real = true }", "'x' is not one of the parameters (k, m)"),
    ("m = { positive = true, negative = true }", "the assumptions contradict each other"),
    ("m = { negative = true }", "m = 2.0 is not negative"),
    ("k = { integer = false }", "k = 3.0 is integer, which its assumptions exclude"),
])
def test_bad_assumptions_are_refused(table, words):
    with pytest.raises(ModelFileError) as info:
        mf.loads(FILE + "[assumptions]\n" + table + "\n")
    assert words in str(info.value)


@pytest.mark.parametrize("sym", [sp.Symbol("m", prime=True),
                                 sp.Symbol("m", extended_real=True)])
def test_assumptions_a_file_cannot_hold_are_refused_on_writing(sym):
    system = jn.System(jn.JetSpace("x"), sym * jn.JetSpace("x").qd[0]**2 / 2, [],
                       defaults={sym: 2.0})
    with pytest.raises(ModelFileError, match="that a model file cannot hold"):
        mf.dumps(system)


def test_two_parameters_of_one_name_are_refused_on_writing():
    X = jn.JetSpace("x")
    m1, m2 = sp.Symbol("m"), sp.Symbol("m", positive=True)
    system = jn.System(X, m1 * X.qd[0]**2 / 2 + m2 * X.q[0]**2, [])
    with pytest.raises(ModelFileError, match="two parameters named m"):
        mf.dumps(system, params={"m": 1.0})
