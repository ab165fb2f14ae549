"""Code generation (the graph emitter, exact printing, no user text in the source, the
Jacobian kernel) and the disk cache."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given, settings, strategies as st

import jetnh.strategies as jst

from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene, codegen, kernels
from jetnh.numeric.codegen import KernelSpec, text


def disk_system():
    """The catalogue's rolling disk without its default parameters (the tests give them)."""
    return models.rolling_disk().replace(defaults=None)


PARAMS = {"R": 1.5, "I1": 0.5, "I2": 0.25}


def test_printer_is_exact_and_cheap():
    x, y = sp.symbols("x y")
    p = text.print_expr
    assert float(p(sp.Float(0.1))) == 0.1
    v = 1 / 3
    assert float(p(sp.Float(v))) == v   # repr round-trips every double
    assert p(x**2) == "(x*x)"
    assert p(1 / x**3) == "(1.0/(x*x*x))"
    assert p(sp.sqrt(x)) == "math.sqrt(x)"
    assert p(sp.Rational(1, 4) * x).replace("(0.25)", "0.25") == "0.25*x"
    assert "**" in p(x**sp.Rational(3, 2))


def test_generated_source_renames_every_symbol():
    s = disk_system()
    ks = codegen.generate(KernelSpec(s, "vakonomic", PARAMS))
    src = ks.source
    for name in ("phi", "psi", "lambda", "R*", "I1", "I2"):
        assert name not in src.split("LAYOUT")[0], name
    assert "1.5" in src  # the parameter R is a compiled constant
    assert ks.layout.states == ("x", "y", "phi", "psi", "phi_t", "psi_t", "lambda_x", "lambda_y")
    assert ks.layout.dependent_velocities == ("x_t", "y_t")
    compile(src, "<kernels>", "exec")  # valid Python


def test_missing_parameter_in_codegen():
    with pytest.raises(JetnhError, match="no value: I2"):
        codegen.generate(KernelSpec(disk_system(), "chetaev", {"R": 1.0, "I1": 1.0}))


def test_key_depends_on_the_symbolic_input():
    s = disk_system()
    k1 = KernelSpec(s, "chetaev", PARAMS).key
    assert k1 == KernelSpec(disk_system(), "chetaev", dict(PARAMS)).key
    assert KernelSpec(s, "chetaev", PARAMS) == KernelSpec(disk_system(), "chetaev", PARAMS)
    assert k1 != KernelSpec(s, "vakonomic", PARAMS).key
    assert k1 != KernelSpec(s, "chetaev", dict(PARAMS, R=1.5000000000000002)).key
    assert k1 != KernelSpec(s, "chetaev", PARAMS, runtime_params=("R",)).key
    keys = {KernelSpec(s, "chetaev", PARAMS, variant=v).key
            for v in ("", "jacobian", "sensitivities", "discrete")}
    assert len(keys) == 4                     # each kernel set of a scene has its own key


def test_runtime_parameters(tmp_path):
    s = disk_system()
    ini = dict(x=0.0, y=0.0, phi=0.0, psi=0.0, phi_t=1.0, psi_t=0.5)
    sc = Scene(s, "chetaev", params=PARAMS, initial=ini, t_span=(0, 3), runtime_params=["R"],
               cache=False)
    a = sc.run(rtol=1e-11, atol=1e-13, save="final")
    b = sc.run(rtol=1e-11, atol=1e-13, save="final", params=[3.0])
    # x scales with R
    assert abs(b["x"][-1] / a["x"][-1] - 2.0) < 1e-9


SCRIPT = r"""
import json, sys, time
t0 = time.perf_counter()
import sympy as sp, jetnh as jn
from jetnh.mechanics.system import System
from jetnh.numeric import Scene
J = jn.JetSpace("x y z")
x, y, z = J.q
xd, yd, zd = J.qd
s = System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])
t1 = time.perf_counter()
sc = Scene(s, "chetaev", initial=dict(x=0, y=0, z=0, x_t=1, y_t=0.5), t_span=(0, 3))
k = sc.kernels
t2 = time.perf_counter()
tr = sc.run(rtol=1e-10, atol=1e-12, save="final")
t3 = time.perf_counter()
print(json.dumps(dict(hit=k.hit, kernels=t2 - t1, run=t3 - t2, x=tr["x"][-1],
                      rhs_cache_hits=k.rhs_c.cache_hits, steps=sorted(k.timings))))
"""


