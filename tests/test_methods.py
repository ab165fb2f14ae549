"""The table of integration methods: one ``Method`` value per method, asked by every caller."""

import pytest

from jetnh.errors import JetnhError
from jetnh.numeric import methods
from jetnh.numeric.methods import METHODS, SCIPY_METHODS, Method, Solver, method


def test_every_name_and_alias_reads_its_method_in_any_case():
    for m in METHODS.values():
        for name in (m.name, *m.aliases):
            assert method(name) is m and method(name.upper()) is m
        assert method(m) is m


def test_the_compiled_methods_and_what_they_can_do():
    table = {m.name: (m.solver, m.order, m.adaptive, m.dense, m.ensemble, m.newton)
             for m in METHODS.values() if m.solver is not Solver.SCIPY}
    assert table == {
        "dop853": (Solver.EXPLICIT, 8, True, True, True, False),
        "dopri5": (Solver.EXPLICIT, 5, True, True, True, False),
        "rk4": (Solver.EXPLICIT, 4, False, False, True, False),
        "radau": (Solver.IMPLICIT, 5, True, True, True, True),
        "dla": (Solver.DISCRETE, 2, False, False, False, True),
        "dvi": (Solver.DISCRETE, 2, False, False, False, True),
    }
    assert [m.name for m in METHODS.values() if m.fixed_step] == ["rk4", "dla", "dvi"]
    assert [m.name for m in METHODS.values() if m.projection] == ["dla"]
    # an explicit method's order is its tableau's
    for m in METHODS.values():
        if m.solver is Solver.EXPLICIT:
            assert m.tableau.order == m.order and m.tableau.adaptive == m.adaptive


def test_scipy_methods_by_name_and_by_backend():
    assert SCIPY_METHODS == ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
    for name in SCIPY_METHODS:
        m = method(f"scipy-{name}")
        assert (m.name, m.scipy, m.solver) == (f"scipy-{name}", name, Solver.SCIPY)
        assert m.dense and not m.ensemble
    assert method("DOP853", backend="scipy") is method("scipy-DOP853")
    assert method("dopri5", backend="scipy") is method("scipy-RK45")
    assert method("rk45", backend="scipy") is method("scipy-RK45")


@pytest.mark.parametrize("name, backend, words", [
    ("euler", None, "unknown method 'euler'; choose one of dop853, dopri5, rk4, radau, dla, "
                    "dvi or scipy-<RK45|RK23|DOP853|Radau|BDF|LSODA>"),
    ("scipy-euler", None, "unknown scipy method 'euler'"),
    ("euler", "scipy", "unknown scipy method 'euler'"),
    ("dop853", "cuda", "unknown backend 'cuda'"),
])
def test_unknown_methods_are_named(name, backend, words):
    with pytest.raises(JetnhError) as info:
        method(name, backend)
    assert words in str(info.value)


def test_methods_are_values():
    m = method("dop853")
    with pytest.raises(AttributeError):
        m.adaptive = False
    assert isinstance(m, Method) and m == methods.METHODS["dop853"]
