"""Trajectories as data: DataFrame, xarray, plot, evaluation inside the span (``at``), and
the bounded HTML/LaTeX displays of System, Equations, Comparison, Trajectory, Ensemble."""

import sys

import matplotlib
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh import display, models
from jetnh.mechanics.equivalence import Comparison
from jetnh.errors import ArgumentError, JetnhError
from jetnh.numeric import Event, Scene

matplotlib.use("Agg")

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)
TOL = dict(rtol=1e-8, atol=1e-10)


@pytest.fixture(scope="module")
def disk():
    s = models.get("rolling_disk")
    return Scene(s, "chetaev", initial=DISK0, t_span=(0.0, 6.0),
                 integrals={"E2": s.L}).compile()


@pytest.fixture(scope="module")
def vak():
    s = models.get("rolling_disk")
    ini = dict(DISK0, lambda_x=0.2, lambda_y=-0.1)
    return Scene(s, "vakonomic", initial=ini, t_span=(0.0, 3.0)).compile()


@pytest.fixture(scope="module")
def traj(disk):
    return disk.run(**TOL)


def phi_values(scene, traj):
    """The dependent velocities from System.phi by sympy (the second route)."""
    s = scene.system
    out = {}
    for v, expr in s.phi.items():
        syms = sorted(expr.free_symbols, key=lambda x: x.name)
        f = sp.lambdify(syms, expr, "numpy")
        args = [np.full(len(traj), scene.params[x.name]) if x.name in scene.params
                else traj[x.name] for x in syms]
        out[v.name] = np.broadcast_to(f(*args), (len(traj),))
    return out


# ---------------------------------------------------------------------- DataFrame, xarray
def test_dataframe_columns_and_values(disk, traj):
    df = traj.to_dataframe()
    assert list(df.columns) == ["t", "x", "y", "phi", "psi", "x_t", "y_t", "phi_t", "psi_t",
                                "E2", "energy", "residual[0]", "residual[1]"]
    assert len(df) == len(traj) > 3
    assert np.array_equal(df["t"], traj.t)
    for j, name in enumerate(disk.state_names):
        assert np.array_equal(df[name], traj.y[:, j])
    for name, ref in phi_values(disk, traj).items():          # dependent velocities
        np.testing.assert_allclose(df[name], ref, rtol=1e-13, atol=1e-13)
    assert np.max(np.abs(df[["residual[0]", "residual[1]"]].to_numpy())) < 1e-7
    # energy and the integral E2 = L agree on the disk (L is kinetic)
    np.testing.assert_allclose(df["energy"], df["E2"], rtol=1e-12)
    assert df.attrs["method"] == "dop853" and df.attrs["principle"] == "chetaev"
    assert df.attrs["status"] == 0 and "end" in df.attrs["stop_reason"]
    assert '"R": 1.0' in df.attrs["parameters"]
    assert list(traj.to_dataframe(diagnostics=False).columns)[-1] == "psi_t"


def test_dataframe_multipliers_and_discrete_velocities(vak):
    tr = vak.run(**TOL)
    df = tr.to_dataframe(diagnostics=False)
    assert list(df.columns)[-2:] == ["lambda_x", "lambda_y"]
    assert np.array_equal(df["lambda_x"], tr.y[:, vak.state_names.index("lambda_x")])
    dvi = vak.run(method="dvi", h=0.05)
    d2 = dvi.to_dataframe()
    assert list(d2.columns[:11]) == list(df.columns)
    assert np.array_equal(d2["x_t"], dvi["x_t"]) and d2.attrs["method"] == "dvi"


def test_to_xarray(traj):
    pytest.importorskip("xarray")
    ds = traj.to_xarray()
    df = traj.to_dataframe()
    assert list(ds.dims) == ["t"] and ds.sizes["t"] == len(traj)
    assert set(ds.data_vars) == set(df.columns) - {"t"}
    for name in ds.data_vars:
        assert np.array_equal(ds[name].values, df[name].to_numpy())
    assert ds["x_t"].attrs["kind"] == "dependent velocity"
    assert ds["phi_t"].attrs["kind"] == "velocity"
    for key in ("method", "status", "stop_reason", "principle", "parameters"):
        assert ds.attrs[key] == df.attrs[key]