def test_disk_cache_across_processes(tmp_path):
    env = dict(os.environ, JETNH_CACHE=str(tmp_path))

    def run():
        out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                             text=True, timeout=600)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])

    cold = run()
    warm = run()
    assert not cold["hit"] and warm["hit"]
    assert warm["rhs_cache_hits"] >= 1          # numba loaded machine code, no compile
    assert warm["x"] == cold["x"]
    assert "derive" in cold["steps"] and "derive" not in warm["steps"]   # nothing derived
    print(f"\nkernels cold {cold['kernels']:.2f} s, warm {warm['kernels']:.2f} s")
    assert any(p.name == "layout.json" for p in tmp_path.rglob("layout.json"))


def test_cache_root_env(tmp_path, monkeypatch):
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path))
    assert str(kernels.cache_root()).startswith(str(tmp_path))


# ---------------------------------------------------------------------- the emitter
class _NoNumba:
    """Stands for numba while a generated module runs as plain Python (no compilation)."""

    @staticmethod
    def njit(*args, **kwargs):
        return lambda f: f

    cfunc = njit


def _interpret(ops):
    """A straight-line program (``codegen.llvm.program``) run by Python: what the LLVM
    instructions of ``straight_line`` compute, written a second time."""
    import math

    def run(t, y, p, out):
        flat = out.reshape(-1)
        vals = []
        for op in ops:
            kind, v = op[0], None
            if kind in ("y", "p"):
                v = (y if kind == "y" else p)[op[1]]
            elif kind == "t":
                v = t
            elif kind == "c":
                v = op[1]
            elif kind == "add":
                v = sum(vals[a] for a in op[1:])
            elif kind == "mul":
                v = math.prod(vals[a] for a in op[1:])
            elif kind == "div":
                v = vals[op[1]] / vals[op[2]]
            elif kind == "powi":
                v = vals[op[1]] ** op[2]
            elif kind == "pow":
                v = vals[op[1]] ** vals[op[2]]
            elif kind == "fn":
                f = abs if op[1] == "abs" else getattr(math, op[1])
                v = f(*[vals[a] for a in op[2:]])
            else:
                flat[op[1]] = vals[op[2]]
            vals.append(v)

    return run


def _plain(source):
    """The generated module's namespace, executed as Python (numba decorators inert;
    the straight-line programs interpreted)."""
    source = source.replace("from jetnh.numeric.codegen.llvm import straight_line",
                            "straight_line = _interpret")
    ns = {"_interpret": _interpret}
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(sys.modules, "numba", _NoNumba)
        exec(compile(source, "<kernels>", "exec"), ns)
    return ns


def _chain(depth):
    """A chain whose tree has 3^depth leaves but 4 depth nodes: e <- sin(e) e + e^2/(1+e)."""
    x, y = sp.symbols("s0 s1")
    e = x + y
    for _ in range(depth):
        e = sp.sin(e) * e + e**2 / (1 + e)
    return e


def test_emitter_prints_each_shared_node_once():
    """Generation and text are linear in the shared size (never the tree), and the
    straight-line code computes the graph's value."""
    import math

    sizes = {}
    for depth in (10, 20, 40):
        e = _chain(depth)
        em = text.Emitter([e])
        lines = em.emit([("r", e)])
        sizes[depth] = sum(map(len, lines))
        if depth == 10:
            ns = {"math": math, "s0": 0.3, "s1": -0.1}
            exec("\n".join(lines), ns)
            from jetnh.algebra import dag
            ref = dag.evaluate(e, {sp.Symbol("s0"): 0.3, sp.Symbol("s1"): -0.1})
            assert ns["r"] == pytest.approx(float(ref), rel=1e-12)
    assert sizes[40] < 4.5 * sizes[10]        # linear (the tree grows by 3^30)
    assert sizes[40] < 12000


def test_emitter_merges_equal_copies():
    """Two equal but distinct copies of a subgraph are one set of assignments."""
    from sympy.core.cache import clear_cache

    x, y = sp.symbols("s0 s1")
    a = _chain(6)
    clear_cache()
    b = _chain(6)                    # built again: equal, distinct objects at every level
    assert a == b and a is not b and a.args[0] is not b.args[0]
    c = sp.cos(x) * y
    em = text.Emitter([a + c, b * c])
    lines = em.emit([("out[0]", a + c), ("out[1]", b * c)])
    single = text.Emitter([a]).emit([("r", a)])
    assert len(lines) <= len(single) + 4     # + a named, c, two outputs


