"""A built unit calibrated from a few presses (docs/method.md §13.3).

A unit differs from its design by a few physical parameters (:class:`UnitParameters`): the
stiffness of its body (G scale, multiplies every force), the remanence of its magnet (B scale,
multiplies the magnet's field), where its chip sits (chip offset d, moves the Hall point) and a
constant field offset b. Each press i is a measured pair (B_i, F_i) at an unknown load, the
features w_i = (p, q_x, q_y) of the magnet's displacement. The fit minimises

    Σ_i |B(w_i; θ) − B_i|² / σ_B² + |F(w_i; θ) − F_i|² / σ_F²

over the parameters θ and every w_i jointly (the field model is the exact field of the magnet at
the shifted Hall point, :func:`magtact.magnetics.cylinder_field`). The fit's own conditioning
says what the presses identify: the parameters' standard deviations are the square roots of the
diagonal of (JᵀJ)⁻¹ restricted to θ, J the Jacobian of the whitened residuals at the solution.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from .._errors import MagtactError
from .._numbers import parse_float
from .._records import entry, to_json
from ..study import from_si, mm, to_si
from ..validation import DataError, read_cell, read_row, read_table_lines
from ._map import SensorMap, UnitParameters, _check_readings

#: The names of the unit's scales (of stiffness and remanence): the fields of
#: :class:`UnitParameters` that hold them.
G_SCALE, B_SCALE = (f.name for f in fields(UnitParameters)[:2])
#: Parameter names in the order of :meth:`UnitParameters.vector`, with the unit they are shown in.
PARAMETERS = (G_SCALE, B_SCALE, "chip_offset_x", "chip_offset_y", "chip_offset_z",
              "field_offset_x", "field_offset_y", "field_offset_z")
SHOW = dict(zip(PARAMETERS, [("", 1.0)] * 2 + [("mm", 1e3)] * 3 + [("mT", 1e3)] * 3,
                strict=True))
#: The parameters fitted by default: the field offset is left out, because with a few presses
#: it trades off against the remanence and the chip's height (docs/method.md §13.3).
DEFAULT_FIT = PARAMETERS[:5]
#: The largest standard deviation a fitted parameter may have (SI): 1 % of a scale, 10 µm of
#: an offset of the chip, 50 µT of a field offset.
TOLERANCE = dict(zip(PARAMETERS, [1e-2] * 2 + [1e-5] * 3 + [5e-5] * 3, strict=True))
#: Default noise of one press (1 σ per axis; a press is the mean of repeated readings):
#: field [T], force [N]. Assumed figures, not a datasheet's: give the rig's own.
SIGMA_B, SIGMA_F = 5e-6, 2e-3
#: Parameter scales of the solver (SI per unit of its variables).
_SCALE = np.array([1.0, 1.0, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4])

#: Columns of a press file, with their units.
PRESS_COLUMNS = ("B_x_T", "B_y_T", "B_z_T", "F_x_N", "F_y_N", "F_z_N")
#: Largest RMS of the fit's whitened residuals (residual / noise) of presses a unit's model
#: explains: presses of a unit of this design leave about 1 (0.73 for FE presses of the
#: bundled data at H = 3 mm), readings of something else hundreds.
MAX_RMS_RESIDUAL = 10.0
#: Most presses of one unit (a calibration uses tens; the fit's memory grows with their number).
MAX_PRESSES = 10_000
#: Largest field component of a press [T]: above the remanence of any permanent magnet (the
#: strongest sintered NdFeB grades stay below 1.5 T), so a larger value is a unit mistake.
MAX_FIELD = 2.0
#: Largest force component of a press [N]: a soft tactile body of centimetres carries far less
#: (1 kN on 1 cm² is 10 MPa, beyond any silicone), so a larger value is a unit mistake.
MAX_FORCE = 1000.0
#: Range of a press's noise figures [SI]: σ_B 1 nT to 10 mT, σ_F 1 µN to 100 N.
SIGMA_BOUNDS = {"sigma_B": (1e-9, 1e-2), "sigma_F": (1e-6, 100.0)}
#: Physical range of a built unit's scales: the stiffness of a cast silicone body within a
#: factor 5 of its design's (batches, mixing ratio, cure), the remanence of its magnet within
#: ±50 % (sintered NdFeB grades span B_r 1.17–1.48 T; a bonded or heated magnet less). A fit
#: outside is no unit of this design: wrong units, sign or design.
SCALE_RANGE = {G_SCALE: (0.2, 5.0), B_SCALE: (0.5, 1.5)}


@dataclass(frozen=True)
class Presses:
    """Measured (B, F) pairs of one unit: ``B`` (n, 3) [T], ``F`` (n, 3) [N]; ``source``: the
    file; ``sigma_B``, ``sigma_F``: the noise of one press (1 σ per axis)."""

    B: np.ndarray
    F: np.ndarray
    source: str = ""
    sigma_B: float = SIGMA_B
    sigma_F: float = SIGMA_F

    def __post_init__(self):
        B = _check_readings(self.B, "presses B")
        F = _check_readings(self.F, "presses F")
        if B.ndim != 2 or B.shape != F.shape:
            raise MagtactError(f"presses: B and F must both be (n, 3), got {B.shape} and "
                               f"{F.shape}")
        if len(B) > MAX_PRESSES:
            raise MagtactError(f"presses: {len(B):,} presses; at most {MAX_PRESSES:,} (a unit "
                               "is calibrated from tens)")
        for values, top, what in ((B, MAX_FIELD, "B"), (F, MAX_FORCE, "F")):
            big = np.abs(values) > top
            if big.any():
                i, a = (int(v) for v in np.argwhere(big)[0])
                raise MagtactError(f"presses {what}: press {i} component {'xyz'[a]} is "
                                   f"{values[i, a]:.6g} {'T' if what == 'B' else 'N'}; a "
                                   f"press's {what} is within ±{top:g} "
                                   f"{'T' if what == 'B' else 'N'}")
        for name in ("sigma_B", "sigma_F"):
            lo, hi = SIGMA_BOUNDS[name]
            v = getattr(self, name)
            if not (isinstance(v, int | float | np.floating) and lo <= v <= hi):
                raise MagtactError(f"presses: the noise {name} must be between {lo:g} and "
                                   f"{hi:g} {'T' if name == 'sigma_B' else 'N'}, got {v!r}")

    def __len__(self) -> int:
        return len(self.B)


def read_presses(path) -> Presses:
    """Presses from a CSV file: ``#`` metadata lines (``key = value``; ``sigma_B_uT``,
    ``sigma_F_mN`` set the noise), a header with the columns ``B_x_T, B_y_T, B_z_T, F_x_N,
    F_y_N, F_z_N`` (any order, others ignored), one row per press. The conventions of
    :func:`magtact.validation.read_experiment`.

    Raises
    ------
    DataError
        Naming the file, line and column of a missing column, an empty or non-numeric cell,
        a NaN, a ragged row or an empty file.
    """
    path = Path(path)
    lines, meta, meta_line, i = read_table_lines(path, "press file",
                                                 "give one CSV file of presses")
    header_no = i + 1
    header = [h.strip() for h in read_row(path, lines[i], header_no)]
    for c in PRESS_COLUMNS:
        if c not in header:
            raise DataError(f"{path}: line {header_no}: missing column {c!r} (the header has "
                            f"{', '.join(header)})")
        if header.count(c) > 1:
            raise DataError(f"{path}: line {header_no}, column {c!r}: column name appears "
                            "twice")
    where = [header.index(c) for c in PRESS_COLUMNS]
    rows = []
    for j in range(i + 1, len(lines)):
        if not lines[j].strip() or lines[j].lstrip().startswith("#"):
            continue
        if len(rows) == MAX_PRESSES:
            raise DataError(f"{path}: line {j + 1}: more than {MAX_PRESSES:,} presses (a unit "
                            "is calibrated from tens)")
        cells = [c.strip() for c in read_row(path, lines[j], j + 1)]
        if len(cells) != len(header):
            raise DataError(f"{path}: line {j + 1}: {len(cells)} cells, the header on line "
                            f"{header_no} has {len(header)} columns")
        row = []
        for c, k in zip(PRESS_COLUMNS, where, strict=True):
            v = read_cell(path, j + 1, c, cells[k])
            top = MAX_FIELD if c.startswith("B") else MAX_FORCE
            if abs(v) > top:
                raise DataError(f"{path}: line {j + 1}, column {c!r}: {cells[k]} is outside "
                                f"±{top:g} {c[-1]}{_unit_hint(c, v)}")
            row.append(v)
        rows.append(row)
    if not rows:
        raise DataError(f"{path}: line {header_no}: header but no presses")
    data = np.asarray(rows)

    def noise(key, unit, default, name):
        if key not in meta:
            return default
        where = f"{path}: line {meta_line[key]}: {key} = {meta[key]!r}"
        try:
            v = to_si(parse_float(meta[key]), unit)
        except ValueError:
            raise DataError(f"{where} is not a number") from None
        lo, hi = SIGMA_BOUNDS[name]
        if not (math.isfinite(v) and lo <= v <= hi):
            raise DataError(f"{where} must be between {from_si(lo, unit):g} and "
                            f"{from_si(hi, unit):g}")
        return v

    return Presses(data[:, :3], data[:, 3:], str(path),
                   noise("sigma_b_ut", "uT", SIGMA_B, "sigma_B"),
                   noise("sigma_f_mn", "mN", SIGMA_F, "sigma_F"))


def _unit_hint(column: str, value: float) -> str:
    """"; did you give mT?" where the value would be a plausible press in a smaller unit."""
    for unit, factor in (("mT", 1e-3), ("µT", 1e-6)) if column.startswith("B") else (
            ("mN", 1e-3),):
        if abs(value) * factor <= (MAX_FIELD if column.startswith("B") else MAX_FORCE):
            return f"; did you give {unit}? The column is in {column[-1]}"
    return ""


def write_presses(presses: Presses, path) -> Path:
    """Presses as the CSV that :func:`read_presses` reads."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        fh.write(f"# sigma_B_uT = {from_si(presses.sigma_B, 'uT'):.6g}\n"
                 f"# sigma_F_mN = {from_si(presses.sigma_F, 'mN'):.6g}\n")
        w = csv.writer(fh)
        w.writerow(PRESS_COLUMNS)
        for b, f in zip(presses.B, presses.F, strict=True):
            w.writerow([f"{v:.12g}" for v in (*b, *f)])
    return path


