"""The finite-element forces of a DOE at one height as a force source of the map
(docs/method.md §13.4).

At a height H the DOE holds paths θ_j (j = 0 … n_θ − 1, θ_0 = 0) sampled at loads t_i, with the
FE reaction forces F_r, F_z at the level G_0 of its first G (the forces of the linear-elastic body
are proportional to G, docs/method.md §3, so F(G) = F(G_0) G / G_0 exactly). The interpolant is
written in the load features w = (p, q) = (t, t tan θ) (docs/method.md §5) so that it is smooth
where (t, θ) is not, at t = 0:

    F_z(p, q) = p Φ(p, v),      F_r(p, q) = q Ψ(p, v),      v = sin² θ = q² / (p² + q²),

Φ = F_z / t on every path and Ψ = F_r / (t tan θ) on the sheared paths (θ > 0) are finite at
t → 0, and v makes F_z even and F_r odd in q. Along p: a cubic spline (not-a-knot) through the
nodes t_i > 0, continued by its own first cubic down to p = 0; along v: the shape-preserving
piecewise cubic Hermite interpolant (PCHIP, Fritsch–Carlson slopes), which does not overshoot
between the few, slightly noisy, paths. Both are C¹; beyond the nodes (p < 0, p > t_max,
v > v_max, and for Ψ v < v_1) each continues linearly with its end slope, so that Newton's
iterates see a C¹ function everywhere, but the map flags every reading there (the region is
capped at the data's t_max, θ_max). The interpolant passes through every FE point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from .._errors import MagtactError
from .._records import entry, to_json
from ..study import mm

#: Heights of a data set and a design agree within this [m].
H_ATOL = 1e-9


def _pchip_slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Fritsch–Carlson slopes (as scipy's PchipInterpolator) of values y (..., n) at nodes x (n)."""
    h = np.diff(x)
    delta = np.diff(y, axis=-1) / h
    n = len(x)
    d = np.zeros_like(y)
    if n == 2:
        d[..., 0] = d[..., 1] = delta[..., 0]
        return d
    w1 = 2 * h[1:] + h[:-1]
    w2 = h[1:] + 2 * h[:-1]
    a, b = delta[..., :-1], delta[..., 1:]
    same = (np.sign(a) * np.sign(b)) > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        hm = (w1 + w2) / (w1 / np.where(same, a, 1.0) + w2 / np.where(same, b, 1.0))
    d[..., 1:-1] = np.where(same, hm, 0.0)

    def end(h0, h1, m0, m1):
        s = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
        s = np.where(np.sign(s) != np.sign(m0), 0.0, s)
        return np.where((np.sign(m0) != np.sign(m1)) & (np.abs(s) > np.abs(3 * m0)), 3 * m0, s)

    d[..., 0] = end(h[0], h[1], delta[..., 0], delta[..., 1])
    d[..., -1] = end(h[-1], h[-2], delta[..., -1], delta[..., -2])
    return d


def _pchip(x: np.ndarray, y: np.ndarray, xq: np.ndarray) -> np.ndarray:
    """PCHIP of per-point values y (m, n) at nodes x (n), at xq (m), continued linearly.

    Each query point has its own row of values (the spline along p evaluated at its own p), so
    scipy's ``PchipInterpolator`` (one set of values, every query) would cost m² here; the
    slopes and the Hermite form are its, and a test holds the two equal.
    """
    if len(x) == 1:
        return y[:, 0].copy()
    d = _pchip_slopes(x, y)
    xc = np.clip(xq, x[0], x[-1])
    k = np.clip(np.searchsorted(x, xc, side="right") - 1, 0, len(x) - 2)
    rows = np.arange(len(xq))
    h = x[k + 1] - x[k]
    s = (xc - x[k]) / h
    y0, y1, d0, d1 = y[rows, k], y[rows, k + 1], d[rows, k], d[rows, k + 1]
    h00, h10, h01, h11 = (2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2,
                          s**3 - s**2)
    value = h00 * y0 + h10 * h * d0 + h01 * y1 + h11 * h * d1
    slope = np.where(xq < x[0], d[:, 0], d[:, -1])
    return value + (xq - xc) * slope