def test_to_xarray_without_xarray_names_the_extra(traj, monkeypatch):
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(JetnhError, match=r"pip install 'jetnh\[xarray\]'"):
        traj.to_xarray()


def test_ensemble_dataframe(disk):
    ens = disk.ensemble({"phi_t": [0.5, 1.0, 1.5]}, t_eval=[0.0, 1.0, 2.0], **TOL)
    df = ens.to_dataframe()
    assert len(df) == 9 and list(df["run"]) == [0, 0, 0, 1, 1, 1, 2, 2, 2]
    assert np.array_equal(df["x"].to_numpy().reshape(3, 3), ens["x"])
    assert np.array_equal(df["y_t"].to_numpy().reshape(3, 3), ens["y_t"])


# ---------------------------------------------------------------------- plot
def test_plot_on_given_axes_and_new_figure(traj):
    from matplotlib.figure import Figure

    from jetnh.numeric.dense import resampled

    ax = Figure().subplots()
    out = traj.plot(["x", sp.Symbol("y_t")], ax=ax)
    assert out is ax
    assert [ln.get_label() for ln in ax.get_lines()] == ["x", "y_t"]
    t_line = ax.get_lines()[1].get_xdata()
    rows = np.isin(t_line, traj.t)                  # the curve passes through every row
    assert rows.sum() == len(traj) and len(t_line) >= 400
    assert np.array_equal(ax.get_lines()[1].get_ydata()[rows], traj["y_t"])
    between = resampled(traj)                       # and through the dense output between
    assert np.array_equal(ax.get_lines()[1].get_ydata(), between["y_t"])
    assert np.array_equal(between.y[~rows], traj.at(t_line[~rows]).to_numpy())
    rough = traj.plot("x", ax=Figure().subplots(), smooth=False, steps=True)
    assert [np.array_equal(ln.get_xdata(), traj.t) for ln in rough.get_lines()] == [True] * 2
    assert ax.get_xlabel() == "t" and ax.get_legend() is not None
    import matplotlib.pyplot as plt

    ax2 = traj.plot()
    try:
        assert [ln.get_label() for ln in ax2.get_lines()] == ["x", "y", "phi", "psi"]
    finally:
        plt.close(ax2.figure)
    with pytest.raises(JetnhError, match="not a series.*choose from"):
        traj.plot(["nope"], ax=ax)
    with pytest.raises(ArgumentError, match="ax must be a matplotlib Axes"):
        traj.plot(ax=ax.figure)
    with pytest.raises(ArgumentError, match="diagnostics must be True or False"):
        traj.to_dataframe(diagnostics="no")
    with pytest.raises(ArgumentError, match="names= or y="):
        traj.plot("x", y="y", ax=ax)


def test_the_path_of_the_disk_is_a_circle():
    """Closed form: with phi_t = 1, psi_t = w and R = 1 the contact point runs on the
    circle of radius 1/w about (0, 1/w) (from x = 0, y = 0, psi = 0); the smooth path
    keeps to it between the steps, where straight chords would leave it."""
    from matplotlib.figure import Figure

    w = 0.7
    sc = Scene(models.get("rolling_disk"), "chetaev", t_span=(0.0, 10.0),
               initial=dict(x=0, y=0, phi=0, psi=0, phi_t=1.0, psi_t=w))
    tr = sc.run(rtol=1e-10, atol=1e-12)
    assert len(tr) < 40                             # few steps: chords would show
    ax = tr.plot_path(ax=Figure().subplots())
    x, y = ax.get_lines()[0].get_data()
    assert ax.get_xlabel() == "x" and ax.get_ylabel() == "y"
    assert ax.get_aspect() == 1.0
    off = np.abs(np.hypot(x, y - 1 / w) - 1 / w)
    assert off.max() < 1e-8 and len(x) >= 400
    mid = (tr["x"][:-1] + tr["x"][1:]) / 2, (tr["y"][:-1] + tr["y"][1:]) / 2
    assert np.max(np.abs(np.hypot(mid[0], mid[1] - 1 / w) - 1 / w)) > 1e-3
    same = tr.plot(x="x", y="y", ax=Figure().subplots())
    assert np.array_equal(same.get_lines()[0].get_xdata(), x)


