"""The jetnh command end to end, in a subprocess."""

import csv
import io
import json
import re
import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "jetnh", *args], capture_output=True,
                          text=True, timeout=300)


def test_compare_rolling_disk():
    r = run("compare", "rolling_disk")
    assert r.returncode == 0, r.stderr
    assert "nonholonomic" in r.stdout and "Chaplygin" in r.stdout
    assert "chetaev and suslov have the same accelerations at every state" in r.stdout
    assert "vakonomic and suslov agree on the branch" in r.stdout


def test_derive_json():
    r = run("derive", "appell_hamel", "--principle", "suslov", "--format", "json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["principle"] == "suslov" and data["multipliers"] == ["lambda_z"]
    assert set(data["accelerations"]) == {"x_tt", "y_tt", "z_tt", "lambda_z_t"}


def test_derive_writes_the_accelerations_in_the_independent_velocities():
    """On the manifold the dependent velocities are their values phi: the Suslov disk's
    accelerations are the closed forms x'' = -R phi' psi' sin(psi), phi'' = psi'' = 0."""
    r = run("derive", "rolling_disk", "--principle", "suslov", "-q")
    assert r.returncode == 0, r.stderr
    acc = r.stdout.split("accelerations on the constraint manifold")[1].split(
        "the constraint manifold")[0]
    assert "(in the independent velocities: x_t, y_t replaced by their values below)" in acc
    assert not re.search(r"\b[xy]_t\b", acc.split("\n", 1)[1])
    assert "x_tt = -R*phi_t*psi_t*sin(psi)" in acc and "phi_tt = 0" in acc


def test_errors_exit_codes_and_no_traceback():
    r = run("derive", "no_such_model")
    assert r.returncode == 1 and "no model named" in r.stderr and "Traceback" not in r.stderr
    r = run("derive", "rolling_disk", "--form", "nonsense")
    assert r.returncode == 1 and "forms" in r.stderr and "Traceback" not in r.stderr
    r = run("frobnicate")
    assert r.returncode == 2 and "Traceback" not in r.stderr


# ---------------------------------------------------------------------- issue 7
import pathlib  # noqa: E402

import pytest  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
DISK = str(ROOT / "examples" / "rolling_disk.toml")


def clean(r, code=0):
    assert r.returncode == code, (r.returncode, r.stdout[-2000:], r.stderr[-2000:])
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout
    return r


def inproc(capsys, *args):
    """The command in this process (fast); returns (exit code, stdout, stderr)."""
    from jetnh.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:                 # argparse: --help (0) and usage errors (2)
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("cmd", ["derive", "compare", "simulate", "models", "bench",
                                 "reproduce"])
def test_help(cmd, capsys):
    code, out, _ = inproc(capsys, cmd, "--help")
    assert code == 0 and "usage: jetnh " + cmd in out


def test_top_level_help_lists_commands():
    r = clean(run("--help"))
    for cmd in ("derive", "compare", "simulate", "models", "bench", "reproduce"):
        assert cmd in r.stdout


def test_derive_model_file_text_and_latex():
    r = clean(run("derive", DISK, "--principle", "vakonomic"))
    assert "vakonomic equations" in r.stdout and "lambda_x_t" in r.stdout
    assert "jetnh: deriving" in r.stderr                    # progress on stderr
    r = clean(run("derive", DISK, "-p", "chetaev", "--format", "latex", "-q"))
    assert r.stdout.startswith(r"\begin{aligned}") and r.stderr == ""


def test_derive_split_and_catalogue_options():
    r = clean(run("derive", "knife_edge", "--split", "x", "--format", "json", "-q"))
    assert json.loads(r.stdout)["dependent"] == ["x"]
    r = clean(run("derive", "particle_chain:N=2", "--format", "json", "-q"))
    data = json.loads(r.stdout)
    assert data["dependent"] == ["z1", "z2"] and "x1_tt" in data["accelerations"]


def test_compare_model_file():
    r = clean(run("compare", str(ROOT / "examples" / "bead_on_parabola.toml"), "-q"))
    assert "integrable" in r.stdout and "equivalence:" in r.stdout


def test_simulate_catalogue_csv_plot_json(tmp_path):
    csv, png = tmp_path / "k.csv", tmp_path / "k.png"
    r = clean(run("simulate", "knife_edge", "--t-end", "0.5", "--set", "alpha=0.4",
                  "--init", "phi_t=1.5", "--csv", str(csv), "--plot", str(png)))
    assert "constraint residual max" in r.stdout and "alpha = 0.4" in r.stdout
    assert "jetnh: integrating" in r.stderr
    head = csv.read_text().splitlines()
    assert head[0].split(",")[:4] == ["t", "x", "y", "phi"] and len(head) == 202
    assert png.stat().st_size > 1000
    r = clean(run("simulate", "nonholonomic_particle", "-p", "suslov", "--t-end", "0.3",
                  "--points", "11", "--init", "lambda_z=0.1", "--format", "json", "-q"))
    data = json.loads(r.stdout)
    assert data["diagnostics"]["residual_max"] < 1e-9 and "lambda_z" in data["final"]


def test_simulate_model_file_with_integrals_and_multipliers():
    r = clean(run("simulate", str(ROOT / "examples" / "heisenberg_vakonomic.toml"),
                  "--t-end", "1", "-q"))
    assert "nonholonomic particle (vakonomic): vakonomic" in r.stdout
    assert "lambda_z = 0.3" in r.stdout and "integral p_x: drift" in r.stdout


def test_simulate_fixed_step():
    r = clean(run("simulate", DISK, "--t-end", "1", "--method", "rk4", "--steps", "50", "-q"))
    assert "steps 50" in r.stdout


def test_models_listing_and_toml(tmp_path):
    r = clean(run("models"))
    assert "n_trailer" in r.stdout and "suslov_rigid_body" in r.stdout
    r = clean(run("models", "chaplygin_sleigh"))
    assert "Source" in r.stdout and "First integral" in r.stdout
    r = clean(run("models", "chaplygin_sleigh", "--toml"))
    path = tmp_path / "sleigh.toml"
    path.write_text(r.stdout)
    r = clean(run("simulate", str(path), "-q"))
    assert "Chaplygin sleigh: chetaev" in r.stdout


def test_bench_lists_the_benchmarks():
    r = clean(run("bench"))
    assert "workprecision" in r.stdout and "report" in r.stdout and "--all" in r.stdout
    assert "_common" not in r.stdout                  # helpers are not benchmarks
    clean(run("bench", "no_such_benchmark"), 1)


@pytest.mark.parametrize("args, words", [
    (("bench", "--quick"), "--quick goes with --all"),
    (("bench", "--all", "workprecision"), "give no NAME"),
])
def test_bench_usage_errors(args, words, capsys):
    code, _, err = inproc(capsys, *args)
    assert code == 2 and words in err


def test_bench_report_renders_any_results(tmp_path):
    """The generic format of benchmarks/report.py (stress_*.json and the like)."""
    doc = {"benchmark": "stress_demo", "date": "2026-01-01T00:00:00+00:00",
           "command": "python benchmarks/stress_demo.py", "title": "A demo stress test",
           "summary": ["drift stays bounded"], "limits": ["cos(phi) < 1e-8: unreliable"],
           "rows": [{"case": "a", "drift": 1.5e-12, "detail": {"steps": 10}}]}
    (tmp_path / "stress_demo.json").write_text(json.dumps(doc))
    out = tmp_path / "B.md"
    clean(run("bench", "report", "--results", str(tmp_path), "--out", str(out)))
    md = out.read_text()
    assert "## Summary" in md and "cos(phi) < 1e-8: unreliable" in md
    assert "## A demo stress test" in md and "| case | drift | detail.steps |" in md
    assert "python benchmarks/stress_demo.py" in md


def test_bench_workprecision_quick_and_report(tmp_path):
    """Smoke test of the quick profile (no timing is asserted)."""
    path = str(tmp_path / "workprecision.json")
    clean(run("bench", "workprecision", "--quick", "--out", path))
    data = json.loads((tmp_path / "workprecision.json").read_text())
    assert data["profile"] == "quick" and data["command"].endswith("--quick --out " + path)
    assert {r["method"] for p in data["panels"] for r in p["runs"]} >= {
        "jetnh dop853", "jetnh dopri5", "scipy RK45", "scipy DOP853", "scipy LSODA", "scipy Radau"}
    exact = data["panels"][0]
    assert exact["reference"]["kind"] == "exact"
    assert exact["reference"]["tight_run_error"] < 1e-12
    for png in data["figures"]:
        assert (tmp_path / png).stat().st_size > 10_000
    for p in data["panels"]:                 # the floor: n x e + c, n jetnh's fewest
        f = p["floor"]
        assert f["per_evaluation_s"] > 0 and f["bare_call_nfev"] >= 6 and f["by_target"]
        for t, b in f["by_target"].items():
            reached = [r["nfev"] for r in p["runs"] if r["method"] in ("jetnh dop853",
                       "jetnh dopri5") and r["error"] is not None and r["error"] <= float(t)]
            assert b["nfev"] == min(reached) and b["loop_nfev"] > 0
            assert b["floor_s"] == b["nfev"] * f["per_evaluation_s"] + f["fixed_s"]
            assert b["scipy_over_floor"] == b["scipy_s"] / b["floor_s"]
    floor = data["summary"]["fastest_scipy_over_floor"]
    assert floor and all(set(v) >= {"geomean", "below_goal", "scipy_over_loop"}
                         for v in floor.values())
    clean(run("bench", "report", "--results", str(tmp_path), "--out", str(tmp_path / "B.md")))
    md = (tmp_path / "B.md").read_text()
    assert "Work-precision" in md and "the most any implementation making jetnh's rhs" in md


@pytest.mark.parametrize("args, code, words", [
    (("derive",), 2, "the following arguments are required"),
    (("simulate", "knife_edge", "--set", "alpha"), 2, "--set takes NAME=VALUE"),
    (("simulate", "knife_edge", "--set", "alpha=big"), 2, "is not a number"),
    (("derive", "n_trailer:N=x"), 2, "must be an integer"),
    (("derive", "--principle", "lagrange", "knife_edge"), 2, "invalid choice"),
    (("simulate", "knife_edge", "--t-end", "1", "--set", "Q=1"), 1, "not a parameter"),
    (("simulate", "knife_edge", "--t-end", "1", "--init", "nope=1"), 1, "not a state"),
    (("simulate", DISK, "--t-end", "1", "--init", "x_t=3"), 1, "--project"),
    (("simulate", DISK, "--t-end", "1", "--method", "nonsense"), 1, "unknown method"),
    (("simulate", DISK, "--t-end", "1", "--csv", "/no/such/dir/x.csv"), 1, "does not exist"),
    (("derive", "missing_model.toml"), 1, "no such file"),
    (("derive", "n_trailer:M=3"), 1, "no option M"),
    (("derive", "knife_edge", "--split", "x,y"), 1, "dependent coordinates"),
])
def test_error_exit_codes(args, code, words, capsys):
    got, out, err = inproc(capsys, *args)
    assert got == code and words in err, (got, err)


@pytest.mark.parametrize("args, code, words", [
    (("simulate", "knife_edge", "--set", "alpha"), 2, "--set takes NAME=VALUE"),
    (("simulate", "knife_edge", "--t-end", "1", "--set", "Q=1"), 1, "not a parameter"),
    (("derive", "missing_model.toml"), 1, "no such file"),
])
def test_error_exit_codes_in_a_subprocess(args, code, words):
    r = clean(run(*args), code)
    assert words in r.stderr, r.stderr


def test_simulate_needs_an_end_time(tmp_path):
    text = pathlib.Path(DISK).read_text().split("[simulation]")[0]
    path = tmp_path / "disk.toml"
    path.write_text(text)
    r = clean(run("simulate", str(path)), 2)
    assert "give --t-end" in r.stderr


def test_numerical_error_exit_code():
    """Suslov's equations of the isokinetic particle are singular everywhere."""
    r = clean(run("simulate", "isokinetic_particle", "-p", "suslov", "--t-end", "0.5",
                  "--init", "y_t=0.3", "-q"), 1)
    assert "singular" in r.stderr


def test_hostile_model_file_is_refused_and_not_executed(tmp_path):
    canary = tmp_path / "pwned"
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'coordinates = ["x"]\n'
        f'lagrangian = "x_t**2/2 + __import__(\'os\').system(\'touch {canary}\')"\n')
    r = clean(run("derive", str(bad)), 1)
    assert "attribute access is not allowed" in r.stderr and "line 1, column" in r.stderr
    bad.write_text('coordinates = ["x"]\n'
                   f'lagrangian = "x_t**2/2"\nconstraints = []\n[integrals]\n'
                   f'E = "open(\'{canary}\', \'w\')"\n')
    r = clean(run("simulate", str(bad), "--t-end", "1"), 1)
    assert "not an allowed function" in r.stderr
    bad.write_text('coordinates = ["x"]\nlagrangian = "9**9**9**9"\n')
    r = clean(run("derive", str(bad)), 1)
    assert "exponents" in r.stderr
    assert not canary.exists()


