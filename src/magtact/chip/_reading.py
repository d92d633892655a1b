"""What the Hall chip reads of a design: the required loads, where it leaves its range, and the
force noise over the loads it must read (docs/method.md §10).

The loads a sensor must read are the points (t, θ) of its stable region t ≤ t_m, θ ≤ θ_m
whose normal force is at most the required one, G f_z(t, θ) ≤ F_z,req: every path up to the
required normal force, and with it every shear force the body carries there. The field scales
exactly with the magnetisation and does not depend on G, so on a grid over the stable region a
design's field per unit M_z, its forces per unit G and its Jacobian per unit G and M_z serve
every grade, chip setting and G at once:

.. math:: B = M_z\\,b(t, θ), \\qquad F = G\\,f(t, θ), \\qquad
          \\frac{∂F}{∂B} = \\frac{G}{M_z}\\,j(t, θ)

A grid point where the chip leaves its range must lie beyond the required loads. So that no
point between two load levels escapes the check, the force compared is the one of the level
before it on the same path, and with a margin of :data:`READ_MARGIN`: the chip reads the
required loads when G f_z(t_{i−1}, θ) > (1 + m) F_z,req at every saturated level i. The
smallest such G is :meth:`SensorGrid.G_range`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from ..metamodel import ExactField, ModelSet
from ..sensitivity import dF_dB
from ..study import Study

#: Load levels and shear angles of the grid over each design's stable region.
N_T, N_THETA = 31, 7
#: Relative margin of force by which the chip's range must outlast the required loads: the grid
#: is coarse, and a designer's sensor should not saturate at exactly its rated force.
READ_MARGIN = 0.02


def exact_field_models(models: ModelSet, study: Study, standoff=None,
                       M_z: float | None = None) -> ModelSet:
    """``models`` with the exact field of ``study``'s magnet and chip position as B_r, B_z
    (the field models fitted to a DOE hold at its chip position only); ``standoff`` [m]: the
    chip's standoff instead of the study's, an array broadcasting against the evaluation
    points for a standoff per point; ``M_z`` [A/m]: the magnet's magnetisation instead of the
    study's (:class:`magtact.metamodel.ExactField`)."""
    return replace(models, B_r=ExactField(study, "B_r", standoff, M_z),
                   B_z=ExactField(study, "B_z", standoff, M_z))