# ---------------------------------------------------------------------- evaluation
@pytest.mark.parametrize("method", ["dop853", "dopri5"])
@pytest.mark.parametrize("first_step", [None, 3.0])
def test_at_is_bitwise_the_t_eval_run(disk, method, first_step):
    rng = np.random.default_rng(3)
    kw = dict(method=method, rtol=1e-7, atol=1e-9, first_step=first_step)
    tr = disk.run(**kw)
    if first_step:                       # a first step too large: rejected steps on the way
        assert tr.diagnostics.rejected > 0
    times = np.concatenate([rng.uniform(0.0, 6.0, 40), tr.t[:4], [0.0, 6.0]])
    ref = disk.run(t_eval=np.sort(times), **kw)
    got = tr.at(times)
    order = np.argsort(times, kind="stable")
    assert list(got.columns) == list(disk.state_names) and np.array_equal(got.index, times)
    states = got.to_numpy()
    assert states.shape == (times.size, 6)
    assert np.array_equal(states[order], ref.y)     # to the last bit
    assert np.array_equal(got["phi_t"].to_numpy()[order], ref["phi_t"])


@settings(max_examples=10)
@given(st.lists(st.floats(-2.0, 0.0), min_size=1, max_size=12),
       st.sampled_from(["dop853", "dopri5"]))
def test_at_backward_runs_match_t_eval(disk, times, method):
    tr = disk.run(method=method, rtol=1e-7, atol=1e-9, t_span=(0.0, -2.0))
    times = np.array(times)
    ref = disk.run(method=method, rtol=1e-7, atol=1e-9, t_span=(0.0, -2.0),
                   t_eval=np.sort(times)[::-1])
    got = tr.at(times).to_numpy()[:, :6]
    assert np.array_equal(got[np.argsort(-times, kind="stable")], ref.y)


def test_at_rk4_hermite_has_the_order_of_rk4(disk):
    ref_run = disk.run(rtol=1e-13, atol=1e-14)
    mid = []
    for n in (60, 120):
        tr = disk.run(method="rk4", n_steps=n)
        # nodes: the stored rows themselves
        assert np.array_equal(tr.at(tr.t[5:8]).to_numpy()[:, :6], tr.y[5:8])
        t_mid = (tr.t[:-1] + tr.t[1:]) / 2
        mid.append(np.max(np.abs(tr.at(t_mid).to_numpy() - ref_run.at(t_mid).to_numpy())))
    assert mid[1] < 1e-6
    assert 10 < mid[0] / mid[1] < 24               # O(h^4): ratio 16 when h halves


def test_at_refusals(disk):
    tr = disk.run(**TOL)
    with pytest.raises(ArgumentError, match="within the trajectory's span"):
        tr.at([7.0])
    with pytest.raises(ArgumentError, match="finite"):
        tr.at([np.nan])
    with pytest.raises(ArgumentError, match="real numbers"):
        tr.at("0.5")                        # never parsed
    with pytest.raises(JetnhError, match="every step.*save='steps'"):
        disk.run(t_eval=[0.0, 1.0], **TOL).at([0.5])
    with pytest.raises(JetnhError, match="every step"):
        disk.run(save="final", **TOL).at([0.5])
    for kw in (dict(method="dla", h=0.1), dict(method="scipy-DOP853")):
        with pytest.raises(JetnhError, match="no dense output.*dop853"):
            disk.run(**kw).at([0.5])


def test_at_after_a_terminal_event(disk):
    tr = disk.run(events=[Event(sp.Symbol("x") - 0.5, terminal=True)], **TOL)
    assert tr.status == 5
    assert np.array_equal(tr.at(tr.t[-1]).to_numpy()[:, :6], tr.y[-1:])
    inside = (tr.t[-2] + tr.t[-1]) / 2
    with pytest.raises(JetnhError, match="stopped inside its last step"):
        tr.at(inside)
    before = (tr.t[-3] + tr.t[-2]) / 2
    ref = disk.run(t_eval=[before], **TOL)
    assert np.array_equal(tr.at(before).to_numpy()[:, :6], ref.y)


# ---------------------------------------------------------------------- displays
@pytest.fixture(scope="module")
def trailer():
    return models.get("n_trailer", N=8)


def test_large_system_and_equations_display_within_budget(trailer):
    for text in (trailer._repr_html_(), trailer._repr_latex_()):
        assert len(text) <= display.BUDGET
        assert "11 coordinates, 9 constraints" in text
    assert "theta8" in trailer._repr_html_()
    eq = trailer.equations("vakonomic")
    html, tex = eq._repr_html_(), eq._repr_latex_()
    assert len(eq.latex()) > 2 * display.BUDGET          # the complete (shared) form is large
    for text in (html, tex):
        assert len(text) <= display.BUDGET
        assert "vakonomic equations" in text
    assert "lambda_theta8" in html and "more lines" in tex
    big = Comparison(("vakonomic", "suslov"), False, None,
                     {q: e for q, e in zip(trailer.J.qdd, eq.expressions)})
    for text in (big._repr_html_(), big._repr_latex_()):
        assert len(text) <= display.BUDGET and "do not share" in text


def test_small_displays_show_the_facts(traj, disk):
    s = disk.system
    html = s._repr_html_()
    assert "x, y, phi, psi" in html and "R = 1" in html and r"\dot{x}" in html
    c = jn.compare(s, "vakonomic", "suslov")
    assert "branch" in c._repr_html_() and "suslov" in c._repr_latex_()
    th = traj._repr_html_()
    assert "dop853" in th and "reached the end" in th and "<th>phi_t</th>" in th
    assert traj._repr_latex_().startswith("$$")
    ens = disk.ensemble({"phi_t": np.linspace(0.5, 1.5, 4)}, save="final", **TOL)
    eh = ens._repr_html_()
    assert "4 x 1 rows, 4 succeeded" in eh and "residual" in eh
    assert len(ens._repr_latex_()) < display.BUDGET


@given(st.data())
def test_tree_size_counts_the_printed_tree(data):
    J = data.draw(jst.jet_spaces(max_n=3))
    e = data.draw(jst.jet_expressions(J, max_depth=3))
    n = sum(1 for _ in sp.preorder_traversal(e))
    assert display.tree_size(e, cap=10_000) == n
    assert display.tree_size(e, cap=3) == min(n, 4)


def test_an_exponentially_large_tree_is_summarized_quickly():
    J = jn.JetSpace("x y")
    e = J.qd[0]
    for _ in range(80):                      # a graph of 160 nodes, a tree of ~2^80
        e = sp.Mul(e, sp.Add(e, J.q[1], evaluate=False), evaluate=False)
    assert display.tree_size(e) == display.TREE_CAP + 1
    c = Comparison(("chetaev", "vakonomic"), True, None, {J.qdd[0]: e, J.qdd[1]: J.q[0]})
    for text in (c._repr_html_(), c._repr_latex_()):              # in shared form
        assert len(text) < display.BUDGET and "u_{1}" in text


@given(jst.systems(min_n=2, max_n=4),
       st.one_of(st.text(max_size=30), st.text(min_size=300, max_size=3000)))
def test_system_displays_stay_in_budget_and_name_the_coordinates(s, name):
    s = s.replace(name=name)
    J, constraints = s.J, s.given_constraints
    html, tex = s._repr_html_(), s._repr_latex_()
    assert len(html) <= display.BUDGET and len(tex) <= display.BUDGET
    assert ", ".join(q.name for q in J.q) in html
    assert f"{J.n} coordinates, {len(constraints)} constraint" in tex
