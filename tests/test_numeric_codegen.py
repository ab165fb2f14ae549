"""Code generation (cse, exact printing, no user text in the source) and the disk cache."""

import json
import os
import subprocess
import sys

import pytest
import sympy as sp

import jetnh as jn
from jetnh.constraints import System
from jetnh.errors import JetnhError
from jetnh.numeric import Scene, cache, codegen


def disk_system():
    J = jn.JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2 = sp.symbols("R I1 I2")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2
    return System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid],
                  dependent=[x, y])


PARAMS = {"R": 1.5, "I1": 0.5, "I2": 0.25}


def test_printer_is_exact_and_cheap():
    x, y = sp.symbols("x y")
    p = codegen.print_expr
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
    ks = codegen.generate(s, "vakonomic", PARAMS, key="k")
    src = ks.source
    for name in ("phi", "psi", "lambda", "R*", "I1", "I2"):
        assert name not in src.split("LAYOUT")[0], name
    assert "1.5" in src  # the parameter R is a compiled constant
    assert ks.layout.states == ("x", "y", "phi", "psi", "phi_t", "psi_t", "lambda_x", "lambda_y")
    assert ks.layout.dependent_velocities == ("x_t", "y_t")
    compile(src, "<kernels>", "exec")  # valid Python


def test_missing_parameter_in_codegen():
    with pytest.raises(JetnhError, match="no value: I2"):
        codegen.generate(disk_system(), "chetaev", {"R": 1.0, "I1": 1.0})


def test_key_depends_on_the_symbolic_input():
    s = disk_system()
    k1 = codegen.symbolic_key(s, "chetaev", PARAMS)
    assert k1 == codegen.symbolic_key(disk_system(), "chetaev", dict(PARAMS))
    assert k1 != codegen.symbolic_key(s, "vakonomic", PARAMS)
    assert k1 != codegen.symbolic_key(s, "chetaev", dict(PARAMS, R=1.5000000000000002))
    assert k1 != codegen.symbolic_key(s, "chetaev", PARAMS, runtime_params=("R",))


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
from jetnh.constraints import System
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
                      rhs_cache_hits=sum(k.rhs.stats.cache_hits.values()))))
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
    assert warm["kernels"] < cold["kernels"]
    print(f"\nkernels cold {cold['kernels']:.2f} s, warm {warm['kernels']:.2f} s")
    assert any(p.name == "layout.json" for p in tmp_path.rglob("layout.json"))


def test_cache_root_env(tmp_path, monkeypatch):
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path))
    assert str(cache.cache_root()).startswith(str(tmp_path))
