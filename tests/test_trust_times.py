"""Extreme times: a span whose floating-point resolution cannot carry steps is refused,
and no run reports success with a NaN or infinite state (API and command line)."""

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from jetnh.errors import ArgumentError, IntegrationError, JetnhError
from jetnh.models import appell_hamel
from jetnh.numeric import Scene
from jetnh.numeric.arguments import MIN_TIME_RESOLUTION, time_span


@pytest.fixture(scope="module")
def scene():
    return Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                 t_span=(0.0, 0.5))


@pytest.mark.parametrize("span", [(1e300, 1e300 * (1 + 1e-15)), (1e16, 1e16 + 2.0),
                                  (-1e308, 1e308), (5.0, 5.0 + 1e-12)])
def test_unresolvable_spans_are_refused(scene, span):
    with pytest.raises(ArgumentError, match="cannot be resolved.*shift the time origin"):
        Scene(appell_hamel(), "chetaev", initial=dict(scene.initial), t_span=span)
    for method in ("dop853", "rk4", "radau", "dla", "scipy-RK45"):
        with pytest.raises(ArgumentError, match="cannot be resolved"):
            scene.run(t_span=span, method=method, n_steps=10) if method in ("rk4", "dla") \
                else scene.run(t_span=span, method=method)


@given(st.floats(-1e300, 1e300), st.floats(0, 1e6, exclude_min=True))
def test_accepted_spans_resolve_their_steps(t0, length):
    """Every accepted span holds MIN_TIME_RESOLUTION distinct times."""
    t1 = t0 + length
    try:
        a, b = time_span((t0, t1))
    except ArgumentError:
        assert t1 == t0 or abs(t1 - t0) < MIN_TIME_RESOLUTION * math.ulp(max(abs(t0), abs(t1)))
        return
    if a != b:
        h = (b - a) / 1000
        assert a + h != a and b - h != b


def test_no_success_with_a_nonfinite_state(scene):
    """Over (-1e308, 0) the steps are huge and the state overflows: an error, or a
    non-success; never success with NaN."""
    for method in ("dop853", "dopri5", "radau", "scipy-RK45"):
        try:
            tr = scene.run(t_span=(-1e308, 0.0), method=method)
        except JetnhError:
            continue
        assert not (tr.success and not np.all(np.isfinite(tr.y))), method
    far = scene.replace(t_span=(-1e308, 0.0))
    try:
        ens = far.ensemble({"x_t": [0.6, 0.6]}, save="final", on_error="record")
    except JetnhError:
        return
    assert not np.any(ens.success & ~np.all(np.isfinite(ens.y_final), axis=1))


def test_cli_refuses_an_unresolvable_span(tmp_path):
    r = subprocess.run([sys.executable, "-m", "jetnh", "simulate", "appell_hamel",
                        "--t-start", "1e300", "--t-end", "1.000000000000001e300"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode != 0 and "cannot be resolved" in r.stderr, r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("method", ["dla", "dvi", "rk4"])
def test_fixed_step_methods_refuse_a_zero_span(scene, method):
    with pytest.raises(ArgumentError, match="zero length"):
        scene.run(method=method, t_span=(1.0, 1.0), n_steps=10)


def test_fast_event_resolved_with_max_step_below_its_root_spacing(scene):
    """The documented resolution limit and its remedy: sin(1000 t) crosses zero every
    pi/1000; with max_step below that every crossing in (0, 0.2) is reported."""
    import sympy as sp

    t = scene.system.J.t
    tr = scene.run(t_span=(0.0, 0.2), events=[sp.sin(1000 * t)], max_step=1e-3,
                   rtol=1e-10, atol=1e-12)
    found = tr.t_events[0]
    found = found[found > 1e-12]                  # sin(1000 t0) = 0 at the start
    expected = np.arange(1, int(0.2 * 1000 / np.pi) + 1) * np.pi / 1000
    assert len(found) == len(expected)
    assert np.max(np.abs(found - expected)) < 1e-9