@dataclass(frozen=True)
class UnitCalibration:
    """The fitted unit: ``unit`` (the parameters), ``std`` (their standard deviations from the
    fit's conditioning, SI, by name), ``corrected`` (the unit's map), the residuals [T], [N]
    of the presses at the solution, and the presses' loads (t, θ, φ) (n, 3)."""

    unit: UnitParameters
    std: dict[str, float]
    corrected: SensorMap
    residual_B: np.ndarray
    residual_F: np.ndarray
    loads: np.ndarray
    presses: Presses

    def to_json(self) -> dict:
        """The fit in user units (``unit.json``, ``calibration.json``'s ``unit``:
        :class:`UnitRecord`)."""
        return to_json(self.record())

    def record(self) -> UnitRecord:
        """The fit as its files give it (:class:`UnitRecord`)."""
        return UnitRecord(
            len(self.presses), self.unit,
            {k: v * SHOW[k][1] for k, v in self.std.items()}, {k: SHOW[k][0] for k in self.std},
            float(np.sqrt(np.mean(self.residual_B**2))),
            float(np.sqrt(np.mean(self.residual_F**2))), self.presses.sigma_B,
            self.presses.sigma_F, self.presses.source)


@dataclass(frozen=True)
class UnitRecord:
    """A built unit's fit as ``unit.json`` (and ``calibration.json``'s ``unit``) gives it.

    Attributes
    ----------
    n_presses : int
    parameters : UnitParameters
        The fitted parameters, in SI.
    std : dict of str to float
        The standard deviation of each fitted parameter in the unit ``std_units`` names (the
        units of :data:`SHOW`: a parameter's unit is named in the file, not in its key).
    std_units : dict of str to str
    rms_residual_B, rms_residual_F : float
        RMS residual of the presses' field [T] and force [N] at the solution.
    sigma_B, sigma_F : float
        The noise of one press [T], [N].
    source : str
        The press file.
    """

    n_presses: int = entry(kind=int)
    parameters: UnitParameters = entry(kind=UnitParameters)
    std: dict[str, float] = entry(levels=("map",))
    std_units: dict[str, str] = entry(kind=str, levels=("map",))
    rms_residual_B: float = entry(unit="uT")
    rms_residual_F: float = entry(unit="mN")
    sigma_B: float = entry(unit="uT")
    sigma_F: float = entry(unit="mN")
    source: str = entry(kind=str)

    def to_json(self) -> dict:
        """The fit in user units."""
        return to_json(self)


