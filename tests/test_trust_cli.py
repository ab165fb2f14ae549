"""The command line keeps a user's data: outputs are checked before any work and written
atomically, option values are checked by the parser, a closed stderr does not crash it;
the kernel cache is covered in test_numeric_cache."""

import errno
import os
import subprocess
import sys

import pytest

from jetnh.cli import outputs
from jetnh.errors import JetnhError


def run(*args, shell=None):
    cmd = shell if shell else [sys.executable, "-m", "jetnh", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300,
                          shell=bool(shell))


@pytest.mark.parametrize("args, words", [
    (("derive", "rolling_disk", "--simplify", "inf"), "--simplify"),
    (("derive", "rolling_disk", "--simplify", "1e300"), "--simplify"),
    (("sweep", "appell_hamel", "--grid", "x_t=0.1:1:2", "--scheduler", "tcp://127.0.0.1:1",
      "--connect-timeout", "nan"), "--connect-timeout"),
    (("sweep", "appell_hamel", "--grid", "x_t=0.1:1:2", "--connect-timeout", "inf"),
     "--connect-timeout"),
    (("simulate", "appell_hamel", "--points", "-5"), "--points"),
    (("sweep", "appell_hamel", "--grid", "x_t=0.1:1:2", "--timeout", "nan"), "--timeout"),
    (("simulate", "appell_hamel", "--t-end", "nan"), "t_span"),
    (("simulate", "appell_hamel", "--steps", "0", "--method", "rk4"), "--steps"),
])
def test_option_values_refused_by_the_parser(args, words):
    r = run(*args)
    assert r.returncode in (1, 2) and words in r.stderr, r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("flag, name, words", [
    ("--plot", "p.xyz", ".xyz is not one of the formats"),
    ("--csv", "", "is a directory"),
    ("--csv", "missing/dir/x.csv", "does not exist"),
])
def test_simulate_checks_outputs_before_running(tmp_path, flag, name, words):
    target = tmp_path / name if name else tmp_path
    r = run("simulate", "appell_hamel", "--t-end", "0.1", flag, str(target))
    assert r.returncode == 1 and words in r.stderr and str(target) in r.stderr, r.stderr
    assert "integrating" not in r.stderr and "deriving" not in r.stderr


@pytest.mark.parametrize("flag, name, words", [
    ("--out", "x.txt", "give a .csv or .parquet path"),
    ("--out", "", "is a directory"),
    ("--plot", "map.xyz", ".xyz is not one of the formats"),
])
def test_sweep_checks_outputs_before_running(tmp_path, flag, name, words):
    target = tmp_path / name if name else tmp_path
    extra = ("--grid", "y_t=0.1:1:2", "--value", "x") if flag == "--plot" else ()
    r = run("sweep", "appell_hamel", "--t-end", "0.1", "--grid", "x_t=0.1:1:2", *extra,
            flag, str(target))
    assert r.returncode == 1 and words in r.stderr, r.stderr
    assert "sweeping" not in r.stderr and "deriving" not in r.stderr


def test_parquet_without_pyarrow_refused_first(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    with pytest.raises(JetnhError, match="parquet needs pyarrow"):
        outputs.check(tmp_path / "x.parquet", outputs.TABLE, "--out")


def test_failed_write_keeps_the_previous_file(tmp_path):
    """A full disk in the middle of a write: the old file stays whole, no temporary file
    is left, and the error names the path."""
    path = tmp_path / "run.csv"
    path.write_text("t,x\n0.0,1.0\n")

    def fill(tmp):
        with open(tmp, "w") as fh:
            fh.write("t,x\n0.0,1.2")                   # cut mid-number
        raise OSError(errno.ENOSPC, "No space left on device", tmp)

    with pytest.raises(JetnhError, match=f"cannot write {path}: No space left on device"):
        outputs.write(path, fill)
    assert path.read_text() == "t,x\n0.0,1.0\n"
    assert os.listdir(tmp_path) == ["run.csv"]
    outputs.write(path, lambda tmp: open(tmp, "w").write("t,x\n1.0,2.0\n"))
    assert path.read_text() == "t,x\n1.0,2.0\n" and os.listdir(tmp_path) == ["run.csv"]


def test_closed_stderr_does_not_crash(tmp_path):
    csv = tmp_path / "r.csv"
    r = run(shell=f"{sys.executable} -m jetnh simulate appell_hamel --t-end 0.1 "
                  f"--csv {csv} 2>&-")
    assert r.returncode == 0 and "final:" in r.stdout, r.stdout
    assert csv.read_text().startswith("t,")


def test_dask_scheduler_that_never_answers(tmp_path):
    """A socket that accepts connections and never answers: the sweep gives up after
    --connect-timeout with the address in the message."""
    pytest.importorskip("distributed")
    import socket
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    port = srv.getsockname()[1]
    held = []
    threading.Thread(target=lambda: [held.append(srv.accept()) for _ in range(8)],
                     daemon=True).start()
    try:
        r = run("sweep", "appell_hamel", "--t-end", "0.1", "--grid", "x_t=0.1:1:2",
                "--scheduler", f"tcp://127.0.0.1:{port}", "--connect-timeout", "2")
    finally:
        srv.close()
    assert r.returncode == 1 and f"127.0.0.1:{port}" in r.stderr, r.stderr
    assert "too large" not in r.stderr and "Traceback" not in r.stderr
