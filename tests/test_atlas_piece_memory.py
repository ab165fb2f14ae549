"""A fixed-step run through many changes of chart keeps memory linear in its steps.

Each piece of such a run was given output rows for every step to the run's end and kept
them until the pieces were stitched: memory quadratic in the switches (rk4 on a knife
edge with a slider, h = 0.01: 970 MB at T = 1000, 3.2 GB at T = 2000, out of memory at
T = 10^4).  The peak resident size of a process that runs T = 250 and one that runs
T = 1000 (273 switches, 10^5 steps of 8 states: ~8 MB of rows) are compared."""

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import resource, sys
    import sympy as sp
    import jetnh as jn
    J = jn.JetSpace("x y th z")
    x, y, th, z = J.q
    xt, yt, tht, zt = J.qd
    a, k, I = sp.symbols("a k I", positive=True)
    L = (xt**2 + yt**2 + I * tht**2 + zt**2) / 2 - k * z**2 / 2
    f = sp.sin(th) * xt - sp.cos(th) * yt
    system = jn.System(J, L, [f, z - a * sp.sin(th)], dependent=["y", "z"])
    T = float(sys.argv[1])
    sc = jn.Scene(system, "chetaev", params={"a": 0.4, "k": 3.0, "I": 0.7},
                  initial={"x": 0.0, "y": 0.0, "th": 0.3, "z": 0.4 * 0.29552020666133955,
                           "x_t": 1.0, "th_t": 0.7}, t_span=(0.0, T))
    tr = sc.run(method="rk4", h=0.01)
    assert tr.status == 0 and len(tr.switches) > T / 5, (tr.status, len(tr.switches))
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)
""")


def _peak_mb(T: float) -> int:
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(T)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return int(done.stdout.split()[-1])


def test_a_run_through_many_switches_keeps_memory_linear_in_its_steps():
    small, large = _peak_mb(250.0), _peak_mb(1000.0)
    assert large - small < 150, (small, large)     # (before: ~700 MB more)