def _model(smap: SensorMap, theta, w):
    """(B, F) of parameter vectors theta (..., 8) at features w (..., n, 3): the exact field at
    the shifted Hall point (as :meth:`SensorMap.B_of` with ``field_source = "exact"``), batched
    over parameter sets."""
    from ..magnetics import cylinder_field

    theta = np.asarray(theta, dtype=float)
    w = np.asarray(w, dtype=float)
    th = theta[..., None, :]
    a, z0 = smap._path
    mag = smap.study.magnet
    x = a * w[..., 1] + th[..., 2]
    y = a * w[..., 2] + th[..., 3]
    z = z0 - a * w[..., 0] + th[..., 4]
    rho = np.hypot(x, y)
    b_rho, b_z = cylinder_field(rho, z, mag.R_m, mag.H_m, smap.magnet_M_z)
    with np.errstate(invalid="ignore", divide="ignore"):
        ex = np.where(rho > 0, x / np.where(rho > 0, rho, 1.0), 0.0)
        ey = np.where(rho > 0, y / np.where(rho > 0, rho, 1.0), 0.0)
    scale = smap.field_scale * th[..., 1]
    B = np.stack([b_rho * ex * scale + th[..., 5], b_rho * ey * scale + th[..., 6],
                  b_z * scale + th[..., 7]], axis=-1)
    F = smap.F_of(w) * th[..., 0][..., None]
    return B, F