# ---------------------------------------------------------------------- issue 16
def test_cache_info_and_clear(capsys, tmp_path, monkeypatch):
    from jetnh.numeric import kernels as cache

    root = tmp_path / "c"
    monkeypatch.setenv("JETNH_CACHE", str(root))
    code, out, err = inproc(capsys, "cache", "info")
    assert code == 0 and str(cache.cache_root()) in out and "entries:      0" in out
    assert "usable:       yes" in out and "JETNH_CACHE" in out
    entry = cache.cache_root() / "kdeadbeef"
    entry.mkdir(parents=True)
    (entry / "kernels.py").write_bytes(b"x" * 2048)
    code, out, _ = inproc(capsys, "cache")
    assert code == 0 and "entries:      1 (2.0 KiB)" in out
    code, out, _ = inproc(capsys, "cache", "clear")
    assert code == 0 and "removed 1 cached entry" in out and not cache.cache_root().exists()
    assert not entry.exists()
    code, out, _ = inproc(capsys, "cache", "clear")
    assert code == 0 and "removed 0 cached entries" in out


def test_cache_info_names_the_fallback(capsys, tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("JETNH_CACHE", str(shared))
    code, out, _ = inproc(capsys, "cache", "info")
    assert code == 0 and "not usable" in out and "writable by group or others" in out
    assert "temporary cache" in out
    code, out, err = inproc(capsys, "cache", "warm")    # nothing compiled for nothing
    assert code == 3 and not out
    assert err.startswith("jetnh cache warm: error: nothing warmed: the kernel cache")
    assert "writable by group" in err and "each run compiles its loops on first use" in err
    code, _, err = inproc(capsys, "cache", "frobnicate")
    assert code == 2 and "invalid choice" in err


@pytest.mark.parametrize("args, words", [
    (("--rtol", "nan"), "--rtol must be 0 or a finite number"),
    (("--atol", "-1"), "--atol must be >= 0"),
    (("--timeout", "0"), "--timeout must be a positive number"),
    (("--method", "rk4", "--steps", "0"), "--steps must be a positive integer"),
    (("--rtol", "0", "--atol", "0"), "--atol is 0 for state 0 while the relative tolerance"),
])
def test_run_argument_errors_name_the_options(capsys, args, words):
    code, out, err = inproc(capsys, "simulate", "knife_edge", "--t-end", "1", "-q", *args)
    assert code == 1 and words in err and "Traceback" not in err, err
    assert "n_steps" not in err and " rtol" not in err and " atol" not in err


def test_sweep_argument_errors_name_the_options(capsys):
    code, _, err = inproc(capsys, "sweep", "rolling_disk", "--t-end", "1", "--grid", "R=1",
                          "--atol", "-1", "-q")
    assert code == 1 and "--atol must be >= 0" in err and "Traceback" not in err


def test_errors_name_the_option_that_gave_the_argument():
    """The command line names a refused argument by the option that gave it, through
    the error's ``argument`` (the message is never rewritten); a value that no option
    gave keeps the library's name."""
    import argparse
    import pickle

    from jetnh.cli import option_name
    from jetnh.errors import ArgumentError

    exc = ArgumentError("= 5 is beyond the budget max_steps = 4", argument="n_steps")
    assert str(exc) == "n_steps = 5 is beyond the budget max_steps = 4"
    given = argparse.Namespace(steps=5, rtol=None)
    assert exc.named(option_name(given, exc.argument)) == \
        "--steps = 5 is beyond the budget max_steps = 4"
    rtol = ArgumentError("must be positive", argument="rtol")
    assert rtol.named(option_name(given, "rtol")) == "rtol must be positive"   # not given
    assert rtol.named(option_name(argparse.Namespace(), "rtol")) == "rtol must be positive"
    back = pickle.loads(pickle.dumps(exc))               # as from a Dask worker
    assert (str(back), back.argument, back.detail) == (str(exc), exc.argument, exc.detail)
    plain = ArgumentError("give n_steps= or h=, not both")
    assert plain.argument is None and plain.named(option_name(given, None)) == str(plain)


def test_quiet_leaves_only_errors(capsys, tmp_path):
    out_csv = str(tmp_path / "k.csv")
    for argv in (("-q", "simulate"), ("simulate", "-q")):
        code, out, err = inproc(capsys, *argv, "knife_edge", "--t-end", "0.5", "--csv",
                                out_csv)
        assert code == 0 and err == "" and "final:" in out, err
    code, _, err = inproc(capsys, "simulate", "knife_edge", "--t-end", "0.5", "--csv",
                          out_csv)
    assert code == 0 and f"wrote {out_csv}" in err
    code, out, err = inproc(capsys, "-q", "sweep", "rolling_disk", "--t-end", "0.5",
                            "--grid", "R=1,2")
    assert code == 0 and err == "" and out.startswith("R,"), err
    code, _, err = inproc(capsys, "-q", "simulate", "no_such_model")
    assert code == 1 and "no model named" in err


@pytest.mark.parametrize("cmd", ["", "derive", "compare", "simulate", "sweep", "models",
                                 "bench", "reproduce", "cache"])
def test_help_is_plain_text(cmd, capsys):
    code, out, _ = inproc(capsys, *([cmd] if cmd else []), "--help")
    assert code == 0 and "``" not in out and "usage: jetnh" in out


def test_simulate_help_documents_the_discrete_methods(capsys):
    _, out, _ = inproc(capsys, "simulate", "--help")
    text = " ".join(out.split())
    assert "dla (discrete Lagrange-d'Alembert" in text and "dvi (discrete vakonomic)" in text


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_long_steps_show_a_sign_of_life_on_a_terminal_only(monkeypatch):
    """On a terminal a step shows its elapsed time while it runs (a tqdm status line,
    here from the start), cleared before its final line; elsewhere plain lines; -q
    nothing."""
    import jetnh.cli as cli

    monkeypatch.setattr(cli.progress, "SIGN_OF_LIFE", 0.0)
    tty = _Terminal()
    with cli.Progress(stream=tty).step("deriving the chetaev equations"):
        pass
    text = tty.getvalue()
    assert "\rjetnh: deriving the chetaev equations ... 00:00" in text
    assert text.splitlines()[-1].startswith("jetnh: deriving the chetaev equations ... done (")
    pipe = io.StringIO()
    with cli.Progress(stream=pipe).step("deriving"):
        pass
    assert pipe.getvalue() == "jetnh: deriving ...\n"
    quiet = _Terminal()
    with cli.Progress(quiet=True, stream=quiet).step("deriving"):
        pass
    assert quiet.getvalue() == ""


def test_sweep_progress_is_a_bar_on_a_terminal_and_tenths_elsewhere():
    from jetnh.cli import Progress

    pipe = io.StringIO()
    show, close = Progress(stream=pipe).bar("sweeping on this machine", "point")
    for done in range(1, 21):
        show(done, 20)
    close()
    lines = pipe.getvalue().splitlines()
    assert len(lines) == 11 and "\r" not in pipe.getvalue()       # tenths 0 to 10
    assert lines[-1].startswith("jetnh: sweeping on this machine: 20/20 points [")
    tty = _Terminal()
    show, close = Progress(stream=tty).bar("sweeping", "point")
    for done in (5, 20):
        show(done, 20)
    close()
    assert "\r" in tty.getvalue() and "20/20" in tty.getvalue()
    assert Progress(quiet=True).bar("sweeping", "point")[0] is None


# ---------------------------------------------------------------------- issue 13
def test_derive_large_model_bounded_on_screen_and_complete_in_a_file(capsys, tmp_path):
    code, out, err = inproc(capsys, "derive", "n_trailer:N=8", "-p", "vakonomic")
    assert code == 0 and len(out) <= 21_000
    assert "x_tt = " in out and "where" in out and "more named quantities" in out
    assert "--out FILE" in out and "simplifying" not in err
    path = tmp_path / "full.json"
    code, out, err = inproc(capsys, "derive", "n_trailer:N=8", "-p", "vakonomic",
                            "--format", "json", "--out", str(path))
    assert code == 0 and out == "" and f"wrote {path}" in err
    data = json.loads(path.read_text())
    assert "omitted" not in data and len(data["where"]) > 300
    assert set(data["accelerations"]) >= {"x_tt", "theta8_tt", "lambda_theta8_t"}
    names = set(data["where"])
    used = {w for text in data["accelerations"].values() for w in text.replace("(", " ")
            .replace(")", " ").replace("*", " ").replace("/", " ").split() if w in names}
    assert used                              # the rows refer to the named quantities
    tex = tmp_path / "full.tex"
    code, _, _ = inproc(capsys, "derive", "n_trailer:N=8", "-p", "vakonomic",
                        "--format", "latex", "--out", str(tex), "-q")
    text = tex.read_text()
    assert code == 0 and text.startswith(r"\begin{aligned}") and "more" not in text
    assert text.count(" &= ") >= len(data["where"]) + len(data["accelerations"])


def test_simplify_applies_to_small_results_and_zero_skips_it(capsys):
    code, out, err = inproc(capsys, "derive", DISK, "-p", "vakonomic")
    assert code == 0 and "simplified" in err and "I1 + R**2)" in out
    code, out, err = inproc(capsys, "derive", DISK, "-p", "vakonomic", "--simplify", "0")
    assert code == 0 and "simplif" not in err and "sin(psi)**2" in out


def test_compare_large_model_bounded(capsys):
    code, out, err = inproc(capsys, "compare", "n_trailer:N=5")
    assert code == 0 and len(out) <= 30_000
    assert "T and the forms on L~" in out and "chetaev accelerations" in out
    assert "vakonomic and holder have the same accelerations" in out
    assert ("vakonomic and suslov have the same accelerations at states on the branch" in out
            and "the motion leaves the branch" in out)      # (dL~/dq^alpha != 0 here)
    code, out, _ = inproc(capsys, "compare", "rolling_disk", "--format", "json", "-q")
    data = json.loads(out)
    assert "T^x_phi" in data["the constraint manifold and the embedded Lagrangian"]
    assert any("chetaev and suslov have the same" in v for v in data["equivalence"])


def test_simulate_plot_has_the_path_panel():
    """--plot adds the path in the (x, y) plane when the model has those coordinates,
    --path chooses the plane, --path none leaves it out."""
    import matplotlib

    matplotlib.use("Agg")
    from jetnh import models
    from jetnh.cli.commands.simulate import _figure, _path_names
    from jetnh.cli.usage import UsageError
    from jetnh.numeric import Scene

    disk = models.get("rolling_disk")
    assert _path_names(None, disk) == ("x", "y")
    assert _path_names("phi, psi", disk) == ("phi", "psi") and _path_names("none", disk) is None
    assert _path_names(None, models.get("suslov_rigid_body")) is None
    with pytest.raises(UsageError, match="two series names"):
        _path_names("x", disk)
    traj = Scene(disk, "chetaev", initial=models.initial("rolling_disk"),
                 t_span=(0.0, 2.0)).run(rtol=1e-8, atol=1e-10)
    fig = _figure(traj, disk, "disk", ("x", "y"))
    plane = fig.axes[-1]
    assert (plane.get_xlabel(), plane.get_ylabel()) == ("x", "y") and len(fig.axes) == 4
    assert plane.get_aspect() == 1.0
    assert len(_figure(traj, disk, "disk").axes) == 3


def test_the_default_tolerances_are_step_controls(capsys, monkeypatch):
    """Settings a model does not give fall back on StepControl's tolerances (read when
    a command runs), which the help shows (read from StepControl's source)."""
    import argparse

    from jetnh.cli.loading import load_model, settings
    from jetnh.numeric.options import StepControl

    rtol, atol = StepControl.rtol, StepControl.atol
    monkeypatch.setattr(StepControl, "rtol", 2.5e-7)
    monkeypatch.setattr(StepControl, "atol", 3.5e-11)
    opts = settings(argparse.Namespace(), load_model("chaplygin_sleigh"))
    assert (opts.rtol, opts.atol, opts.points, opts.t_start) == (2.5e-7, 3.5e-11, 201, 0.0)
    monkeypatch.undo()
    code, out, _ = inproc(capsys, "simulate", "--help")
    out = " ".join(out.split())
    assert code == 0 and "--rtol RTOL relative tolerance of the adaptive methods (default: " \
                         f"the model's, else {rtol:g})" in out
    assert "--atol ATOL absolute tolerance of the adaptive methods (default: the model's, " \
           f"else {atol:g})" in out
    assert "(default: the model's, else 201; 0: every step)" in out
    assert "--t-start T0 start time (default: the model's, else 0)" in out


def test_declared_defaults_are_the_imported_ones(monkeypatch, tmp_path):
    """The help's defaults read from the numerics' source (``cli.declared``) are the
    values a run imports: StepControl's fields, connect's keywords; a default the source
    does not give as a literal (or a module without source) is imported."""
    import inspect

    from jetnh.cli import declared as module
    from jetnh.numeric.connect import connect
    from jetnh.numeric.options import StepControl

    for name in ("rtol", "atol", "max_steps", "first_step"):
        assert module.declared("options", "StepControl", name) == getattr(StepControl, name)
    for name in ("tol", "rtol", "atol", "max_iter", "method", "segments"):
        assert module.declared("connect", "connect", name) == \
            inspect.signature(connect).parameters[name].default
    (tmp_path / "options.py").write_text("class StepControl:\n    rtol: float = 2 * 1e-3\n")
    monkeypatch.setattr(module, "NUMERIC", tmp_path)
    assert module.declared("options", "StepControl", "rtol") == StepControl.rtol
    assert module.declared("connect", "connect", "rtol") == \
        inspect.signature(connect).parameters["rtol"].default


def test_help_and_version_do_not_import_the_numerics():
    """--help of jetnh and of every subcommand, and --version, print without importing
    jetnh.numeric (numba, scipy): in a fresh interpreter, the modules loaded after."""
    code = """if True:
        import contextlib, io, json, sys
        from jetnh.cli import main
        from jetnh.cli.commands import COMMANDS
        for args in [["--help"], ["--version"]] + [[c.__name__.rsplit(".", 1)[1], "--help"]
                                                   for c in COMMANDS]:
            with contextlib.redirect_stdout(io.StringIO()) as out:
                try:
                    main(args)
                except SystemExit as exc:
                    assert exc.code == 0, (args, exc.code)
            assert out.getvalue(), args
        print(json.dumps(sorted(m for m in sys.modules if m.startswith("jetnh.numeric")
                                or m.split(".")[0] in ("numba", "scipy"))))
    """
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.splitlines()[-1]) == []


