"""The Newton solver of the discrete integrators' step equations (dla and dvi).

``solve_step`` solves ``G(z) = 0`` for z = (q_k+1 - q_k, multipliers) from the predictor
in z, with the exact Jacobian of the step kernel ``step_residual(t, h, q, p_k, z, p, G,
J)`` (generated symbolically, ``codegen.generate_dla``): ``z += J^-1 (-G)`` until the
update of the coordinates is below ``tol (1 + |z|)`` (max norms), in at most
``max_iter`` iterations.
"""

from ._common import all_finite, jit, solve_linear


@jit
def solve_step(step_residual, t, h, q, pk, z, p, G, Jm, dz, n, m, tol, max_iter, stats):
    """Newton for the step equations; True when converged (``stats[1]`` counts the
    iterations)."""
    for it in range(max_iter):
        step_residual(t, h, q, pk, z, p, G, Jm)
        stats[1] += 1
        for i in range(m):
            G[i] = -G[i]
        if not solve_linear(Jm, G, dz):
            return False
        size = 0.0
        scale = 0.0
        for i in range(m):
            z[i] += dz[i]
            if i < n:
                size = max(size, abs(dz[i]))
                scale = max(scale, abs(z[i]))
        if not all_finite(z):
            return False
        if size <= tol * (1.0 + scale):
            return True
    return False