class _Problem:
    """The whitened residuals of the joint fit, and their Jacobian by central differences with
    every column in one batched evaluation."""

    def __init__(self, smap, presses, free, theta0, model_error=None):
        self.smap, self.presses, self.free, self.theta0 = smap, presses, free, theta0
        self.n, self.k = len(presses), int(free.sum())
        # the force's weight per press and axis: its noise and the force model's own error
        eps = (0.0, 0.0) if model_error is None else model_error
        F = np.asarray(presses.F, dtype=float)
        rel = np.stack([eps[0] * np.hypot(F[:, 0], F[:, 1])] * 2 + [eps[1] * np.abs(F[:, 2])],
                       axis=-1)
        self.sigma_F = np.sqrt(presses.sigma_F**2 + rel**2)

    def unpack(self, x):
        x = np.asarray(x, dtype=float)
        theta = np.broadcast_to(self.theta0, x.shape[:-1] + (8,)).copy()
        theta[..., self.free] = x[..., :self.k] * _SCALE[self.free]
        return theta, x[..., self.k:].reshape(x.shape[:-1] + (self.n, 3))

    def __call__(self, x):
        x = np.asarray(x, dtype=float)
        theta, w = self.unpack(x)
        B, F = _model(self.smap, theta, w)
        p = self.presses
        lead = x.shape[:-1]
        return np.concatenate([((B - p.B) / p.sigma_B).reshape(lead + (-1,)),
                               ((F - p.F) / self.sigma_F).reshape(lead + (-1,))], axis=-1)

    def blocks(self, x) -> tuple[np.ndarray, np.ndarray]:
        """The Jacobian of the residuals by central differences, in its two blocks: J_θ
        (6n, k) of the parameters, and J_w (n, 6, 3) of each press's residuals (B then F) with
        respect to its own features (a press's residuals depend on no other press's features).
        2k + 6 batched evaluations; memory linear in the number of presses."""
        x = np.asarray(x, dtype=float)
        n, k = self.n, self.k
        h = 1e-6 * np.maximum(1.0, np.abs(x))
        steps = np.zeros((2 * k + 6, x.size))
        for j in range(k):
            steps[j, j], steps[k + j, j] = h[j], -h[j]
        hw = h[k:].reshape(n, 3)
        for d in range(3):
            col = k + 3 * np.arange(n) + d
            steps[2 * k + d, col], steps[2 * k + 3 + d, col] = hw[:, d], -hw[:, d]
        r = self(x + steps)
        J_theta = ((r[:k] - r[k:2 * k]) / (2 * h[:k, None])).T
        dw = (r[2 * k:2 * k + 3] - r[2 * k + 3:]).reshape(3, 2, n, 3)  # d, (B|F), press, axis
        J_w = (dw / (2 * hw.T[:, None, :, None])).transpose(2, 1, 3, 0).reshape(n, 6, 3)
        return J_theta, J_w

    def sparse(self, J_theta: np.ndarray, J_w: np.ndarray):
        """The blocks as one sparse Jacobian (6n, k + 3n), rows and columns as the residuals
        and the solver's variables."""
        from scipy.sparse import coo_matrix, csr_matrix, hstack

        n = self.n
        press = np.repeat(np.arange(n), 18)
        half = np.tile(np.repeat(np.arange(2), 9), n)
        axis = np.tile(np.repeat(np.arange(3), 3), 2 * n)
        d = np.tile(np.arange(3), 6 * n)
        rows = half * 3 * n + 3 * press + axis
        cols = 3 * press + d
        W = coo_matrix((J_w.reshape(-1), (rows, cols)), shape=(6 * n, 3 * n))
        return hstack([csr_matrix(J_theta), W], format="csr")

    def jac(self, x):
        return self.sparse(*self.blocks(x))


