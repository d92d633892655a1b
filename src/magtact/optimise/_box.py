"""Bound-constrained optimisation of a smooth function of (t, θ) over a box.

Three methods:

- :func:`multistart_optimum` (many problems at once, one box per row): the best local optima of
  a dense grid on each box, each refined by :func:`batch_optimum`; the best result per box.
  Used for every per-design result (:func:`magtact.optimise.per_heights`).
- :func:`batch_optimum` (many problems at once): the best point of a regular start grid (or
  given starts), refined by a vectorised projected Newton method with an active set. Used
  where thousands of heights are needed (NSGA-II, the exact reduction).
- :func:`box_optimum` (one problem): a seeded differential evolution (SciPy
  ``differential_evolution``) finds the basin, SciPy ``trust-constr`` with the exact gradient
  and Hessian refines it: the independent reference the tests check the other two against.

A box side of zero width (a degenerate box, t_m = 0 or θ_m = 0) fixes that variable; the other is
optimised alone, or the single point is evaluated.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, differential_evolution, minimize

VARS: tuple[str, str] = ("t", "theta")

Fun = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class BoxOptimum:
    """Optimum of one response over a box in (t, θ).

    Attributes
    ----------
    t, theta : float
        Location [-], [rad].
    value : float
        Response at the optimum (per unit G: N/Pa or N/(T·Pa)).
    start_t, start_theta, start_value : float
        Best point of the differential evolution (the start of the refinement) and its value.
    iterations : int
        Trust-region iterations of the refinement (0 if nothing was free to optimise).
    kkt : float
        Largest projected gradient component times the box width, relative to ``max(|value|,
        scale)``: 0 at an exact bound-constrained optimum.
    active : tuple of str
        Bounds the optimum lies on, among ``"t_lower", "t_upper", "theta_lower",
        "theta_upper"``; a zero-width side counts as both of its bounds.
    """

    t: float
    theta: float
    value: float
    start_t: float
    start_theta: float
    start_value: float
    iterations: int
    kkt: float
    active: tuple[str, ...]


def _active(x, lo, hi) -> tuple[str, ...]:
    out = []
    for i, name in enumerate(VARS):
        if x[i] <= lo[i]:
            out.append(f"{name}_lower")
        if x[i] >= hi[i]:
            out.append(f"{name}_upper")
    return tuple(out)


def _projected_gradient(g, x, lo, hi):
    """Gradient components that could still decrease a minimised function (zero at bounds)."""
    out = np.where((x <= lo) & (g > 0) | (x >= hi) & (g < 0), 0.0, g)
    return np.where(hi - lo <= 0, 0.0, out)


def box_optimum(fun: Fun, jac: Fun, hess: Fun, lo, hi, *, maximise: bool, population: int,
                generations: int, seed: int, tol: float) -> BoxOptimum:
    """Optimise ``fun`` over the box ``[lo, hi]`` in (t, θ): seeded differential evolution
    start, trust-region finish.

    Parameters
    ----------
    fun, jac, hess : callable
        Vectorised in x of shape (n, 2) = (t, θ): value (n,), gradient (n, 2), Hessian (n, 2, 2).
    lo, hi : array_like, shape (2,)
        Box bounds; ``lo[i] == hi[i]`` fixes variable i.
    maximise : bool
        Maximise instead of minimise.
    population, generations, seed : int
        Differential evolution's population (about; a multiple of the free variables), number
        of generations and random seed.
    tol : float
        ``gtol``, ``xtol`` and ``barrier_tol`` of ``trust-constr``.

    Returns
    -------
    BoxOptimum

    Notes
    -----
    The refinement minimises φ(x) = s·f(x)/c with s = −1 to maximise and c the magnitude of f at
    the evolution's point, so the tolerances are relative. The interior-point iterates of
    ``trust-constr`` stop at the barrier's distance from an active bound (about 1e-7 here), so an
    active-set step finishes the job: variables that lean on a bound are held there and
    ``trust-exact`` (unconstrained trust region, exact Hessian) solves for the others, which
    brings the projected gradient to ``tol``. The result is never worse than the evolution's
    start.
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    if lo.shape != (2,) or hi.shape != (2,) or np.any(hi < lo):
        raise ValueError(f"box bounds must be two pairs with lo <= hi, got lo={lo}, hi={hi}")
    sign = -1.0 if maximise else 1.0
    free = np.flatnonzero(hi > lo)

    def full(z):
        z = np.atleast_2d(z)
        x = np.broadcast_to(lo, (z.shape[0], 2)).copy()
        x[:, free] = z
        return x

    def phi_raw(z):
        v = sign * np.asarray(fun(full(z)), float)
        return np.where(np.isfinite(v), v, np.inf)

    if free.size == 0:
        x = lo.copy()
        v = float(fun(x[None])[0])
        return BoxOptimum(x[0], x[1], v, x[0], x[1], v, 0, 0.0, _active(x, lo, hi))

    z0 = _evolution(phi_raw, lo[free], hi[free], population, generations, seed)
    v0 = float(sign * phi_raw(z0[None])[0])
    scale = abs(v0) if v0 != 0 and np.isfinite(v0) else 1.0

    def phi(z):
        return float(phi_raw(z[None])[0]) / scale

    def dphi(z):
        return sign * np.asarray(jac(full(z)), float)[0][free] / scale

    def d2phi(z):
        return sign * np.asarray(hess(full(z)), float)[0][np.ix_(free, free)] / scale

    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore",
                                                divide="ignore"):
        warnings.filterwarnings("ignore", message=".*delta_grad == 0.0.*")
        res = minimize(phi, z0, method="trust-constr", jac=dphi, hess=d2phi,
                       bounds=Bounds(lo[free], hi[free], keep_feasible=True),
                       options={"gtol": tol, "xtol": tol, "barrier_tol": tol, "maxiter": 2000})
        z, nit = _active_set_finish(phi, dphi, d2phi, np.clip(res.x, lo[free], hi[free]),
                                    lo[free], hi[free], tol)
    if not phi(z) <= phi(z0) + _ROUNDOFF * max(1.0, abs(phi(z0))):
        z = z0
    x = full(z)[0]
    value = float(fun(x[None])[0])
    g = sign * np.asarray(jac(x[None]), float)[0]
    pg = _projected_gradient(g, x, lo, hi) * (hi - lo)
    kkt = float(np.max(np.abs(pg)) / max(abs(value), scale))
    xs = full(z0)[0]
    return BoxOptimum(float(x[0]), float(x[1]), value, float(xs[0]), float(xs[1]), v0,
                      int(res.nit) + nit, kkt, _active(x, lo, hi))