def test_make_installs_with_an_unusable_cache(tmp_path):
    """make's install step runs `jetnh cache warm` and accepts its exit code 3 (the
    cache cannot be used; runs still work) with a note, but stops on any other failure:
    the step as `make -n` prints it, run by sh with jetnh in place of the venv's."""
    import os
    import shutil
    from pathlib import Path

    import pytest

    if shutil.which("make") is None:
        pytest.skip("no make")
    root = Path(__file__).resolve().parents[1]
    venv = tmp_path / "venv"
    printed = subprocess.run(["make", "-n", "-C", str(root), f"VENV={venv}",
                              f"{venv}/.installed"], capture_output=True, text=True,
                             timeout=60)
    assert printed.returncode == 0, printed.stderr
    script = printed.stdout
    step = script[script.index(f"{venv}/bin/jetnh"):script.index(f"touch {venv}")]
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    env = {**os.environ, "JETNH_CACHE": str(shared)}

    def install(jetnh):
        return subprocess.run(["sh", "-c", step.replace(f"{venv}/bin/jetnh", jetnh)],
                              capture_output=True, text=True, env=env, timeout=300)
    r = install(f"{sys.executable} -m jetnh")
    assert r.returncode == 0, r.stderr
    assert "jetnh cache warm: error: nothing warmed" in r.stderr
    assert "make: installed without warming the cache (see above)" in r.stdout
    for code in (1, 2):                                   # any other failure stops make
        r = install(f"sh -c 'exit {code}'")
        assert r.returncode != 0 and "installed without" not in r.stdout