@dataclass(frozen=True)
class SensorGrid:
    """Per-unit responses of designs on a grid over each one's stable region.

    Arrays have shape (n, N_T, N_THETA) for n designs (heights H with their stable bounds).

    Attributes
    ----------
    T, TH : numpy.ndarray
        Load levels t ∈ [0, t_m] and shear angles θ ∈ [0, θ_m] [rad].
    f_r, f_z : numpy.ndarray
        Forces per unit G [N/Pa].
    b_x, b_z : numpy.ndarray
        Field per unit M_z [T m/A] (x: shear, z: normal).
    j : numpy.ndarray, shape (n, N_T, N_THETA, 2, 2)
        ∂F/∂B per unit G and per unit M_z: rows (F_r, F_z), columns (B_x, B_z).
    """

    T: np.ndarray
    TH: np.ndarray
    f_r: np.ndarray
    f_z: np.ndarray
    b_x: np.ndarray
    b_z: np.ndarray
    j: np.ndarray

    def take(self, rows) -> SensorGrid:
        """The grid of the designs ``rows`` (index array or mask)."""
        return SensorGrid(*(getattr(self, f.name)[rows] for f in fields(self)))

    def M_limit(self, range_x, range_z) -> np.ndarray:
        """The magnetisation [A/m] above which the chip leaves its range (±range_x, ±range_z
        [T]) at each point, min(range_x / |b_x|, range_z / |b_z|) (inf where the field is
        zero); ``range_x``, ``range_z`` scalars or of shape (n,)."""
        rx, rz = (np.asarray(v, float).reshape(-1, 1, 1) for v in (range_x, range_z))
        with np.errstate(divide="ignore"):
            return np.minimum(rx / np.abs(self.b_x), rz / np.abs(self.b_z))

    def saturated(self, M_z, range_x, range_z) -> np.ndarray:
        """Where the chip leaves its range (±range_x, ±range_z [T]) with magnetisation M_z
        [A/m] (arrays of shape (n,) or scalars)."""
        return np.asarray(M_z, float).reshape(-1, 1, 1) > self.M_limit(range_x, range_z)

    def G_range(self, M_z, range_x, range_z, F_z: float) -> np.ndarray:
        """The smallest G [Pa] at which the chip reads every load up to the normal force F_z
        [N] (see the module notes); inf where it leaves its range at rest."""
        return self.G_range_at(self.M_limit(range_x, range_z), M_z, self.read_need(F_z))

    def read_need(self, F_z: float) -> np.ndarray:
        """The G [Pa] at which each point lies beyond the normal force F_z [N] by its level
        before, F_z / f_z(t_(i−1), θ) (inf at the first level)."""
        before = np.concatenate([np.zeros_like(self.f_z[:, :1]), self.f_z[:, :-1]], axis=1)
        with np.errstate(divide="ignore"):
            return np.where(before > 0, F_z / np.where(before > 0, before, 1.0), np.inf)

    def G_range_at(self, M_limit: np.ndarray, M_z, need: np.ndarray) -> np.ndarray:
        """:meth:`G_range` from the points' :meth:`M_limit` and :meth:`read_need` (computed
        once for a range and a force, and asked for every magnetisation)."""
        sat = np.asarray(M_z, float).reshape(-1, 1, 1) > M_limit
        need = np.where(sat, need, 0.0)
        return need.reshape(need.shape[0], -1).max(axis=1) * (1.0 + READ_MARGIN)

    def read_order(self, F_z: float) -> _ReadOrder:
        """:meth:`G_range` for the normal force F_z [N] at many ranges and magnetisations:
        the points in the order of their :meth:`read_need` (:class:`_ReadOrder`), sorted
        once; per range one pass over the points, per magnetisation a count."""
        return _ReadOrder(self, F_z)

    def unit_noise(self, noise_x, noise_z) -> np.ndarray:
        """Force noise per unit G / M_z at every point, shape (n, N_T, N_THETA, 2) (F_r, F_z):
        σ_F,k = √(j_kx² σ_x² + j_kz² σ_z²); ``noise_x``, ``noise_z`` [T RMS] scalars or (n,)."""
        sx, sz = (np.asarray(v, float).reshape(-1, 1, 1, 1) for v in (noise_x, noise_z))
        return np.sqrt(self.j[..., 0] ** 2 * sx ** 2 + self.j[..., 1] ** 2 * sz ** 2)

    def sigma(self, G, M_z, noise_x, noise_z, F_z: float) -> tuple[np.ndarray, np.ndarray]:
        """Worst σ_Fr, σ_Fz [N] over the required loads (G f_z ≤ F_z) with field noise
        (σ_x, σ_z) [T RMS]; arrays of shape (n,)."""
        G, M_z = (np.asarray(v, float).reshape(-1, 1, 1) for v in (G, M_z))
        with np.errstate(invalid="ignore"):  # G = inf: no design, σ inf
            region = G * self.f_z <= F_z
        s = self.unit_noise(noise_x, noise_z) * (G / M_z)[..., None]
        s = np.where(region[..., None], s, 0.0)
        worst = s.reshape(s.shape[0], -1, 2).max(axis=1)
        return worst[:, 0], worst[:, 1]

    def F_saturation(self, G, M_z, range_x, range_z) -> np.ndarray:
        """The smallest normal force [N] on the grid at which the chip has left its range
        (inf: it reads the whole stable region)."""
        sat = self.saturated(M_z, range_x, range_z)
        with np.errstate(invalid="ignore"):
            F = np.asarray(G, float).reshape(-1, 1, 1) * self.f_z
        F = np.where(sat, F, np.inf)
        return F.reshape(F.shape[0], -1).min(axis=1)


class _ReadOrder:
    """Per design of a grid: its points in the order of their :meth:`SensorGrid.read_need`
    for the normal force F_z [N], the greatest first, for :meth:`SensorGrid.G_range` of many
    ranges and magnetisations at once (:meth:`SensorGrid.read_order`).

    G_range is the greatest need among the saturated points, and a point saturates where the
    magnetisation exceeds its :meth:`SensorGrid.M_limit`: in this order it is the need of the
    first point whose M_limit lies below the magnetisation, the first point where the running
    least M_limit does (NaN limits, which never saturate, skipped). The first level's need is
    inf, so a design saturated there reads inf, and one saturated nowhere 0, as
    :meth:`SensorGrid.G_range_at` (the needs of a force F_z ≥ 0 are ≥ 0). Arrays point
    first, design last."""

    def __init__(self, grid: SensorGrid, F_z: float):
        need = grid.read_need(F_z)
        n = need.shape[0]
        need = need.reshape(n, -1)
        order = np.argsort(-need, axis=1, kind="stable")
        self.need = np.ascontiguousarray(np.take_along_axis(need, order, axis=1).T)
        self.b_x, self.b_z = (
            np.ascontiguousarray(np.take_along_axis(np.abs(b.reshape(n, -1)), order, axis=1).T)
            for b in (grid.b_x, grid.b_z))

    def least_limit(self, range_x: float, range_z: float) -> np.ndarray:
        """The running least M_limit [A/m] (:meth:`SensorGrid.M_limit`, the same quotients)
        over the points in this order, shape (P, n); ``range_x``, ``range_z`` [T] scalars."""
        with np.errstate(divide="ignore"):
            limit = np.minimum(range_x / self.b_x, range_z / self.b_z)
        return np.fmin.accumulate(limit, axis=0, out=limit)

    def G_range(self, least: np.ndarray, M_z: float) -> np.ndarray:
        """G_range [Pa] per design at magnetisation M_z [A/m] (the field's, times any factor)
        from :meth:`least_limit`."""
        P = least.shape[0]
        first = P - np.count_nonzero(least < M_z, axis=0)  # the first saturated point, or P
        need = np.take_along_axis(self.need, np.minimum(first, P - 1)[None], axis=0)[0]
        return np.where(first < P, np.maximum(need, 0.0), 0.0) * (1.0 + READ_MARGIN)


def sensor_grid(models: ModelSet, study: Study, H, t_m, theta_m,
                standoff=None, n: tuple[int, int] = (N_T, N_THETA)) -> SensorGrid:
    """:class:`SensorGrid` of designs at heights H [m] with stable bounds t_m, θ_m (arrays of
    shape (n,)) and the chip at ``standoff`` [m] (default the study's; an array of shape (n,)
    gives each design its own); ``n``: load levels and shear angles of the grid.

    All designs are evaluated together: one evaluation of the force models and one of the
    exact field (at every design's own standoff) for the whole set.
    """
    H, t_m, theta_m = (np.atleast_1d(np.asarray(v, float)) for v in (H, t_m, theta_m))
    per_design = standoff is not None and np.ndim(standoff) > 0
    if per_design:
        standoff = np.broadcast_to(np.asarray(standoff, float), H.shape)
    key = (id(models), hash(study), tuple(n), H.tobytes(), t_m.tobytes(), theta_m.tobytes(),
           None if standoff is None else np.asarray(standoff, float).tobytes())
    for i, (k, m, st, grid) in enumerate(_GRIDS):
        if k == key and m is models and st == study:
            _GRIDS.insert(0, _GRIDS.pop(i))
            return grid
    grid = _build(models, study, H, t_m, theta_m, standoff, per_design, n)
    for f in fields(grid):  # shared by every caller: read only
        getattr(grid, f.name).flags.writeable = False
    _GRIDS.insert(0, (key, models, study, grid))
    del _GRIDS[GRIDS_KEPT:]
    return grid


#: Sensor grids kept for reuse (:func:`sensor_grid` of the same models, study and designs
#: returns the grid already built): the sensor problem solved again for another corner of the
#: tolerances asks for the same grids.
GRIDS_KEPT = 4
_GRIDS: list = []


def _build(models, study, H, t_m, theta_m, standoff, per_design, n) -> SensorGrid:
    step = max(1, CHUNK_POINTS // (n[0] * n[1]))
    parts = []
    for a in range(0, H.size, step):  # designs in chunks: the field's work arrays stay small
        b = slice(a, a + step)
        parts.append(_grid(models, study, H[b], t_m[b], theta_m[b],
                           standoff[b] if per_design else standoff, n))
    if len(parts) == 1:
        return parts[0]
    return SensorGrid(*(np.concatenate([getattr(p, f.name) for p in parts])
                        for f in fields(SensorGrid)))


#: Grid points per evaluation of the field in :func:`sensor_grid`.
CHUNK_POINTS = 50_000


def _grid(models, study, H, t_m, theta_m, standoff, n) -> SensorGrid:
    s = np.linspace(0.0, 1.0, n[0])[None, :, None]
    u = np.linspace(0.0, 1.0, n[1])[None, None, :]
    T = s * t_m[:, None, None] + 0.0 * u
    TH = u * theta_m[:, None, None] + 0.0 * s
    HH = np.broadcast_to(H[:, None, None], T.shape)
    if standoff is not None and np.ndim(standoff) > 0:
        unit = exact_field_models(models, study, standoff[:, None, None], M_z=1.0)
    else:
        unit = exact_field_models(models, study, standoff, M_z=1.0)
    f_r, f_z = unit.forces(T, TH, HH, 1.0)
    j = dF_dB(unit, T, TH, HH, 1.0)
    b_x, b_z = unit.fields(T, TH, HH)
    return SensorGrid(T, TH, np.asarray(f_r), np.asarray(f_z), np.asarray(b_x),
                      np.asarray(b_z), np.asarray(j))
