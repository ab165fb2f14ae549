"""The transversality conditions of a free end as numbers (``problem.Momenta``): a
straight line of Python float operations prepared once from the shared graph
(``problem.straight_line``) against the graph walked by numpy (``Momenta.walk``) on
random systems (hypothesis), their derivatives against central differences, a closed
form (Heisenberg: P_z = lambda_z), and the walk where a float operation raises (a
division by zero: numpy's inf) or a head has no float function."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh import strategies as jst
from jetnh.errors import JetnhError
from jetnh.models import get
from jetnh.numeric.connect.problem import Momenta, Unknowns, _scene, straight_line


def _momenta(system, principle, free, at=0.0):
    """The scene (its start at every coordinate ``at``) and its ``Momenta``."""
    shape = Unknowns.of(system, principle)
    coords = shape.coords
    params = {s.name: float(system.defaults.get(s, 0.7)) for s in system.parameters}
    scene = _scene(system, principle, params,
                   {**{c: at for c in coords}, **{u: 0.0 for u in shape.unknowns},
                    **shape.fixed}, (0.0, 1.0))
    return scene, Momenta(scene, free)


@settings(max_examples=25, deadline=None)
@given(jst.systems(min_n=2, max_n=4), st.sampled_from(["vakonomic", "holder"]),
       st.data())
def test_prepared_momenta_are_the_graph_walk(system, principle, data):
    coords = [q.name for q in system.J.q]
    free = data.draw(st.lists(st.sampled_from(coords), min_size=1, unique=True),
                     label="free")
    try:
        scene, m = _momenta(system, principle, free)
    except JetnhError:
        assume(False)
    assert m._line is not None
    n = len(scene.state_names)
    y = np.array(data.draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n),
                           label="state"))
    t = data.draw(st.floats(0.0, 1.0), label="t")
    values, G = m(t, y)
    walked, Gw = m.walk(t, y)
    assume(np.all(np.isfinite(walked)) and np.all(np.isfinite(Gw)))
    assert values.shape == walked.shape and G.shape == Gw.shape == (len(m.free), n)
    # the same operations in the same order; the functions' last bits may differ
    # (numpy's and the math module's)
    assert np.allclose(values, walked, rtol=1e-13, atol=1e-13)
    assert np.allclose(G, Gw, rtol=1e-13, atol=1e-13)
    # dP/dy by central differences of the prepared values
    h = 1e-6
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd = (m(t, y + e)[0] - m(t, y - e)[0]) / (2 * h)
        assert np.allclose(G[:, j], fd, rtol=1e-6, atol=1e-6 * (1 + np.abs(values).max()))


def test_heisenberg_transversality_is_the_multiplier():
    """Heisenberg, end leaving z free: P_z = lambda_z, so dP_z/dy is the unit row."""
    scene, m = _momenta(get("heisenberg"), "vakonomic", ["z"])
    y = np.linspace(-0.4, 0.9, len(scene.state_names))
    values, G = m(0.3, y)
    i = scene.state_names.index("lambda_z")
    assert values.tolist() == [y[i]]
    assert G.tolist() == [[1.0 if j == i else 0.0 for j in range(len(y))]]


def test_a_float_operation_that_raises_falls_back_to_numpy():
    """x ydot = xdot (y dependent: ydot = xdot / x): P_y = xdot / x + lambda_y x has a
    division by x; at x = 0 Python's float division raises, so the call is the walk's
    (numpy: inf), the same as ``walk``; elsewhere the straight line."""
    J = jn.JetSpace("x y")
    x, y = J.q
    xt, yt = J.qd
    system = jn.System(J, (xt**2 + yt**2) / 2, [x * yt - xt], dependent=[y])
    scene, m = _momenta(system, "vakonomic", ["y"], at=1.0)
    names = scene.state_names
    state = np.zeros(len(names))
    state[names.index("x_t")], state[names.index("lambda_y")] = 0.5, 0.25
    with np.errstate(all="ignore"):
        values, G = m(0.0, state)
        walked, Gw = m.walk(0.0, state)
    assert not np.all(np.isfinite(values))
    assert np.array_equal(values, walked, equal_nan=True)
    assert np.array_equal(G, Gw, equal_nan=True)
    state[names.index("x")] = 2.0
    values, _ = m(0.0, state)
    assert values.tolist() == [0.5 / 2.0 + 0.25 * 2.0]


def test_a_head_without_a_float_function_is_walked():
    t, a, b = sp.symbols("t a b")
    assert straight_line([sp.besselj(0, a) * b], t, [a, b], {}) is None
    assert straight_line([sp.I * a], t, [a, b], {}) is None
    line = straight_line([a * b + sp.sin(t) * sp.Symbol("c"), a**2 / b],
                         t, [a, b], {sp.Symbol("c"): 3.0})
    assert line(0.5, [2.0, 4.0]) == [8.0 + math.sin(0.5) * 3.0, 1.0]
    with pytest.raises(ZeroDivisionError):
        line(0.5, [2.0, 0.0])