# ---------------------------------------------------------------------- help as read
def test_help_is_filled_to_the_terminal(capsys, monkeypatch):
    """Descriptions and epilogs wrap at the terminal's width (examples, indented, stay
    whole); every command has a description and helps its positional arguments."""
    monkeypatch.setenv("COLUMNS", "80")
    for command in ("", "models", "derive", "compare", "simulate", "connect", "sweep",
                    "linearize", "bench", "cache", "reproduce"):
        code, out, _ = inproc(capsys, *command.split(), "--help")
        assert code == 0
        long = [line for line in out.splitlines()
                if len(line) > 80 and not line.startswith("  jetnh ")]
        assert not long, (command, long)
        usage, description = out.split("\n\n")[:2]
        assert not description.startswith(("positional", "options")), command
    code, out, _ = inproc(capsys, "bench", "--help")
    assert "a benchmark script of benchmarks/" in out and "the script's own options" in out
    code, out, _ = inproc(capsys, "models", "--help")
    assert "a catalogue name, with options" in " ".join(out.split())
    code, out, _ = inproc(capsys, "--help")
    assert "derive, compare, simulate, connect, sweep and linearize" in " ".join(out.split())


def test_connect_offers_only_what_it_uses(capsys, monkeypatch, tmp_path):
    """connect's help states its own defaults (vakonomic, jetnh.connect's tolerances); it
    has no --convention or --steps, which it would ignore; a model file's principle is
    its default, as for the other commands."""
    import inspect
    from pathlib import Path

    from jetnh.errors import ConnectError
    from jetnh.numeric import connect as connecting

    code, out, _ = inproc(capsys, "connect", "--help")
    out = " ".join(out.split())
    rtol = inspect.signature(connecting.connect).parameters["rtol"].default
    assert code == 0 and f"(default: jetnh.connect's, {rtol:g})" in out
    assert "(default: the model's, else vakonomic);" in out
    for option in (("--convention", "imposed"), ("--steps", "5")):
        code, _, err = inproc(capsys, "connect", "heisenberg", "--to", "x=1", *option)
        assert code == 2 and f"unrecognized arguments: {' '.join(option)}" in err

    used = []

    def connect(system, principle, *args, **kw):
        used.append(principle)
        raise ConnectError("stopped by the test")
    monkeypatch.setattr(connecting, "connect", connect)
    vakonomic = Path(__file__).resolve().parents[1] / "examples" / "heisenberg_vakonomic.toml"
    holder = tmp_path / "heisenberg_holder.toml"
    holder.write_text(vakonomic.read_text().replace('principle = "vakonomic"',
                                                    'principle = "holder"'))
    for args in (("heisenberg",), ("heisenberg", "-p", "chetaev"), (str(holder),),
                 (str(holder), "-p", "vakonomic")):
        code, _, err = inproc(capsys, "connect", *args, "--to", "x=1", "--t-end", "1", "-q")
        assert code == 1 and "stopped by the test" in err
    assert used == ["vakonomic", "chetaev", "holder", "vakonomic"]


