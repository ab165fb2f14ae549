"""Code generation: equations of motion -> numba kernels, from the shared graph.

A scene's equations become Python source text for its kernels, written to a module file
and compiled by numba as C callbacks with explicit signatures (``@cfunc(sig,
cache=True)``), so that a second process finds the machine code on disk (see
``jetnh.numeric.kernels``).  The integrators receive ``rhs_c`` as a first-class
function and are compiled once for all scenes; from Python, ``CompiledKernels.rhs`` and
the like call the callbacks through trampolines compiled once
(``jetnh.numeric.kernels.calls``).  Each body is compiled once: an njit function beside
its callback would compile it a second time.

``rhs(t, y, p, out)``
    the first-order system.  State layout ``y = (q^1..q^n, qdot^mu, lambda_a)``: every
    coordinate, the independent velocities, and the multipliers of the principles that
    have them (vakonomic, Hoelder, Suslov).  The dependent velocities are not states:
    the kernel computes qdot^alpha = phi^alpha(t, q, qdot^mu) first and uses them.
``aux(t, y, p, out)``
    ``out = (qdot^alpha (k), f^a (k), E, I_1..I_m[, P])``: dependent velocities, the
    residuals of the constraints as the user wrote them, the energy ``E = qdot^s dF/dqdot^s
    - F`` of ``F = L + lambda_a f^a`` on the constraints, user first integrals and, for a
    system with generalized forces, their power ``P = Q_s qdot^s`` (dE/dt = P - dF/dt).
``sing(t, y, p, out)``
    the *singularity indicators* (``singular_indicators``): quantities whose vanishing
    makes the equations singular -- det(df/dqdot^alpha) on the constraints (the split),
    and every denominator, square-root (fractional-power) argument, log argument, cos of
    a tan argument, ... that occurs in phi^alpha or in the accelerations (the reduced mass
    matrix's determinant is one of them).  The integrators stop where one of them
    crosses zero or falls below ``singular_tol`` times its initial size.
``hol(t, y, p, out)`` (systems with holonomic constraints g = 0 only)
    ``out = (g_1..g_m, dg_i/dq^j row by row)``, in the "sensitivities" variant followed
    by ``dg_i/dp_k`` (the runtime parameters) row by row: what the projection of an
    accepted step onto g = 0 evaluates (``methods.projection``).  ``aux`` then ends with
    g_1..g_m.
``jac(t, y, p, J)`` (the "jacobian" variant, ``kernels.jacobian_kernels(scene)``)
    ``J[i, j] = d rhs_i / d y_j`` (an n_state x n_state C-contiguous array), by forward
    mode over the graph (signature ``layout.JAC_SIGNATURE``).
``events(t, y, p, out)`` (``generate_events``, a separate small module)
    user event functions given as sympy expressions (an njit function, which compiled
    event callables call, and its callback ``events_c``).
``verdicts_c(t, y, p, out)`` (the "verdicts" variant, ``verdicts.generate_verdicts``, a
    separate small module) L and the first derivatives of the constraints that
    connect's verdicts read along a motion.

The module defines ``rhs_c``, ``aux_c``, ``sing_c`` (and ``jac_c``), the callbacks of the
kernels above.

``p`` holds the *runtime* parameters only (for ensembles over parameters without
recompiling); every other parameter is a number substituted on the graph
(``dag.xreplace``), so the compiler sees constants.  Numbers are printed with
``repr(float)``, which round-trips exactly.  Nothing is simplified, and no expression is
flattened: the accelerations share their subexpressions (the block solve's intermediate
quantities), and ``Emitter`` prints each distinct node once, in topological order, as
an assignment or inline in its only parent -- generation time and source size are
linear in the shared size.  ``jac`` (optional) differentiates the same graph node by
node.

The generated code is our own text (no user string is evaluated): user expressions are
sympy objects and reach the source only through the printer, with every symbol renamed
to a generated identifier (``s3``, ``v0``, ``p1``, ``c12``).

The modules, in the order of the data flow: ``spec`` (``KernelSpec``, the identity of a
kernel set and its key), ``prepare`` (user expressions in kernel symbols), ``indicators``
(singularity indicators), ``text`` (the printer and the ``Emitter``), ``llvm``
(straight-line programs and their derivatives), ``continuous`` and ``discrete`` (the
kernel modules' source).
"""

from .continuous import generate, generate_events, kernel_expressions
from .discrete import generate_dla
from .indicators import discrete_indicators, singular_indicators
from .spec import KernelSource, KernelSpec, multiplier_names, multiplier_symbols

__all__ = ["KernelSpec", "KernelSource", "generate", "generate_events", "generate_dla",
           "kernel_expressions", "multiplier_names", "multiplier_symbols",
           "singular_indicators", "discrete_indicators"]