def test_emitter_prints_exact_numbers_and_fallback_heads():
    import math

    x, y = sp.symbols("s0 s1")
    exprs = [sp.Rational(1, 3) * x - 2 * y**3 / sp.sqrt(x),
             sp.Piecewise((x, y > 0), (-x, True)) + sp.Abs(y) + sp.atan2(y, x),
             x ** sp.Rational(3, 2) + sp.exp(-x) / (1 + y**2) ** 2]
    em = text.Emitter(exprs)
    lines = em.emit([(f"r{i}", e) for i, e in enumerate(exprs)])
    for point in ({"s0": 0.7, "s1": -0.4}, {"s0": 1.3, "s1": 0.9}):
        ns = {"math": math, **point}
        exec("\n".join(lines), ns)
        for i, e in enumerate(exprs):
            ref = float(e.subs({x: point["s0"], y: point["s1"]}).evalf(30))
            assert ns[f"r{i}"] == pytest.approx(ref, rel=1e-14, abs=1e-15), (i, lines)


# ---------------------------------------------------------------------- the Jacobian
def _jacobian_route(s, principle, params, n, y, t):
    """d rhs / d y by sympy on the (small) kernel expressions, phi substituted for v<a>,
    evaluated at 40 digits: the second route."""
    from jetnh.algebra import dag

    phi, rhs = codegen.kernel_expressions(s, principle, params)
    vs = {sp.Symbol(f"v{a}"): f for a, f in enumerate(phi)}
    rhs = [e.xreplace(vs) for e in rhs]
    ys = [sp.Symbol(f"s{i}") for i in range(n)]
    point = {sym: sp.Float(v, 40) for sym, v in zip(ys, y)}
    point[sp.Symbol("t")] = sp.Float(t, 40)
    entries = [sp.diff(e, q) for e in rhs for q in ys]
    vals = dag.evaluate(entries, point, dps=40)
    return np.array([float(v) for v in vals]).reshape(n, n)


@pytest.mark.parametrize("principle", ["chetaev", "vakonomic"])
@settings(max_examples=6, deadline=None)
@given(s=jst.systems(min_n=2, max_n=3))
def test_jacobian_matches_the_derivative_of_the_expressions(s, principle):
    """jac (forward mode over the graph) against sympy's derivative of the kernel
    expressions at 40 digits, at random states of random systems."""
    try:
        ks = codegen.generate(KernelSpec(s, principle, {}, variant="jacobian"))
    except JetnhError:
        assume(False)
    ns = _plain(ks.source)
    n = ks.layout.n_state
    rng = np.random.default_rng(11)
    for _ in range(2):
        y = rng.uniform(-1.2, 1.2, n)
        t = float(rng.uniform(0.0, 1.0))
        Jm = np.full((n, n), np.nan)
        try:
            ns["jac_c"](t, y, np.empty(0), Jm)
        except (ZeroDivisionError, ValueError):
            continue                          # a singular state of this draw
        ref = _jacobian_route(s, principle, {}, n, y, t)
        ok = np.isfinite(ref)
        assert np.allclose(Jm[ok], ref[ok], rtol=1e-9, atol=1e-9 * (1 + abs(ref[ok]).max()))


def test_compiled_jacobian_against_finite_differences():
    """The compiled jac_c/jac of the disk's vakonomic scene against central differences
    of the compiled rhs (``jacobian_kernels``)."""
    s = disk_system()
    ini = dict(x=0.0, y=0.0, phi=0.3, psi=0.2, phi_t=1.0, psi_t=0.5,
               lambda_x=0.1, lambda_y=-0.2)
    sc = Scene(s, "vakonomic", params=PARAMS, initial=ini, cache=False)
    ck = kernels.jacobian_kernels(sc)
    assert ck.jac_c._sig is not None
    n = len(sc.state_names)
    y = sc.y0 + np.linspace(0.1, 0.4, n)
    Jm = np.zeros((n, n))
    ck.jac(0.2, y, np.empty(0), Jm)
    fd = np.zeros((n, n))
    for j in range(n):
        h = 1e-6 * (1 + abs(y[j]))
        yp, ym, op, om = y.copy(), y.copy(), np.zeros(n), np.zeros(n)
        yp[j] += h
        ym[j] -= h
        ck.rhs(0.2, yp, np.empty(0), op)
        ck.rhs(0.2, ym, np.empty(0), om)
        fd[:, j] = (op - om) / (2 * h)
    assert np.allclose(Jm, fd, rtol=1e-6, atol=1e-7)
    assert np.count_nonzero(Jm) > n            # not trivially the kinematic rows


