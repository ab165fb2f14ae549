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


def mesh_functions(scene, jacobian=True):
    """``(fun, fun_jac)`` for ``solve_bvp``: ``scene``'s compiled right-hand side and its
    Jacobian (None without ``jacobian``) at every node of a mesh."""
    kern, p, n = scene.kernels, scene.p, len(scene.state_names)
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

    return fun, (fun_jac if jacobian else None)


def problem(scene, start, end, t1, jacobian=True, nodes=11):
    """``(fun, fun_jac, bc, t, Y)`` for ``solve_bvp`` on ``scene``'s equations from
    ``start`` (every coordinate) at 0 to ``end`` (a dict of coordinates) at ``t1``."""
    names, nq = scene.state_names, len(scene.coordinates)
    fun, fun_jac = mesh_functions(scene, jacobian)

    rows = [names.index(k) for k in end]
    target = np.array([end[k] for k in end], dtype=float)
    first = np.array([start[names[i]] for i in range(nq)], dtype=float)

    def bc(ya, yb):
        return np.concatenate([ya[:nq] - first, yb[rows] - target])

    t = np.linspace(0.0, t1, nodes)
    Y = np.full((len(names), t.size), 0.5)
    Y[nq + len(scene.velocities):] = 0.0
    for i, name in enumerate(names[:nq]):
        rate = (end.get(name, start[name]) - start[name]) / t1
        Y[i] = start[name] + rate * t
        if name in end and f"{name}_t" in names:
            Y[names.index(f"{name}_t")] = rate
    return fun, fun_jac, bc, t, Y


#: the warm start's mesh: its first nodes, its largest size and its tolerance (a start
#: for Newton, not the answer)
WARM_NODES, WARM_MAX_NODES, WARM_TOL = 21, 5000, 1e-5


def warm_start(shooter, rows=None, u=None):
    """The initial unknowns of ``shooter``'s problem (``solve.Search``) from direct
    collocation: ``solve_bvp`` on the scene's compiled equations and Jacobian, every
    coordinate and the fixed initial values (Suslov's multipliers) at t0, the end
    conditions ``rows`` (all when None: the named coordinates and the free ones'
    transversality conditions) at t1, on ``WARM_NODES`` nodes: first from the run with
    the unknowns ``u`` (a motion that misses the end), its named coordinates bent
    linearly in t onto the end, then from the straight line between the
    configurations (the velocities its rates, the multipliers 0).  None where the
    boundary conditions do not square with the states or solve_bvp finds no solution
    within ``WARM_MAX_NODES`` nodes from either."""
    import warnings

    from scipy.integrate import solve_bvp

    scene = shooter.scene
    names = scene.state_names
    nq = len(scene.coordinates)
    conds = list(range(len(shooter.target))) if rows is None else list(rows)
    fixed = [names.index(f) for f in shooter.fixed]
    if nq + len(fixed) + len(conds) != len(names):
        return None
    fun, fun_jac = mesh_functions(scene)
    y0, target = shooter.y0, shooter.target[conds]
    t0, t1 = shooter.span

    def bc(ya, yb):
        values, _ = shooter.conditions_at(t1, yb)
        return np.concatenate([ya[:nq] - y0[:nq], ya[fixed] - y0[fixed],
                               values[conds] - target])

    t = np.linspace(t0, t1, WARM_NODES)
    ends = dict(zip(shooter.end_names, shooter.target))
    meshes = []
    got = None if u is None else shooter.endpoint(u)
    if got is not None:
        Y = got[2].trajectory.at(t).to_numpy().T.copy()
        miss = shooter.target[:len(shooter.rows)] - Y[shooter.rows, -1]
        Y[shooter.rows] += np.outer(miss, (t - t0) / (t1 - t0))
        meshes.append(Y)
    Y = np.zeros((len(names), t.size))
    Y[fixed] = y0[fixed][:, None]
    for i, name in enumerate(names[:nq]):
        rate = (ends.get(name, y0[i]) - y0[i]) / (t1 - t0)
        Y[i] = y0[i] + rate * (t - t0)
        if f"{name}_t" in names:
            Y[names.index(f"{name}_t")] = rate
    meshes.append(Y)
    for Y in meshes:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            try:
                sol = solve_bvp(fun, bc, t, Y, fun_jac=fun_jac, tol=WARM_TOL,
                                max_nodes=WARM_MAX_NODES)
            except (ValueError, np.linalg.LinAlgError, ZeroDivisionError):
                continue
        if sol.status == 0 and np.all(np.isfinite(sol.y[:, 0])):
            return sol.y[shooter.cols, 0]
    return None
