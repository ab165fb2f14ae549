"""Events and singularity stops inside the compiled integrators (no Python per step).

Two kinds of zero-finding run on the dense output of an accepted step:

*User events* follow ``scipy.integrate.solve_ivp`` exactly: an event function g(t, y)
is active in a step when ``g_old <= 0 <= g_new`` (direction > 0), ``g_old >= 0 >= g_new``
(direction < 0) or either (direction 0); its root is found by Brent's method
(``brentq`` with ``xtol = rtol = 4 eps``, a port of scipy's ``brentq.c``) on
``g(t, dense(t))``; ``terminal = m > 0`` stops at the m-th occurrence (counts of all
active events are raised first, then the roots sorted in the direction of integration).

*Singularity indicators* g_i (``codegen.singular_indicators``): with the sign s_i and the
size |g_i| at the initial state, the integration stops at the first time where
``s_i g_i <= singular_tol |g_i(t0)|`` or g_i is not finite (a crossing of zero or a fall
below the threshold), located by bisection on the dense output to the resolution of t;
the reported state is the last regular one (the left end of the final bracket).  If the
dense output of the step is not finite down to its start, the stop state is the start of
the step.

The ends of every step are checked (``watch_end``: the indicators at the step's end,
compared with their thresholds and with ``WATCH`` of their initial sizes; the explicit
loop writes the same check out), and nothing more is done in a step where no
indicator is violated or below WATCH at either end and no user event is active.  A step
where an indicator is below ``WATCH`` (1 %) of its initial size at an end is also
searched *inside* (``sing_dip``), so that a zero it only touches -- xdot^2 + ydot^2 at
a velocity reversal, which a step jumps over -- is not missed.  The search works on the margin
``w(theta) = min_i (s_i g_i - eps_i) / |g_i(t0)|`` along the interpolant (w <= 0:
violated): ``SAMPLES`` (8) equal parts of the step, their 7 inner points evaluated and the
ends known; m = ``CURVE`` (4) times the largest |w''| that the samples' second
differences show.  Between two points a distance l apart, a function with |w''| <= m lies
above the lower of its two values less m l^2 / 8 (its *floor*).  Every local minimum of
the samples (the smallest first) whose two neighbouring parts have a floor at or below
zero is searched by golden section in the bracket of its neighbours, which stops at a
violated point (returned), at a bracket narrower than 1e-15, or as soon as the floor of
its four points (with CURVE times their own curvature) is above zero: the step's least
value is then decided, above the threshold.  A step whose samples' floors are all above
zero needs the 7 samples only; a dip well above the threshold costs ~10-25 evaluations
(the golden section alone took ~70 to narrow the bracket to 1e-15), a dip that reaches
the threshold is searched as before, to the resolution of theta.  A dip the samples do
not show -- narrower than a part, curved more than CURVE times what the samples around it
show -- can be missed, as with any sampling.

*Crawling* (``sing_crawl``, adaptive loops): an indicator below ``WATCH`` that falls in a
step by less than ``CRAWL`` of its value while the step is below ``CRAWL`` of the longest
step since the watch began.  Approaching a zero at which the solution has a singularity
of finite order, an adaptive method takes steps a fixed fraction (~ tol^(1/(p+1))) of
the time left, so the relative fall per step stays bounded below; a fall per step that
shrinks without bound means the step is held by something the approach does not
explain -- typically the rounding of a 0/0 that the equations in this form cannot
resolve (Suslov's equations at the singular set of their split) -- and the run would
grind through its step budget without reaching the threshold.  ``loop`` stops such a
run as a singular stop after a run of crawling steps.

Dense output of every method in one form (``dense_eval``): with ``th1 = 1 - theta``::

    y(theta) = y0 + theta (F0 + th1 (F1 + theta (F2 + th1 (F3 + ...))))

which is Hairer's ``contd8`` (DOP853, 7 rows), ``contd5`` (DOPRI5, 4 rows) and, with 3
rows, the cubic Hermite interpolant used for the fixed-step RK4.
"""