def test_models_toml_needs_a_name(capsys):
    code, out, err = inproc(capsys, "models", "--toml")
    assert code == 2 and not out and "--toml prints one model as a model file" in err


def test_method_default_is_the_models(capsys):
    for command in ("simulate", "sweep"):
        code, out, _ = inproc(capsys, command, "--help")
        assert "(default: the model's, else dop853)" in " ".join(out.split()), command


# ------------------------------------------------- arguments dropped or checked late
@pytest.mark.parametrize("option", ["--from", "--to", "--guess", "--set"])
def test_connect_refuses_a_name_given_twice(capsys, option):
    """A NAME=VALUE list (the one parser of --from, --to, --guess, --set, --init, --at)
    refuses a name given twice, in one item or in two, rather than keeping the last."""
    base = {"--from": "x=0,y=0", "--to": "x=1,y=0.5,z=0.2"}
    twice = {"--from": "x=0,x=0.5", "--to": "x=1,x=2", "--guess": "x_t=1,x_t=2",
             "--set": "m=1,m=2"}
    args = ["connect", "heisenberg", "-q", "--t-end", "1"]
    for opt in ("--from", "--to"):
        if opt != option:
            args += [opt, base[opt]]
    code, out, err = inproc(capsys, *args, option, twice[option])
    assert code == 2 and out == ""
    name = twice[option].split("=")[0]
    assert f"{option} gives {name} twice; give each name once" in err


