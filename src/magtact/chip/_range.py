"""The Hall chip's range: as a constraint of the optimisation, along a design's paths, and
against the field at rest (docs/method.md §10).

The field along a path depends on the geometry only (H, t, θ), not on G, and so does the stable
region t ≤ t_m(H), θ ≤ θ_m(H): a chip that must stay within its range over the region the sensor
is used in restricts the heights, whatever the silicone.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from ..metamodel import ExactField, ModelSet
from ..study import HallChip, Study, StudyError, hall_chip, mm, mt

#: Load levels and angles of the saturation scan along the paths (the scan brackets where the
#: chip leaves its range; a bisection locates it, :func:`onset`).
N_SCAN_T, N_SCAN_THETA = 101, 21
#: Precision of :func:`onset`: t to 2^-50 of a level's width (or the floats' resolution).
ONSET_ITERATIONS = 50

#: |ratio − 1| below which a point of :func:`onset`'s search is the crossing (round-off of the
#: field's evaluation).
G_ROUNDOFF = 1e-14
#: Paths per level of the zooming search over θ of :func:`saturation`, and the width (a
#: fraction of θ_max) at which it stops; each level narrows the bracket (N - 1) / 2-fold.
ZOOM_N, ZOOM_XATOL = 33, 1e-6

#: Grid over each height's stable region (fractions of t_m and θ_m) on which the field is read.
N_T, N_THETA = 41, 11


def chip_margin(study: Study, H, t_m, theta_m, geometry: dict | None = None, *,
                chip: HallChip | None = None, M_z: float | None = None,
                standoff: float | None = None) -> np.ndarray:
    """How far the exact field exceeds the chip's range over each height's stable region.

    .. math:: m(H) = \\max_{t \\le t_m,\\ θ \\le θ_m}
              \\max\\left(\\frac{|B_x|}{B_{x,\\mathrm{range}}},
              \\frac{|B_z|}{B_{z,\\mathrm{range}}}\\right) - 1

    Parameters
    ----------
    study : Study
        Geometry, loading path and the ``[hall]`` chip.
    H, t_m, theta_m : array_like, shape (n,)
        Heights [m] and their stable shear bounds (t_m, θ_m [rad]).
    geometry : dict of array_like, optional
        Each row's values [m] of the study's geometric design variables (shape (n,)); the
        field depends on the magnet's (R_m, H_m).
    chip : HallChip, optional
        The chip at a design's setting (default: the study's ``[hall]`` chip).
    M_z, standoff : float, optional
        A design's magnetisation [A/m] and chip standoff [m] (default: the study's).

    Returns
    -------
    numpy.ndarray, shape (n,)
        ≤ 0 where the chip reads the whole stable region.
    """
    chip = hall_chip(study) if chip is None else chip
    H, t_m, theta_m = (np.atleast_1d(np.asarray(v, float)) for v in (H, t_m, theta_m))
    s = np.linspace(0.0, 1.0, N_T)[:, None, None]
    u = np.linspace(0.0, 1.0, N_THETA)[None, :, None]
    T, TH = s * t_m[None, None, :], u * theta_m[None, None, :]
    HH = np.broadcast_to(H[None, None, :], T.shape)
    B_r, B_z = ExactField(study, "B_r", standoff, M_z), ExactField(study, "B_z", standoff, M_z)
    geo = {k: np.broadcast_to(np.asarray(v, float), H.shape)[None, None, :]
           for k, v in (geometry or {}).items() if k in B_r.geometry}
    ratio = np.maximum(np.abs(B_r.value(T, TH, HH, **geo)) / chip.range_x,
                       np.abs(B_z.value(T, TH, HH, **geo)) / chip.range_z)
    return ratio.max(axis=(0, 1)) - 1.0


@dataclass(frozen=True)
class Saturation:
    """The largest field along the paths against the chip's range, and where the chip first
    leaves it (:func:`saturation`)."""

    B_max_x: float
    B_max_z: float
    #: The load t (and its θ, axis, forces [N]) at which the chip leaves its range on the
    #: path where that happens at the smallest normal force; None: never.
    t: float | None = None
    theta: float | None = None
    axis: str | None = None
    F_r: float | None = None
    F_z: float | None = None
    #: :func:`magtact.optimise.chip_margin` over the design's stable region (≤ 0: the chip reads
    #: all of it); NaN when not computed.
    region_margin: float = float("nan")

    @property
    def saturates(self) -> bool:
        return self.t is not None

    @property
    def in_region(self) -> bool:
        """Whether the chip saturates inside the stable region (where the sensor is used)."""
        return bool(self.region_margin > 0)


def onset(ratio, theta, t_max, n_scan: int = N_SCAN_T, iterations: int = ONSET_ITERATIONS
          ) -> np.ndarray:
    """The load t at which the chip first leaves its range on each path, by a scan of
    ``n_scan`` levels over [0, t_max] that brackets the first crossing and an Illinois search
    in the bracket (:func:`_illinois`) to 2^-iterations of a level's width (or the floats'
    resolution).

    Parameters
    ----------
    ratio : callable
        ``ratio(t, theta)`` → max(|B_x| / range_x, |B_z| / range_z) at loads t and angles θ;
        called with ``t`` of shape (n_scan,) + θ's shape and of θ's shape (so that it may
        hold per-path arrays of θ's shape); the chip has left its range where it exceeds 1.
    theta, t_max : array_like
        The paths' angles [rad] and the largest load of each (broadcast together).

    Returns
    -------
    numpy.ndarray
        The first t with ratio > 1 on each path (0: at rest); NaN where the chip stays in
        its range up to t_max.

    Notes
    -----
    A crossing narrower than a level of the scan is not seen: the field varies along a path
    on the scale of the magnet–chip distance, far wider than 1/``n_scan`` of the path.
    """
    theta, t_max = np.broadcast_arrays(np.asarray(theta, float), np.asarray(t_max, float))
    s = np.linspace(0.0, 1.0, n_scan).reshape((-1,) + (1,) * theta.ndim)
    T = s * t_max[None]
    over = ratio(T, np.broadcast_to(theta, T.shape)) > 1.0
    hit = over.any(axis=0)
    i = np.argmax(over, axis=0)
    hi = np.take_along_axis(T, i[None], axis=0)[0]
    lo = np.take_along_axis(T, np.maximum(i - 1, 0)[None], axis=0)[0]
    todo = hit & (i > 0)
    if todo.any():  # every path at once (ratio may close over per-path arrays)
        lo, hi = _illinois(ratio, theta, lo, hi, todo, (hi - lo) * 2.0 ** -iterations)
    return np.where(hit, np.where(todo, hi, 0.0), np.nan)


def _illinois(ratio, theta, lo, hi, todo, xtol, max_steps: int = 200):
    """Narrow the brackets [lo, hi] (ratio ≤ 1 at lo, > 1 at hi) of the rows ``todo`` to
    ``xtol`` (or to the floats' resolution) by the Illinois variant of false position: the
    secant's point where the ratio is smooth, with the retained end's excess halved when the
    same end is kept twice, so that both ends converge; a bisection where the secant's point
    falls outside the bracket. A point whose ratio is within :data:`G_ROUNDOFF` of 1 ends its
    row as the crossing (returned as ``hi``)."""
    g_lo = np.where(todo, ratio(lo, theta) - 1.0, -1.0)
    g_hi = np.where(todo, ratio(hi, theta) - 1.0, 1.0)
    side = np.zeros(lo.shape, int)  # the end replaced last: -1 lo, +1 hi
    tol = np.maximum(xtol, 4.0 * np.finfo(float).eps * np.abs(hi))
    active = todo & (hi - lo > tol)
    for _ in range(max_steps):
        if not active.any():
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            x = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        mid = 0.5 * (lo + hi)
        x = np.where(np.isfinite(x) & (x > lo) & (x < hi), x, mid)
        g = ratio(x, theta) - 1.0
        over = (g > 0) & active
        under = ~(g > 0) & active
        # Illinois: keep the far end's excess halved when the same end moves twice
        g_lo = np.where(over & (side == 1), 0.5 * g_lo, g_lo)
        g_hi = np.where(under & (side == -1), 0.5 * g_hi, g_hi)
        hi, g_hi = np.where(over, x, hi), np.where(over, g, g_hi)
        lo, g_lo = np.where(under, x, lo), np.where(under, g, g_lo)
        side = np.where(over, 1, np.where(under, -1, side))
        # a point within round-off of the range's edge is the crossing
        root = active & (np.abs(g) <= G_ROUNDOFF)
        hi = np.where(root, x, hi)
        active &= (hi - lo > tol) & ~root
    return lo, hi


def field_ratio(study: Study, H, chip: HallChip | tuple[float, float], *,
                M_z: float | None = None, standoff: float | None = None):
    """``ratio(t, θ)`` of :func:`onset` for the exact field of ``study``'s magnet and chip
    position (or a design's ``M_z`` [A/m] and ``standoff`` [m]) at height(s) H [m], against
    the range of ``chip`` (or (range_x, range_z) [T])."""
    rx, rz = (chip.range_x, chip.range_z) if isinstance(chip, HallChip) else chip
    B_r, B_z = ExactField(study, "B_r", standoff, M_z), ExactField(study, "B_z", standoff, M_z)

    def ratio(t, theta):
        return np.maximum(np.abs(B_r.value(t, theta, H)) / rx,
                          np.abs(B_z.value(t, theta, H)) / rz)
    return ratio


def saturation(study: Study, models: ModelSet, H: float, G: float, chip: HallChip,
               t_max: float = 1.0, theta_max: float | None = None, *,
               M_z: float | None = None, standoff: float | None = None) -> Saturation:
    """Where the exact field first leaves the chip's range, over the paths θ ∈ [0, θ_max]
    up to the load t_max (default: the whole paths, t ∈ [0, 1], θ ∈ [0, loading.theta_max]).

    On each of ``N_SCAN_THETA`` paths the load at which the chip leaves its range is found by
    :func:`onset` (a root of the field's ratio to the range along the path); the path of the least
    normal force at that load is then refined between its neighbours (a zooming grid over θ,
    :data:`ZOOM_N` paths a level, to :data:`ZOOM_XATOL` of θ_max). The normal force there is *the*
    saturation figure of the design. A range below the field at rest shows as saturation at t = 0
    (see :func:`check_rest_field` for the study-wide check).

    The forces are G times the models' per-unit-G forces, so where the chip leaves its range
    does not depend on G: it is found once per (study, models, H, range, path box, magnet and
    chip position) and kept, for a grid of designs that differ in G alone. ``M_z`` [A/m] and
    ``standoff`` [m]: a design's magnet and chip position (default: the study's).
    """
    theta_max = study.loading.theta_max if theta_max is None else float(theta_max)
    s = _unit_saturation(study, models, float(H), (float(chip.range_x), float(chip.range_z)),
                         float(t_max), theta_max,
                         None if M_z is None else float(M_z),
                         None if standoff is None else float(standoff))
    if s.F_z is None:
        return s
    G = np.asarray(G, dtype=float)
    return replace(s, F_r=float(G * s.F_r), F_z=float(G * s.F_z))


@functools.lru_cache(maxsize=256)
def _unit_saturation(study: Study, models: ModelSet, H: float, chip: tuple[float, float],
                     t_max: float, theta_max: float, M_z: float | None,
                     standoff: float | None) -> Saturation:
    """:func:`saturation` at G = 1 Pa against the range ``chip`` = (range_x, range_z) [T]."""
    G = 1.0
    t = np.linspace(0.0, t_max, N_SCAN_T)
    th = np.linspace(0.0, theta_max, N_SCAN_THETA)
    T, TH = np.meshgrid(t, th, indexing="ij")
    B_r, B_z = ExactField(study, "B_r", standoff, M_z), ExactField(study, "B_z", standoff, M_z)
    B_x = np.abs(B_r.value(T, TH, H))
    out = dict(B_max_x=float(B_x.max()), B_max_z=float(np.abs(B_z.value(T, TH, H)).max()))
    ratio = field_ratio(study, H, chip, M_z=M_z, standoff=standoff)
    t_on = onset(ratio, th, t_max)
    if np.isnan(t_on).all():
        return Saturation(**out)

    def F_z_at(theta, t_on):  # the normal force where the chip leaves its range on paths θ
        return np.where(np.isnan(t_on), np.inf,
                        np.asarray(models.forces(np.nan_to_num(t_on), theta, H, G)[1], float))

    F_z = F_z_at(th, t_on)
    j = int(np.argmin(F_z))
    best_theta, best_F = float(th[j]), float(F_z[j])
    if th.size > 1:  # zoom in between the neighbours, every path of a level in one call
        lo, hi = th[max(j - 1, 0)], th[min(j + 1, th.size - 1)]
        while hi - lo > ZOOM_XATOL * max(theta_max, 1e-9):
            cand = np.linspace(lo, hi, ZOOM_N)
            F = F_z_at(cand, onset(ratio, cand, t_max))
            k = int(np.argmin(F))
            if F[k] < best_F:
                best_theta, best_F = float(cand[k]), float(F[k])
            step = cand[1] - cand[0]
            lo, hi = max(lo, best_theta - step), min(hi, best_theta + step)
    ts = float(onset(ratio, np.array([best_theta]), t_max)[0])
    bx = abs(float(B_r.value(ts, best_theta, H))) / chip[0]
    bz = abs(float(B_z.value(ts, best_theta, H))) / chip[1]
    F_r, F_z_s = models.forces(ts, best_theta, H, G)
    return Saturation(**out, t=ts, theta=best_theta, axis="x" if bx > bz else "z",
                      F_r=float(F_r), F_z=float(F_z_s))


def saturation_force(study: Study, models: ModelSet, H: float, G: float, chip: HallChip,
                     t_m: float, theta_m: float, *, M_z: float | None = None,
                     standoff: float | None = None) -> float:
    """The design's saturation figure: the smallest normal force [N] at which the chip leaves
    its range inside the stable region t ≤ t_m, θ ≤ θ_m (:func:`saturation`); inf: never."""
    s = saturation(study, models, H, G, chip, t_m, theta_m, M_z=M_z, standoff=standoff)
    return float("inf") if s.F_z is None else s.F_z


def _weakest(study: Study) -> tuple[float, float]:
    """(M_z [A/m], standoff [m]) of the sensor problem's weakest field: the lowest grade, the
    largest standoff."""
    from ..parts import grade
    from ..study import MU0

    d = study.design
    M_z = min((grade(g).M_z(MU0)[0] for g in d.grades), default=study.magnet.M_z)
    standoff = d.standoff[1] if d.standoff[1] > 0 else study.hall.standoff
    return float(M_z), float(standoff)


def check_rest_field(study: Study) -> None:
    """Refuse a chip range below the field at rest of every design in the study's range.

    The field at rest is weakest at the tallest body (the magnet farthest from the chip); in
    the sensor problem also with the weakest grade and the chip at its largest standoff.

    Raises
    ------
    StudyError
        Naming ``hall.range_x_mT`` or ``hall.range_z_mT``.
    """
    M_z, s = study.magnet.M_z, study.hall.standoff
    if study.optimise.problem == "sensor" and not study.geometric_variables:
        M_z, s = _weakest(study)
    chip = hall_chip(study)
    H = study.design.H[1]
    below = f", the chip {mm(s):.3g} mm below the body" if s > 0 else ""
    for axis, name in (("x", "B_r"), ("z", "B_z")):
        b = abs(float(ExactField(study, name, s, M_z).value(0.0, 0.0, H)))
        limit = chip.range_x if axis == "x" else chip.range_z
        if b > limit:
            raise StudyError(f"hall.range_{axis}_mT",
                             f"{mt(limit):.4g} mT is below the field at rest of every design "
                             f"(|B_{axis}| = {mt(b):.4g} mT even at the tallest, H = "
                             f"{mm(H):.3g} mm{below}): the {chip.name} would read nothing but "
                             "its limit")
