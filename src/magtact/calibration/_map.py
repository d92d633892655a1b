"""The sensor's field-to-force map of one design, and its forward map (docs/method.md §13).

Conventions. x, y span the base plane, z is up (docs/method.md §1). The sensor is axisymmetric,
so a press sheared along the azimuth φ is magtact's (r, z) problem turned by φ: the magnet moves
by u = (u_r cos φ, u_r sin φ, u_z) with u_r ≥ 0, u_z ≤ 0. The reading is
B = (B_r cos φ, B_r sin φ, B_z) with B_r ≥ 0 (the field of the sheared magnet points along the
shear at the Hall point, :func:`magtact.magnetics.hall_field`) and the force is
F = (F_r cos φ, F_r sin φ, F_z): the reaction of the base on the body (docs/method.md §3), so
F_r ≤ 0 against the shear and F_z > 0 in compression; the load applied on the top is −F.

The unknowns of the inversion are the features w = (p, q_x, q_y) = (t, t tan θ cos φ,
t tan θ sin φ), linear in the magnet's displacement (docs/method.md §5): B(w) and F(w) are smooth
there and their Jacobians are regular at t = 0, where (t, θ) are not.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from .._errors import MagtactError
from .._records import entry, to_json
from .._sensor import Sensor, SettingRecord
from ..doe import check_design
from ..geometry import hall_from_magnet_centre, loading_path
from ..metamodel import ModelSet
from ..optimise import per_design
from ..study import Study, mm
from ._fe import FEForces, fe_forces

#: Where the map's forces come from: the metamodels, or the DOE's FE paths at the design's H.
FORCE_SOURCES = ("models", "fe")
#: Flags of a reading (``Reading.flag``).
OK, OUTSIDE, NO_INVERSE, NOT_UNIQUE = 0, 1, 2, 3
FLAG_NAMES = {OK: "in the stable region", OUTSIDE: "outside the stable region",
              NO_INVERSE: "no inverse (Newton did not converge)",
              NOT_UNIQUE: "not unique (the map folds there)"}

#: Relative slack of the region test (the solution's (t, θ) against (t_m, θ_m)).
REGION_RTOL = 1e-7
#: Newton: iterations, finite-difference step in the features, relative residual tolerance.
MAX_ITER, FD_STEP, RTOL = 40, 1e-6, 1e-13
#: Nodes of the start table over the region: load levels × angles.
N_START = (61, 25)


@dataclass(frozen=True)
class UnitParameters:
    """What one built sensor differs by from its design (docs/method.md §13.3).

    Attributes
    ----------
    G_scale : float
        Stiffness of the body over the design's G: multiplies every force.
    B_scale : float
        Remanence of the magnet over the design's: multiplies the magnet's field.
    chip_offset : tuple of float
        (d_x, d_y, d_z) [m]: the Hall point's displacement from the body's axis and base.
    field_offset : tuple of float
        (b_x, b_y, b_z) [T]: a constant field added to every reading (chip offset, stray field).
    """

    G_scale: float = entry(default=1.0)
    B_scale: float = entry(default=1.0)
    chip_offset: tuple[float, float, float] = entry(unit="mm", levels=("list",),
                                                    default=(0.0, 0.0, 0.0))
    field_offset: tuple[float, float, float] = entry(unit="mT", levels=("list",),
                                                     default=(0.0, 0.0, 0.0))

    @property
    def nominal(self) -> bool:
        return (self.G_scale == 1.0 and self.B_scale == 1.0
                and not any(self.chip_offset) and not any(self.field_offset))

    def vector(self) -> np.ndarray:
        """(G_scale, B_scale, d_x, d_y, d_z, b_x, b_y, b_z) in SI."""
        return np.array([self.G_scale, self.B_scale, *self.chip_offset, *self.field_offset])

    @classmethod
    def from_vector(cls, v) -> UnitParameters:
        v = [float(x) for x in v]
        return cls(v[0], v[1], tuple(v[2:5]), tuple(v[5:8]))

    def to_json(self) -> dict:
        """User units, the unit in each key."""
        return to_json(self)


@dataclass(frozen=True)
class Reading:
    """Forces from field readings (:meth:`SensorMap.force`), all of the readings' shape.

    ``F`` (..., 3) [N] is NaN where ``flag`` is not OK: outside the stable region, without an
    inverse or where the inverse is not unique, the map gives no force (never an extrapolation).
    ``t``, ``theta`` [rad], ``phi`` [rad] are the solution of the inversion (NaN where Newton did
    not converge); ``F_model`` the models' force there, also outside the region (for diagnosis).
    """

    F: np.ndarray
    flag: np.ndarray
    t: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    F_model: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        return self.flag == OK


def _check_readings(B, name: str = "B") -> np.ndarray:
    B = np.asarray(B, dtype=float)
    if B.ndim == 0 or B.shape[-1] != 3:
        raise MagtactError(f"{name}: readings must have 3 components in the last axis "
                           f"(x, y, z), got shape {B.shape}")
    bad = ~np.isfinite(B)
    if bad.any():
        i = np.argwhere(bad)[0]
        raise MagtactError(f"{name}: reading {tuple(int(k) for k in i[:-1])} component "
                           f"{'xyz'[i[-1]]} is {B[tuple(i)]}: a reading must be a finite number")
    return B


@dataclass(frozen=True, eq=False)
class SensorMap:
    """F(B) and B(F) of one design over its stable region (docs/method.md §13).

    Build one with :func:`sensor_map`. ``field_source`` is ``"models"`` (the model set's B_r,
    B_z along the plane of shear) or ``"exact"`` (the closed-form field of the magnet at any
    point, :func:`magtact.magnetics.cylinder_field`; needed for a chip offset).
    ``force_source`` is ``"models"`` (the model set's f_r, f_z times G) or ``"fe"`` (``fe``:
    the DOE's FE forces at H, interpolated, :class:`FEForces`, docs/method.md §13.4).
    """

    models: ModelSet
    study: Study
    H: float
    G: float
    t_m: float
    theta_m: float
    field_scale: float = 1.0
    unit: UnitParameters = field(default_factory=UnitParameters)
    field_source: str = "models"
    force_source: str = "models"
    fe: FEForces | None = None
    #: The sensor this map is for: its magnet, the chip's setting and standoff, the silicone.
    sensor: Sensor | None = None

    def __str__(self) -> str:
        from .._display import sensor_map_rows, text_block

        return text_block(*sensor_map_rows(self))

    def _repr_html_(self) -> str:
        from .._display import html_block, sensor_map_rows

        return html_block(*sensor_map_rows(self))

    def __post_init__(self):
        if self.sensor is None:  # the study's own parts
            object.__setattr__(self, "sensor", Sensor.of_study(
                self.study, self.H, self.G, self.study.magnet.M_z * self.field_scale))
        if self.field_source not in ("models", "exact"):
            raise ValueError(f"field_source must be 'models' or 'exact', got "
                             f"{self.field_source!r}")
        if self.force_source not in FORCE_SOURCES or (self.force_source == "fe") != (
                self.fe is not None):
            raise ValueError(f"force_source must be 'models' (without fe) or 'fe' (with fe), "
                             f"got {self.force_source!r}")
        if any(self.unit.chip_offset) and self.field_source != "exact":
            raise ValueError("a chip offset needs field_source = 'exact'")

    # ---- the model in the features w = (p, q_x, q_y) ---------------------------------------
    @cached_property
    def _path(self) -> tuple[float, float]:
        """(a, z0): u_z = a p (a < 0) and the Hall point's height below the unloaded magnet
        centre, z = z0 − a p (docs/method.md §1)."""
        a = float(loading_path(self.study, 1.0, 0.0, self.H)[1])
        z0 = float(hall_from_magnet_centre(self.study, 0.0, 0.0, self.H,
                                           self.sensor.standoff)[1])
        return a, z0

    @property
    def magnet_M_z(self) -> float:
        """The magnetisation [A/m] whose exact field ``field_scale`` scales: the sensor's
        magnet over the scale (the study's magnet where the scale is a design's M_z)."""
        return self.sensor.M_z / self.field_scale

    def _pq(self, w):
        p, qx, qy = w[..., 0], w[..., 1], w[..., 2]
        q = np.hypot(qx, qy)
        with np.errstate(invalid="ignore", divide="ignore"):
            cx = np.where(q > 0, qx / np.where(q > 0, q, 1.0), 1.0)
            cy = np.where(q > 0, qy / np.where(q > 0, q, 1.0), 0.0)
        # the models take (t, θ) = (p, atan(q / p)); p is kept off 0 where q > 0
        ps = np.where(np.abs(p) < 1e-12, np.where(p < 0, -1e-12, 1e-12), p)
        return p, q, cx, cy, ps

    def _plane(self, model, p, q, ps):
        theta = np.arctan2(q, ps)
        t = np.where(q > 0, ps, p)
        with np.errstate(all="ignore"):
            return np.asarray(model.value(t, np.where(q > 0, theta, 0.0), self.H), dtype=float)

    def B_of(self, w) -> np.ndarray:
        """Reading (..., 3) [T] at features w (..., 3), with the unit's parameters."""
        w = np.asarray(w, dtype=float)
        u = self.unit
        scale = self.field_scale * u.B_scale
        p, q, cx, cy, ps = self._pq(w)
        if self.field_source == "models":
            br = self._plane(self.models.B_r, p, q, ps)
            bz = self._plane(self.models.B_z, p, q, ps)
            out = np.stack([br * cx, br * cy, bz], axis=-1) * scale
        else:
            from ..magnetics import cylinder_field

            a, z0 = self._path
            m = self.study.magnet
            d = u.chip_offset
            x, y, z = a * w[..., 1] + d[0], a * w[..., 2] + d[1], z0 - a * p + d[2]
            rho = np.hypot(x, y)
            b_rho, bz = cylinder_field(rho, z, m.R_m, m.H_m, self.magnet_M_z)
            with np.errstate(invalid="ignore", divide="ignore"):
                ex = np.where(rho > 0, x / np.where(rho > 0, rho, 1.0), 0.0)
                ey = np.where(rho > 0, y / np.where(rho > 0, rho, 1.0), 0.0)
            out = np.stack([b_rho * ex, b_rho * ey, bz], axis=-1) * scale
        return out + np.asarray(u.field_offset)

    def F_of(self, w) -> np.ndarray:
        """Force (..., 3) [N] at features w (..., 3), with the unit's G scale."""
        w = np.asarray(w, dtype=float)
        p, q, cx, cy, ps = self._pq(w)
        g = self.G * self.unit.G_scale
        if self.fe is not None:
            fr, fz = self.fe.forces(p, q, g)
            return np.stack([fr * cx, fr * cy, fz], axis=-1)
        fr = self._plane(self.models.f_r, p, q, ps) * g
        fz = self._plane(self.models.f_z, p, q, ps) * g
        return np.stack([fr * cx, fr * cy, fz], axis=-1)

    def features(self, t, theta, phi=0.0) -> np.ndarray:
        """w (..., 3) of the load (t, θ [rad], φ [rad]) (broadcast)."""
        t, theta, phi = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                              for v in (t, theta, phi)))
        q = t * np.tan(theta)
        return np.stack([t, q * np.cos(phi), q * np.sin(phi)], axis=-1)

    def at_load(self, t, theta, phi=0.0) -> tuple[np.ndarray, np.ndarray]:
        """(B (..., 3) [T], F (..., 3) [N]) of the load (t, θ, φ)."""
        w = self.features(t, theta, phi)
        return self.B_of(w), self.F_of(w)

    # ---- the region ------------------------------------------------------------------------
    def inside(self, w) -> np.ndarray:
        """Whether features w lie in the stable region 0 ≤ t ≤ t_m, 0 ≤ θ ≤ θ_m."""
        w = np.asarray(w, dtype=float)
        p, q = w[..., 0], np.hypot(w[..., 1], w[..., 2])
        slack = REGION_RTOL * max(self.t_m, 1e-3)
        return ((p >= -slack) & (p <= self.t_m * (1 + REGION_RTOL) + slack)
                & (q <= np.maximum(p, 0.0) * np.tan(self.theta_m) * (1 + REGION_RTOL) + slack))

    def region_samples(self, n: int, seed: int = 0) -> np.ndarray:
        """n loads (t, θ, φ) (n, 3) spread uniformly over the region's features (p, q) and φ."""
        rng = np.random.default_rng(seed)
        p = self.t_m * np.sqrt(rng.random(n))  # uniform over the triangle 0 ≤ q ≤ p tan θ_m
        s = rng.random(n)
        theta = np.arctan(s * np.tan(self.theta_m))
        return np.stack([p, theta, rng.uniform(-np.pi, np.pi, n)], axis=-1)

    @cached_property
    def ranges(self) -> tuple[float, float]:
        """(max |F_r|, max F_z) [N] over the region's start table: the force ranges."""
        F = self.F_of(self._grid)
        return float(np.abs(F[..., 0]).max()), float(np.abs(F[..., 2]).max())

    @cached_property
    def _grid(self) -> np.ndarray:
        n_p, n_s = N_START
        p = self.t_m * np.linspace(0.0, 1.0, n_p) ** 1.5
        s = np.linspace(0.0, 1.0, n_s)
        P, S = np.meshgrid(p, s, indexing="ij")
        return np.stack([P, P * S * np.tan(self.theta_m), np.zeros_like(P)], axis=-1)

    def _table(self, which: str):
        fun = self.B_of if which == "B" else self.F_of
        grid = self._grid.reshape(-1, 3)
        y = fun(grid)
        planar = np.stack([np.hypot(y[:, 0], y[:, 1]), y[:, 2]], axis=-1)
        scale = np.ptp(planar, axis=0) + 1e-300
        return cKDTree(planar / scale), scale, grid

    @cached_property
    def _start_B(self):
        return self._table("B")

    @cached_property
    def _start_F(self):
        return self._table("F")

    @cached_property
    def folds(self) -> dict[str, np.ndarray]:
        """Cells of the start table where det ∂B/∂(p, q) (``"B"``) or det ∂F/∂(p, q) (``"F"``)
        changes sign: there the inverse is not unique. Empty arrays: one-to-one everywhere."""
        out = {}
        for which, fun in (("B", self.B_of), ("F", self.F_of)):
            g = self._grid
            d = _planar_det(fun, g)
            ref = np.sign(np.median(d[1:, 1:]))
            bad = np.sign(d) != ref
            bad[0, :] = False  # t = 0: every θ is the same point
            out[which] = g[bad]
        return out

    # ---- inversion -------------------------------------------------------------------------
    def _invert(self, fun, target, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Features w with fun(w) = target (..., 3), and a converged mask."""
        tree, scale, grid = self._start_B if which == "B" else self._start_F
        y = target.reshape(-1, 3)
        sign = 1.0 if which == "B" else -1.0  # F_xy points against the shear
        if which == "B":
            shifted = y - np.asarray(self.unit.field_offset)
        else:
            shifted = y
        planar = np.stack([np.hypot(shifted[:, 0], shifted[:, 1]), shifted[:, 2]], axis=-1)
        _, k = tree.query(planar / scale)
        w = grid[k].copy()
        r_xy = np.hypot(shifted[:, 0], shifted[:, 1])
        cx = np.where(r_xy > 0, sign * shifted[:, 0] / np.where(r_xy > 0, r_xy, 1.0), 1.0)
        cy = np.where(r_xy > 0, sign * shifted[:, 1] / np.where(r_xy > 0, r_xy, 1.0), 0.0)
        q0 = w[:, 1]
        w[:, 1], w[:, 2] = q0 * cx, q0 * cy
        # readings in the plane of the map's mirror symmetry (b_y = 0 without a sideways chip
        # offset: a table's nodes) keep q_y = 0: Newton in (p, q_x) alone, the same steps
        planar = (not self.unit.chip_offset[1] and not shifted[:, 1].any()
                  and not w[:, 2].any())
        yg = np.max(np.abs(fun(grid)), axis=0)
        yscale = np.array([yg[0], yg[0], yg[2]]) + 1e-300
        tol = RTOL * yscale.max()
        res = fun(w) - y
        norm = np.max(np.abs(res) / yscale, axis=-1)
        done = np.max(np.abs(res), axis=-1) <= tol
        for _ in range(MAX_ITER):
            act = ~done
            if not act.any():
                break
            wa = w[act]
            step = _newton_step(fun, wa, res[act], planar)
            step = np.where(np.isfinite(step), step, 0.0)
            big = np.max(np.abs(step), axis=-1, keepdims=True)
            step *= np.minimum(1.0, 0.25 / np.maximum(big, 1e-300))  # at most 0.25 in t per step
            lam = np.ones(len(wa))
            new_w, new_res, new_norm = wa + step, None, None
            for _ in range(8):  # backtrack where the residual grows
                new_w = wa + lam[:, None] * step
                new_res = fun(new_w) - y[act]
                new_norm = np.max(np.abs(new_res) / yscale, axis=-1)
                worse = ~(new_norm <= norm[act]) & (lam > 1e-3)
                if not worse.any():
                    break
                lam = np.where(worse, lam / 2, lam)
            idx = np.flatnonzero(act)
            w[idx], res[idx], norm[idx] = new_w, new_res, new_norm
            done[idx] = (np.max(np.abs(new_res), axis=-1) <= tol) | (
                np.max(np.abs(lam[:, None] * step), axis=-1) <= 1e-15)
        ok = np.max(np.abs(res), axis=-1) <= 1e3 * tol
        return w.reshape(target.shape), ok.reshape(target.shape[:-1])

    def _flags(self, w, ok, which: str) -> np.ndarray:
        flag = np.where(ok, np.where(self.inside(w), OK, OUTSIDE), NO_INVERSE).astype(np.int8)
        folds = self.folds[which]
        if folds.size:
            near = _near_fold(w, folds, self.t_m)
            flag = np.where((flag == OK) & near, NOT_UNIQUE, flag).astype(np.int8)
        return flag

    def force(self, B) -> Reading:
        """The force of field readings B (..., 3) [T] (docs/method.md §13.1).

        Raises
        ------
        MagtactError
            For readings that are not finite or not 3-vectors.
        """
        B = _check_readings(B)
        if B.size == 0:
            e = np.zeros(B.shape[:-1])
            return Reading(np.zeros(B.shape), e.astype(np.int8), e, e, e, np.zeros(B.shape))
        w, ok = self._invert(self.B_of, B, "B")
        flag = self._flags(w, ok, "B")
        F_model = self.F_of(w)
        F = np.where((flag == OK)[..., None], F_model, np.nan)
        nan = np.where(ok, 0.0, np.nan)
        p, q = w[..., 0], np.hypot(w[..., 1], w[..., 2])
        return Reading(F, flag, p + nan, np.arctan2(q, p) + nan,
                       np.arctan2(w[..., 2], w[..., 1]) + nan, F_model)

    def field(self, F) -> tuple[np.ndarray, np.ndarray]:
        """The field readings (..., 3) [T] of forces F (..., 3) [N], and their flags: the
        forward map through the inverse of F(t, θ) (NaN where the flag is not OK)."""
        F = _check_readings(F, "F")
        if F.size == 0:
            return np.zeros(F.shape), np.zeros(F.shape[:-1], dtype=np.int8)
        w, ok = self._invert(self.F_of, F, "F")
        flag = self._flags(w, ok, "F")
        B = np.where((flag == OK)[..., None], self.B_of(w), np.nan)
        return B, flag

    def with_unit(self, unit: UnitParameters) -> SensorMap:
        """The map of a built unit that differs from the design by ``unit``."""
        source = "exact" if any(unit.chip_offset) else self.field_source
        return replace(self, unit=unit, field_source=source)

    def describe(self) -> dict:
        """The design, the region and the conventions, in user units (for files:
        :class:`MapDesign`)."""
        return to_json(self.design_record())

    def design_record(self) -> MapDesign:
        """The design, its parts, the region and the conventions (:class:`MapDesign`)."""
        F_r, F_z = self.ranges
        setting = self.sensor.setting
        return MapDesign(
            self.H, self.G, self.sensor.M_z, self.sensor.grade, self.sensor.silicone,
            self.sensor.standoff, self.sensor.chip,
            SettingRecord(*(getattr(self.study.hall, f.name) if setting is None
                            else int(getattr(setting, f.name)) for f in fields(SettingRecord))),
            self.t_m, self.theta_m, F_r, F_z, self.field_source, self.force_source, self.unit)


#: The conventions of a map's readings and forces, as its files state them.
CONVENTION = ("B = (B_r cos phi, B_r sin phi, B_z), F = (F_r cos phi, F_r sin phi, F_z); phi: "
              "the shear azimuth; F: the reaction of the base on the body (F_r <= 0 against "
              "the shear, F_z > 0 in compression); the load applied on the top is -F")


@dataclass(frozen=True)
class MapDesign:
    """The design of a map as its files give it (``design`` of ``calibration.json`` and
    ``force_map.json``), in SI.

    Attributes
    ----------
    H, G, M_z : float
        Body height [m], shear modulus [Pa], the magnet's magnetisation [A/m].
    magnet_grade, silicone, chip : str
        The parts the field depends on.
    standoff : float
        The chip's distance below the body [m].
    chip_setting : SettingRecord
        The chip's setting.
    t_m, theta_m : float
        The stable region [1, rad].
    F_r_range, F_z_range : float
        The force ranges [N].
    field_source, force_source : str
        Where the map's field and forces come from.
    unit : UnitParameters
        What the built unit differs by from its design.
    convention : str
        The conventions of readings and forces, in words.
    """

    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    M_z: float = entry(unit="A_per_m")
    magnet_grade: str = entry(kind=str)
    silicone: str = entry(kind=str)
    standoff: float = entry(unit="mm")
    chip: str = entry(kind=str)
    chip_setting: SettingRecord = entry(kind=SettingRecord)
    t_m: float = entry()
    theta_m: float = entry(unit="rad")
    F_r_range: float = entry(unit="N")
    F_z_range: float = entry(unit="N")
    field_source: str = entry(kind=str)
    force_source: str = entry(kind=str)
    unit: UnitParameters = entry(kind=UnitParameters)
    convention: str = entry(kind=str, default=CONVENTION)


def _jacobian(fun, w, columns: int = 3) -> np.ndarray:
    """∂fun/∂w (n, 3, columns) by central differences of step FD_STEP: the derivatives along
    the first ``columns`` features."""
    J = np.empty(w.shape[:-1] + (3, columns))
    for k in range(columns):
        e = np.zeros(3)
        e[k] = FD_STEP
        J[..., k] = (fun(w + e) - fun(w - e)) / (2 * FD_STEP)
    return J


def _newton_step(fun, w, res, planar: bool) -> np.ndarray:
    """The Newton step (n, 3) of features w (n, 3) whose residuals fun(w) − target are ``res``
    (n, 3). ``planar``: every w and target in the mirror plane q_y = 0, b_y = 0, where
    ∂(b_x, b_z)/∂q_y and ∂b_y/∂(p, q_x) vanish and b_y's residual is 0: the step in (p, q_x)
    from their 2 × 2 system (that of the full system, whose q_y step is 0)."""
    rows = [0, 2] if planar else [0, 1, 2]
    J = _jacobian(fun, w, len(rows))[:, rows]
    r = -res[:, rows, None]
    try:
        step = np.linalg.solve(J, r)[..., 0]
    except np.linalg.LinAlgError:  # a singular Jacobian somewhere in the batch
        step = (np.linalg.pinv(J) @ r)[..., 0]
    return np.concatenate([step, np.zeros((len(w), 3 - len(rows)))], axis=-1)


def _planar_det(fun, g) -> np.ndarray:
    """det ∂(y_r, y_z)/∂(p, q) on a grid g (..., 3) in the plane q_y = 0."""
    J = _jacobian(fun, g.reshape(-1, 3))
    det = J[:, 0, 0] * J[:, 2, 1] - J[:, 0, 1] * J[:, 2, 0]
    return det.reshape(g.shape[:-1])


def _near_fold(w, folds, t_m) -> np.ndarray:
    pq = np.stack([w[..., 0], np.hypot(w[..., 1], w[..., 2])], axis=-1)
    fpq = np.stack([folds[:, 0], np.hypot(folds[:, 1], folds[:, 2])], axis=-1)
    d, _ = cKDTree(fpq).query(pq.reshape(-1, 2))
    return (d <= 2 * t_m / (N_START[0] - 1)).reshape(w.shape[:-1])


def sensor_map(models: ModelSet, study: Study, H: float, G: float, M_z: float | None = None,
               field_source: str | None = None, design=None, force_source: str = "models",
               dataset=None, sensor: Sensor | None = None) -> SensorMap:
    """The field-to-force map of design (H [m], G [Pa][, M_z [A/m]]) over its stable region.

    The region is that of :func:`magtact.optimise.per_design`: t ≤ t_m, θ ≤ θ_m, every
    azimuth φ. ``design``: that function's result for this design, if already at hand.
    ``force_source``: ``"models"`` (the metamodels' forces) or ``"fe"`` (the FE forces of
    ``dataset``'s paths at H, interpolated, docs/method.md §13.4; the region is then also
    capped at the paths' largest t and θ). ``field_source``: ``"models"`` or ``"exact"``;
    default ``"exact"`` with the FE forces (the FE source is meant to carry no model error),
    else ``"models"``. ``sensor``: the design's parts (its magnet, the chip's setting and
    standoff, the silicone), default the study's own.

    Raises
    ------
    MagtactError
        If G or M_z is not positive, the stable region is degenerate (t_m = 0), the force
        source is unknown, or (FE source) ``dataset`` is missing, does not describe the study
        or holds no paths at H (the message names what is missing).
    """
    if force_source not in FORCE_SOURCES:
        raise MagtactError(f"force source {force_source!r} is unknown: choose "
                           f"{' or '.join(FORCE_SOURCES)}")
    check_design(study, H, dataset)  # outside the data's domain the models extrapolate
    fe = fe_forces(dataset, H, study) if force_source == "fe" else None
    if field_source is None:
        field_source = "exact" if fe is not None else "models"
    design = per_design(models, H, G, study, M_z) if design is None else design
    if not design.t_m > 0:
        raise MagtactError(f"design H = {mm(H):.4g} mm has no stable region (t_m = 0): no map")
    t_m, theta_m = float(design.t_m), float(design.theta_m)
    if fe is not None:  # no force beyond the FE paths
        t_m, theta_m = min(t_m, fe.t_max), min(theta_m, fe.theta_max)
    return SensorMap(models, study, float(H), float(G), t_m, theta_m,
                     float(design.field_scale), UnitParameters(), field_source, force_source, fe,
                     sensor)