def test_a_name_given_twice_in_two_items_is_refused():
    from jetnh.cli.running import assignments
    from jetnh.cli.usage import UsageError

    assert assignments(["a=1,b=2", "c=3"], "--set") == {"a": 1.0, "b": 2.0, "c": 3.0}
    with pytest.raises(UsageError, match="--init gives a twice"):
        assignments(["a=1", "b=2,a=1"], "--init")


def test_connect_notes_the_start_coordinates_from_the_model(capsys):
    """--from x=0,y=0 on heisenberg: z comes from the model's initial values, and the
    output says so (text and json), apart from those set to 0."""
    args = ["connect", "heisenberg", "-q", "--from", "x=0,y=0", "--to", "x=1,y=0.5,z=0.2",
            "--t-end", "1"]
    code, out, err = inproc(capsys, *args)
    assert code == 0, err
    assert "(not given, the model's initial values: z)" in out
    assert "set to 0" not in out
    code, out, err = inproc(capsys, *args, "--format", "json")
    data = json.loads(out)
    assert data["model_start"] == ["z"] and data["zero_start"] == []
    from jetnh import models
    assert data["start"]["z"] == models.model("heisenberg").initial["z"]


def test_simulate_refuses_an_unwritable_directory_before_the_run(capsys, monkeypatch,
                                                                 tmp_path):
    """A directory os.access calls writable (root, /proc) where no file can be made: the
    check makes one, before the run; an error never names the temporary file."""
    import tempfile

    from jetnh import errors
    from jetnh.cli import outputs

    real = tempfile.mkstemp

    def refuse(*a, dir=None, **kw):
        if dir is not None and pathlib.Path(dir) == tmp_path:
            raise PermissionError(13, "Permission denied", str(tmp_path / ".x.tmp"))
        return real(*a, dir=dir, **kw)

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    target = tmp_path / "x.csv"
    code, out, err = inproc(capsys, "simulate", "rolling_disk", "--t-end", "1",
                            "--csv", str(target))
    assert code == 1 and out == "" and "integrating" not in err
    assert f"cannot write --csv {target}: the directory {tmp_path} is not writable" in err
    with pytest.raises(errors.JetnhError) as exc:
        outputs.write(target, lambda tmp: None)
    assert str(target) in str(exc.value) and ".x.tmp" not in str(exc.value)
    assert "partial" not in str(exc.value)


