"""Numeric properties on random systems, states and principles (``jetnh.strategies``):
the compiled right-hand side equals the symbolic accelerations evaluated with mpmath,
an ensemble equals its single runs to the last bit, and run options given as values or
as keywords give the same run."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh import models
from jetnh.algebra import dag

#: each example derives and compiles a new system: a few examples, no deadline
FEW = settings(max_examples=4, deadline=None,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _expected_rates(scene):
    """dy/dt at the scene's initial state from the symbolic accelerations (mpmath)."""
    system = scene.system
    J = system.J
    eom = system.equations(scene.principle, form=scene.form, convention=scene.convention)
    by_name = {s.name: s for s in (*J.q, *J.qd, *eom.multipliers)}
    point = {J.t: scene.t_span[0]}
    point.update({by_name[n]: v for n, v in zip(scene.state_names, scene.y0)})
    dep = list(system.phi)
    point.update(zip(dep, dag.evaluate([system.phi[v] for v in dep], point)))
    acc = eom.accelerations()
    symbols = [by_name[n] for n in scene.state_names]
    rates = [acc[J.qdd[J.qd.index(s)]] if s in J.qd else acc[eom.J.jet(s, 1)]
             for s in symbols if s not in J.q]
    moving = iter(dag.evaluate(rates, point))
    return np.array([float(point[J.qd[J.q.index(s)]] if s in J.q else next(moving))
                     for s in symbols])


@FEW
@given(jst.scenes(jst.systems(max_n=3, affine=True), t_end=1.0))
def test_compiled_rhs_equals_the_accelerations_in_mpmath(scene):
    out = np.empty_like(scene.y0)
    scene.kernels.rhs(scene.t_span[0], scene.y0, scene.p, out)
    np.testing.assert_allclose(out, _expected_rates(scene), rtol=1e-9, atol=1e-11)


_KNIFE = jn.Scene(models.get("knife_edge"), "chetaev",
                  initial={"x": 0.0, "y": 0.0, "phi": 0.0, "phi_t": 1.0, "x_t": 1.0},
                  t_span=(0.0, 2.0))
_value = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=10, deadline=None)
@given(st.lists(st.tuples(_value, _value), min_size=1, max_size=5),
       st.sampled_from(["dop853", "dopri5", "radau"]))
def test_an_ensemble_equals_its_single_runs_to_the_bit(velocities, method):
    index = [_KNIFE.state_names.index(n) for n in ("phi_t", "x_t")]
    Y0 = np.tile(_KNIFE.y0, (len(velocities), 1))
    Y0[:, index] = velocities
    ens = jn.numeric.run_ensemble(_KNIFE, Y0, method=method, parallel="serial")
    for r, y0 in enumerate(Y0):
        single = _KNIFE.run(method=method, y0=y0, save="final")
        assert np.array_equal(ens.y_final[r], single.y[-1])
        assert ens.t_final[r] == single.t[-1]


@st.composite
def _option_spellings(draw):
    """A method and its run options, as the values ``StepControl``/``Singular``/``Newton``
    and as the equivalent keywords."""
    method = draw(st.sampled_from(["dop853", "dopri5", "rk4", "radau"]))
    if method == "rk4":
        step = {"n_steps": draw(st.integers(5, 40))}
    else:
        step = {"rtol": draw(st.sampled_from([1e-6, 1e-8, 1e-10])),
                "atol": draw(st.sampled_from([1e-9, 1e-12])),
                "max_step": draw(st.sampled_from([None, 0.05, 0.3])),
                "first_step": draw(st.sampled_from([None, 1e-3])),
                "max_steps": draw(st.sampled_from([10_000_000, 50]))}
        step = {k: v for k, v in step.items() if v is not None}
    singular = {"action": draw(st.sampled_from(["stop", "ignore"])),
                "tol": draw(st.sampled_from([1e-10, 1e-7]))}
    newton = {"tol": draw(st.sampled_from([None, 1e-10])),
              "max_iter": draw(st.sampled_from([None, 4, 12]))} if method == "radau" else {}
    newton = {k: v for k, v in newton.items() if v is not None}
    values = dict(step=jn.numeric.StepControl(**step),
                  singular=jn.numeric.Singular(**singular))
    keywords = dict(step, singular=singular["action"], singular_tol=singular["tol"])
    if newton:
        values["newton"] = jn.numeric.Newton(**newton)
        keywords.update(newton_tol=newton.get("tol"), max_newton=newton.get("max_iter"))
    return method, values, keywords


def _outcome(scene, **options):
    """The arrays of a run, or the error it raised (type and message)."""
    try:
        tr = scene.run(save="steps", **options)
    except jn.JetnhError as exc:
        return type(exc), str(exc)
    return tr.status, tr.stop_reason, tr.diagnostics.steps, tr.diagnostics.rejected, tr.t, tr.y


@FEW
@given(jst.scenes(jst.systems(max_n=3, affine=True), t_end=0.5), _option_spellings())
def test_options_as_values_and_as_keywords_give_identical_runs(scene, spellings):
    """``scene.run(step=StepControl(...), singular=Singular(...), newton=Newton(...))`` and
    the same options as keywords run the same steps: equal to the last bit."""
    method, values, keywords = spellings
    a = _outcome(scene, method=method, **values)
    b = _outcome(scene, method=method, **{k: v for k, v in keywords.items() if v is not None})
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True)
        else:
            assert x == y