def _std(J_theta: np.ndarray, J_w: np.ndarray) -> np.ndarray:
    """Standard deviations of the k parameters from the whitened Jacobian's blocks: the
    square roots of the diagonal of (JᵀJ)⁻¹ restricted to them, by the Schur complement over
    the presses' features (each press's 3 × 3 block inverted on its own; directions of a
    press's features that move no residual are left out by the pseudo-inverse); infinite along
    directions the presses do not see. Memory linear in the number of presses."""
    n, k = len(J_w), J_theta.shape[1]
    Jt = J_theta.reshape(2, n, 3, k).transpose(1, 0, 2, 3).reshape(n, 6, k)
    A = J_theta.T @ J_theta
    Bm = np.einsum("nrk,nrd->nkd", Jt, J_w)  # (n, k, 3)
    D = np.einsum("nrd,nre->nde", J_w, J_w)  # (n, 3, 3)
    s, U = np.linalg.eigh(D)
    keep = s > 1e-12 * np.maximum(s.max(axis=-1, keepdims=True), 1e-300)
    inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    D_pinv = np.einsum("nde,ne,nfe->ndf", U, inv, U)
    S = A - np.einsum("nkd,nde,nje->kj", Bm, D_pinv, Bm)
    S = 0.5 * (S + S.T)
    s, U = np.linalg.eigh(S)
    null = s <= 1e-12 * max(s.max(), 1e-300)
    inv = np.where(null, 0.0, 1.0 / np.where(null, 1.0, s))
    d = (U ** 2) @ inv
    if null.any():
        d = d + np.where((np.abs(U[:, null]) > 1e-6).any(axis=1), np.inf, 0.0)
    return np.sqrt(np.maximum(d, 0.0))