def test_simulate_checks_the_path_names_before_the_run(capsys, tmp_path):
    """--path q,r: both unknown names, before anything is compiled or run; --path
    without --plot is refused (it would be dropped)."""
    code, out, err = inproc(capsys, "simulate", "rolling_disk", "--t-end", "1", "--path",
                            "q,r", "--plot", str(tmp_path / "p.png"))
    assert code == 2 and out == ""
    assert "--path: 'q', 'r' are not series of this run; choose from t, x, y," in err
    assert "compiling" not in err and "integrating" not in err
    assert not (tmp_path / "p.png").exists()
    code, out, err = inproc(capsys, "simulate", "rolling_disk", "--t-end", "1", "--path",
                            "x,r", "--plot", str(tmp_path / "p.png"))
    assert code == 2 and "--path: 'r' is not a series" in err and "'x'" not in err
    code, out, err = inproc(capsys, "simulate", "rolling_disk", "--t-end", "1", "--path",
                            "x,y")
    assert code == 2 and "give --plot PATH too" in err


def test_a_run_stopped_by_its_budget_prints_where_it_stopped(capsys):
    """--max-steps stops the run long before t_end, after its last output row: the final
    state printed is the state where it stopped (the run keeps it), the same as with
    --points 0 (every step: its last row); the stop names the budget's option."""
    args = ["simulate", "rolling_disk", "-q", "--t-end", "1e300", "--max-steps", "300"]
    code, out, err = inproc(capsys, *args)
    assert code == 1 and "final:      x = " in out and "last row" not in out
    assert re.search(r"stopped:    at t = 258\.\d+: the step budget of 300 steps "
                     r"\(--max-steps\) ran out; raise --max-steps to go further", out), out
    assert re.search(r"jetnh: error: the integration stopped early: the step budget of 300 "
                     r"steps \(--max-steps\) ran out at t = 258\.\d+;", err), err
    code, out, err = inproc(capsys, *args, "--format", "json")
    points = json.loads(out)
    code, out, err = inproc(capsys, *args, "--points", "0", "--format", "json")
    every = json.loads(out)
    assert code == 1 and every["diagnostics"]["steps"] == points["diagnostics"]["steps"] == 300
    for data in (points, every):
        assert data["final_is_last_state"] is True and data["final_t"] > 250
    assert points["final_t"] == every["final_t"] and points["final"] == every["final"]
    # rolling_disk: phi_t is constant, so phi(t) = phi0 + phi_t t at the stop
    assert points["final"]["phi"] == pytest.approx(
        points["initial"]["phi"] + points["initial"]["phi_t"] * points["final_t"], rel=1e-9)