import math

import numpy as np

from ._common import EVENT, SINGULAR, inline, jit  # noqa: F401

EPS = np.finfo(np.float64).eps
#: indicators below this fraction of their initial size are searched inside each step
WATCH = 1e-2
#: crawling (module docstring): a fall per step and a step ratio below this
CRAWL = 1e-4
GOLD = 0.3819660112501051
#: the search inside a step (``sing_dip``): the samples a step is cut into, and the factor
#: on the curvature the samples show that bounds it where no sample is
SAMPLES = 8
CURVE = 4.0


@jit
def dense_eval(theta, y, F, out):
    """y(theta) from the coefficient rows F (the form above)."""
    th1 = 1.0 - theta
    m = F.shape[0]
    for i in range(y.shape[0]):
        v = F[m - 1, i]
        for j in range(m - 2, -1, -1):
            if j % 2 == 0:
                v = F[j, i] + th1 * v
            else:
                v = F[j, i] + theta * v
        out[i] = y[i] + theta * v


@inline
def sing_init(sing, n_sing, tol, t, y, p, g, sig, eps, gref):
    """Signs, sizes and thresholds of the indicators at the initial state; returns the
    index of an indicator already zero or not finite there, else -1."""
    if n_sing == 0:
        return -1
    sing(t, y, p, g)
    for i in range(n_sing):
        if not math.isfinite(g[i]) or g[i] == 0.0:
            return i
        sig[i] = 1.0 if g[i] > 0.0 else -1.0
        gref[i] = abs(g[i])
        eps[i] = tol * gref[i]
    return -1


@inline
def near(sig, g_old, g_new, gref):
    """Whether an indicator of sign ``sig`` and initial size ``gref`` is below WATCH of
    that size at either end of a step (values g_old, g_new)."""
    return sig * g_old < WATCH * gref or sig * g_new < WATCH * gref


@inline
def sing_watch(n_sing, g_old, g_new, sig, gref):
    """Whether some indicator is below WATCH of its initial size at either end."""
    for i in range(n_sing):
        if near(sig[i], g_old[i], g_new[i], gref[i]):
            return True
    return False


@inline
def watch_end(sing, uev, n_sing, t_new, y_new, p, gs, gs_old, sig, eps, gref, gu_old,
              gu_new, ev_dir):
    """The watched quantities at the end (t_new, y_new) of an accepted step: the
    indicators into ``gs``, the user event functions into ``gu_new``.  Returns ``(si,
    more)``: the index of an indicator violated there (else -1), and whether the step
    needs more than these values (``loop.after_step``): an indicator violated, or below
    WATCH of its initial size at either end, or a user event active.  Most steps need
    nothing more: then the loop only moves the end's values to the ``_old`` arrays."""
    si = np.int64(-1)       # (not the literal -1: after_step is compiled once)
    more = False
    if n_sing > 0:
        si = sing_violated(sing, n_sing, t_new, y_new, p, gs, sig, eps)
        more = si >= 0 or sing_watch(n_sing, gs_old, gs, sig, gref)
    if ev_dir.shape[0] > 0:
        uev(t_new, y_new, p, gu_new)
        if any_user_active(gu_old, gu_new, ev_dir):
            more = True
    return si, more


@inline
def watch_next(n_sing, gs, gs_old, gu_old, gu_new):
    """The end's values of the watched quantities become the next step's start's."""
    for i in range(n_sing):
        gs_old[i] = gs[i]
    for i in range(gu_new.shape[0]):
        gu_old[i] = gu_new[i]


@inline
def sing_crawl(n_sing, g_old, g_new, sig, gref):
    """``(watched, index)`` over a step: whether an indicator is below WATCH of its
    initial size at its end, and the index of one that falls by less than CRAWL of its
    value there (else -1)."""
    watched = False
    idx = -1
    for i in range(n_sing):
        a = sig[i] * g_old[i]
        b = sig[i] * g_new[i]
        if b < WATCH * gref[i]:
            watched = True
            if b < a and a - b < CRAWL * b:
                idx = i
    return watched, idx