def _candidate_kinds(smap: SensorMap) -> dict[str, np.ndarray]:
    """The kinds of press the advice may ask for, as loads (t, θ, φ) at 3/4 of the region."""
    t, th = 0.75 * smap.t_m, smap.theta_m
    return {"normal presses (no shear) at other depths": np.array([[t, 0.0, 0.0],
                                                                    [t / 3, 0.0, 0.0]]),
            "presses sheared along x": np.array([[t, th, 0.0], [t / 3, th, np.pi]]),
            "presses sheared along y": np.array([[t, th, np.pi / 2], [t / 3, th, -np.pi / 2]])}


def _advice(smap, presses, theta, free, w, bad, model_error=None) -> dict[str, str]:
    """For each of the ``bad`` parameters, the kind of press whose addition lowers its deviation
    most (from the same conditioning, with the added presses' Jacobian at the fitted unit)."""
    names = [p for p, f in zip(PARAMETERS, free, strict=True) if f]
    std = {}
    for label, load in _candidate_kinds(smap).items():
        wk = smap.features(load[:, 0], load[:, 1], load[:, 2])
        Bk, Fk = _model(smap, theta, wk)
        extra = Presses(np.concatenate([presses.B, Bk]), np.concatenate([presses.F, Fk]),
                        sigma_B=presses.sigma_B, sigma_F=presses.sigma_F)
        x = np.concatenate([theta[free] / _SCALE[free], np.concatenate([w, wk]).ravel()])
        prob = _Problem(smap, extra, free, theta, model_error)
        std[label] = _std(*prob.blocks(x)) * _SCALE[free]
    return {b: min(std, key=lambda lab, b=b: std[lab][names.index(b)]) for b in bad}