@pytest.mark.parametrize("args, code, words", [
    (("--max-steps", "0"), 2, "argument --max-steps: '0' is below 1"),
    (("--max-steps", str(2**60)), 1, "--max-steps must be a positive integer of at most"),
    (("--steps", "50"), 2, "--steps sets the steps of the fixed-step methods rk4, dla and "
                           "dvi; dop853 chooses its own: give "),
    (("--steps", "50"), 2, ", --max-steps N for a step budget, or --method rk4 --steps N "
                           "for fixed steps"),
    (("--method", "radau", "--steps", "50"), 2, "radau chooses its own"),
    (("--method", "rk4", "--max-steps", "500"), 2, "--max-steps 500 is below the 1000 "
                                                   "steps of rk4 (--steps, default 1000)"),
    (("--method", "rk4", "--steps", "80", "--max-steps", "50"), 2,
     "--max-steps 50 is below the 80 steps of rk4 (--steps 80)"),
])
def test_step_options_are_checked_before_the_run(capsys, args, code, words):
    """--steps with an adaptive method would be ignored: refused, naming what to give
    instead; --max-steps is checked (and against the fixed steps) before anything is
    derived or compiled, in simulate and in sweep."""
    for command in (["simulate", "rolling_disk"],
                    ["sweep", "rolling_disk", "--grid", "R=1,2"]):
        got, out, err = inproc(capsys, *command, "--t-end", "1", *args)
        assert got == code and words in err and out == "", (command, err)
        assert "compiling" not in err and "Traceback" not in err
        if "--steps sets" in err:       # the command's own option of output times
            assert ("--points N for N output points" if command[0] == "simulate" else
                    "--times for output times") in err


def test_max_steps_reaches_the_runs_of_simulate_and_sweep(capsys):
    """The budget is passed through: rk4 with --steps 20 --max-steps 20 runs, and a sweep
    whose points stop by their budget says so in each row."""
    code, out, err = inproc(capsys, "simulate", "rolling_disk", "-q", "--t-end", "1",
                            "--method", "rk4", "--steps", "20", "--max-steps", "20",
                            "--format", "json")
    assert code == 0 and json.loads(out)["diagnostics"]["steps"] == 20
    code, out, err = inproc(capsys, "sweep", "rolling_disk", "-q", "--t-end", "1e300",
                            "--grid", "R=1,2", "--max-steps", "50")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and len(rows) == 2
    for row in rows:
        assert row["success"] == "False" and row["steps"] == "50"
        assert "stopped after max_steps steps" in row["stop_reason"]


def test_help_shows_the_step_budget(capsys):
    from jetnh.numeric.options import StepControl

    for command in ("simulate", "sweep"):
        code, out, _ = inproc(capsys, command, "--help")
        out = " ".join(out.split())
        assert code == 0 and (f"--max-steps N step budget of a run: it stops after N steps "
                              f"and says where (default {StepControl.max_steps})") in out
        assert "refused with the adaptive methods, which choose their own steps " \
               "(--max-steps bounds them)" in out


def test_connect_reports_legendre_and_plots_atomically(capsys, tmp_path, monkeypatch):
    """connect prints Legendre's margin (Heisenberg: the Hessian of L on the independent
    velocities xdot, ydot is the identity (L has no zdot), so 1) and records it in JSON;
    --plot replaces its file whole or not at all: a failure while writing leaves the
    previous file and no temporary one."""
    from matplotlib.figure import Figure

    target = tmp_path / "g.png"
    args = ["connect", "heisenberg", "-q", "--from", "x=0,y=0,z=0", "--to",
            "x=1,y=0.5,z=0.2", "--t-end", "1"]
    code, out, err = inproc(capsys, *args, "--format", "json")
    data = json.loads(out)
    assert code == 0 and data["legendre"] == pytest.approx(1.0, abs=1e-12)
    code, out, err = inproc(capsys, *args)
    assert code == 0 and "legendre:  1 (" in out
    assert ": positive definite all along)" in out
    chetaev = ["connect", "heisenberg", "-q", "-p", "chetaev", "--to", "x=1,y=0.5",
               "--t-end", "1"]
    code, out, err = inproc(capsys, *chetaev, "--format", "json")
    assert code == 0 and json.loads(out)["legendre"] is None    # not an extremal
    code, out, err = inproc(capsys, *chetaev)
    assert code == 0 and "cost:" in out and "legendre" not in out
    target.write_bytes(b"the previous plot")
    real = Figure.savefig

    def failing(self, fname, *a, **kw):
        real(self, fname, *a, **kw)              # a partial file, then the disk is full
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(Figure, "savefig", failing)
    code, out, err = inproc(capsys, *args, "--plot", str(target))
    assert code == 1 and f"cannot write {target}: No space left on device" in err
    assert target.read_bytes() == b"the previous plot"
    assert [p.name for p in tmp_path.iterdir()] == ["g.png"]
    monkeypatch.undo()
    target.chmod(0o640)
    code, out, err = inproc(capsys, *args, "--plot", str(target))
    assert code == 0 and target.read_bytes()[:4] == b"\x89PNG"
    assert target.stat().st_mode & 0o777 == 0o640           # the replaced file's


def test_a_model_option_given_twice_is_refused(capsys):
    code, out, err = inproc(capsys, "derive", "n_trailer:N=2,N=3", "-q")
    assert code == 2 and out == ""
    assert "model option N is given twice in 'n_trailer:N=2,N=3'" in err
