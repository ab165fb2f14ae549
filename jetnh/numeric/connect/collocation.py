"""The two-point problem of a scene as collocation data for ``scipy.integrate.solve_bvp``:
an independent route to ``connect``'s answers (the same compiled equations, solved on a
mesh instead of by shooting) and the baseline its benchmark measures against.

``problem(scene, start, end, t1)`` gives ``(fun, fun_jac, bc, t, Y)``: the right-hand
side and its Jacobian vectorised over the mesh (``fun_jac`` from the compiled Jacobian
of the derivation, or None for solve_bvp's finite differences), the boundary conditions
(every coordinate at t0, the coordinates named in ``end`` at t1) and a straight-line
guess on ``nodes`` mesh points (velocities of the named coordinates from the line, other
velocities 0.5, multipliers 0).
"""

from __future__ import annotations

import numpy as np

from .. import kernels


def problem(scene, start, end, t1, jacobian=True, nodes=11):
    """``(fun, fun_jac, bc, t, Y)`` for ``solve_bvp`` on ``scene``'s equations from
    ``start`` (every coordinate) at 0 to ``end`` (a dict of coordinates) at ``t1``."""
    kern, p, names = scene.kernels, scene.p, scene.state_names
    n, nq = len(names), len(scene.coordinates)
    jac = kernels.jacobian_kernels(scene).jac if jacobian else None

    def fun(t, Y):
        out, o = np.empty_like(Y), np.empty(n)
        for i in range(Y.shape[1]):
            kern.rhs(float(t[i]), np.ascontiguousarray(Y[:, i]), p, o)
            out[:, i] = o
        return out

    def fun_jac(t, Y):
        out, Jm = np.empty((n, n, Y.shape[1])), np.empty((n, n))
        for i in range(Y.shape[1]):
            jac(float(t[i]), np.ascontiguousarray(Y[:, i]), p, Jm)
            out[:, :, i] = Jm
        return out

    rows = [names.index(k) for k in end]
    target = np.array([end[k] for k in end], dtype=float)
    first = np.array([start[names[i]] for i in range(nq)], dtype=float)

    def bc(ya, yb):
        return np.concatenate([ya[:nq] - first, yb[rows] - target])

    t = np.linspace(0.0, t1, nodes)
    Y = np.full((n, t.size), 0.5)
    Y[nq + len(scene.velocities):] = 0.0
    for i, name in enumerate(names[:nq]):
        rate = (end.get(name, start[name]) - start[name]) / t1
        Y[i] = start[name] + rate * t
        if name in end and f"{name}_t" in names:
            Y[names.index(f"{name}_t")] = rate
    return fun, (fun_jac if jacobian else None), bc, t, Y