def calibrate_unit(smap: SensorMap, presses: Presses, fit=DEFAULT_FIT,
                   tolerance: dict | None = None,
                   model_error: tuple[float, float] | None = None) -> UnitCalibration:
    """Fit a built unit's parameters to its presses (docs/method.md §13.3).

    Parameters
    ----------
    smap : SensorMap
        The design's map (:func:`sensor_map`); the unit's map uses the exact field.
    presses : Presses
        At least 2 presses (6 readings each, 3 unknown load features each).
    fit : sequence of str
        The parameters to fit (names of :data:`PARAMETERS`; default :data:`DEFAULT_FIT`); the
        others stay nominal.
    tolerance : dict, optional
        The largest standard deviation of each parameter [SI] (default :data:`TOLERANCE`).
    model_error : (float, float), optional
        Relative error (ε_xy, ε_z) of the force models: each press's force noise becomes
        sqrt(σ_F² + (ε |F|)²) per axis, so that the fit and its conditioning count the models'
        own error (e.g. the max relative error of their fit report). Default: none.

    Raises
    ------
    MagtactError
        For too few presses, an unknown parameter name, presses the model does not explain
        (whitened residuals above :data:`MAX_RMS_RESIDUAL` in RMS), or presses that do not
        identify a parameter: the message names it, its deviation from the fit's
        conditioning, and the kind of press that would identify it best.
    """
    unknown = [f for f in fit if f not in PARAMETERS]
    if unknown:
        raise MagtactError(f"unknown unit parameters {unknown}; choose among {PARAMETERS}")
    tol = {**TOLERANCE, **(tolerance or {})}
    free = np.array([p in fit for p in PARAMETERS])
    n, k = len(presses), int(free.sum())
    if 3 * n < k or n < 2:
        raise MagtactError(f"{n} presses cannot identify {k} parameters: each press adds 3 "
                           f"unknown load features and 6 readings, so at least "
                           f"{max(2, -(-k // 3))} presses are needed")
    exact = replace(smap, field_source="exact", unit=UnitParameters())
    start = exact.force(presses.B)
    w0 = exact.features(np.nan_to_num(start.t), np.nan_to_num(start.theta),
                        np.nan_to_num(start.phi))
    theta0 = UnitParameters().vector()
    if model_error is not None and not all(e >= 0 for e in model_error):
        raise MagtactError(f"model_error must be two relative errors >= 0, got {model_error}")
    prob = _Problem(exact, presses, free, theta0, model_error)
    x0 = np.concatenate([theta0[free] / _SCALE[free], w0.ravel()])
    # trust-region reflective with a sparse Jacobian: the features couple to their own press
    # only, so the fit's memory grows with the number of presses, not with its square
    sol = least_squares(prob, x0, jac=prob.jac, method="trf", x_scale="jac", xtol=1e-12,
                        ftol=1e-12, gtol=1e-12, max_nfev=200, tr_solver="lsmr")
    theta, w = prob.unpack(sol.x)
    fit_rms = float(np.sqrt(np.mean(sol.fun ** 2)))
    # residuals first: a fit that explains nothing has no meaningful scale to check
    if not fit_rms <= MAX_RMS_RESIDUAL:
        B, F = _model(exact, theta, w)
        rb = from_si(float(np.sqrt(np.mean((B - presses.B) ** 2))), "uT")
        rf = from_si(float(np.sqrt(np.mean((F - presses.F) ** 2))), "mN")
        raise MagtactError(
            f"these {n} presses do not fit a unit of this design: the best fit leaves "
            f"residuals of {fit_rms:.3g} times their noise (RMS {rb:.3g} µT against sigma_B "
            f"{from_si(presses.sigma_B, 'uT'):.3g} µT, {rf:.3g} mN against sigma_F "
            f"{from_si(presses.sigma_F, 'mN'):.3g} mN; at most {MAX_RMS_RESIDUAL:g} times). "
            "Check the columns' units (T, N), their sign, the design (H, G) and the noise "
            "metadata")
    _check_scales(theta, free, n)
    s = _std(*prob.blocks(sol.x)) * _SCALE[free]
    names = [p for p, f in zip(PARAMETERS, free, strict=True) if f]
    std = dict(zip(names, s.tolist(), strict=True))
    bad = [p for p in names if not std[p] <= tol[p]]
    if bad:
        kinds = _advice(exact, presses, theta, free, w, bad, model_error)

        def show(p, v):
            unit, f = SHOW[p]
            return f"{v * f:.3g}" + (f" {unit}" if unit else "")

        what = ", ".join(f"{p} (±{show(p, std[p])} from the fit's conditioning, tolerance "
                         f"{show(p, tol[p])})" for p in bad)
        add = {}
        for p in bad:
            add.setdefault(kinds[p], []).append(p)
        advice = "; ".join(f"{k} (for {', '.join(v)})" for k, v in add.items())
        raise MagtactError(f"these {n} presses do not identify {what}. Add {advice}, or leave "
                           "the parameter out of the fit")
    unit = UnitParameters.from_vector(theta)
    corrected = exact.with_unit(unit)
    B, F = _model(exact, theta, w)
    p, q = w[:, 0], np.hypot(w[:, 1], w[:, 2])
    loads = np.stack([p, np.arctan2(q, p), np.arctan2(w[:, 2], w[:, 1])], axis=-1)
    return UnitCalibration(unit, std, corrected, B - presses.B, F - presses.F, loads, presses)