def test_printed_jacobian_for_heads_the_program_lacks():
    """Emitter.jacobian (the text path: Abs, Piecewise) against sympy's derivative."""
    import math

    x, y = sp.symbols("s0 s1", real=True)
    v = sp.Symbol("v0")
    phi = sp.Abs(x) * y + sp.sin(x * y)
    exprs = [v * sp.Piecewise((x**2, y > 0), (sp.cos(x), True)) + sp.atan2(y, x), v / (1 + y**2)]
    em = text.Emitter([phi] + exprs, inline=0)
    lines = em.emit([("v0", phi)]) + em.emit([(None, e) for e in exprs])
    lines += em.jacobian(list(enumerate(exprs)), {x: 0, y: 1}, {v: phi})
    full = [e.xreplace({v: phi}) for e in exprs]
    for point in ({x: 0.7, y: -0.4}, {x: -1.3, y: 0.9}):
        J = np.zeros((2, 2))
        ns = {"math": math, "J": J, "s0": point[x], "s1": point[y]}
        exec("\n".join(lines), ns)
        for i, e in enumerate(full):
            for j, s in enumerate((x, y)):
                ref = float(sp.diff(e, s).subs(point).evalf(30))
                assert J[i, j] == pytest.approx(ref, rel=1e-13, abs=1e-14), (i, j)


def test_kernels_are_compiled_once_and_called_from_python_through_their_callbacks():
    """The module holds the C callbacks alone (one compilation of each body); from Python
    ``rhs``/``aux``/``sing``/``aux_rows`` call them, and refuse arrays the kernels would
    read or write out of bounds."""
    s = disk_system()
    ini = dict(x=0.0, y=0.0, phi=0.3, psi=0.2, phi_t=1.0, psi_t=0.5)
    sc = Scene(s, "chetaev", params=PARAMS, initial=ini, cache=False)
    ck = sc.kernels
    assert not any(hasattr(ck.kernels, name) for name in ("rhs", "aux", "sing", "aux_rows"))
    lay = ck.layout
    n, p = lay.n_state, np.empty(0)
    ys = np.ascontiguousarray(sc.y0 + np.outer(np.linspace(0, 1, 4), np.ones(n)))
    ts = np.linspace(0.0, 0.3, 4)
    rows = np.zeros((4, lay.n_aux))
    ck.aux_rows(ts, ys, p, rows)
    for i in range(4):
        one = np.zeros(lay.n_aux)
        ck.aux(ts[i], ys[i], p, one)
        assert np.array_equal(one, rows[i])
    f = np.zeros(n)
    ck.rhs(0.1, ys[1], p, f)
    phi, rhs = codegen.kernel_expressions(s, "chetaev", PARAMS)   # the second route
    point = {sp.Symbol(f"s{i}"): v for i, v in enumerate(ys[1])}
    point[sp.Symbol("t")] = 0.1
    point.update({sp.Symbol(f"v{a}"): float(e.xreplace(point)) for a, e in enumerate(phi)})
    assert np.allclose(f, [float(e.xreplace(point)) for e in rhs], rtol=1e-12, atol=1e-14)
    g = np.zeros(len(lay.indicators))
    ck.sing(0.1, ys[1], p, g)
    assert np.all(np.isfinite(g))
    with pytest.raises(TypeError, match="C-contiguous float64"):
        ck.rhs(0.1, ys[:, 0], p, f)                      # a strided column
    with pytest.raises(TypeError, match="C-contiguous float64"):
        ck.rhs(0.1, ys[1].astype(np.float32), p, f)
    with pytest.raises(ValueError, match="needs"):
        ck.rhs(0.1, ys[1], p, np.zeros(n - 1))         # out too short
    with pytest.raises(ValueError, match="rows"):
        ck.aux_rows(ts, ys[:3], p, rows)


# ---------------------------------------------------------------------- calls from Python
@pytest.fixture(scope="module")
def affine_kernel():
    """A C callback of the kernels' signature, ``out[i] = p[0] y[i] + p[1] + t`` (i < 3),
    called from Python (sizes (3, 2, 3)) and from compiled code."""
    import numba

    from jetnh.numeric.kernels.calls import Kernel
    from jetnh.numeric.layout import SIGNATURE

    @numba.cfunc(SIGNATURE)
    def affine(t, y, p, out):
        for i in range(3):
            out[i] = p[0] * y[i] + p[1] + t

    @numba.njit(SIGNATURE)
    def direct(t, y, p, out):
        affine(t, y, p, out)

    return Kernel(affine, (3, 2, 3)), direct


@settings(max_examples=25, deadline=None)
@given(n_y=st.integers(0, 4), n_p=st.integers(0, 3), n_out=st.integers(0, 4),
       frozen=st.sampled_from(["", "y", "p", "out"]), t=st.floats(-2, 2))
def test_a_kernel_call_checks_every_array(affine_kernel, n_y, n_p, n_out, frozen, t):
    """A kernel called from Python runs only when y, p and out hold what it reads and
    writes, and then computes what the same callback computes called from compiled code;
    read-only inputs are taken, a read-only output is refused, and a refused call writes
    nothing."""
    kernel, direct = affine_kernel
    rng = np.random.default_rng(n_y * 100 + n_p * 10 + n_out)
    y, p = rng.uniform(-1, 1, n_y), rng.uniform(-1, 1, n_p)
    out = np.full(n_out, 7.0)
    for name, a in (("y", y), ("p", p), ("out", out)):
        a.flags.writeable = frozen != name
    fits = n_y >= 3 and n_p >= 2 and n_out >= 3
    if frozen == "out":
        with pytest.raises(TypeError, match="read-only"):
            kernel(t, y, p, out)
    elif not fits:
        with pytest.raises(ValueError, match="fewer entries than the kernel needs"):
            kernel(t, y, p, out)
        assert np.all(out == 7.0)
    else:
        kernel(t, y, p, out)
        ref = np.full(n_out, 7.0)
        direct(t, y.copy(), p.copy(), ref)
        assert np.array_equal(out, ref)
        assert np.allclose(out[:3], p[0] * y[:3] + p[1] + t, rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("name, principle", [
    ("n_trailer", "vakonomic"), ("n_trailer", "suslov"), ("rolling_disk", "holder"),
    ("chaplygin_sleigh", "chetaev"), ("appell_hamel", "vakonomic")])
def test_indicators_prepared_from_the_rhs_are_prepared_alike(name, principle):
    """``Preparer.adopt``: the sing kernel's expressions prepared with what the rhs's
    preparation already made (numbers substituted first, then renamed) are those a fresh
    preparer makes of them (compared by structure, ``dag.fingerprint``)."""
    from jetnh.algebra import dag
    from jetnh.numeric.codegen.continuous import _rhs_parts
    from jetnh.numeric.codegen.indicators import singular_indicators
    from jetnh.numeric.codegen.prepare import Preparer

    system = models.get(name)
    spec = KernelSpec(system, principle, dict(system.defaults))
    eom, acc, prepare, _, _ = _rhs_parts(spec)
    J = system.J
    wanted = ([acc[J.jet(J.split(v)[0], 2)] for v in system.independent_velocities]
              + [acc[r] for r in eom.multiplier_rates])
    numbered: dict = {}
    indicators = singular_indicators(system, wanted, prepare.numbers, numbered)
    adopted = len(prepare.memo)
    prepare.adopt(numbered)
    assert len(prepare.memo) > adopted                 # the substitution's parts are known
    pairs = [(e, "indicator") for _, e in indicators]
    fresh = Preparer(system, tuple(eom.multipliers), spec.params, spec.runtime_params)
    assert dag.fingerprint(prepare.many(pairs)) == dag.fingerprint(fresh.many(pairs))


def test_a_parsed_program_links_with_or_without_numbas_private_final_module(monkeypatch):
    """A program above the quick threshold is parsed as LLVM text and linked through
    numba's private ``_final_module`` (present in the numba installed: a release without
    it is seen here); where a library has none it goes through ``add_llvm_module``, and
    both compute the program (y0 * y1 + sin(p0), and t)."""
    import math

    import numba

    from jetnh.numeric.codegen import llvm

    monkeypatch.setenv("JETNH_QUICK_OPS", "0")
    ops = (("y", 0), ("y", 1), ("p", 0), ("mul", 0, 1), ("fn", "sin", 2), ("add", 3, 4),
           ("out", 0, 5), ("t",), ("out", 1, 7))
    real, libraries = llvm._link, []

    class Bare:                       # a code library without _final_module
        def __init__(self, library):
            self.add_llvm_module = library.add_llvm_module

    def recorded(library, module, bare):
        libraries.append(library)
        real(Bare(library) if bare else library, module)

    y, p = np.array([2.0, 3.0]), np.array([0.5])
    for bare in (False, True):
        monkeypatch.setattr(llvm, "_link", lambda lib, mod, b=bare: recorded(lib, mod, b))
        body = llvm.straight_line(ops)

        @numba.njit
        def kernel(t, y, p, out):
            body(t, y, p, out)

        out = np.zeros(2)
        kernel(1.25, y, p, out)
        assert out.tolist() == [6.0 + math.sin(0.5), 1.25]
    assert len(libraries) == 2 and hasattr(libraries[0], "_final_module")