@inline
def _margin(n_sing, g, sig, eps, gref):
    """min_i (s_i g_i - eps_i) / |g_i(t0)| over the indicator values g (-inf if one is not
    finite): positive where every indicator is regular."""
    w = np.inf
    for i in range(n_sing):
        v = (sig[i] * g[i] - eps[i]) / gref[i]
        if not math.isfinite(v):
            return -np.inf
        w = min(w, v)
    return w


@jit
def _worst(sing, n_sing, t, y, p, g, sig, eps, gref):
    """The margin (``_margin``) of the indicators at (t, y), evaluated into g."""
    sing(t, y, p, g)
    return _margin(n_sing, g, sig, eps, gref)


@inline
def _floor(xa, fa, xb, fb, m):
    """A lower bound of a function on [xa, xb] from its values at the ends and a bound m
    of its second derivative: the chord's lower end less m (xb - xa)^2 / 8."""
    return min(fa, fb) - m * (xb - xa) ** 2 / 8.0


@inline
def _curvature(xa, fa, xb, fb, xc, fc):
    """|f''| from three points xa < xb < xc (twice the second divided difference)."""
    return 2.0 * abs(((fc - fb) / (xc - xb) - (fb - fa) / (xb - xa)) / (xc - xa))


@jit
def _golden(sing, n_sing, t_old, h, y_old, F, p, g, sig, eps, gref, ytmp, a, fa, b, fb):
    """theta in (a, b) where an indicator is violated on the step's interpolant, or -1.0:
    golden-section search for the least margin (``_worst``) on [a, b] (``fa``, ``fb``
    its values at the ends), until a point is violated, or the bracket's floor
    (``_floor`` over its four points with CURVE times their largest curvature) is above
    the threshold (the minimum is decided), or b - a < 1e-15."""
    x1 = a + GOLD * (b - a)
    x2 = b - GOLD * (b - a)
    dense_eval(x1, y_old, F, ytmp)
    f1 = _worst(sing, n_sing, t_old + x1 * h, ytmp, p, g, sig, eps, gref)
    dense_eval(x2, y_old, F, ytmp)
    f2 = _worst(sing, n_sing, t_old + x2 * h, ytmp, p, g, sig, eps, gref)
    for _ in range(80):
        if not (f1 > 0.0):
            return x1
        if not (f2 > 0.0):
            return x2
        if b - a < 1e-15:
            break
        m = CURVE * max(_curvature(a, fa, x1, f1, x2, f2), _curvature(x1, f1, x2, f2, b, fb))
        if min(_floor(a, fa, x1, f1, m), _floor(x1, f1, x2, f2, m),
               _floor(x2, f2, b, fb, m)) > 0.0:
            break
        if f1 < f2:
            b, fb = x2, f2
            x2, f2 = x1, f1
            x1 = a + GOLD * (b - a)
            dense_eval(x1, y_old, F, ytmp)
            f1 = _worst(sing, n_sing, t_old + x1 * h, ytmp, p, g, sig, eps, gref)
        else:
            a, fa = x1, f1
            x1, f1 = x2, f2
            x2 = b - GOLD * (b - a)
            dense_eval(x2, y_old, F, ytmp)
            f2 = _worst(sing, n_sing, t_old + x2 * h, ytmp, p, g, sig, eps, gref)
    return -1.0


