"""Per-design extrema (docs/method.md §7.1): stable shear bounds, then the largest F_z, Γ_r, Γ_z.

Every force and sensitivity is G times a function of (t, θ, H): F = G f, Γ = G γ. The stable shear
bounds (t_m, θ_m) and the locations of the maxima therefore do not depend on G; they are computed
once per height H (:class:`HeightResult`) and scaled by G for a design (:class:`DesignResult`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from .._errors import MagtactError
from ..metamodel import ModelSet
from ..sensitivity import Responses
from ..study import Study
from ._box import BatchOptimum, BoxOptimum, _active, batch_optimum, multistart_optimum

#: Stage-2 responses, maximised over [0, t_m] × [0, θ_m].
MAXIMISED: tuple[str, ...] = ("f_z", "gamma_r", "gamma_z")


def as_responses(models: Responses | ModelSet) -> Responses:
    """``models`` as :class:`magtact.sensitivity.Responses` (a ModelSet is wrapped)."""
    if isinstance(models, Responses):
        return models
    if isinstance(models, ModelSet):
        return Responses(models)
    raise TypeError(f"expected Responses or ModelSet, got {type(models).__name__}")


@dataclass(frozen=True)
class HeightResult:
    """Per-unit-G extrema at one height H (independent of G).

    Attributes
    ----------
    H : float
        Base height [m].
    f_r_min : BoxOptimum
        Minimum of f_r = F_r / G [N/Pa] over t ∈ [0, 1], θ ∈ [0, θ_max]; its location is
        (t_m, θ_m), the stable shear bounds.
    f_z_max, gamma_r_max, gamma_z_max : BoxOptimum
        Maxima of f_z [N/Pa], γ_r, γ_z [N/(T·Pa)] over t ∈ [0, t_m], θ ∈ [0, θ_m].
    """

    H: float
    f_r_min: BoxOptimum
    f_z_max: BoxOptimum
    gamma_r_max: BoxOptimum
    gamma_z_max: BoxOptimum

    @property
    def t_m(self) -> float:
        """Load at the minimum of F_r [-]."""
        return self.f_r_min.t

    @property
    def theta_m(self) -> float:
        """Shear angle at the minimum of F_r [rad]."""
        return self.f_r_min.theta

    @property
    def degenerate(self) -> str | None:
        """``None``, or which side of the stable box [0, t_m] × [0, θ_m] has zero width."""
        return _degenerate(self.t_m, self.theta_m)


def _degenerate(t_m: float, theta_m: float) -> str | None:
    if t_m == 0 and theta_m == 0:
        return "t_m = theta_m = 0"
    if t_m == 0:
        return "t_m = 0"
    if theta_m == 0:
        return "theta_m = 0"
    return None


@dataclass(frozen=True)
class DesignResult:
    """Extrema of a design (H, G) (docs/method.md §7.1), in SI units.

    Attributes
    ----------
    H, G : float
        Design [m], [Pa].
    height : HeightResult
        The per-unit-G extrema at H, with locations and refinement diagnostics.
    M_z : float or None
        Magnetisation [A/m] where it is a design variable (None: the magnet's own).
    field_scale : float
        The design's field over the models' field, M_z / magnet.M_z: B ∝ M_z, so every
        sensitivity (∂F/∂B) is divided by it.
    """

    H: float
    G: float
    height: HeightResult
    M_z: float | None = None
    field_scale: float = 1.0

    @property
    def t_m(self) -> float:
        """Stable shear bound in t [-]."""
        return self.height.t_m

    @property
    def theta_m(self) -> float:
        """Stable shear bound in θ [rad]."""
        return self.height.theta_m

    @property
    def degenerate(self) -> str | None:
        """See :attr:`HeightResult.degenerate`."""
        return self.height.degenerate

    @property
    def F_r_min(self) -> float:
        """Smallest (most negative) shear force F_r,min [N]."""
        return self.G * self.height.f_r_min.value

    @property
    def F_z_max(self) -> float:
        """Largest normal force F_z,max in the stable box [N]."""
        return self.G * self.height.f_z_max.value

    @property
    def Gamma_r_max(self) -> float:
        """Largest shear sensitivity Γ_r,max in the stable box [N/T]."""
        return self.G * self.height.gamma_r_max.value / self.field_scale

    @property
    def Gamma_z_max(self) -> float:
        """Largest normal sensitivity Γ_z,max in the stable box [N/T]."""
        return self.G * self.height.gamma_z_max.value / self.field_scale


def per_height(models: Responses | ModelSet, H: float, study: Study) -> HeightResult:
    """Per-unit-G extrema at height H [m] (:func:`per_heights` of one height).

    Parameters
    ----------
    models : Responses or ModelSet
        The metamodels (with their sensitivities).
    H : float
        Base height [m].
    study : Study
        Supplies θ_max and the ``[optimise]`` settings (start_t, start_theta, tol).

    Returns
    -------
    HeightResult
    """
    return per_heights(models, [float(H)], study)[0]


#: Grid points that start a refinement in each per-height problem (the best local optima of the
#: dense start grid).
STARTS = 4


def per_heights(models: Responses | ModelSet, H, study: Study) -> tuple[HeightResult, ...]:
    """Per-unit-G extrema at every height of ``H`` [m], all heights solved together.

    Notes
    -----
    Step 1 minimises f_r over [0, 1] × [0, θ_max] → (t_m, θ_m). Step 2 maximises f_z, γ_r, γ_z over
    [0, t_m] × [0, θ_m]; a side of zero width (degenerate box) fixes that variable, and the
    single point (0, 0) is simply evaluated. Each problem, for all heights at once:
    ``multistart_optimum`` (``optimise/_box.py``) on a ``start_t × start_theta`` grid over its
    box, the ``STARTS`` best local optima of the grid refined by projected Newton steps with
    the exact gradient and Hessian to the relative tolerance ``tol``.
    """
    H = np.atleast_1d(np.asarray(H, dtype=float))
    if H.ndim != 1:
        raise ValueError(f"heights must be a 1-D array, got shape {H.shape}")
    fr, rest = _extrema(as_responses(models), H, {}, study, starts=STARTS)
    lo = np.zeros(2)
    full = np.array([1.0, study.loading.theta_max])

    def box(res, i, hi) -> BoxOptimum:
        x = np.array([res.t[i], res.theta[i]])
        return BoxOptimum(float(x[0]), float(x[1]), float(res.value[i]), float(res.start_t[i]),
                          float(res.start_theta[i]), float(res.start_value[i]),
                          int(res.iterations[i]), float(res.kkt[i]), _active(x, lo, hi))

    out = []
    for i, h in enumerate(H):
        hi = np.array([fr.t[i], fr.theta[i]])
        out.append(HeightResult(float(h), box(fr, i, full), *(box(r, i, hi) for r in rest)))
    return tuple(out)


def per_design(models: Responses | ModelSet, H: float, G: float, study: Study,
               M_z: float | None = None) -> DesignResult:
    """Extrema of the design (H [m], G [Pa][, M_z [A/m]]): :func:`per_height` at H, forces and
    sensitivities scaled by G, sensitivities divided by M_z / magnet.M_z.

    Raises
    ------
    MagtactError
        If G or M_z is not positive.
    """
    if not G > 0:
        raise MagtactError(f"shear modulus G must be positive, got {G} Pa")
    if M_z is not None and not M_z > 0:
        raise MagtactError(f"magnetisation M_z must be positive, got {M_z} A/m")
    scale = 1.0 if M_z is None else float(M_z) / study.magnet.M_z
    return DesignResult(float(H), float(G), per_height(models, H, study),
                        None if M_z is None else float(M_z), scale)


#: The fields of :class:`HeightTable` that hold the stable box and the extrema per unit G (t_m …
#: gamma_z_max, between H and the maxima's locations).
_EXTREMA = slice(1, 7)


@dataclass(frozen=True)
class HeightTable:
    """Per-unit-G extrema at many heights, from the batched solver (arrays of shape (n,)).

    ``H`` [m]; ``t_m, theta_m`` the stable shear bounds; ``f_r_min, f_z_max`` [N/Pa];
    ``gamma_r_max, gamma_z_max`` [N/(T·Pa)]; ``loc_*`` the (t, θ) of each maximum, shape (n, 2);
    ``converged`` whether all four refinements met the tolerance; ``geometry`` each row's values
    [m] of the geometric design variables besides H, by name (empty without them).
    """

    H: np.ndarray
    t_m: np.ndarray
    theta_m: np.ndarray
    f_r_min: np.ndarray
    f_z_max: np.ndarray
    gamma_r_max: np.ndarray
    gamma_z_max: np.ndarray
    loc_f_z: np.ndarray
    loc_gamma_r: np.ndarray
    loc_gamma_z: np.ndarray
    converged: np.ndarray
    geometry: dict = field(default_factory=dict)

    def take(self, rows) -> HeightTable:
        """The table of the rows ``rows`` (index or mask)."""
        return HeightTable(*(getattr(self, f.name)[rows] for f in fields(self)[:-1]),
                           {k: v[rows] for k, v in self.geometry.items()})

    def at(self, H) -> HeightTable:
        """The table read at heights ``H`` within its own (rows sorted by H, no geometric
        variables): the extrema interpolated linearly between the bracketing rows, the maxima's
        locations those of the nearer row, converged where both rows are."""
        H = np.atleast_1d(np.asarray(H, float))
        i = np.clip(np.searchsorted(self.H, H), 1, self.H.size - 1)
        w = (H - self.H[i - 1]) / (self.H[i] - self.H[i - 1])
        near = np.where(w < 0.5, i - 1, i)

        def line(a):
            return a[i - 1] + w * (a[i] - a[i - 1])

        return HeightTable(H, *(line(getattr(self, f.name)) for f in fields(self)[_EXTREMA]),
            self.loc_f_z[near], self.loc_gamma_r[near], self.loc_gamma_z[near],
            self.converged[i - 1] & self.converged[i])


def heights_batch(models: Responses | ModelSet, H, study: Study,
                  warm: HeightTable | None = None, coarse_start: bool = True,
                  geometry: dict | None = None, maxiter: int = 100) -> HeightTable:
    """Per-unit-G extrema at many heights at once (vectorised over H).

    The same two steps as :func:`per_height`, each solved for all heights together by
    :func:`batch_optimum` (projected Newton with the exact gradient and Hessian, tolerance
    ``tol``). Used by NSGA-II and the exact reduction, where thousands of heights are needed;
    the tests check it against :func:`per_height`.

    Parameters
    ----------
    H : array_like, shape (n,)
        Heights [m].
    warm : HeightTable, optional
        Solved heights. Without it every problem starts from the best point of a
        ``start_t × start_theta`` grid on its box. With it, each problem is solved from three
        starts and the best result kept: the optima at the two heights of ``warm`` (of the same
        geometry) that bracket H, and the best point of a coarse 6 × 4 grid. An optimum that
        jumps between basins somewhere between two table heights is thereby still found on
        both sides of the jump.
    coarse_start : bool
        With ``warm``: also start from the coarse grid. NSGA-II, which warm-starts from the
        dense sweep, leaves it out.
    geometry : dict of array_like, optional
        For models over geometric design variables: each problem's values [m] by name
        (shape (n,), like ``H``), so that designs of different geometries are solved together.
    maxiter : int
        Newton iterations at most per problem (:func:`batch_optimum`).
    """
    H = np.atleast_1d(np.asarray(H, dtype=float))
    geo = {k: np.broadcast_to(np.asarray(v, dtype=float), H.shape)
           for k, v in (geometry or {}).items()}
    fr, res = _extrema(as_responses(models), H, geo, study, warm=warm,
                       coarse_start=coarse_start, maxiter=maxiter)
    conv = fr.converged & np.logical_and.reduce([r.converged for r in res])
    locs = [np.stack([r.t, r.theta], axis=1) for r in res]
    return HeightTable(H, fr.t, fr.theta, fr.value, res[0].value, res[1].value, res[2].value,
                       *locs, conv, {k: np.array(v) for k, v in geo.items()})


def force_extrema(models: Responses | ModelSet, H, study: Study
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t_m, θ_m, f_r,min, f_z,max) per unit G at every height of ``H`` [m]: the forces' part
    of :func:`per_heights` (the same solves, the sensitivities' maxima left out), for work
    that needs the stable box and the force range only."""
    H = np.atleast_1d(np.asarray(H, dtype=float))
    fr, (fz,) = _extrema(as_responses(models), H, {}, study, starts=STARTS, maximised=("f_z",))
    return fr.t, fr.theta, fr.value, fz.value


def force_table(models: Responses | ModelSet, study: Study, n: int) -> HeightTable:
    """The table of :func:`force_extrema` on ``n`` equally spaced heights over the H bounds:
    the stable box and the force extrema, the sensitivities' maxima NaN (what the sensor
    problem reads of a table, :meth:`SensorSpace.box`, at a fraction of a sweep's cost)."""
    H = np.linspace(*study.design.H, n)
    t_m, theta_m, f_r_min, f_z_max = force_extrema(models, H, study)
    nan, loc = np.full(n, np.nan), np.full((n, 2), np.nan)
    return HeightTable(H, t_m, theta_m, f_r_min, f_z_max, nan, nan.copy(), loc, loc.copy(),
                       loc.copy(), np.ones(n, bool))


def _extrema(R: Responses, H: np.ndarray, geo: dict, study: Study,
             warm: HeightTable | None = None, coarse_start: bool = True, maxiter: int = 100,
             starts: int = 1, maximised: tuple[str, ...] = MAXIMISED
             ) -> tuple[BatchOptimum, list[BatchOptimum]]:
    """The two steps of the per-height problem for every height of ``H`` at once: the minimum
    of f_r (its location the stable box) and the maxima of ``maximised`` over the box. Without
    ``warm``, each problem starts from its ``start_t × start_theta`` grid (the ``starts`` best
    local optima of it); with it, see :func:`heights_batch`."""
    o = study.optimise
    n = H.size

    def at(r, t):
        return R.at(_rows(H, r, t), **{k: _rows(v, r, t) for k, v in geo.items()})

    def solve(name, lo, hi, maximise, warm_starts):
        def fun(r, t, th):
            return at(r, t).value(name, t, th)

        def jac(r, t, th):
            return at(r, t).grad(name, t, th)

        def hess(r, t, th):
            return at(r, t).hess(name, t, th)

        kw = {"maximise": maximise, "tol": o.tol, "maxiter": maxiter}
        if warm_starts is None:
            if starts > 1:
                return multistart_optimum(fun, jac, hess, lo, hi,
                                          grid=(o.start_t, o.start_theta), starts=starts, **kw)
            return batch_optimum(fun, jac, hess, lo, hi, grid=(o.start_t, o.start_theta), **kw)
        runs = [batch_optimum(fun, jac, hess, lo, hi, grid=(6, 4), **kw)] if coarse_start else []
        first = batch_optimum(fun, jac, hess, lo, hi, grid=(6, 4), start=warm_starts[0], **kw)
        runs.append(first)
        width = np.where(hi - lo > 0, hi - lo, 1.0)
        for s in warm_starts[1:]:
            # a start beside the first one ends in the same optimum: only the others run
            far = np.flatnonzero(np.max(np.abs(s - warm_starts[0]) / width, axis=1) > SAME_START)
            runs.append(_rows_run(first, far, lambda r, far=far, s=s: batch_optimum(
                *(_on_rows(f, far) for f in (fun, jac, hess)), lo[far], hi[far],
                grid=(6, 4), start=s[far], **kw)))
        return _best(runs, maximise)

    lo = np.zeros((n, 2))
    hi = np.tile([1.0, study.loading.theta_max], (n, 1))
    warm_starts = [None] * 4
    if warm is not None:
        sides = _bracket(warm.H, H, *_groups(warm.geometry, geo))
        warm_starts = [[np.stack([warm.t_m[k], warm.theta_m[k]], axis=1) for k in sides],
                       [warm.loc_f_z[k] for k in sides], [warm.loc_gamma_r[k] for k in sides],
                       [warm.loc_gamma_z[k] for k in sides]]
    fr = solve("f_r", lo, hi, False, warm_starts[0])
    box = np.stack([fr.t, fr.theta], axis=1)
    res = [solve(name, lo, box, True, s)
           for name, s in zip(MAXIMISED, warm_starts[1:], strict=True) if name in maximised]
    return fr, res


#: Distance between two warm starts, relative to the box, below which they count as one.
SAME_START = 1e-3


def _on_rows(f, rows: np.ndarray):
    """``f`` of the problems ``rows`` (a sub-problem's row k is the problem ``rows[k]``)."""
    return lambda r, t, th: f(rows[np.asarray(r)], t, th)


def _rows_run(base: BatchOptimum, rows: np.ndarray, solve) -> BatchOptimum:
    """``base`` with the rows ``rows`` replaced by ``solve()``'s results (solved only where
    there are any)."""
    if rows.size == 0:
        return base
    sub = solve(rows)
    out = {}
    for f in fields(BatchOptimum):
        a, b = getattr(base, f.name), getattr(sub, f.name)
        if a is None or b is None:
            out[f.name] = None
            continue
        a = a.copy()
        a[rows] = b
        out[f.name] = a
    return BatchOptimum(**out)


def _best(runs: list[BatchOptimum], maximise: bool) -> BatchOptimum:
    """Row-wise best of several solutions of the same problems."""
    V = np.stack([r.value for r in runs])
    V = np.where(np.isfinite(V), V, -np.inf if maximise else np.inf)
    k = np.argmax(V, axis=0) if maximise else np.argmin(V, axis=0)
    rows = np.arange(V.shape[1])

    def pick(attr):
        return np.stack([getattr(r, attr) for r in runs])[k, rows]

    # ties within round-off: converged if any of the tied runs converged
    tied = np.abs(V - V[k, rows]) <= 1e-12 * np.abs(V[k, rows])
    converged = np.any(tied & np.stack([r.converged for r in runs]), axis=0)
    return BatchOptimum(pick("t"), pick("theta"), pick("value"), pick("kkt"), converged)


def _groups(warm: dict, query: dict) -> tuple[np.ndarray, np.ndarray]:
    """Group numbers of the rows of two tables by their geometric values (equal values, same
    group; a query geometry absent from ``warm`` gets a group of its own)."""
    names = sorted(warm)
    if sorted(query) != names:
        raise ValueError(f"the warm table's geometric variables {names} are not the "
                         f"problems' {sorted(query)}")
    if not names:
        return np.zeros(0, int), np.zeros(0, int)
    n = next(iter(warm.values())).size
    both = np.stack([np.concatenate([warm[k], query[k]]) for k in names], axis=1)
    _, group = np.unique(both, axis=0, return_inverse=True)
    group = np.ravel(group)
    return group[:n], group[n:]


def _bracket(grid: np.ndarray, x: np.ndarray, grid_group=None, x_group=None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the elements of ``grid`` just below and above each ``x``, among those of the
    same group (all in one group when no groups are given; a group without elements falls
    back to the first group)."""
    x = np.asarray(x, float)
    if grid_group is None or grid_group.size == 0:
        grid_group, x_group = np.zeros(grid.size, int), np.zeros(x.shape, int)
    # one exact integer sort key: the group, then the value's rank among all values
    values = np.unique(np.concatenate([grid, x.ravel()]))
    size = values.size + 1
    key = grid_group * size + np.searchsorted(values, grid)
    order = np.argsort(key, kind="stable")
    g_sorted = grid_group[order]
    first = np.searchsorted(g_sorted, x_group, side="left")
    last = np.searchsorted(g_sorted, x_group, side="right") - 1
    empty = last < first
    first, last = np.where(empty, 0, first), np.where(empty, grid.size - 1, last)
    k = np.searchsorted(key[order], np.where(empty, 0, x_group) * size
                        + np.searchsorted(values, x))
    hi = np.clip(k, np.minimum(first + 1, last), last)
    lo = np.maximum(hi - 1, first)
    return order[lo], order[hi]


def _rows(H: np.ndarray, r, t) -> np.ndarray:
    """Heights (or another per-problem value) of the problems ``r``, shaped to broadcast
    against ``t``."""
    h = H[np.asarray(r)]
    return h.reshape(h.shape + (1,) * (np.ndim(t) - h.ndim))


@dataclass(frozen=True)
class DesignMaps:
    """Per-design results on a grid of (H, G) (docs/method.md §7.1).

    Attributes
    ----------
    H : numpy.ndarray, shape (n_H,)
        Heights [m].
    G : numpy.ndarray, shape (n_G,)
        Shear moduli [Pa].
    heights : tuple of HeightResult
        The per-unit-G extrema at each H (:func:`per_heights`).

    Properties ``F_r_min, F_z_max, Gamma_r_max, Gamma_z_max`` are arrays of shape (n_H, n_G)
    [N, N, N/T, N/T].
    """

    H: np.ndarray
    G: np.ndarray
    heights: tuple[HeightResult, ...]

    def _grid(self, per_height) -> np.ndarray:
        """A quantity per unit G, one value per height, scaled by G: shape (n_H, n_G)."""
        return np.array(per_height)[:, None] * self.G[None, :]

    @property
    def F_r_min(self) -> np.ndarray:
        """F_r,min [N], shape (n_H, n_G)."""
        return self._grid([h.f_r_min.value for h in self.heights])

    @property
    def F_z_max(self) -> np.ndarray:
        """F_z,max [N], shape (n_H, n_G)."""
        return self._grid([h.f_z_max.value for h in self.heights])

    @property
    def Gamma_r_max(self) -> np.ndarray:
        """Γ_r,max [N/T], shape (n_H, n_G)."""
        return self._grid([h.gamma_r_max.value for h in self.heights])

    @property
    def Gamma_z_max(self) -> np.ndarray:
        """Γ_z,max [N/T], shape (n_H, n_G)."""
        return self._grid([h.gamma_z_max.value for h in self.heights])

    def design(self, i: int, j: int) -> DesignResult:
        """The design (H[i], G[j])."""
        return DesignResult(float(self.H[i]), float(self.G[j]), self.heights[i])



def design_maps(models: Responses | ModelSet, study: Study) -> DesignMaps:
    """Per-design results on the ``grid_n × grid_n`` grid of (H, G) over the design bounds.

    :func:`per_heights` on the H levels, all at once (the G levels only scale them).
    """
    n = study.optimise.grid_n
    H = np.linspace(*study.design.H, n)
    G = np.linspace(*study.design.G, n)
    return DesignMaps(H, G, per_heights(models, H, study))