#: Relative change of the normalised objective below which two points count as equally good.
_ROUNDOFF = 1e-13


def _active_set_finish(phi, dphi, d2phi, z, lo, hi, tol, rounds: int = 4):
    """Finish a bound-constrained minimum with ``trust-exact`` on the free face.

    A variable within 1e-4 of the box width of a bound with its gradient pointing out of the box
    is held on that bound; ``trust-exact`` (exact Hessian, unconstrained) minimises over the
    others. The candidate replaces ``z`` when it stays in the box and is not worse beyond
    round-off; a held variable whose gradient then points inwards is released and the step
    repeated (at most ``rounds`` times). Returns the point and the iterations used.
    """
    width = hi - lo
    nit = 0
    for _ in range(rounds):
        g = dphi(z)
        held_lo = (z - lo <= 1e-4 * width) & (g > 0)
        held_hi = (hi - z <= 1e-4 * width) & (g < 0)
        cand = np.where(held_lo, lo, np.where(held_hi, hi, z))
        face = ~(held_lo | held_hi)
        if face.any():
            def put(y, base=cand, face=face):
                out = base.copy()
                out[face] = y
                return out

            try:
                res = minimize(lambda y, put=put: phi(put(y)), cand[face], method="trust-exact",
                               jac=lambda y, put=put, face=face: dphi(put(y))[face],
                               hess=lambda y, put=put, face=face: d2phi(put(y))[np.ix_(face,
                                                                                       face)],
                               options={"gtol": tol, "maxiter": 200})
            except ValueError:
                # the unconstrained step left the box into a region where a fitted model's
                # Hessian overflows; keep the bound-constrained point found so far
                break
            nit += int(res.nit)
            cand = _newton_polish(phi, dphi, d2phi, put(res.x), face, lo, hi)
        if np.any(cand < lo) or np.any(cand > hi):
            break
        if not phi(cand) <= phi(z) + _ROUNDOFF * max(1.0, abs(phi(z))):
            break
        z = cand
        g = dphi(z)
        wrong = (z <= lo) & (g < 0) | (z >= hi) & (g > 0)
        if not wrong.any():
            break
    return z, nit


