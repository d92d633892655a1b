"""Neighbours in a taxel array: their field at this taxel's chip by superposition of the exact
cylinder field, and the false force when a neighbour is loaded (docs/method.md §12).

Coordinates: this taxel's Hall point is the origin, z up; every taxel is the same sensor, its
magnet on its own chip's axis. A neighbour's magnet is axially magnetised, so its field at a
point is the axisymmetric solution (B_ρ, B_z) of :func:`magtact.magnetics.cylinder_field`, B_ρ
along the horizontal direction from the magnet's axis to the point.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import hall_from_magnet_centre, loading_path
from ..magnetics import cylinder_field
from ..study import Study

#: Load levels and angles of a neighbour's stable region, and directions of its shear.
N_T, N_THETA, N_PHI = 11, 6, 16


def neighbour_offsets(layout: str, rings: int, pitch: float) -> np.ndarray:
    """Horizontal centres (x, y) [m] of the neighbours, shape (n, 2).

    ``"square"``: the points p (i, j) with 0 < max(|i|, |j|) ≤ rings (8, 24, ... of them);
    ``"hexagonal"``: the points p (i + j/2, j √3/2) of hexagonal distance 1 ... rings
    (6, 18, ...).
    """
    k = range(-rings, rings + 1)
    if layout == "square":
        pts = [(i, j) for i in k for j in k if 0 < max(abs(i), abs(j))]
        return pitch * np.array(pts, dtype=float)
    if layout == "hexagonal":
        pts = [(i + j / 2, j * math.sqrt(3) / 2) for i in k for j in k
               if 0 < max(abs(i), abs(j), abs(i + j)) <= rings]
        return pitch * np.array(pts, dtype=float)
    raise ValueError(f"unknown array layout {layout!r}; choose 'square' or 'hexagonal'")


def magnets_field(study: Study, centres, M_z: float | None = None) -> np.ndarray:
    """Field (B_x, B_y, B_z) [T] at the origin of axial magnets centred at ``centres``.

    Parameters
    ----------
    centres : array_like, shape (..., n, 3)
        Magnet centres [m] (the study's magnet, axis along z); the fields of the n magnets are
        summed (superposition).
    M_z : float, optional
        Magnetisation [A/m]; default ``magnet.M_z``.

    Returns
    -------
    numpy.ndarray, shape (..., 3)

    Notes
    -----
    The origin relative to a magnet at c is d = −c; with ρ = |d_xy| the horizontal field is
    B_ρ(ρ, d_z) d_xy / ρ (zero on the axis), the vertical field B_z(ρ, d_z).
    """
    c = np.asarray(centres, dtype=float)
    m = study.magnet
    d = -c
    rho = np.hypot(d[..., 0], d[..., 1])
    B_rho, B_z = cylinder_field(rho, d[..., 2], m.R_m, m.H_m, m.M_z if M_z is None else M_z)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux = np.where(rho > 0, d[..., 0] / np.where(rho > 0, rho, 1.0), 0.0)
        uy = np.where(rho > 0, d[..., 1] / np.where(rho > 0, rho, 1.0), 0.0)
    return np.stack([(B_rho * ux).sum(-1), (B_rho * uy).sum(-1), B_z.sum(-1)], axis=-1)


def neighbour_changes(study: Study, H: float, t_m: float, theta_m: float, offsets,
                      M_z: float | None = None, standoff: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Change of the field at this chip when neighbours are loaded through their stable region.

    Every neighbour is the same design, loaded at (t, θ) ∈ [0, t_m] × [0, θ_m] (an N_T × N_THETA
    grid) with its shear along one of N_PHI directions φ; its magnet moves by
    u = (u_r cos φ, u_r sin φ, u_z) (:func:`magtact.geometry.loading_path`).

    Returns
    -------
    one, all : numpy.ndarray, shape (m, 3)
        ΔB [T] when one neighbour is loaded (every neighbour, state and direction), and when
        all are loaded alike (every state and direction): the field minus the field at rest,
        which a calibration removes.
    """
    offsets = np.asarray(offsets, dtype=float)
    t = np.linspace(0.0, t_m, N_T)
    th = np.linspace(0.0, theta_m, N_THETA)
    T, TH = (a.ravel() for a in np.meshgrid(t, th, indexing="ij"))
    u_r, u_z = loading_path(study, T, TH, H)
    _, z = hall_from_magnet_centre(study, u_r, u_z, H, standoff)  # −(height of the centre)
    phi = np.linspace(0.0, 2 * np.pi, N_PHI, endpoint=False)
    # centres (state, φ, neighbour, 3)
    cx = offsets[None, None, :, 0] + (u_r[:, None] * np.cos(phi))[:, :, None]
    cy = offsets[None, None, :, 1] + (u_r[:, None] * np.sin(phi))[:, :, None]
    cz = np.broadcast_to((-z)[:, None, None], cx.shape)
    centres = np.stack([cx, cy, cz], axis=-1)
    _, z0 = hall_from_magnet_centre(study, 0.0, 0.0, H, standoff)
    rest = np.concatenate([offsets, np.full((len(offsets), 1), -float(z0))], axis=1)
    B_rest = magnets_field(study, rest[:, None, :], M_z)  # (n, 3), each magnet alone
    each = magnets_field(study, centres[..., None, :], M_z) - B_rest  # (state, φ, n, 3)
    one = each.reshape(-1, 3)
    all_ = each.sum(axis=-2).reshape(-1, 3)
    return one, all_


def worst_false_force(J: np.ndarray, dB: np.ndarray) -> np.ndarray:
    """Largest false force [N] per component (F_r, F_z) of field changes ``dB`` (m, 3) through
    Jacobians ``J`` (..., 2, 2), over every J, every ΔB and the orientation of this taxel's
    plane of shear.

    The 2 × 2 Jacobian acts on the field in the plane of shear (B_x, B_z); this taxel's shear
    direction x may point anywhere in the horizontal plane, so the worst false force of
    component k is |J_k,x| |ΔB_h| + |J_k,z| |ΔB_z|, with ΔB_h the horizontal change.
    """
    Jk = np.abs(np.asarray(J, dtype=float).reshape(-1, 2, 2))
    dB = np.asarray(dB, dtype=float).reshape(-1, 3)
    hz = _front(np.stack([np.hypot(dB[:, 0], dB[:, 1]), np.abs(dB[:, 2])], axis=1))
    return np.array([(_front(Jk[:, k, :]) @ hz.T).max() for k in range(2)])


def _front(a: np.ndarray) -> np.ndarray:
    """The rows of ``a`` (m, 2), a ≥ 0, that no other row exceeds in both columns: the only
    candidates for the largest a · b with b ≥ 0 (the others cannot win)."""
    order = np.lexsort((-a[:, 1], -a[:, 0]))  # by the first column, then the second, falling
    a = a[order]
    best = np.maximum.accumulate(a[:, 1])
    keep = np.ones(len(a), dtype=bool)
    keep[1:] = a[1:, 1] > best[:-1]
    return a[keep]


def crosstalk(study: Study, H: float, t_m: float, theta_m: float, J: np.ndarray, pitch: float,
              layout: str, rings: int, M_z: float | None = None,
              standoff: float | None = None) -> dict:
    """Worst false force [N] per component (F_r, F_z) from loaded neighbours at ``pitch``.

    ``J``: this taxel's Jacobians (..., 2, 2) [N/T] (at rest, or over its stable region);
    ``M_z`` [A/m], ``standoff`` [m]: the design's magnet and chip position (default the
    study's).
    Returns ``{"one": (F_r, F_z), "all": (F_r, F_z), "worst": (F_r, F_z)}``: one neighbour
    loaded, all loaded alike, and the larger of the two.
    """
    offsets = neighbour_offsets(layout, rings, pitch)
    one, all_ = neighbour_changes(study, H, t_m, theta_m, offsets, M_z, standoff)
    f_one, f_all = worst_false_force(J, one), worst_false_force(J, all_)
    return {"one": f_one, "all": f_all, "worst": np.maximum(f_one, f_all)}


def smallest_pitch(study: Study, H: float, t_m: float, theta_m: float, J: np.ndarray,
                   limit, layout: str, rings: int, M_z: float | None = None,
                   rtol: float = 1e-4, standoff: float | None = None) -> float:
    """Smallest pitch [m] ≥ the body's diameter 2R at which the neighbours' worst false force
    stays at or below ``limit`` = (F_r, F_z) [N] in both components.

    The crosstalk falls with the pitch (the field of a magnet falls with distance); the pitch
    is bracketed by doubling from 2R and bisected to ``rtol``.
    """
    limit = np.asarray(limit, dtype=float)

    def ok(p):
        return bool(np.all(crosstalk(study, H, t_m, theta_m, J, p, layout, rings,
                                     M_z, standoff)["worst"] <= limit))

    lo = 2 * study.body.R
    if ok(lo):
        return lo
    hi = 2 * lo
    while not ok(hi):
        lo, hi = hi, 2 * hi
        if hi > 1.0:  # a metre apart: no sensor pitch
            return float("inf")
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi
