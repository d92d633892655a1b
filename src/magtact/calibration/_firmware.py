"""A compact approximation of a sensor map for firmware, and its C99 header, JSON and CSV
(docs/method.md §13.2).

The map is axisymmetric, so the approximation works in the plane of the reading:
b_r = sqrt(B_x² + B_y²) ≥ 0 and b_z = B_z; then F_x = F_r B_x / b_r, F_y = F_r B_y / b_r,
F_z = F_z. Two kinds of candidate, measured alike on readings the fit never saw:

* ``poly``: F_r and F_z each a sum of products of Chebyshev polynomials T_i(ξ) T_j(η),
  i + j ≤ n, of the scaled variables ξ = 2 (b_r − b_r,lo) / (b_r,hi − b_r,lo) − 1 and
  η = the same of v(b_z), with v one of ``B_z``, ``1/B_z`` (a rational map) or ``B_z^(-1/3)``
  (∝ the magnet's distance for a dipole), fitted by least squares;
* ``table``: F_r and F_z on an n × n grid of (b_r, b_z) over the region's bounding box,
  interpolated bilinearly.

The region test of the firmware is a polygon through the image of the region's three edges in
(b_r, b_z) (θ = 0, θ = θ_m, t = t_m), N_EDGE vertices per edge.
"""

from __future__ import annotations

import csv
import weakref
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path

import numpy as np
from numpy.polynomial import chebyshev as cheb

from .. import _files as files
from .._errors import MagtactError
from .._parallel import fork_map
from .._records import entry, from_json, from_json_lenient, to_json
from ..study import from_si, mm, to_si
from ._map import OK, MapDesign, SensorMap

#: Transforms of b_z for the polynomial candidates: name → (NumPy function, C expression).
TRANSFORMS = {"B_z": (lambda v: v, "bz"), "1/B_z": (lambda v: 1.0 / v, "1.0 / bz"),
              "B_z^(-1/3)": (lambda v: 1.0 / np.cbrt(v), "1.0 / cbrt(bz)")}
#: Candidate degrees and table sizes.
DEGREES = (4, 6, 8, 10, 12, 14, 16)
TABLE_SIZES = (16, 32, 64, 128, 256)
#: Bytes of one stored number (float32).
BYTES = 4
#: Vertices per edge of the region polygon.
N_EDGE = 16
#: Training and held-out readings over the region.
N_TRAIN, N_TEST = 2500, 20000
#: Size budget when no candidate reaches the target [bytes].
BUDGET = 32768
#: Slack of the two-stage candidate's region test, in the features.
REGION_SLACK = 1e-6


@dataclass(frozen=True)
class Approximation:
    """One firmware approximation of a map, with its measured held-out error.

    ``kind`` ``"poly"`` (``degree``, ``transform``, ``coef_r``/``coef_z`` over the basis of
    :func:`basis_terms`) or ``"table"`` (``coef_r``/``coef_z`` of shape (n, n) on the grid of
    ``limits``). ``limits`` = (b_r,lo, b_r,hi, v_lo, v_hi) of the scaled variables (v = b_z for a
    table). ``polygon`` (k, 2): (b_r, b_z) [T] of the region test. ``err_r``, ``err_z`` [N]: the
    largest held-out error of F_r and F_z over the region.
    """

    kind: str
    degree: int
    transform: str
    limits: tuple[float, float, float, float]
    coef_r: np.ndarray
    coef_z: np.ndarray
    polygon: np.ndarray
    err_r: float = float("nan")
    err_z: float = float("nan")
    meta: dict = field(default_factory=dict)
    #: ``"features"`` only: the second stage and the unit's corrections (see
    #: :func:`fit_features`).
    stage: FeatureStage | None = None

    @property
    def n_coefficients(self) -> int:
        st = self.stage
        extra = 0 if st is None else np.size(st.coef_p) + np.size(st.coef_q)
        return int(self.coef_r.size + self.coef_z.size + extra)

    @property
    def bytes(self) -> int:
        """Stored numbers (coefficients, limits, polygon) × 4 bytes (float32), plus the
        polynomial's exponent table (2 bytes per term)."""
        extra = 2 * len(basis_terms(self.degree)) if self.kind != "table" else 0
        consts = 4 + (4 + 9 + 2 if self.kind == "features" else 0)
        return BYTES * (self.n_coefficients + consts + self.polygon.size) + extra

    @property
    def multiplies(self) -> int:
        """Multiplications and divisions of one evaluation (the region test excluded)."""
        common = 3 + 2 + 3  # b_r² and the two directions; F_x, F_y
        if self.kind == "table":
            return common + 4 + 2 * 4 + 2  # scaled indices, two bilinear blends, weights
        n = self.degree
        terms = len(basis_terms(n))
        one = 4 + 2 * 2 * max(n - 1, 0) + 3 * terms  # scaling, recurrences, the sum
        if self.kind == "features":  # the unit's correction, two stages, the directions
            return common + 7 + 2 * one + 2 + (1 if self.transform != "B_z" else 0)
        return common + one + (1 if self.transform != "B_z" else 0)

    # ---- evaluation ------------------------------------------------------------------------
    def planar(self, b_r, b_z) -> tuple[np.ndarray, np.ndarray]:
        """(F_r, F_z) [N] at (b_r, b_z) [T]."""
        b_r, b_z = np.broadcast_arrays(np.asarray(b_r, float), np.asarray(b_z, float))
        lo_r, hi_r, lo_v, hi_v = self.limits
        if self.kind == "table":
            return _bilinear(self.coef_r, self.coef_z, b_r, b_z, self.limits)
        v = TRANSFORMS[self.transform][0](b_z)
        xi = 2 * (b_r - lo_r) / (hi_r - lo_r) - 1
        eta = 2 * (v - lo_v) / (hi_v - lo_v) - 1
        A = _basis(xi, eta, self.degree)
        return A @ self.coef_r, A @ self.coef_z

    def evaluate(self, B) -> tuple[np.ndarray, np.ndarray]:
        """(F (..., 3) [N], inside (...)) of readings B (..., 3) [T], as the C function."""
        B = np.asarray(B, dtype=float)
        if self.kind == "features":
            return _evaluate_features(self, B)
        return self.forces(B), in_polygon(self.polygon, np.hypot(B[..., 0], B[..., 1]),
                                          B[..., 2])

    def forces(self, B) -> np.ndarray:
        """F (..., 3) [N] of readings B (..., 3) [T], as :meth:`evaluate` gives them, without
        the region test."""
        B = np.asarray(B, dtype=float)
        if self.kind == "features":
            return _evaluate_features(self, B)[0]
        b_r = np.hypot(B[..., 0], B[..., 1])
        F_r, F_z = self.planar(b_r, B[..., 2])
        with np.errstate(invalid="ignore", divide="ignore"):
            cx = np.where(b_r > 0, B[..., 0] / np.where(b_r > 0, b_r, 1.0), 0.0)
            cy = np.where(b_r > 0, B[..., 1] / np.where(b_r > 0, b_r, 1.0), 0.0)
        return np.stack([F_r * cx, F_r * cy, F_z], axis=-1)

    def to_json(self) -> dict:
        """The approximation as ``force_map.json``'s ``approximation`` holds it
        (:class:`ApproximationRecord`)."""
        return to_json(self.record())

    def record(self) -> ApproximationRecord:
        """The approximation as its file gives it (:class:`ApproximationRecord`)."""
        return ApproximationRecord(
            APPROXIMATION_FORMAT, self.kind, self.degree, self.transform, self.limits,
            self.coef_r.tolist(), self.coef_z.tolist(),
            basis_terms(self.degree) if self.kind != "table" else None, self.polygon,
            self.err_r, self.err_z, self.bytes, self.multiplies, self.stage, self.meta)


@dataclass(frozen=True)
class FeatureStage:
    """The second stage of a two-stage candidate and the unit's corrections
    (:func:`fit_features`), in SI.

    Attributes
    ----------
    coef_p, coef_q : numpy.ndarray
        The features' Chebyshev coefficients in (b_r, v(b_z)).
    limits_pq : numpy.ndarray
        (p_lo, p_hi, q_lo, q_hi) of the force's scaled variables.
    B_scale : float
        The unit's remanence over the design's.
    field_offset : numpy.ndarray
        The unit's field offset (b_x, b_y, b_z) [T].
    G_scale : float
        The unit's stiffness over the design's.
    delta : numpy.ndarray
        The shift of the features by the chip's offset, (−d_z, d_x, d_y) / a.
    region : numpy.ndarray
        (t_m, tan θ_m) of the region test.
    """

    coef_p: np.ndarray = entry(levels=("list",), array=True)
    coef_q: np.ndarray = entry(levels=("list",), array=True)
    limits_pq: np.ndarray = entry(levels=("list",), array=True)
    B_scale: float = entry()
    field_offset: np.ndarray = entry(levels=("list",), array=True)
    G_scale: float = entry()
    delta: np.ndarray = entry(levels=("list",), array=True)
    region: np.ndarray = entry(levels=("list",), array=True)


#: ``format`` of an approximation's JSON.
APPROXIMATION_FORMAT = "magtact-calibration/1"


@dataclass(frozen=True)
class ApproximationRecord:
    """An approximation as ``force_map.json``'s ``approximation`` gives it; SI (T, N).

    ``coef_r``, ``coef_z``: the coefficients as nested lists (one list for a polynomial, n
    rows for a table); ``basis``: the (i, j) of each polynomial coefficient (None for a table);
    ``stage``: the two-stage candidate's (:class:`FeatureStage`), written as an empty object for
    the others; ``meta``: further entries of the object as they are.
    """

    format: str = entry(kind=str)
    kind: str = entry(kind=str)
    degree: int = entry(kind=int)
    transform: str = entry(kind=str)
    limits: tuple[float, ...] = entry(levels=("list",))
    coef_r: list = entry(kind=object)
    coef_z: list = entry(kind=object)
    basis: tuple | None = entry(kind=int, levels=("list", "list"), optional=True)
    polygon: np.ndarray = entry("polygon_T", levels=("list", "list"), array=True)
    err_r: float = entry("max_error_F_r_N", "N")
    err_z: float = entry("max_error_F_z_N", "N")
    bytes: int = entry(kind=int)
    multiplies: int = entry(kind=int)
    stage: FeatureStage | None = entry(kind=FeatureStage, shape="dict", default=None)
    meta: dict = entry(kind=object, levels=("map",), inline=True, default_factory=dict)


def basis_terms(n: int) -> list[tuple[int, int]]:
    """(i, j) of the basis T_i(ξ) T_j(η), i + j ≤ n, in the order of the coefficients."""
    return [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]


@cache
def _basis_index(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The i and the j of :func:`basis_terms` as two index arrays."""
    terms = np.array(basis_terms(n), dtype=np.intp).reshape(-1, 2)
    return terms[:, 0], terms[:, 1]


def _basis(xi, eta, n) -> np.ndarray:
    """The basis T_i(ξ) T_j(η) of :func:`basis_terms` at (ξ, η) (...), shape (..., terms), in
    C order (the layout its products with the coefficients are computed in)."""
    i, j = _basis_index(n)
    return (np.take(cheb.chebvander(xi, n), i, axis=-1)
            * np.take(cheb.chebvander(eta, n), j, axis=-1))


def _bilinear(cr, cz, b_r, b_z, limits):
    lo_r, hi_r, lo_z, hi_z = limits
    n = cr.shape[0]
    x = np.clip((b_r - lo_r) / (hi_r - lo_r) * (n - 1), 0.0, n - 1 - 1e-9)
    y = np.clip((b_z - lo_z) / (hi_z - lo_z) * (n - 1), 0.0, n - 1 - 1e-9)
    i, j = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - i, y - j

    def interp(c):
        return ((c[i, j] * (1 - fy) + c[i, j + 1] * fy) * (1 - fx)
                + (c[i + 1, j] * (1 - fy) + c[i + 1, j + 1] * fy) * fx)

    return interp(cr), interp(cz)


def in_polygon(poly, x, y) -> np.ndarray:
    """Crossing-number test of points (x, y) against the closed polygon (k, 2), as in C."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    inside = np.zeros(x.shape, dtype=bool)
    for a in range(len(poly)):
        (x1, y1), (x2, y2) = poly[a], poly[a - 1]
        if y1 == y2:  # a horizontal edge crosses no horizontal ray
            continue
        inside ^= ((y1 > y) != (y2 > y)) & (x < (x2 - x1) * (y - y1) / (y2 - y1) + x1)
    return inside


def region_polygon(smap: SensorMap, n: int = N_EDGE) -> np.ndarray:
    """(b_r, b_z) [T] around the image of the stable region: θ = θ_m from t = 0 to t_m, then
    t = t_m back to θ = 0, then θ = 0 back to t = 0 (moved to b_r < 0: readings have b_r ≥ 0,
    so the axis itself is inside)."""
    s = np.linspace(0.0, 1.0, n)
    tm, thm = smap.t_m, smap.theta_m
    edges = [smap.features(tm * s, thm), smap.features(tm, thm * s[::-1])[1:],
             smap.features(tm * s[::-1], 0.0)[1:]]
    B = smap.B_of(np.concatenate(edges))
    b_r = np.hypot(B[:, 0], B[:, 1])
    pad = 1e-3 * b_r.max()
    b_r[-(n - 1):] = -pad
    b_r[0] = -pad  # the rest point: on the axis
    # the polygon widened by a hair so that readings on the region's edges count as inside
    b_z = B[:, 2]
    return np.stack([b_r, b_z], axis=-1)


def _samples(smap: SensorMap, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Readings and forces of n loads over the region, at random azimuths."""
    L = smap.region_samples(n, seed)
    return smap.at_load(L[:, 0], L[:, 1], L[:, 2])


def _test_set(smap: SensorMap, n: int, seed: int):
    B, F = _samples(smap, n, seed)
    s = np.linspace(0.0, 1.0, 200)
    phi = np.random.default_rng(seed).uniform(-np.pi, np.pi, 200)
    edges = np.concatenate([smap.features(smap.t_m * s, smap.theta_m, phi),
                            smap.features(smap.t_m, smap.theta_m * s, phi),
                            smap.features(smap.t_m * s, 0.0, phi)])
    return np.concatenate([B, smap.B_of(edges)]), np.concatenate([F, smap.F_of(edges)])


def fit_poly(smap: SensorMap, degree: int, transform: str, train, polygon) -> Approximation:
    """A polynomial candidate fitted by least squares to ``train`` = (B, F)."""
    B, F = train
    b_r, v = np.hypot(B[:, 0], B[:, 1]), TRANSFORMS[transform][0](B[:, 2])
    limits = (float(b_r.min()), float(b_r.max()), float(v.min()), float(v.max()))
    xi = 2 * (b_r - limits[0]) / (limits[1] - limits[0]) - 1
    eta = 2 * (v - limits[2]) / (limits[3] - limits[2]) - 1
    A = _basis(xi, eta, degree)
    F_r = np.hypot(F[:, 0], F[:, 1]) * np.sign(F[:, 0] * B[:, 0] + F[:, 1] * B[:, 1])
    c = np.linalg.lstsq(A, np.stack([F_r, F[:, 2]], axis=-1), rcond=None)[0]
    c_r, c_z = c[:, 0], c[:, 1]
    return Approximation("poly", degree, transform, limits, c_r, c_z, polygon)


def fit_table(smap: SensorMap, n: int, polygon) -> Approximation:
    """A bilinear table candidate: the map's own F_r, F_z at the nodes of an n × n grid over
    the region's bounding box (nodes outside the region hold the models' force at the
    inversion's solution, or the nearest node's value where there is none)."""
    return fit_tables(smap, (n,), polygon)[0]


def fit_tables(smap: SensorMap, sizes, polygon) -> list[Approximation]:
    """:func:`fit_table` for each size in ``sizes``, the map inverted once at every node of
    every table."""
    if not sizes:
        return []
    lo_r, hi_r = 0.0, float(polygon[:, 0].max())
    lo_z, hi_z = float(polygon[:, 1].min()), float(polygon[:, 1].max())
    grids = [np.meshgrid(np.linspace(lo_r, hi_r, n), np.linspace(lo_z, hi_z, n), indexing="ij")
             for n in sizes]
    B = np.concatenate([np.stack([R, np.zeros_like(R), Z], axis=-1).reshape(-1, 3)
                        for R, Z in grids])
    reading = smap.force(B)
    out, start = [], 0
    for n in sizes:
        F = reading.F_model[start:start + n * n].reshape(n, n, 3).copy()
        good = (np.isfinite(F).all(axis=-1)
                & (reading.flag[start:start + n * n].reshape(n, n) != 2))
        start += n * n
        if not good.all():
            from scipy.spatial import cKDTree

            _, k = cKDTree(np.argwhere(good)).query(np.argwhere(~good))
            F[~good] = F[good][k]
        out.append(Approximation("table", n, "B_z", (lo_r, hi_r, lo_z, hi_z),
                                 F[..., 0], F[..., 2], polygon))
    return out


def _measured(a: Approximation, test) -> Approximation:
    """``a`` with its largest errors on the readings ``test`` = (B, F): |ΔF_xy| (the shear
    force's error, ``err_r``) and |ΔF_z|."""
    B, F = test
    approx = a.forces(B)
    return replace(a, err_r=float(np.hypot(*(approx[:, :2] - F[:, :2]).T).max()),
                   err_z=float(np.abs(approx[:, 2] - F[:, 2]).max()))


# ---- the two-stage approximation: the load features, then the force -------------------------
def _cheb_fit(x, y, degree, targets):
    lim = (float(x.min()), float(x.max()), float(y.min()), float(y.max()))
    A = _basis(2 * (x - lim[0]) / (lim[1] - lim[0]) - 1, 2 * (y - lim[2]) / (lim[3] - lim[2]) - 1,
               degree)
    c = np.linalg.lstsq(A, np.stack(targets, axis=-1), rcond=None)[0]
    return lim, [c[:, k] for k in range(len(targets))]


def _cheb_eval(lim, coef, x, y, degree):
    A = _basis(2 * (x - lim[0]) / (lim[1] - lim[0]) - 1, 2 * (y - lim[2]) / (lim[3] - lim[2]) - 1,
               degree)
    return [A @ c for c in coef]


class _FeatureSamples:
    """The samples :func:`fit_features` fits to, the same for each degree and transform of one
    map and seed: the load features w (with a margin around the region) and the design's field
    there, and the force's samples with its fit of each degree (which the transform of b_z does
    not enter).

    Parameters
    ----------
    smap : SensorMap
        The map (a built unit's: its chip offset moves the features).
    seed : int
        As :func:`fit_features`.
    """

    def __init__(self, smap: SensorMap, seed: int):
        base = replace(smap, unit=type(smap.unit)())
        a, _ = smap._path
        d = smap.unit.chip_offset
        self.delta = np.array([-d[2] / a, d[0] / a, d[1] / a])
        margin = float(np.abs(self.delta).max()) + 0.02 * smap.t_m
        rng = np.random.default_rng(seed + 5)
        n = N_TRAIN
        self.p = rng.uniform(-margin, smap.t_m + margin, n)
        self.q = rng.uniform(0.0, 1.0, n) * (np.maximum(self.p, 0.0) * np.tan(smap.theta_m)
                                             + margin)
        self.B0 = base.B_of(np.stack([self.p, self.q, np.zeros(n)], axis=-1))
        # the force per unit of the unit's g, over the region (with the same margin)
        self.pf = rng.uniform(0.0, smap.t_m + margin, n)
        self.qf = rng.uniform(0.0, 1.0, n) * (self.pf * np.tan(smap.theta_m) + margin)
        self.F0 = base.F_of(np.stack([self.pf, self.qf, np.zeros(n)], axis=-1))
        self._force_fits: dict[int, tuple] = {}

    def force_fit(self, degree: int) -> tuple:
        """(limits, [c_r, c_z]) of the force's Chebyshev fit of ``degree`` in (p, |q|)."""
        if degree not in self._force_fits:
            self._force_fits[degree] = _cheb_fit(self.pf, self.qf, degree,
                                                 [self.F0[:, 0], self.F0[:, 2]])
        return self._force_fits[degree]


def fit_features(smap: SensorMap, degree: int, transform: str, seed: int = 0,
                 samples: _FeatureSamples | None = None) -> Approximation:
    """A two-stage candidate, for a design and for a built unit (docs/method.md §13.2).

    A unit's field is its design's field at shifted load features, scaled and offset:
    B(w) = s B₀(w + δ) + b with δ = (−d_z, d_x, d_y) / a (a chip offset d is a displacement of
    the magnet the other way; a, §5), and its force is g F₀(w). So: (1) the corrected reading
    B' = (B − b) / s; (2) the features (p', q') of the design's axisymmetric field from
    (|B'_xy|, B'_z), a Chebyshev polynomial of degree ``degree`` as in ``poly``, and
    q' = q' B'_xy / |B'_xy|; (3) w = w' − δ; (4) F = g (f_r(p, |q|) q / |q|, f_z(p, |q|)), the
    design's force per Chebyshev polynomial of the same degree in (p, |q|). The region test is
    exact in the features: 0 ≤ p ≤ t_m, |q| ≤ p tan θ_m. ``samples``: the map's samples for
    ``seed`` where the caller fits several candidates (drawn here otherwise).
    """
    unit = smap.unit
    s = _FeatureSamples(smap, seed) if samples is None else samples
    b_r, v = s.B0[:, 0], TRANSFORMS[transform][0](s.B0[:, 2])
    lim_b, (c_p, c_q) = _cheb_fit(b_r, v, degree, [s.p, s.q])
    lim_f, (c_r, c_z) = s.force_fit(degree)
    stage = FeatureStage(c_p, c_q, np.array(lim_f), unit.B_scale, np.array(unit.field_offset),
                         unit.G_scale, s.delta, np.array([smap.t_m, np.tan(smap.theta_m)]))
    return Approximation("features", degree, transform, lim_b, c_r, c_z, np.zeros((0, 2)),
                         stage=stage)


def _evaluate_features(ap: Approximation, B) -> tuple[np.ndarray, np.ndarray]:
    st = ap.stage
    Bc = (B - np.asarray(st.field_offset)) / st.B_scale
    b_r = np.hypot(Bc[..., 0], Bc[..., 1])
    v = TRANSFORMS[ap.transform][0](Bc[..., 2])
    p1, q1 = _cheb_eval(ap.limits, [st.coef_p, st.coef_q], b_r, v, ap.degree)
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = np.where(b_r > 0, Bc[..., 0] / np.where(b_r > 0, b_r, 1.0), 1.0)
        cy = np.where(b_r > 0, Bc[..., 1] / np.where(b_r > 0, b_r, 1.0), 0.0)
    delta = np.asarray(st.delta)
    p = p1 - delta[0]
    qx, qy = q1 * cx - delta[1], q1 * cy - delta[2]
    q = np.hypot(qx, qy)
    f_r, f_z = _cheb_eval(tuple(st.limits_pq), [ap.coef_r, ap.coef_z], p, q, ap.degree)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux = np.where(q > 0, qx / np.where(q > 0, q, 1.0), 0.0)
        uy = np.where(q > 0, qy / np.where(q > 0, q, 1.0), 0.0)
    g = st.G_scale
    t_m, tan_m = st.region
    inside = (p >= -REGION_SLACK) & (p <= t_m + REGION_SLACK) & (
        q <= np.maximum(p, 0.0) * tan_m + REGION_SLACK)
    return np.stack([g * f_r * ux, g * f_r * uy, g * f_z], axis=-1), inside


@dataclass(frozen=True)
class FrontierPoint:
    """One firmware candidate on the size–error plane (:meth:`FirmwareChoice.frontier`).

    Attributes
    ----------
    kind, transform : str
        The approximation's kind (``poly``, ``table``, ``features``) and the transform of B_z.
    degree : int
        Its degree (a table: points per side).
    bytes, multiplies : int
        Its size and its multiplies per evaluation.
    err_r, err_z : float
        Its largest held-out error of F_r and F_z [N].
    error_over_sigma : float
        The larger of the two errors over the target σ_F,r, σ_F,z [1].
    on_frontier : bool
        Whether no candidate of at most its size has a smaller ``error_over_sigma``.
    """

    kind: str = entry(kind=str, fallback="")
    degree: int = entry("degree_or_n", kind=int, fallback=0)
    transform: str = entry(kind=str, fallback="")
    bytes: int = entry(kind=int)
    multiplies: int = entry(kind=int, fallback=0)
    err_r: float = entry("max_error_F_r_mN", "mN", fallback=np.nan)
    err_z: float = entry("max_error_F_z_mN", "mN", fallback=np.nan)
    error_over_sigma: float = entry()
    on_frontier: bool = entry(kind=bool, fallback=False)

    def to_json(self) -> dict:
        """The candidate in user units (mN), as ``calibration.json``'s frontier holds it."""
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> FrontierPoint | None:
        """The candidate :meth:`to_json` wrote, in SI; None for anything but a JSON object
        with a size and a score (another value missing or of another type reads as NaN, 0,
        empty text or False)."""
        p = from_json_lenient(cls, data)
        return None if p is None or p.bytes is None or p.error_over_sigma is None else p


@dataclass(frozen=True)
class FirmwareChoice:
    """The chosen approximation, every candidate measured, and the target it was held to.

    ``target_r``, ``target_z`` [N]: σ_F,r and σ_F,z (the worst over the region); ``reached``:
    whether the chosen one's largest held-out error is within them; ``rule``: how it was chosen.
    """

    chosen: Approximation
    candidates: list[Approximation]
    target_r: float
    target_z: float
    reached: bool
    rule: str

    def frontier_points(self) -> list[FrontierPoint]:
        """Every candidate on the size–error plane, with whether it is on the frontier (no
        candidate of at most its size has a smaller error)."""
        scores = [max(a.err_r / self.target_r, a.err_z / self.target_z)
                  for a in self.candidates]
        return [FrontierPoint(a.kind, a.degree, a.transform, a.bytes, a.multiplies, a.err_r,
                              a.err_z, score,
                              not any(o.bytes <= a.bytes and s < score
                                      for j, (o, s) in enumerate(zip(self.candidates, scores,
                                                                     strict=True))
                                      if j != i))
                for i, (a, score) in enumerate(zip(self.candidates, scores, strict=True))]

    def frontier(self) -> list[dict]:
        """Every candidate: kind, degree, transform, bytes, multiplies, errors [mN], whether it
        is on the size–error frontier (:meth:`frontier_points` in user units)."""
        return [p.to_json() for p in self.frontier_points()]


def firmware_approximation(smap: SensorMap, sigma_F: tuple[float, float],
                           degrees=DEGREES, table_sizes=TABLE_SIZES, budget: int = BUDGET,
                           seed: int = 0, n_test: int = N_TEST) -> FirmwareChoice:
    """Measure the candidates on held-out readings and choose one (docs/method.md §13.2).

    Rule: the smallest (in bytes, then multiplies) candidate whose largest held-out errors of
    F_r and F_z are within ``sigma_F`` = (σ_F,r, σ_F,z) [N]; if none is, the candidate with the
    smallest error relative to σ_F within ``budget`` bytes (the frontier is then the answer).
    The held-out readings: ``n_test`` loads uniform over the region's features plus 600 on its
    edges.

    Raises
    ------
    MagtactError
        If σ_F is not positive.
    """
    sr, sz = (float(s) for s in sigma_F)
    if not (sr > 0 and sz > 0):
        raise MagtactError(f"the target sigma_F must be positive, got {sigma_F} N")
    polygon = region_polygon(smap)
    train = _samples(smap, N_TRAIN, seed + 1)
    test = _test_set(smap, n_test, seed + 2)
    axisymmetric = not any(smap.unit.chip_offset) and not any(smap.unit.field_offset[:2])
    samples = _FeatureSamples(smap, seed)
    jobs = [("features", tr, n) for tr in TRANSFORMS for n in degrees]
    if axisymmetric:  # the planar forms need a map that is the same at every azimuth
        jobs += [("poly", tr, n) for tr in TRANSFORMS for n in degrees] + [("tables", "", 0)]

    def measured(job) -> list[Approximation]:
        kind, tr, n = job
        if kind == "features":
            made = [fit_features(smap, n, tr, seed, samples)]
        elif kind == "poly":
            made = [fit_poly(smap, n, tr, train, polygon)]
        else:
            made = fit_tables(smap, tuple(table_sizes), polygon)
        return [_measured(a, test) for a in made]

    # the candidates are independent: on the machine's cores, the tables (the longest job)
    # first
    cands = [a for made in fork_map(measured, jobs, first=lambda job: job[0] != "tables")
             for a in made]

    def score(a):
        return max(a.err_r / sr, a.err_z / sz)

    good = [a for a in cands if score(a) <= 1.0]
    if good:
        chosen = min(good, key=lambda a: (a.bytes, score(a)))
        rule = "the smallest candidate (bytes) within σ_F, then the most accurate"
    else:
        small = [a for a in cands if a.bytes <= budget] or cands
        chosen = min(small, key=score)
        rule = (f"no candidate reaches sigma_F: the smallest error within {budget} bytes "
                "(see the frontier)")
    return FirmwareChoice(chosen, cands, sr, sz, bool(good), rule)


# ---- writers ---------------------------------------------------------------------------------
#: Half-width of the band around the field at rest inside which a reading is valid, in the
#: chip's RMS noise per axis: a sensor at rest reads its rest field plus noise, on both sides of
#: the region's edge at t = 0.
BAND_SIGMAS = 3.0

#: A reading whose B_z (after the offset) is at most this fraction of B_z at rest has no
#: field from the magnet (B_z grows from its rest value as the body is loaded).
NO_FIELD_FRACTION = 0.5

#: Return codes of the C function ``magtact_force``.
C_RETURN = {"MAGTACT_FORCE_OK": 0, "MAGTACT_FORCE_OUTSIDE": 1, "MAGTACT_FORCE_NO_FIELD": 2}


def _c_array(name: str, values, indent: str = "    ") -> str:
    vals = [f"{float(v):.17g}" for v in np.ravel(values)]
    lines = [", ".join(vals[k:k + 4]) for k in range(0, len(vals), 4)]
    inner = indent + "    "
    return (f"{indent}static const MAGTACT_REAL {name}[{len(vals)}] = {{\n{inner}"
            + f",\n{inner}".join(lines) + f"\n{indent}}};\n")


def _c_index(name: str, values, indent: str = "    ") -> str:
    return (f"{indent}static const unsigned char {name}[{len(values)}] = "
            f"{{{', '.join(str(v) for v in values)}}};\n")


def rest_field(smap: SensorMap) -> np.ndarray:
    """The reading (B_x, B_y, B_z) [T] of the map's sensor at rest (no load)."""
    return np.asarray(smap.at_load(np.array([0.0]), 0.0)[0][0], dtype=float)


def c_header(a: Approximation, smap: SensorMap, choice: FirmwareChoice | None = None,
             noise: tuple[float, float] | None = None) -> str:
    """The C99 header ``force.h`` (:func:`c_source`) with its largest error against
    ``force_table.csv`` measured in each build of :data:`BUILDS` (:func:`measure_builds`)
    stated at its top; a float build whose error exceeds the target σ_F (or that could not be
    measured) is refused at compile time.
    """
    builds = measure_builds(c_source(a, smap, choice, noise), smap, a)
    return c_source(a, smap, choice, noise, builds)


def c_source(a: Approximation, smap: SensorMap, choice: FirmwareChoice | None = None,
             noise: tuple[float, float] | None = None, builds: dict | None = None) -> str:
    """The C99 header ``force.h``: ``magtact_force`` and ``magtact_force_tare``, both
    ``static inline`` (a file that includes the header and calls neither compiles without a
    warning; every file that calls them gets its own copy), with no dependency beyond
    <math.h> (link with ``-lm``).

    ``magtact_force(bx, by, bz, offset, out)`` returns 0 (``MAGTACT_FORCE_OK``) inside the
    stable region or within :data:`BAND_SIGMAS` × the chip's ``noise`` (σ_x, σ_z) [T] of the
    field at rest, 1 (``MAGTACT_FORCE_OUTSIDE``, ``out`` zero: an extrapolation is no
    measurement) elsewhere and 2 (``MAGTACT_FORCE_NO_FIELD``, ``out`` zero) for B_z at most
    :data:`NO_FIELD_FRACTION` of B_z at rest (B = 0, B_z < 0 included) or a reading that is not
    finite. ``offset`` (or NULL) is subtracted from the
    reading first; ``magtact_force_tare`` sets it from the mean of n readings at rest.
    """
    d = smap.design_record()
    rest = rest_field(smap)
    band = (0.0, 0.0) if noise is None else tuple(BAND_SIGMAS * float(v) for v in noise)
    double = (builds or {}).get(BUILDS[0][0])
    missed = (choice is not None and choice.reached and double is not None
              and not _within(double, choice))
    target = ("" if choice is None else
              " *   target sigma_F (the design's resolution): "
              f"F_r {from_si(choice.target_r, 'mN'):.4g} mN, "
              f"F_z {from_si(choice.target_z, 'mN'):.4g} mN; "
              f"{'reached' if choice.reached and not missed else 'NOT reached'} "
              f"({choice.rule}"
              + ("; held out within it, but not against force_table.csv in double" if missed
                 else "") + ")\n")
    band_text = (" *   no band around the rest field (the chip's noise was not given)\n"
                 if noise is None else
                 f" *   valid band around the rest field: {BAND_SIGMAS:g} x the chip's RMS "
                 f"noise, {from_si(band[0], 'uT'):.4g} uT in x and y, "
                 f"{from_si(band[1], 'uT'):.4g} uT in z\n")
    rest_mT = ", ".join(f"{from_si(v, 'mT'):.6g}" for v in rest)
    kind = (f" of degree {a.degree} in b_r and {a.transform}" if a.kind == "poly"
            else f" {a.degree} x {a.degree} bilinear in (b_r, b_z)" if a.kind == "table"
            else f": load features of degree {a.degree} in b_r and {a.transform}, then the "
                 f"force of degree {a.degree} in the features")
    head = (
        "/* magtact field-to-force calibration (generated; docs/method.md section 13).\n"
        f" *   design: H = {mm(d.H):.4g} mm, G = {from_si(d.G, 'kPa'):.4g} kPa, "
        f"M_z = {d.M_z:.4g} A/m\n"
        " *   units: bx, by, bz in tesla (the Hall chip's axes: x, y in the base plane, z up);"
        " out[3] in newtons\n"
        " *   out = (F_x, F_y, F_z): the reaction of the base on the body (F_r <= 0 against the "
        "shear,\n *   F_z > 0 in compression); the load applied on the top is -out.\n"
        f" *   region: t <= {d.t_m:.6g}, theta <= {d.theta_m:.6g} rad (every azimuth); "
        f"F_r down to -{d.F_r_range:.4g} N, F_z up to {d.F_z_range:.4g} N\n"
        f" *   field at rest: ({rest_mT}) mT\n"
        + band_text +
        f" *   approximation: {a.kind}{kind}\n"
        + _unit_line(smap) +
        f" *   largest error over the region (held out, NumPy in double): F_r "
        f"{from_si(a.err_r, 'mN'):.4g} mN, F_z {from_si(a.err_z, 'mN'):.4g} mN\n"
        + _builds_text(builds, choice) + target +
        f" *   size: {a.bytes} bytes of float32 numbers (about twice in double), "
        f"{a.multiplies} multiplications per call\n"
        " *\n"
        " * Use: #include \"force.h\" in any number of C files (the functions are static\n"
        " * inline; a file that calls neither compiles without warnings) and link with -lm\n"
        " * (sqrt, cbrt, fabs of <math.h>), e.g. cc -std=c99 main.c -lm\n"
        " *   MAGTACT_REAL offset[3] = {0, 0, 0};\n"
        " *   MAGTACT_REAL rest[16][3];  16 readings (bx, by, bz) taken with no load\n"
        " *   magtact_force_tare(rest, 16, offset);  once: their mean is the rest reading\n"
        " *   rc = magtact_force(bx, by, bz, offset, out);  offset may be NULL (no tare)\n"
        " * A tare from one reading carries the chip's whole noise into every later force and\n"
        " * moves rest readings out of the valid band; the mean of n has 1/sqrt(n) of it.\n"
        " * magtact_force returns MAGTACT_FORCE_OK (0) inside the region or within the band\n"
        " * around the rest field, MAGTACT_FORCE_OUTSIDE (1, out = 0) elsewhere,\n"
        " * MAGTACT_FORCE_NO_FIELD (2, out = 0) for bz <= MAGTACT_BZ_MIN (half the field at rest,\n"
        " * after the offset) or a reading that is not a finite number (no magnet above the\n"
        " * chip, the chip upside down, a bad read).\n"
        " * Numbers are stored and returned as MAGTACT_REAL (double by default; define it as\n"
        " * float before including for float32 tables); the sums are computed in MAGTACT_ACC\n"
        " * (double by default, also with float tables; define it as float where double\n"
        " * arithmetic is too slow). The error of each build is stated above; a float build\n"
        " * whose error exceeds the target sigma_F does not compile (typedef below). */\n"
        "#ifndef MAGTACT_FORCE_H\n#define MAGTACT_FORCE_H\n#include <math.h>\n"
        "#include <stddef.h>\n#include <stdint.h>\n#include <string.h>\n"
        "#ifndef MAGTACT_REAL\n#define MAGTACT_REAL double\n#endif\n"
        "#ifndef MAGTACT_ACC\n#define MAGTACT_ACC double\n#endif\n"
        + "".join(f"#define {k} {v}\n" for k, v in C_RETURN.items())
        + f"#define MAGTACT_REST_X ({rest[0]:.17g})\n#define MAGTACT_REST_Y ({rest[1]:.17g})\n"
        f"#define MAGTACT_REST_Z ({rest[2]:.17g})\n"
        f"#define MAGTACT_BZ_MIN ({NO_FIELD_FRACTION * max(rest[2], 0.0):.17g})\n"
        f"#define MAGTACT_BAND_XY ({band[0]:.17g})\n#define MAGTACT_BAND_Z ({band[1]:.17g})\n\n"
        + _float_guards(builds, choice) + _C_FINITE)
    helpers, block = _c_features(a) if a.kind == "features" else ("", _c_planar(a))
    func = (
        "/* The force of a reading (see the top of this file). */\n"
        "static inline int magtact_force(MAGTACT_REAL bx, MAGTACT_REAL by, MAGTACT_REAL bz,\n"
        "                                const MAGTACT_REAL *offset, MAGTACT_REAL out[3])\n{\n"
        "    int inside = 0;\n"
        "    out[0] = 0;\n    out[1] = 0;\n    out[2] = 0;\n"
        "    if (!magtact_force_finite(bx) || !magtact_force_finite(by)\n"
        "        || !magtact_force_finite(bz))\n"
        "        return MAGTACT_FORCE_NO_FIELD;\n"
        "    if (offset != NULL) {\n"
        "        bx -= offset[0];\n        by -= offset[1];\n        bz -= offset[2];\n    }\n"
        "    if (!magtact_force_finite(bx) || !magtact_force_finite(by)\n"
        "        || !magtact_force_finite(bz) || !(bz > MAGTACT_BZ_MIN))\n"
        "        return MAGTACT_FORCE_NO_FIELD;\n"
        + block +
        "    if (!inside && fabs((double)bx - MAGTACT_REST_X) <= MAGTACT_BAND_XY\n"
        "        && fabs((double)by - MAGTACT_REST_Y) <= MAGTACT_BAND_XY\n"
        "        && fabs((double)bz - MAGTACT_REST_Z) <= MAGTACT_BAND_Z)\n"
        "        inside = 1;  /* at rest, within the chip's noise */\n"
        "    if (!inside) {  /* an extrapolation is no measurement: none is returned */\n"
        "        out[0] = 0;\n        out[1] = 0;\n        out[2] = 0;\n"
        "        return MAGTACT_FORCE_OUTSIDE;\n    }\n"
        "    return MAGTACT_FORCE_OK;\n}\n\n"
        "/* The offset that magtact_force subtracts: the mean of n readings b[0..n-1] taken\n"
        " * with no load, minus the design's rest field (n = 16 leaves a quarter of the chip's\n"
        " * noise in the offset). Returns MAGTACT_FORCE_NO_FIELD (offset unchanged) for n < 1\n"
        " * or if any reading is one magtact_force would refuse (not a finite number, or\n"
        " * bz <= MAGTACT_BZ_MIN). */\n"
        "static inline int magtact_force_tare(MAGTACT_REAL (*b)[3], int n,\n"
        "                                     MAGTACT_REAL offset[3])\n{\n"
        "    double sx = 0, sy = 0, sz = 0;\n    int k;\n"
        "    if (b == NULL || offset == NULL || n < 1)\n        return MAGTACT_FORCE_NO_FIELD;\n"
        "    for (k = 0; k < n; k++) {\n"
        "        if (!magtact_force_finite(b[k][0]) || !magtact_force_finite(b[k][1])\n"
        "            || !magtact_force_finite(b[k][2]) || !(b[k][2] > MAGTACT_BZ_MIN))\n"
        "            return MAGTACT_FORCE_NO_FIELD;\n"
        "        sx += b[k][0];\n        sy += b[k][1];\n        sz += b[k][2];\n    }\n"
        "    offset[0] = (MAGTACT_REAL)(sx / n - MAGTACT_REST_X);\n"
        "    offset[1] = (MAGTACT_REAL)(sy / n - MAGTACT_REST_Y);\n"
        "    offset[2] = (MAGTACT_REAL)(sz / n - MAGTACT_REST_Z);\n"
        "    return MAGTACT_FORCE_OK;\n}\n\n#endif\n")
    return head + helpers + func


#: Whether a value is a finite number, from its bits (exponent not all ones): holds under
#: -ffast-math and -ffinite-math-only, where isfinite(x) and x != x may be folded to constants.
_C_FINITE = (
    "/* 1 if x is a finite number, from its bits (holds under -ffast-math) */\n"
    "static inline int magtact_force_finite(MAGTACT_REAL x)\n{\n"
    "    if (sizeof(MAGTACT_REAL) == sizeof(uint32_t)) {\n"
    "        uint32_t u;\n        memcpy(&u, &x, sizeof u);\n"
    "        return (u & 0x7f800000u) != 0x7f800000u;\n    } else {\n"
    "        uint64_t u;\n        double d = (double)x;\n        memcpy(&u, &d, sizeof u);\n"
    "        return (u & 0x7ff0000000000000ull) != 0x7ff0000000000000ull;\n    }\n}\n\n")

#: The builds of ``force.h`` whose error is measured: (name, MAGTACT_REAL, MAGTACT_ACC).
BUILDS = (("double", "double", "double"), ("float tables, double sums", "float", "double"),
          ("float", "float", "float"))
#: C compilers tried, in order, to measure the builds.
COMPILERS = ("cc", "gcc", "clang")

_C_DRIVER = """#include <stdio.h>
#include "force.h"
int main(void)
{
    double x, y, z;
    MAGTACT_REAL o[3];
    while (scanf("%lf %lf %lf", &x, &y, &z) == 3) {
        int rc = magtact_force((MAGTACT_REAL)x, (MAGTACT_REAL)y, (MAGTACT_REAL)z, NULL, o);
        printf("%d %.17g %.17g %.17g\\n", rc, (double)o[0], (double)o[1], (double)o[2]);
    }
    return 0;
}
"""


def table_readings(smap: SensorMap, n: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """The readings B (k, 3) [T] (b_r along x) and forces (F_r, F_z) (k, 2) [N] of the points of
    ``force_table.csv`` inside the region, as the file holds them (its digits)."""
    rows = [r for r in _table_rows(smap, n) if r[4] == 1]
    B = np.array([[to_si(float(r[0]), "mT"), 0.0, to_si(float(r[1]), "mT")] for r in rows])
    F = np.array([[float(r[2]), float(r[3])] for r in rows])
    return B.reshape(-1, 3), F.reshape(-1, 2)


def _compiler() -> str | None:
    import shutil

    return next((c for c in COMPILERS if shutil.which(c)), None)


def run_header(header: str, B: np.ndarray, real: str = "double", acc: str = "double",
               flags: tuple[str, ...] = ()) -> tuple[np.ndarray, np.ndarray] | None:
    """(rc (k,), out (k, 3)) of ``magtact_force`` of the C header ``header`` compiled with
    MAGTACT_REAL = ``real``, MAGTACT_ACC = ``acc`` and ``flags`` on readings B (k, 3) [T];
    None where no C compiler is found."""
    got = run_headers(header, B, ((real, acc),), flags)
    return None if got is None else got[0]


def run_headers(header: str, B: np.ndarray, builds, flags: tuple[str, ...] = ()
                ) -> list[tuple[np.ndarray, np.ndarray]] | None:
    """:func:`run_header` for each (MAGTACT_REAL, MAGTACT_ACC) of ``builds``, the builds
    compiled at once (a compiler process each); None where no C compiler is found.

    Raises
    ------
    subprocess.CalledProcessError
        If a build does not compile or its program fails.
    subprocess.TimeoutExpired
        If a compiler or a program takes over two minutes (the compilers still running are
        ended).
    """
    import subprocess
    import tempfile

    cc = _compiler()
    if cc is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "force.h").write_text(header, encoding="utf-8")
        (folder / "m.c").write_text(_C_DRIVER, encoding="utf-8")
        programs = [folder / f"m{k}" for k in range(len(builds))]
        jobs = [subprocess.Popen([cc, "-std=c99", "-O2", *flags, f"-DMAGTACT_REAL={real}",
                                  f"-DMAGTACT_ACC={acc}", "-o", str(program),
                                  str(folder / "m.c"), "-lm"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE)
                for program, (real, acc) in zip(programs, builds, strict=True)]
        try:
            for job in jobs:
                out, err = job.communicate(timeout=120)
                if job.returncode:
                    raise subprocess.CalledProcessError(job.returncode, job.args, out, err)
        finally:
            for job in jobs:
                if job.poll() is None:
                    job.kill()
                    job.wait()
        text = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(B, float).tolist())
        runs = [subprocess.run([str(program)], input=text, capture_output=True, text=True,
                               check=True, timeout=120).stdout.split() for program in programs]
    values = [np.array(out, dtype=float).reshape(-1, 4) for out in runs]
    return [(v[:, 0].astype(int), v[:, 1:]) for v in values]


def measure_builds(header: str, smap: SensorMap, a: Approximation) -> dict:
    """The largest error of each build of :data:`BUILDS` against the points of
    ``force_table.csv`` inside the region: name → {``err_r``, ``err_z`` [N], ``points``,
    ``outside`` (points the build reads as outside the region), ``how``}; a float build is None
    where no C compiler is found (the double build is then NumPy's evaluation of the map)."""
    B, F = table_readings(smap)
    runs = run_headers(header, B, [(real, acc) for _, real, acc in BUILDS])
    out = {}
    for k, (name, real, _) in enumerate(BUILDS):
        got = None if runs is None else runs[k]
        if got is None and real != "double":
            out[name] = None
            continue
        if got is None:
            approx, inside = a.evaluate(B)
            rc, how = np.where(inside, 0, 1), "NumPy, no C compiler found"
        else:
            (rc, approx), how = got, f"compiled with {_compiler()} -O2"
        ok = rc == 0
        err_r = float(np.abs(approx[ok, 0] - F[ok, 0]).max()) if ok.any() else float("nan")
        err_z = float(np.abs(approx[ok, 2] - F[ok, 1]).max()) if ok.any() else float("nan")
        out[name] = {"err_r": err_r, "err_z": err_z, "points": int(len(B)),
                     "outside": int((~ok).sum()), "how": how}
    return out


def _within(m: dict | None, choice: FirmwareChoice | None) -> bool:
    return choice is None or (m is not None and m["err_r"] <= choice.target_r
                              and m["err_z"] <= choice.target_z)


def _builds_text(builds: dict | None, choice: FirmwareChoice | None) -> str:
    if not builds:
        return ""
    lines = [" *   largest error against force_table.csv (its points inside the region), per "
             "build:\n"]
    for name, real, acc in BUILDS:
        m = builds.get(name)
        what = f"MAGTACT_REAL {real}, MAGTACT_ACC {acc}"
        if m is None:
            lines.append(f" *     {name} ({what}): not measured (no C compiler at generation); "
                         "refused below\n")
            continue
        refused = ("" if _within(m, choice) else "; above the target sigma_F"
                   + ("" if real == "double" else ": refused below"))
        lines.append(f" *     {name} ({what}): F_r {from_si(m['err_r'], 'mN'):.4g} mN, F_z "
                     f"{from_si(m['err_z'], 'mN'):.4g} mN over {m['points'] - m['outside']} of "
                     f"{m['points']} points ({m['outside']} read as outside; {m['how']})"
                     f"{refused}\n")
    return "".join(lines)


def _float_guards(builds: dict | None, choice: FirmwareChoice | None) -> str:
    """Compile-time refusals (C99: an array of negative size) of the float builds whose error
    exceeds the target σ_F or was not measured."""
    if not builds:
        return ""
    out = ""
    tables, sums = BUILDS[1][0], BUILDS[2][0]
    if not _within(builds.get(tables), choice):
        out += ("/* float tables exceed the target sigma_F (see the top): build with double */\n"
                "typedef char magtact_force_float_tables_exceed_sigma_F"
                "[sizeof(MAGTACT_REAL) >= sizeof(double) ? 1 : -1];\n")
    if not _within(builds.get(sums), choice):
        out += ("/* float sums exceed the target sigma_F (see the top): keep MAGTACT_ACC "
                "double */\n"
                "typedef char magtact_force_float_sums_exceed_sigma_F"
                "[sizeof(MAGTACT_ACC) >= sizeof(double) || sizeof(MAGTACT_REAL) >= "
                "sizeof(double) ? 1 : -1];\n")
    if not out:
        return ""
    return ("/* Define MAGTACT_ALLOW_FLOAT to build in float regardless (its error is stated at\n"
            " * the top). */\n#ifndef MAGTACT_ALLOW_FLOAT\n" + out + "#endif\n\n")


def _c_planar(a: Approximation) -> str:
    """The block of ``magtact_force`` for a ``poly`` or ``table`` approximation: sets out and
    inside from (bx, by, bz), bz > 0."""
    lo_r, hi_r, lo_v, hi_v = a.limits
    n = a.degree
    k = len(a.polygon)
    ind = "        "
    block = ("    {\n" + _c_array("coef_r", a.coef_r, ind) + _c_array("coef_z", a.coef_z, ind)
             + _c_array("poly_r", a.polygon[:, 0], ind)
             + _c_array("poly_z", a.polygon[:, 1], ind))
    if a.kind == "poly":
        terms = basis_terms(n)
        block += (_c_index("ti", [i for i, _ in terms], ind)
                  + _c_index("tj", [j for _, j in terms], ind))
    block += (f"{ind}MAGTACT_REAL br = (MAGTACT_REAL)sqrt((double)(bx * bx + by * by));\n"
              f"{ind}MAGTACT_REAL fr = 0, fz = 0;\n{ind}int a, b;\n")
    if a.kind == "poly":
        v = {"B_z": "bz", "1/B_z": "(MAGTACT_ACC)(1.0 / (double)bz)",
             "B_z^(-1/3)": "(MAGTACT_ACC)(1.0 / cbrt((double)bz))"}[a.transform]
        terms = basis_terms(n)
        block += (
            f"{ind}MAGTACT_ACC v = {v};\n"
            f"{ind}MAGTACT_ACC xi = 2 * ((MAGTACT_ACC)br - ({lo_r:.17g})) / ({hi_r - lo_r:.17g})"
            " - 1;\n"
            f"{ind}MAGTACT_ACC eta = 2 * (v - ({lo_v:.17g})) / ({hi_v - lo_v:.17g}) - 1;\n"
            f"{ind}MAGTACT_ACC tx[{n + 1}], ty[{n + 1}], sr = 0, sz = 0;\n{ind}int k;\n"
            f"{ind}tx[0] = 1;\n{ind}ty[0] = 1;\n"
            + (f"{ind}tx[1] = xi;\n{ind}ty[1] = eta;\n"
               f"{ind}for (k = 2; k <= {n}; k++) {{\n"
               f"{ind}    tx[k] = 2 * xi * tx[k - 1] - tx[k - 2];\n"
               f"{ind}    ty[k] = 2 * eta * ty[k - 1] - ty[k - 2];\n{ind}}}\n"
               if n >= 1 else "")
            + f"{ind}for (k = 0; k < {len(terms)}; k++) {{\n"
            f"{ind}    MAGTACT_ACC t = tx[ti[k]] * ty[tj[k]];\n"
            f"{ind}    sr += coef_r[k] * t;\n{ind}    sz += coef_z[k] * t;\n{ind}}}\n"
            f"{ind}fr = (MAGTACT_REAL)sr;\n{ind}fz = (MAGTACT_REAL)sz;\n")
    else:
        block += (
            f"{ind}MAGTACT_REAL x = (br - ({lo_r:.17g})) / ({hi_r - lo_r:.17g}) * {n - 1};\n"
            f"{ind}MAGTACT_REAL y = (bz - ({lo_v:.17g})) / ({hi_v - lo_v:.17g}) * {n - 1};\n"
            f"{ind}MAGTACT_REAL fx, fy;\n{ind}int i, j;\n"
            f"{ind}if (x < 0) x = 0;\n{ind}if (x > {n - 1} - 1e-6) x = {n - 1} - 1e-6;\n"
            f"{ind}if (y < 0) y = 0;\n{ind}if (y > {n - 1} - 1e-6) y = {n - 1} - 1e-6;\n"
            f"{ind}i = (int)x;\n{ind}j = (int)y;\n{ind}fx = x - i;\n{ind}fy = y - j;\n"
            + "".join(
                f"{ind}f{c} = (coef_{c}[i * {n} + j] * (1 - fy) + coef_{c}[i * {n} + j + 1] "
                f"* fy) * (1 - fx)\n"
                f"{ind}    + (coef_{c}[(i + 1) * {n} + j] * (1 - fy) "
                f"+ coef_{c}[(i + 1) * {n} + j + 1] * fy) * fx;\n" for c in ("r", "z")))
    block += (
        f"{ind}for (a = 0, b = {k - 1}; a < {k}; b = a++) {{\n"
        f"{ind}    MAGTACT_REAL x1 = poly_r[a], y1 = poly_z[a];\n"
        f"{ind}    MAGTACT_REAL x2 = poly_r[b], y2 = poly_z[b];\n"
        f"{ind}    if (((y1 > bz) != (y2 > bz))\n"
        f"{ind}        && (br < (x2 - x1) * (bz - y1) / (y2 - y1) + x1))\n"
        f"{ind}        inside = !inside;\n{ind}}}\n"
        f"{ind}if (br > 0) {{\n{ind}    out[0] = fr * bx / br;\n"
        f"{ind}    out[1] = fr * by / br;\n{ind}}}\n"
        f"{ind}out[2] = fz;\n    }}\n")
    return block


def _unit_line(smap: SensorMap) -> str:
    u = smap.unit
    if u.nominal:
        return ""
    d = ", ".join(f"{mm(v):.4g}" for v in u.chip_offset)
    b = ", ".join(f"{from_si(v, 'mT'):.4g}" for v in u.field_offset)
    return (f" *   built unit: G x {u.G_scale:.5g}, remanence x {u.B_scale:.5g}, chip offset "
            f"({d}) mm, field offset ({b}) mT\n")


def _c_features(a: Approximation) -> tuple[str, str]:
    """The helper and the block of ``magtact_force`` of the two-stage candidate (see
    :func:`fit_features`)."""
    st = a.stage
    n = a.degree
    terms = basis_terms(n)
    lo_r, hi_r, lo_v, hi_v = a.limits
    lo_p, hi_p, lo_q, hi_q = (float(v) for v in st.limits_pq)
    b0 = [float(v) for v in st.field_offset]
    d = [float(v) for v in st.delta]
    t_m, tan_m = (float(v) for v in st.region)
    helper = (
        f"/* two sums of c[k] T_i(xi) T_j(eta) over the basis i + j <= {n} */\n"
        "static inline void magtact_force_cheb2(const MAGTACT_REAL *c1, const MAGTACT_REAL *c2,\n"
        "                                       MAGTACT_ACC xi, MAGTACT_ACC eta,\n"
        "                                       MAGTACT_ACC *s1, MAGTACT_ACC *s2)\n{\n"
        + _c_index("ti", [i for i, _ in terms]) + _c_index("tj", [j for _, j in terms]) +
        f"    MAGTACT_ACC tx[{n + 1}], ty[{n + 1}], a = 0, b = 0;\n    int k;\n"
        "    tx[0] = 1;\n    ty[0] = 1;\n    tx[1] = xi;\n    ty[1] = eta;\n"
        f"    for (k = 2; k <= {n}; k++) {{\n"
        "        tx[k] = 2 * xi * tx[k - 1] - tx[k - 2];\n"
        "        ty[k] = 2 * eta * ty[k - 1] - ty[k - 2];\n    }\n"
        f"    for (k = 0; k < {len(terms)}; k++) {{\n"
        "        MAGTACT_ACC t = tx[ti[k]] * ty[tj[k]];\n"
        "        a += c1[k] * t;\n        b += c2[k] * t;\n    }\n"
        "    *s1 = a;\n    *s2 = b;\n}\n\n")
    v = {"B_z": "cz", "1/B_z": "(MAGTACT_ACC)(1.0 / (double)cz)",
         "B_z^(-1/3)": "(MAGTACT_ACC)(1.0 / cbrt((double)cz))"}[a.transform]
    ind = "        "
    block = (
        "    {\n"
        + _c_array("coef_p", st.coef_p, ind) + _c_array("coef_q", st.coef_q, ind)
        + _c_array("coef_r", a.coef_r, ind) + _c_array("coef_z", a.coef_z, ind) +
        f"{ind}const MAGTACT_ACC s = {float(st.B_scale):.17g}, g = "
        f"{float(st.G_scale):.17g};\n"
        f"{ind}MAGTACT_ACC cx = ((MAGTACT_ACC)bx - ({b0[0]:.17g})) / s;\n"
        f"{ind}MAGTACT_ACC cy = ((MAGTACT_ACC)by - ({b0[1]:.17g})) / s;\n"
        f"{ind}MAGTACT_ACC cz = ((MAGTACT_ACC)bz - ({b0[2]:.17g})) / s;\n"
        f"{ind}MAGTACT_ACC br = (MAGTACT_ACC)sqrt((double)(cx * cx + cy * cy));\n"
        f"{ind}MAGTACT_ACC p, q1, qx, qy, q, fr, fz, v, ux = 1, uy = 0;\n"
        f"{ind}if (!(cz > 0))  /* the unit's field offset leaves no field from the magnet */\n"
        f"{ind}    return MAGTACT_FORCE_NO_FIELD;\n"
        f"{ind}v = {v};\n"
        f"{ind}magtact_force_cheb2(coef_p, coef_q,\n"
        f"{ind}                    2 * (br - ({lo_r:.17g})) / ({hi_r - lo_r:.17g}) - 1,\n"
        f"{ind}                    2 * (v - ({lo_v:.17g})) / ({hi_v - lo_v:.17g}) - 1, &p, &q1);\n"
        f"{ind}if (br > 0) {{\n{ind}    ux = cx / br;\n{ind}    uy = cy / br;\n{ind}}}\n"
        f"{ind}p -= ({d[0]:.17g});\n"
        f"{ind}qx = q1 * ux - ({d[1]:.17g});\n{ind}qy = q1 * uy - ({d[2]:.17g});\n"
        f"{ind}q = (MAGTACT_ACC)sqrt((double)(qx * qx + qy * qy));\n"
        f"{ind}magtact_force_cheb2(coef_r, coef_z,\n"
        f"{ind}                    2 * (p - ({lo_p:.17g})) / ({hi_p - lo_p:.17g}) - 1,\n"
        f"{ind}                    2 * (q - ({lo_q:.17g})) / ({hi_q - lo_q:.17g}) - 1, &fr, &fz);\n"
        f"{ind}if (q > 0) {{\n{ind}    out[0] = (MAGTACT_REAL)(g * fr * qx / q);\n"
        f"{ind}    out[1] = (MAGTACT_REAL)(g * fr * qy / q);\n{ind}}}\n"
        f"{ind}out[2] = (MAGTACT_REAL)(g * fz);\n"
        f"{ind}inside = p >= -{REGION_SLACK!r} && p <= {t_m:.17g} + {REGION_SLACK!r}\n"
        f"{ind}         && q <= (p > 0 ? p : 0) * {tan_m:.17g} + {REGION_SLACK!r};\n"
        "    }\n")
    return helper, block


#: The rows of ``force_table.csv`` of each map, by size (:func:`_table_rows`).
_ROWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _table_rows(smap: SensorMap, n: int = 64) -> tuple[tuple, ...]:
    """The rows of ``force_table.csv`` (:func:`write_table_csv`) as written: text cells, the
    last the ``inside`` flag (int). Kept with the map: the file and the measurement of its
    header's builds (:func:`table_readings`) read the same rows, the map inverted once."""
    by_size = _ROWS.setdefault(smap, {})
    if n not in by_size:
        by_size[n] = _grid_rows(smap, n)
    return by_size[n]


def _grid_rows(smap: SensorMap, n: int) -> tuple[tuple, ...]:
    """:func:`_table_rows` computed."""
    polygon = region_polygon(smap)
    R, Z = np.meshgrid(np.linspace(0.0, polygon[:, 0].max(), n),
                       np.linspace(polygon[:, 1].min(), polygon[:, 1].max(), n), indexing="ij")
    r = smap.force(np.stack([R, np.zeros_like(R), Z], axis=-1))
    rows = []
    for k in np.ndindex(R.shape):
        ok = r.flag[k] == OK
        # fields to 12 digits: at 6, the rounding of B alone moves the force by ~Γ × 1e-6 B,
        # tens of µN, more than a map's error at a small noise
        rows.append((f"{from_si(R[k], 'mT'):.12g}", f"{from_si(Z[k], 'mT'):.12g}",
                     f"{r.F[k][0]:.9g}" if ok else "", f"{r.F[k][2]:.9g}" if ok else "",
                     int(ok)))
    return tuple(rows)


def write_table_csv(smap: SensorMap, path: Path, n: int = 64) -> Path:
    """The exact map on an n × n grid of (b_r, b_z) over the region's bounding box: columns
    ``B_r_mT, B_z_mT, F_r_N, F_z_N, inside`` (forces empty outside the region)."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["B_r_mT", "B_z_mT", "F_r_N", "F_z_N", "inside"])
        w.writerows(_table_rows(smap, n))
    return path


#: How to evaluate an approximation of ``force_map.json``, in words.
EVALUATION = ("b_r = sqrt(bx^2 + by^2); poly: xi = 2 (b_r - limits[0]) / (limits[1] - limits[0]) "
              "- 1, eta likewise of transform(bz) with limits[2:4]; F_r = sum coef_r[k] T_i(xi) "
              "T_j(eta) over basis[k] = (i, j), F_z likewise; table: bilinear in (b_r, bz) on an "
              "n x n grid over limits, coef[i][j]; out = (F_r bx / b_r, F_r by / b_r, F_z); "
              "inside: crossing-number test of (b_r, bz) against polygon_T")


@dataclass(frozen=True)
class TargetSigma:
    """The target σ_F,r, σ_F,z [N] of ``force_map.json``."""

    r: float = entry("target_sigma_F_r_mN", "mN")
    z: float = entry("target_sigma_F_z_mN", "mN")


@dataclass(frozen=True)
class ForceMapFile:
    """``force_map.json``: the design, the chosen approximation and the frontier (for
    Python/MicroPython), in SI.

    Attributes
    ----------
    design : MapDesign
    approximation : ApproximationRecord
    target_sigma_F : (float, float)
        σ_F,r, σ_F,z [N] the approximation was held to.
    reached, rule
        Whether the chosen approximation reaches them, and how it was chosen.
    frontier : tuple of FrontierPoint
        Every candidate measured.
    evaluation, units : str
        How to evaluate the approximation, and its units, in words.
    H : float
        The design's body height [m].
    """

    design: MapDesign = entry(kind=MapDesign)
    approximation: ApproximationRecord = entry(kind=ApproximationRecord)
    target_sigma_F: tuple[float, float] = entry(kind=TargetSigma, inline=True, shape="tuple")
    reached: bool = entry(kind=bool)
    rule: str = entry(kind=str)
    frontier: tuple[FrontierPoint, ...] = entry(kind=FrontierPoint, levels=("list",))
    evaluation: str = entry(kind=str, default=EVALUATION)
    units: str = entry(kind=str, default="B in T, F in N")
    H: float = entry(unit="mm", default=np.nan)


def approximation_json(choice: FirmwareChoice, smap: SensorMap) -> dict:
    """The design, the chosen approximation and the frontier (JSON for Python/MicroPython:
    ``force_map.json``, :class:`ForceMapFile`)."""
    return to_json(ForceMapFile(smap.design_record(), choice.chosen.record(),
                                (choice.target_r, choice.target_z), choice.reached,
                                choice.rule, tuple(choice.frontier_points()), H=smap.H))


def load_approximation(data: dict) -> Approximation:
    """An approximation back from its JSON (the ``approximation`` entry).

    Raises
    ------
    RecordError
        If ``data`` is not an approximation's JSON (the message names the key).
    """
    r = from_json(ApproximationRecord, data, "force_map.json's approximation")
    return Approximation(r.kind, r.degree, r.transform, r.limits,
                         np.asarray(r.coef_r, float), np.asarray(r.coef_z, float),
                         np.asarray(r.polygon, float).reshape(-1, 2), r.err_r, r.err_z,
                         r.meta, None if not r.stage else FeatureStage(**r.stage))


def write_json(obj: dict, path: Path) -> Path:
    """Write the document ``obj`` to ``path`` atomically (indented by one, no NaN)."""
    return files.write_json(path, obj, indent=1, allow_nan=False)