def _newton_polish(phi, dphi, d2phi, z, face, lo, hi, steps: int = 3):
    """Plain Newton steps on ``face`` accepted while the gradient shrinks.

    Near an optimum the change of φ over the last steps is below round-off, so value-based
    trust-region tests stop early; gradient-based acceptance takes the last digits.
    """
    for _ in range(steps):
        g = dphi(z)[face]
        try:
            step = np.linalg.solve(d2phi(z)[np.ix_(face, face)], -g)
        except np.linalg.LinAlgError:
            break
        new = z.copy()
        new[face] += step
        if (np.any(new < lo) or np.any(new > hi)
                or not np.linalg.norm(dphi(new)[face]) < np.linalg.norm(g)
                or not phi(new) <= phi(z) + _ROUNDOFF * max(1.0, abs(phi(z)))):
            break
        z = new
    return z


def _evolution(phi, lo, hi, population, generations, seed) -> np.ndarray:
    """Best point of a seeded differential evolution minimising ``phi`` (vectorised) over
    ``[lo, hi]``: about ``population`` members (rounded up to a multiple of the free
    variables), ``generations`` generations, no early stop and no polish (the trust region
    refines the point).

    The evolution runs on the box widened by a tenth of its width on each side and evaluates a
    point outside at its projection onto the box, so that members land on a bound an optimum
    lies on. SciPy's own bound handling redraws a member that leaves the box at random, never
    on a bound, and from a start short of a bound along which the response is flat the
    refinement stops short of the bound too.
    """
    n, margin = lo.size, 0.1 * (hi - lo)
    with np.errstate(over="ignore", invalid="ignore"):
        # ``seed`` rather than ``rng``: the oldest SciPy magtact supports has no ``rng``
        res = differential_evolution(lambda z: phi(np.clip(z.T, lo, hi)),
                                     list(zip(lo - margin, hi + margin, strict=True)),
                                     popsize=max(1, -(-population // n)), maxiter=generations,
                                     tol=0.0, atol=0.0, polish=False, seed=seed,
                                     vectorized=True, updating="deferred")
    return np.clip(np.atleast_1d(np.asarray(res.x, float)), lo, hi)


# ---- many boxes at once -------------------------------------------------------------------------

BatchFun = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class BatchOptimum:
    """Optima of one response over one box per row (arrays of shape (n,)).

    ``t, theta, value`` as in :class:`BoxOptimum`; ``kkt`` the relative projected gradient;
    ``converged`` whether ``kkt <= tol`` or the iterate stopped moving.
    """

    t: np.ndarray
    theta: np.ndarray
    value: np.ndarray
    kkt: np.ndarray
    converged: np.ndarray
    #: The start of each row's refinement (the best grid point, or the given start) and the
    #: response there; Newton iterations of the returned row.
    start_t: np.ndarray | None = None
    start_theta: np.ndarray | None = None
    start_value: np.ndarray | None = None
    iterations: np.ndarray | None = None


def grid_local_optima(V: np.ndarray, k: int) -> np.ndarray:
    """Flat indices of up to ``k`` best local minima of each row's grid ``V`` (n, a, b),
    best first, shape (n, k); a row with fewer repeats its best.

    A point is a local minimum when no neighbour among its eight (fewer on an edge) is lower.
    """
    n, a, b = V.shape
    P = np.pad(V, ((0, 0), (1, 1), (1, 1)), constant_values=np.inf)
    local = np.ones(V.shape, bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                local &= V <= P[:, 1 + di:1 + di + a, 1 + dj:1 + dj + b]
    W = np.where(local, V, np.inf).reshape(n, -1)
    order = np.argsort(W, axis=1, kind="stable")[:, :k]
    best = np.argmin(V.reshape(n, -1), axis=1)
    ok = np.isfinite(np.take_along_axis(W, order, axis=1))
    order[:, 0] = best  # the best point is a local minimum unless every value is inf
    return np.where(ok | (np.arange(order.shape[1]) == 0), order, best[:, None])


def box_grid(fun: BatchFun, lo, hi, grid: tuple[int, int], sign: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A uniform ``grid`` of points (bounds included) on each of n boxes [lo, hi] and
    ``sign · fun`` there (inf where not finite): T, TH and values, each of shape (n, points)."""
    rows = np.arange(lo.shape[0])
    width = hi - lo
    s_t, s_th = np.linspace(0, 1, grid[0]), np.linspace(0, 1, grid[1])
    S_t, S_th = (a.ravel() for a in np.meshgrid(s_t, s_th, indexing="ij"))
    T = lo[:, :1] + width[:, :1] * S_t
    TH = lo[:, 1:] + width[:, 1:] * S_th
    V = sign * np.asarray(fun(rows[:, None], T, TH), float)
    return T, TH, np.where(np.isfinite(V), V, np.inf)


def multistart_optimum(fun: BatchFun, jac: BatchFun, hess: BatchFun, lo, hi, *,
                       maximise: bool, grid: tuple[int, int], tol: float, starts: int = 4,
                       maxiter: int = 100) -> BatchOptimum:
    """Optimise over n boxes at once from the best ``starts`` local optima of a dense grid.

    Every box gets a uniform ``grid`` of points (including its bounds); the ``starts`` best
    grid points that no neighbour improves on start a projected Newton refinement each
    (:func:`batch_optimum`, all rows and starts in one call), and each box keeps its best
    result. Where a response has several basins on the box the grid's resolution picks out
    every one deeper than its neighbours, and the refinement reaches each basin's optimum.
    Arguments as :func:`batch_optimum`; ``start_*`` of the result is the best grid point.
    """
    lo, hi = np.atleast_2d(np.asarray(lo, float)), np.atleast_2d(np.asarray(hi, float))
    n = lo.shape[0]
    sign = -1.0 if maximise else 1.0
    rows = np.arange(n)
    T, TH, V = box_grid(fun, lo, hi, grid, sign)
    k = grid_local_optima(V.reshape(n, grid[0], grid[1]), max(1, int(starts)))
    m = k.shape[1]
    orig = np.repeat(rows, m)
    x0 = np.stack([T[orig, k.ravel()], TH[orig, k.ravel()]], axis=1)

    def on(f):
        return lambda r, t, th: f(orig[np.asarray(r)], t, th)

    res = batch_optimum(on(fun), on(jac), on(hess), lo[orig], hi[orig], maximise=maximise,
                        grid=grid, tol=tol, maxiter=maxiter, start=x0)
    val = (sign * res.value).reshape(n, m)
    val = np.where(np.isfinite(val), val, np.inf)
    # the first of equally good results (within round-off): the best grid point's basin
    best = val.min(axis=1, keepdims=True)
    pick = np.argmax(val <= best + _ROUNDOFF * np.maximum(np.abs(best), 1e-300), axis=1)
    j = rows * m + pick
    b0 = k[:, 0]
    return BatchOptimum(res.t[j], res.theta[j], res.value[j], res.kkt[j], res.converged[j],
                        T[rows, b0], TH[rows, b0], sign * V[rows, b0], res.iterations[j])


def batch_optimum(fun: BatchFun, jac: BatchFun, hess: BatchFun, lo, hi, *, maximise: bool,
                  grid: tuple[int, int], tol: float, maxiter: int = 100,
                  start: np.ndarray | None = None) -> BatchOptimum:
    """Optimise over n boxes at once: best start-grid point (or given starts), projected Newton.

    Parameters
    ----------
    fun, jac, hess : callable
        ``fun(row, t, theta)``: the response of problem ``row`` (integer array) at (t, θ), all
        three broadcasting; ``jac`` returns (..., 2), ``hess`` (..., 2, 2) in (t, θ).
    lo, hi : array_like, shape (n, 2)
        Box of each problem; a zero-width side fixes that variable.
    maximise : bool
        Maximise instead of minimise.
    grid : (int, int)
        Start grid points along t and θ of each box (uniform, including the bounds).
    tol : float
        Stop a row when its relative projected gradient (see :class:`BoxOptimum`) is below tol.
    maxiter : int
        Newton iterations at most.
    start : numpy.ndarray, shape (n, 2), optional
        Start points (clipped to the boxes) instead of the grid: a warm start from known optima
        of nearby problems.

    Notes
    -----
    Minimises φ = s f with s = −1 to maximise. Active set: a variable at a bound whose gradient
    points out of the box, or a fixed one. On the free variables the step solves
    (∇²φ + μ I) d = −∇φ with μ ≥ 0 the smallest shift making the reduced Hessian's least
    eigenvalue at least max(1e-10 |λ|_max, −λ_min) (Newton where convex, the mirrored negative
    curvature elsewhere); the step is projected onto the box and halved until the Armijo
    condition φ(x⁺) ≤ φ(x) + 1e-4 ∇φ·(x⁺ − x) holds (where the reduced Hessian is positive
    definite the full step is also taken when φ changes only within round-off, so the location
    converges beyond what values resolve). A row stops when its relative projected
    gradient is below ``tol``, when the Newton step is below 1e-13 of the box width, or when no
    step along d decreases φ.
    """
    lo, hi = np.atleast_2d(np.asarray(lo, float)), np.atleast_2d(np.asarray(hi, float))
    n = lo.shape[0]
    sign = -1.0 if maximise else 1.0
    rows = np.arange(n)
    width = hi - lo

    def phi(r, x):
        v = sign * np.asarray(fun(r, x[:, 0], x[:, 1]), float)
        return np.where(np.isfinite(v), v, np.inf)

    if start is None:  # best point of a grid on each box
        T, TH, V = box_grid(fun, lo, hi, grid, sign)
        k = np.argmin(V, axis=1)
        x = np.stack([T[rows, k], TH[rows, k]], axis=1)
        f = V[rows, k]
        spread = np.max(np.where(np.isfinite(V), np.abs(V), 0), axis=1)
    else:
        x = np.clip(np.asarray(start, float), lo, hi)
        f = phi(rows, x)
        spread = np.abs(f)
    scale = np.maximum(np.abs(f), spread * 1e-3)
    scale = np.where(scale > 0, scale, 1.0)

    x_start, f_start = x.copy(), sign * f
    done = np.zeros(n, bool)
    kkt = np.full(n, np.inf)
    iterations = np.zeros(n, int)
    for _ in range(maxiter):
        r = np.flatnonzero(~done)
        if r.size == 0:
            break
        xr, lr, hr, wr = x[r], lo[r], hi[r], width[r]
        g = sign * np.asarray(jac(r, xr[:, 0], xr[:, 1]), float)
        Hs = sign * np.asarray(hess(r, xr[:, 0], xr[:, 1]), float)
        act = (wr <= 0) | (xr <= lr) & (g > 0) | (xr >= hr) & (g < 0)
        pg = np.where(act, 0.0, g)
        kkt[r] = np.max(np.abs(pg) * wr, axis=1) / np.maximum(np.abs(f[r]), scale[r])
        stop = kkt[r] <= tol
        done[r[stop]] = True
        keep = ~stop
        r, xr, lr, hr, pg, Hs, act = r[keep], xr[keep], lr[keep], hr[keep], pg[keep], Hs[keep], \
            act[keep]
        if r.size == 0:
            break
        d, convex = _newton_step(pg, Hs, act)
        # a Newton step below 1e-13 of the box: the location is resolved, stop there
        flat = np.max(np.abs(d) / np.where(wr[keep] > 0, wr[keep], 1.0), axis=1) <= 1e-13
        done[r[flat]] = True
        r, xr, lr, hr, pg, d, convex = (r[~flat], xr[~flat], lr[~flat], hr[~flat], pg[~flat],
                                         d[~flat], convex[~flat])
        if r.size == 0:
            break
        alpha = np.ones(r.size)
        moved = np.zeros(r.size, bool)
        x_new = xr.copy()
        pending = np.ones(r.size, bool)
        for _ in range(40):
            p = np.flatnonzero(pending)
            if p.size == 0:
                break
            trial = np.clip(xr[p] + alpha[p, None] * d[p], lr[p], hr[p])
            ft = phi(r[p], trial)
            ok = ft <= f[r[p]] + 1e-4 * np.sum(pg[p] * (trial - xr[p]), axis=1)
            # near a convex minimum φ changes below round-off: take the full Newton step
            ok |= (alpha[p] == 1) & convex[p] & (
                ft <= f[r[p]] + 1e-14 * np.maximum(np.abs(f[r[p]]), scale[r[p]]))
            same = np.all(trial == xr[p], axis=1)
            acc = p[ok & ~same]
            x_new[acc] = trial[ok & ~same]
            f[r[acc]] = ft[ok & ~same]
            moved[acc] = True
            pending[p[ok | same]] = False
            alpha[p[~(ok | same)]] *= 0.5
        x[r] = x_new
        iterations[r[moved]] += 1
        done[r[~moved]] = True  # no descent possible any more: converged to round-off
    converged = kkt <= tol
    # final values and KKT measure at the returned points
    value = sign * phi(rows, x)
    g = sign * np.asarray(jac(rows, x[:, 0], x[:, 1]), float)
    pg = _projected_gradient(g, x, lo, hi)
    kkt = np.max(np.abs(pg) * width, axis=1) / np.maximum(np.abs(value), scale)
    converged = converged | (kkt <= max(tol, 1e-9))
    return BatchOptimum(x[:, 0].copy(), x[:, 1].copy(), value, kkt, converged,
                        x_start[:, 0], x_start[:, 1], f_start, iterations)


def _newton_step(g, Hs, act) -> tuple[np.ndarray, np.ndarray]:
    """Regularised Newton step on the free variables of each row (2 variables), and whether
    the reduced Hessian was positive definite (no shift)."""
    Hm = Hs.copy()
    for i in range(2):
        Hm[:, i, :] = np.where(act[:, i:i + 1], 0.0, Hm[:, i, :])
        Hm[:, :, i] = np.where(act[:, i:i + 1], 0.0, Hm[:, :, i])
        Hm[:, i, i] = np.where(act[:, i], 1.0, Hm[:, i, i])
    a, b, c = Hm[:, 0, 0], Hm[:, 0, 1], Hm[:, 1, 1]
    mean, rad = 0.5 * (a + c), np.sqrt(0.25 * (a - c) ** 2 + b * b)
    lmin, lmax = mean - rad, np.maximum(np.abs(mean) + rad, 1e-300)
    floor = np.maximum(1e-10 * lmax, -lmin)
    mu = np.where(lmin < floor, floor - lmin, 0.0)
    a, c = a + mu, c + mu
    det = a * c - b * b
    # a row with a zero determinant steps to ±inf (the line search clips the trial to the
    # box) or NaN (never accepted): the numbers are meant, no warning
    with np.errstate(divide="ignore", invalid="ignore"):
        d0 = -(c * g[:, 0] - b * g[:, 1]) / det
        d1 = -(a * g[:, 1] - b * g[:, 0]) / det
    d = np.stack([d0, d1], axis=1)
    return np.where(act, 0.0, d), mu == 0