@inline
def sing_dip(sing, n_sing, t_old, h, y_old, F, p, g, g_new, sig, eps, gref, ytmp):
    """Search inside a step whose ends are regular for a dip of an indicator below its
    threshold (module docstring); returns theta in (0, 1) where one is violated, or -1.0.
    ``g`` holds the indicators at the step's start (then scratch), ``g_new`` at its
    end."""
    w = np.empty(SAMPLES + 1)
    w[0] = _margin(n_sing, g, sig, eps, gref)
    w[SAMPLES] = _margin(n_sing, g_new, sig, eps, gref)
    kbest = 1
    for k in range(1, SAMPLES):
        th = k / SAMPLES
        dense_eval(th, y_old, F, ytmp)
        w[k] = _worst(sing, n_sing, t_old + th * h, ytmp, p, g, sig, eps, gref)
        if not (w[k] > 0.0):
            return th
        if w[k] < w[kbest]:
            kbest = k
    m = 0.0
    for k in range(1, SAMPLES):
        m = max(m, _curvature((k - 1) / SAMPLES, w[k - 1], k / SAMPLES, w[k],
                              (k + 1) / SAMPLES, w[k + 1]))
    m *= CURVE
    # golden section around the smallest sample, then around every other local minimum
    # of the samples, wherever the floor next to it may reach the threshold
    for j in range(SAMPLES):
        k = kbest if j == 0 else j
        if j > 0 and (k == kbest or w[k] > w[k - 1] or w[k] > w[k + 1]):
            continue
        a, b = (k - 1) / SAMPLES, (k + 1) / SAMPLES
        if min(_floor(a, w[k - 1], k / SAMPLES, w[k], m),
               _floor(k / SAMPLES, w[k], b, w[k + 1], m)) > 0.0:
            continue
        th = _golden(sing, n_sing, t_old, h, y_old, F, p, g, sig, eps, gref, ytmp, a,
                     w[k - 1], b, w[k + 1])
        if th > 0.0:
            return th
    return -1.0


@inline
def sing_violated(sing, n_sing, t, y, p, g, sig, eps):
    """Index of the first indicator with ``sig g <= eps`` or not finite, else -1."""
    sing(t, y, p, g)
    for i in range(n_sing):
        v = sig[i] * g[i]
        if not (v > eps[i]):          # also NaN
            return i
    return -1


@inline
def hermite_defect(rhs, t_old, h, y_old, F, p, ytmp, fmid):
    """Relative defect of the cubic Hermite interpolant at the middle of a step:
    |p'(1/2)/h - f(t + h/2, p(1/2))| / |f| (RMS norms).  O(h^3) where the solution is
    smooth, O(1) where the step straddles a kink of the right-hand side."""
    dense_eval(0.5, y_old, F, ytmp)
    rhs(t_old + 0.5 * h, ytmp, p, fmid)
    num = 0.0
    den = 0.0
    for i in range(y_old.shape[0]):
        d = (F[0, i] + 0.25 * F[2, i]) / h
        num += (d - fmid[i]) ** 2
        den += fmid[i] ** 2 + d * d
    if den == 0.0:
        return 0.0
    return math.sqrt(2.0 * num / den)


@inline
def most_watched(n_sing, g, sig, gref):
    """Index of the indicator smallest relative to its initial size."""
    best = np.inf
    k = 0
    for i in range(n_sing):
        v = sig[i] * g[i] / gref[i]
        if v < best:
            best = v
            k = i
    return k


@inline
def crossed(g_old, g_new, direction):
    """Whether an event function went from g_old to g_new across zero in ``direction``
    (> 0 up, < 0 down, 0 either; scipy's rule)."""
    up = g_old <= 0.0 and g_new >= 0.0
    down = g_old >= 0.0 and g_new <= 0.0
    if direction > 0:
        return up
    if direction < 0:
        return down
    return up or down


@jit
def user_active(g_old, g_new, direction, i):
    return crossed(g_old[i], g_new[i], direction[i])


@inline
def any_user_active(g_old, g_new, direction):
    for i in range(direction.shape[0]):
        if user_active(g_old, g_new, direction, i):
            return True
    return False


@inline
def _event_value(uev, i, t, t_old, h, y_old, F, p, ytmp, g):
    dense_eval((t - t_old) / h, y_old, F, ytmp)
    uev(t, ytmp, p, g)
    return g[i]


@inline
def brentq_event(uev, i, xa, xb, t_old, h, y_old, F, p, ytmp, g):
    """Root of event i on [xa, xb] by scipy's brentq (xtol = rtol = 4 eps, 100 iterations).
    If rounding of the dense output unbrackets the root, the end nearer to zero wins."""
    xtol = 4.0 * EPS
    rtol = 4.0 * EPS
    xpre = xa
    xcur = xb
    xblk = 0.0
    fblk = 0.0
    spre = 0.0
    scur = 0.0
    fpre = _event_value(uev, i, xpre, t_old, h, y_old, F, p, ytmp, g)
    fcur = _event_value(uev, i, xcur, t_old, h, y_old, F, p, ytmp, g)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if (fpre > 0.0) == (fcur > 0.0):
        return xpre if abs(fpre) < abs(fcur) else xcur
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and ((fpre > 0.0) != (fcur > 0.0)):
            xblk = xpre
            fblk = fpre
            spre = xcur - xpre
            scur = spre
        if abs(fblk) < abs(fcur):
            xpre = xcur
            xcur = xblk
            xblk = xpre
            fpre = fcur
            fcur = fblk
            fblk = fpre
        delta = (xtol + rtol * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre = scur
                scur = stry
            else:
                spre = sbis
                scur = sbis
        else:
            spre = sbis
            scur = sbis
        xpre = xcur
        fpre = fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = _event_value(uev, i, xcur, t_old, h, y_old, F, p, ytmp, g)
    return xcur


@inline
def sing_locate(sing, n_sing, t_old, h, y_old, F, p, g, sig, eps, ytmp, theta_hi):
    """Bisection for the first violation of an indicator in the step (it is regular at
    theta = 0 and violated at theta_hi).  Returns (theta_regular, index violated)."""
    lo = 0.0
    hi = theta_hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        t_mid = t_old + mid * h
        if t_mid == t_old + lo * h or t_mid == t_old + hi * h:
            break
        dense_eval(mid, y_old, F, ytmp)
        if sing_violated(sing, n_sing, t_mid, ytmp, p, g, sig, eps) < 0:
            lo = mid
        else:
            hi = mid
    dense_eval(hi, y_old, F, ytmp)
    idx = sing_violated(sing, n_sing, t_old + hi * h, ytmp, p, g, sig, eps)
    return lo, idx


@inline
def store_event(ev_t, ev_i, ev_y, n_ev, t, i, y):
    if n_ev >= ev_t.shape[0]:
        cap = max(2 * ev_t.shape[0], 8)
        t2 = np.empty(cap)
        i2 = np.empty(cap, dtype=np.int64)
        y2 = np.empty((cap, ev_y.shape[1]))
        for r in range(n_ev):
            t2[r] = ev_t[r]
            i2[r] = ev_i[r]
            for j in range(ev_y.shape[1]):
                y2[r, j] = ev_y[r, j]
        ev_t, ev_i, ev_y = t2, i2, y2
    ev_t[n_ev] = t
    ev_i[n_ev] = i
    for j in range(y.shape[0]):
        ev_y[n_ev, j] = y[j]
    return ev_t, ev_i, ev_y, n_ev + 1


@inline
def locate(sing, uev, n_sing, si, theta_hi, t_old, h, y_old, F, p, gs, sig, eps, gu_old,
           gu_new, ev_dir, ev_max, counts, ytmp, gtmp, roots, which, ev_t, ev_i, ev_y, n_ev,
           y_stop):
    """Everything that happened in the step from t_old to t_old + h (si: index of an
    indicator violated at theta_hi, or -1).

    Records the user events (up to a stop), and returns
    ``(stop, t_stop, sing_index, ev_t, ev_i, ev_y, n_ev)``: stop is 0 (go on), EVENT or
    SINGULAR, with the stop state in ``y_stop``.
    """
    direction = 1.0 if h > 0.0 else -1.0
    t_new = t_old + h
    sing_index = -1
    t_sing = t_new
    if si >= 0:
        theta, sing_index = sing_locate(sing, n_sing, t_old, h, y_old, F, p, gs, sig, eps,
                                        ytmp, theta_hi)
        if sing_index < 0:       # rounding: take the end of the step
            sing_index = si
        t_sing = t_old + theta * h
    n_act = 0
    for i in range(ev_dir.shape[0]):
        if user_active(gu_old, gu_new, ev_dir, i):
            roots[n_act] = brentq_event(uev, i, t_old, t_new, t_old, h, y_old, F, p, ytmp,
                                        gtmp)
            which[n_act] = i
            n_act += 1
    for a in range(n_act):
        counts[which[a]] += 1
    terminate = False
    for a in range(n_act):
        if ev_max[which[a]] > 0 and counts[which[a]] >= ev_max[which[a]]:
            terminate = True
    n_keep = n_act
    if terminate:
        # stable insertion sort in the direction of integration
        for a in range(1, n_act):
            r = roots[a]
            w = which[a]
            b = a - 1
            while b >= 0 and direction * (roots[b] - r) > 0.0:
                roots[b + 1] = roots[b]
                which[b + 1] = which[b]
                b -= 1
            roots[b + 1] = r
            which[b + 1] = w
        for a in range(n_act):
            if ev_max[which[a]] > 0 and counts[which[a]] >= ev_max[which[a]]:
                n_keep = a + 1
                break
    stop = 0
    t_stop = t_new
    if terminate:
        stop = EVENT
        t_stop = roots[n_keep - 1]
    if sing_index >= 0 and (stop == 0 or direction * (t_stop - t_sing) > 0.0):
        stop = SINGULAR
        t_stop = t_sing
    else:
        sing_index = -1
    for a in range(n_keep):
        if stop == SINGULAR and direction * (roots[a] - t_stop) > 0.0:
            continue
        dense_eval((roots[a] - t_old) / h, y_old, F, ytmp)
        ev_t, ev_i, ev_y, n_ev = store_event(ev_t, ev_i, ev_y, n_ev, roots[a], which[a], ytmp)
    if stop != 0:
        if t_stop == t_old:         # (F may not be finite: then 0 * F is not 0)
            for j in range(y_old.shape[0]):
                y_stop[j] = y_old[j]
        else:
            dense_eval((t_stop - t_old) / h, y_old, F, y_stop)
    return stop, t_stop, sing_index, ev_t, ev_i, ev_y, n_ev


# ---------------------------------------------------------------------- discrete nodes
@jit
def node_event_values(uev, t, row, cols, p, y, g):
    """The user event functions at a node of a discrete run (dla, dvi): the state ``y =
    row[cols]`` (coordinates, independent velocities, multipliers), ``g = uev(t, y)``."""
    for j in range(cols.shape[0]):
        y[j] = row[cols[j]]
    uev(t, y, p, g)


@jit
def node_events_start(uev, t, row, cols, p, n_user):
    """The work arrays of the user events of a discrete run, with the first node's values:
    the state ``y``, ``g_old`` (this node's values), ``g_new`` and the crossing counts."""
    y = np.empty(cols.shape[0])
    g_old = np.empty(n_user)
    g_new = np.empty(n_user)
    counts = np.zeros(n_user, dtype=np.int64)
    if n_user > 0:
        node_event_values(uev, t, row, cols, p, y, g_old)
    return y, g_old, g_new, counts


@jit
def node_terminal(uev, t, row, cols, p, y, g_old, g_new, direction, max_events, counts):
    """The user events from the previous node (``g_old``) to this one, with the rule of
    ``user_active``: each crossing counted; True if a terminal event (its ``max_events``-th
    crossing) occurred, so that the run ends at this node (the root between the two is
    located afterwards, ``numeric.discrete.node_events``).  ``g_old`` becomes this node's."""
    n_user = direction.shape[0]
    if n_user == 0:
        return False
    node_event_values(uev, t, row, cols, p, y, g_new)
    stop = False
    for i in range(n_user):
        if user_active(g_old, g_new, direction, i):
            counts[i] += 1
            if 0 < max_events[i] <= counts[i]:
                stop = True
        g_old[i] = g_new[i]
    return stop