@dataclass(frozen=True, eq=False)
class FEForces:
    """The DOE's FE forces at one height H as a C¹ interpolant over the load features
    (docs/method.md §13.4). Build it with :func:`fe_forces`.

    Attributes
    ----------
    H : float
        The height [m].
    G_level : float
        The shear modulus [Pa] of the stored forces.
    t : numpy.ndarray
        The load nodes t_i > 0 of the paths.
    theta : numpy.ndarray
        The paths' angles θ_j [rad] (those used: a path may be held out).
    Phi, Psi : numpy.ndarray
        F_z / t (n_t, n_θ) and F_r / (t tan θ) (n_t, number of paths with θ > 0) [N] at G_level.
    """

    H: float
    G_level: float
    t: np.ndarray
    theta: np.ndarray
    Phi: np.ndarray
    Psi: np.ndarray

    @property
    def t_max(self) -> float:
        return float(self.t[-1])

    @property
    def theta_max(self) -> float:
        return float(self.theta[-1])

    def _along_p(self, values: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The spline in p of every column of values, at p (m,): (m, columns); its own cubic
        on [0, t_1], linear beyond [0, t_max]."""
        spline = CubicSpline(self.t, values, axis=0, bc_type="not-a-knot")
        pc = np.clip(p, 0.0, self.t_max)
        return spline(pc) + (p - pc)[:, None] * spline(pc, 1)

    def forces(self, p, q, G: float) -> tuple[np.ndarray, np.ndarray]:
        """(F_r, F_z) [N] of the in-plane features p = t, q = t tan θ ≥ 0 (broadcast), at
        shear modulus G [Pa]; F_r ≤ 0 against the shear (docs/method.md §13)."""
        p, q = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(q, dtype=float))
        shape = p.shape
        p, q = p.ravel(), q.ravel()
        r2 = p**2 + q**2
        v = np.where(r2 > 0, q**2 / np.where(r2 > 0, r2, 1.0), 0.0)
        sheared = self.theta > 0
        phi = _pchip(np.sin(self.theta) ** 2, self._along_p(self.Phi, p), v)
        psi = _pchip(np.sin(self.theta[sheared]) ** 2, self._along_p(self.Psi, p), v)
        scale = G / self.G_level
        return (q * psi * scale).reshape(shape), (p * phi * scale).reshape(shape)


def heights(dataset) -> np.ndarray:
    """The heights [m] of a DOE data set's paths."""
    return np.asarray(dataset["H"].values, dtype=float)


def has_height(dataset, H: float) -> bool:
    """Whether a DOE data set holds FE paths at height H [m]."""
    return dataset is not None and bool(np.isclose(heights(dataset), H, rtol=0,
                                                   atol=H_ATOL).any())


def fe_forces(dataset, H: float, study=None, drop_theta: float | None = None) -> FEForces:
    """The FE forces of a DOE data set at height H [m] as a :class:`FEForces` interpolant.

    Parameters
    ----------
    dataset : xarray.Dataset
        A DOE data set (:func:`magtact.doe.load_dataset`) with ``F_r``, ``F_z`` over
        (t, theta, H, G).
    H : float
        One of its heights [m].
    study : Study, optional
        When given, the data set must describe it (:func:`magtact.doe.differences`).
    drop_theta : float, optional
        Leave this path (θ [rad]) out: the interpolant between the others (a held-out check).

    Raises
    ------
    MagtactError
        Naming what is missing: the height (with the data set's heights), a path to drop, the
        paths an interpolant needs (two sheared ones, three loads t > 0), or the
        study's settings the data set differs in.
    """
    if dataset is None:
        raise MagtactError("the FE force source needs the DOE data set (its FE paths): none "
                           "was given (models from files carry none; give the data set, or "
                           "use the metamodels' forces)")
    if study is not None:
        from ..doe import differences

        diff = differences(dataset, study)
        if diff:
            raise MagtactError(f"the DOE data set does not describe study {study.name!r} "
                               f"({'; '.join(diff[:3])}): its FE forces are not this sensor's")
    Hs = heights(dataset)
    j = np.flatnonzero(np.isclose(Hs, H, rtol=0, atol=H_ATOL))
    if not j.size:
        raise MagtactError(
            f"the DOE data set has no FE paths at H = {mm(H):.4g} mm (its heights: "
            f"{', '.join(f'{mm(h):.4g}' for h in Hs)} mm): the FE force source needs a design "
            "at one of them (or use the metamodels' forces)")
    d = dataset.isel(H=int(j[0]))
    t = np.asarray(d["t"].values, dtype=float)
    theta = np.asarray(d["theta"].values, dtype=float)
    G_level = float(d["G"].values[0])
    F_r = np.asarray(d["F_r"].isel(G=0).transpose("t", "theta").values, dtype=float)
    F_z = np.asarray(d["F_z"].isel(G=0).transpose("t", "theta").values, dtype=float)
    keep = np.ones(len(theta), dtype=bool)
    if drop_theta is not None:
        hit = np.isclose(theta, drop_theta, rtol=0, atol=1e-12)
        if not hit.any():
            raise MagtactError(f"the DOE data set has no path θ = {drop_theta:.6g} rad at "
                               f"H = {mm(H):.4g} mm (its paths: "
                               f"{', '.join(f'{v:.6g}' for v in theta)} rad)")
        keep &= ~hit
    pos = t > 0
    finite = np.isfinite(F_r[pos][:, keep]).all(axis=0) & np.isfinite(F_z[pos][:, keep]).all(0)
    if not finite.all():
        bad = theta[keep][~finite]
        raise MagtactError(f"the DOE data set's FE forces at H = {mm(H):.4g} mm are missing "
                           f"(NaN) on the paths θ = {', '.join(f'{v:.4g}' for v in bad)} rad")
    theta, F_r, F_z = theta[keep], F_r[:, keep], F_z[:, keep]
    sheared = theta > 0
    if pos.sum() < 3 or theta[0] < 0 or sheared.sum() < 2 or np.any(np.diff(theta) <= 0):
        raise MagtactError(f"the DOE data set at H = {mm(H):.4g} mm has too few FE paths for an "
                           f"interpolant: it needs two sheared paths (θ > 0) and three "
                           f"loads t > 0 (it has θ = {', '.join(f'{v:.4g}' for v in theta)} rad, "
                           f"{int(pos.sum())} loads t > 0)")
    tp = t[pos]
    Phi = F_z[pos] / tp[:, None]
    Psi = F_r[pos][:, sheared] / (tp[:, None] * np.tan(theta[sheared]))
    return FEForces(float(Hs[j[0]]), G_level, tp, theta, Phi, Psi)


@dataclass(frozen=True)
class PathHoldout:
    """The interpolant's error on one FE path held out (:func:`path_holdout`): ``theta``
    [rad], the largest |error| of F_r, F_z [N] over the path's loads t ≤ t_m, and whether the
    path lies between others (``interior``; the end paths θ = 0 and θ_max are extrapolation)."""

    theta: float = entry(unit="rad")
    err_r: float = entry("err_F_r_mN", "mN")
    err_z: float = entry("err_F_z_mN", "mN")
    interior: bool = entry(kind=bool)

    def to_json(self) -> dict:
        """The path's error in user units (``calibration.json``'s ``force_model_error``)."""
        return to_json(self)


def path_holdout(dataset, H: float, G: float, t_m: float = np.inf,
                 study=None) -> list[PathHoldout]:
    """Leave-one-θ-path-out error of the FE interpolant at height H [m] and shear modulus G
    [Pa] (docs/method.md §13.4): for each path, the interpolant of the other paths against
    that path's FE forces at its loads 0 < t ≤ t_m. The interior paths' error is the map's
    model error between paths (at twice the paths' spacing: an estimate from above for a
    smooth response)."""
    full = fe_forces(dataset, H, study)
    d = dataset.isel(H=int(np.flatnonzero(np.isclose(heights(dataset), H, rtol=0,
                                                      atol=H_ATOL))[0]))
    t = np.asarray(d["t"].values, dtype=float)
    use = (t > 0) & (t <= t_m * (1 + 1e-12))
    scale = G / full.G_level
    out = []
    for j, th in enumerate(full.theta):
        held = fe_forces(dataset, H, drop_theta=th)
        fr, fz = held.forces(t[use], t[use] * np.tan(th), G)
        F_r = d["F_r"].isel(G=0, theta=j).transpose("t").values[use] * scale
        F_z = d["F_z"].isel(G=0, theta=j).transpose("t").values[use] * scale
        out.append(PathHoldout(float(th), float(np.abs(fr - F_r).max()),
                               float(np.abs(fz - F_z).max()),
                               bool(0 < j < len(full.theta) - 1)))
    return out