def _check_scales(theta: np.ndarray, free: np.ndarray, n: int) -> None:
    """Refuse a fit whose stiffness or remanence scale is negative (the presses' sign
    convention is not the map's) or outside :data:`SCALE_RANGE`."""
    g, b = float(theta[0]), float(theta[1])
    if (free[0] and not g > 0) or (free[1] and not b > 0):
        which = " and ".join(f"{name} {v:.3g}" for name, v, f in
                             ((G_SCALE, g, free[0]), (B_SCALE, b, free[1])) if f and not v > 0)
        raise MagtactError(
            f"these {n} presses fit only a unit with a negative scale ({which}): forces look "
            "like the load's sign: F_z must be positive in compression (the reaction of the "
            "base on the body, as force.h returns it; negate F_x, F_y, F_z of a load cell "
            "that reads the load applied on the top), and B_z positive with the magnet above "
            "the chip")
    for name, v, f in ((G_SCALE, g, free[0]), (B_SCALE, b, free[1])):
        lo, hi = SCALE_RANGE[name]
        if f and not lo <= v <= hi:
            what = "stiffness of the body" if name == G_SCALE else "remanence of the magnet"
            raise MagtactError(
                f"these {n} presses fit {name} = {v:.3g}, outside the physical range {lo:g} to "
                f"{hi:g} of a unit of this design (the {what} over the design's): check the "
                "columns' units (T, N), their sign and the design (H, G)")


def fe_readings(dataset, smap: SensorMap, unit: UnitParameters, azimuth=None, seed: int = 0
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Readings of a synthetic unit made from the finite-element paths of a DOE data set at the
    map's height (docs/method.md §13.3): the force of every FE point (scaled from its G level
    to the unit's G_scale · G), the exact field of the unit's magnet (B_scale) at the FE
    displacement, read at the unit's shifted Hall point, plus its field offset; each point
    turned to an azimuth (given, or uniform at random).

    Returns
    -------
    B, F : numpy.ndarray
        (n, 3) [T], [N], n = the number of (t, θ) points of the path grid.
    loads : numpy.ndarray
        (n, 3): t, θ [rad], φ [rad].

    Raises
    ------
    MagtactError
        If the data set has no height level at the map's H.
    """
    H = dataset["H"].values
    j = np.flatnonzero(np.isclose(H, smap.H, rtol=0, atol=1e-9))
    if not j.size:
        raise MagtactError(f"the data set has no height level at H = {mm(smap.H):.4g} mm "
                           f"(levels {', '.join(f'{mm(h):.4g}' for h in H)} mm)")
    d = dataset.isel(H=int(j[0]))
    G_level = float(d["G"].values[0])
    T, TH = np.meshgrid(d["t"].values, d["theta"].values, indexing="ij")
    F_r = d["F_r"].values[..., 0] / G_level * smap.G * unit.G_scale
    F_z = d["F_z"].values[..., 0] / G_level * smap.G * unit.G_scale
    u_r, u_z = d["u_r"].values, d["u_z"].values
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-np.pi, np.pi, T.shape) if azimuth is None else np.broadcast_to(
        np.asarray(azimuth, float), T.shape)
    a, _ = smap._path
    # the features of the FE displacement (u_z = a p, u_r = -a q), so that the field is the
    # unit model's exact field at the FE displacement
    w = np.stack([u_z / a, -u_r / a * np.cos(phi), -u_r / a * np.sin(phi)], axis=-1)
    B, _ = _model(replace(smap, field_source="exact"), unit.vector(), w.reshape(1, -1, 3))
    F = np.stack([F_r * np.cos(phi), F_r * np.sin(phi), F_z], axis=-1)
    loads = np.stack([T, TH, phi], axis=-1)
    return B.reshape(-1, 3), F.reshape(-1, 3), loads.reshape(-1, 3)
