"""Run options as values (``numeric.options``): each value gives the run its keywords
give, bit for bit; keywords and values combine; clashes and bad values are refused."""

import numpy as np
import pytest

from jetnh.errors import ArgumentError, JetnhError
from jetnh.models import appell_hamel
from jetnh.numeric import Newton, Scene, Singular, StepControl, run_ensemble
from jetnh.numeric.options import KEYWORDS, merge


@pytest.fixture(scope="module")
def scene():
    return Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                 t_span=(0.0, 1.0), cache=False).compile()


def same(a, b):
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.y, b.y)
    assert (a.status, a.stop_reason) == (b.status, b.stop_reason)


def test_step_control_equals_keywords(scene):
    kw = dict(rtol=1e-7, atol=1e-10, max_step=0.05, first_step=1e-3)
    same(scene.run(step=StepControl(**kw)), scene.run(**kw))
    # part as a value, part as keywords
    same(scene.run(step=StepControl(rtol=1e-7, atol=1e-10), max_step=0.05, first_step=1e-3),
         scene.run(**kw))
    same(scene.run(method="rk4", step=StepControl(n_steps=50)),
         scene.run(method="rk4", n_steps=50))
    same(scene.run(step=StepControl(atol=np.full(5, 1e-10))),
         scene.run(atol=np.full(5, 1e-10)))


def test_singular_value_equals_keywords(scene):
    a = scene.run(singular=Singular(tol=1e-6))
    b = scene.run(singular_tol=1e-6)
    same(a, b)
    assert a.status == 6          # the horizontal speed reaches zero: a singular stop
    same(scene.run(singular=Singular("ignore"), t_span=(0.0, 0.2)),
         scene.run(singular="ignore", t_span=(0.0, 0.2)))
    same(scene.run(singular=Singular(tol=1e-6), singular_tol=None), b)


def test_newton_value_equals_keywords(scene):
    same(scene.run(method="radau", newton=Newton(tol=1e-8, max_iter=5)),
         scene.run(method="radau", newton_tol=1e-8, max_newton=5))


def test_ensemble_takes_the_values(scene):
    x_t = np.array([0.6, 0.5])
    a = run_ensemble(scene, {"x_t": x_t}, step=StepControl(rtol=1e-7),
                     singular=Singular(tol=1e-6))
    b = run_ensemble(scene, {"x_t": x_t}, rtol=1e-7, singular_tol=1e-6)
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.status, b.status)


def test_clashes_and_bad_values(scene):
    with pytest.raises(ArgumentError, match="rtol given both"):
        scene.run(step=StepControl(rtol=1e-7), rtol=1e-8)
    with pytest.raises(ArgumentError, match="tol given both"):
        scene.run(singular=Singular(tol=1e-6), singular_tol=1e-7)
    with pytest.raises(JetnhError, match="singular must be 'stop' or 'ignore'"):
        Singular("skip")
    with pytest.raises(ArgumentError, match="expected a StepControl"):
        scene.run(step={"rtol": 1e-7})
    with pytest.raises(JetnhError, match="rtol"):
        scene.run(step=StepControl(rtol=-1.0))     # checked where the run uses it
    with pytest.raises(AttributeError):
        StepControl().rtol = 1.0


def test_keyword_table_covers_the_fields():
    assert KEYWORDS["step"] == ("rtol", "atol", "first_step", "max_step", "max_steps",
                                "n_steps", "h")
    assert merge(None, StepControl, {"rtol": None}) == StepControl()
    assert merge(StepControl(h=0.1), StepControl, {"rtol": 1e-3}) == StepControl(1e-3, h=0.1)


def test_sweep_passes_the_values_on(scene):
    from jetnh import sweep

    grid = {"x_t": [0.6, 0.5]}
    a = sweep(scene, grid, step=StepControl(rtol=1e-7), singular=Singular(tol=1e-6))
    b = sweep(scene, grid, rtol=1e-7, singular_tol=1e-6)
    assert a.equals(b)


def test_one_definition_of_the_run_options(scene):
    """Scene.run, run_ensemble and sweep take the run options of ``options.NAMES``; an
    unknown keyword is refused naming them; radau's Newton options reach the ensemble."""
    from jetnh.numeric.options import NAMES, Options, options

    assert set(NAMES) == {"step", "singular", "newton"} | {
        k for ks in KEYWORDS.values() for k in ks}
    for call in (lambda: scene.run(rtool=1e-3), lambda: run_ensemble(scene, rtool=1e-3)):
        with pytest.raises(ArgumentError, match="rtool: not a run option; the run options "
                                                "are step, singular, newton, rtol"):
            call()
    opts = options(rtol=1e-7, singular_tol=1e-6, max_newton=5)
    assert opts == Options(StepControl(rtol=1e-7), Singular(tol=1e-6), Newton(max_iter=5))
    assert options(rtol=1e-7, singular_tol=1e-6, max_newton=5) is opts   # kept
    assert options(rtol=True) is not options(rtol=1)          # the types count
    x_t = np.array([0.6, 0.5])
    ens = run_ensemble(scene, {"x_t": x_t}, method="radau",
                       newton=Newton(tol=1e-8, max_iter=5))
    for r, v in enumerate(x_t):
        one = scene.run(method="radau", newton_tol=1e-8, max_newton=5, y0={"x_t": v},
                        save="final")
        np.testing.assert_array_equal(ens.y[r, -1], one.y[-1])
    with pytest.raises(JetnhError, match="newton_tol and max_newton are options of radau"):
        run_ensemble(scene, {"x_t": x_t}, newton_tol=1e-8)
