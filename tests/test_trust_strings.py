"""No public function executes a user string: canaries that would create a file if a
string were parsed by sympify (eval) are refused with a JetnhError naming the fix, and
the package's source calls sympify only in strict mode (which never parses strings)."""

import pathlib
import re

import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.errors import JetnhError

ROOT = pathlib.Path(jn.__file__).parent


@pytest.fixture
def canary(tmp_path):
    path = tmp_path / "executed"
    return path, f"__import__('pathlib').Path({str(path)!r}).touch()"


def _calls(sysm, code):
    J = sysm.J
    return {
        "conserved_quantities": lambda: jn.conserved_quantities(sysm, "chetaev", 1, [code]),
        "conserved_quantities (mixed)": lambda: jn.conserved_quantities(
            sysm, "chetaev", 1, [1, code]),
        "noether_symmetries": lambda: jn.noether_symmetries(sysm, "chetaev", 1, [code]),
        "lie_symmetries": lambda: jn.lie_symmetries(sysm, "chetaev", 1, [code]),
        "on_constraints": lambda: sysm.on_constraints(code),
        "on_constraints prolonged": lambda: sysm.on_constraints(code, prolonged=True),
        "J.D": lambda: J.D(code),
        "System lagrangian": lambda: jn.System(J, code),
        "System constraint": lambda: jn.System(J, sysm.L, constraints=[code]),
    }


@pytest.mark.parametrize("name", list(_calls(models.get("nonholonomic_particle"), "")))
def test_strings_are_refused_never_executed(name, canary):
    path, code = canary
    sysm = models.get("nonholonomic_particle")
    with pytest.raises(JetnhError, match="string"):
        _calls(sysm, code)[name]()
    assert not path.exists(), f"{name} executed a user string"


def test_refusal_names_the_fix(canary):
    _, code = canary
    sysm = models.get("nonholonomic_particle")
    with pytest.raises(JetnhError, match=r"never parses strings.*sympy\.sin"):
        jn.conserved_quantities(sysm, "chetaev", 1, [code])


def test_source_never_sympifies_a_string():
    """sympify without strict=True (or sympy.S, parse_expr, eval) would parse strings."""
    bad = []
    for p in sorted(ROOT.rglob("*.py")):
        for i, line in enumerate(p.read_text().splitlines(), 1):
            code = line.split("#")[0]
            if (re.search(r"\bsympify\(", code) and "strict=True" not in code
                    and "se.sympify" not in code) or re.search(
                        r"\bparse_expr\b|\bsp\.S\(|(?<![.\w])eval\(", code):
                bad.append(f"{p.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not bad, "\n".join(bad)


def test_symengine_sympify_gets_sympy_objects_only():
    src = (ROOT / "mechanics" / "accelerations.py").read_text()
    assert src.count("se.sympify(") == 1 and "se.sympify(F)" in src   # F: the checked L
    assert isinstance(sp.sympify(1, strict=True), sp.Integer)
