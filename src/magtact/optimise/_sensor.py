"""The whole sensor as the design: H, G, the magnet's grade, the chip's standoff and its setting
(docs/method.md §10).

The problem: minimise the force noise σ_F,r and σ_F,z (1 σ, worst over the loads the sensor
must read) subject to the force constraints (the body carries the required forces stably), to
the shear where it occurs (the loads within the required normal force include the required
shear, as the verdict reads it; where no sensor's do, the problem is solved without it and the
verdict says no) and to the chip's range (it reads every required load without leaving the
range of its setting). The setting must reach the required sample rate. The grade and the
standoff change the field only (exactly: B ∝ M_z, and the chip's position), not the mechanics;
the setting changes the range and the noise; the silicone bounds G to the range of its cited
figures (``[design] silicones``; none named: G free over the design range).

Two solvers answer it, and each checks the other:

- the **exact reduction** enumerates every grade, standoff level, setting and silicone on a
  grid of heights, and is exact in G (within the silicone's G range): over the required
  loads σ_F = (G / M_z) W(F_z,req / G), with W the largest per-unit noise among the grid
  points whose normal force per unit G is at most F_z,req / G. W steps down only where G
  passes a point's F_z,req / f_z, so the least σ_F over G lies at the smallest feasible G,
  just above one of these breakpoints, or where the shear among the loads, G R (R the largest
  |f_r| per unit G among the same points), reaches the required shear;
- **NSGA-II** over the mixed variables (H real; the standoff level, the grade, the chip
  option and the silicone integers, the first three in the order of their effect: standoff,
  magnetisation, range), with
  pymoo's mixed-variable operators, minimising (σ_F,r, σ_F,z); each design it proposes takes
  its least-noise feasible G (the reduction's exact step in G), so that the two solvers differ
  in how they search the heights and the discrete choices.

The decision takes the least √(σ_F,r² + σ_F,z²) of each, and the lower of the two is the answer;
where NSGA-II's lies more than ``WARN_GAP`` above the reduction's, a warning says so. The standoff
takes levels ``STANDOFF_STEP`` apart (boards and spacers come in steps).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .._files import write_json
from .._records import entry, to_json
from ..chip import ChipOption, SensorGrid, chip_options, sensor_grid
from ..metamodel import ModelSet
from ..parts import grade as catalogue_grade
from ..study import MU0, Study, from_si
from ._design import HeightTable
from ._pareto import ForceConstraints, InfeasibleError, feasible_G, force_constraints, sweep

#: Step between the standoff levels [m].
STANDOFF_STEP = 0.1e-3
#: Heights of the exact reduction's grid.
N_H = 41
#: Relative step above a breakpoint of G at which σ_F is evaluated.
G_STEP = 1e-9
#: Largest relative gap between NSGA-II's and the reduction's least σ_F that counts as agreement.
WARN_GAP = 0.05


class SensorGapWarning(UserWarning):
    """NSGA-II's sensor lies more than ``WARN_GAP`` above the exact reduction's: its search fell
    short (the reduction's sensor is the answer)."""


@dataclass(frozen=True)
class SensorSpace:
    """The choices of a sensor design: grades (names and M_z [A/m]), standoff levels [m], chip
    options, the H and G bounds, the per-height table of the stable region and extrema, the
    force constraints and the required normal force F_z [N]; the chip's constraint reads the
    field times ``field_factor`` up to the normal force F_z × ``read_factor`` (a worst corner
    of the parts' tolerances, :func:`magtact.tolerance.worst_factors`; 1: the nominal parts).
    ``F_r`` [N]: the shear the loads within the normal force F_z must include (the shear
    requirement where it occurs, as the verdict reads it; 0: none asked). ``silicones`` and
    ``G_ranges`` (S, 2) [Pa]: the silicones to choose from and the G each reaches within the
    bounds (one entry, the G bounds, where G is free)."""

    grades: tuple[str, ...]
    M_z: np.ndarray
    standoffs: np.ndarray
    options: tuple[ChipOption, ...]
    H_bounds: tuple[float, float]
    G_bounds: tuple[float, float]
    table: HeightTable
    constraints: ForceConstraints
    F_z: float
    field_factor: float = 1.0
    read_factor: float = 1.0
    F_r: float = 0.0
    silicones: tuple[str, ...] = ("none",)
    G_ranges: np.ndarray | None = None

    def G_range_of(self, j: int) -> tuple[float, float]:
        """The G bounds [Pa] of silicone ``j``."""
        return self.G_bounds if self.G_ranges is None else tuple(self.G_ranges[j])

    def box(self, H) -> tuple[np.ndarray, ...]:
        """(t_m, θ_m, f_r,min, f_z,max) at heights H [m], interpolated in the table."""
        H = np.atleast_1d(np.asarray(H, float))
        tb = self.table
        return tuple(np.interp(H, tb.H, v) for v in (tb.t_m, tb.theta_m, tb.f_r_min, tb.f_z_max))

    def G_force(self, f_r_min, f_z_max, j: int | None = None) -> np.ndarray:
        """The smallest G [Pa] meeting the force constraints (inf where none in the bounds;
        ``j``: within silicone j's G range)."""
        bounds = self.G_bounds if j is None else self.G_range_of(j)
        low, high = feasible_G(f_r_min, f_z_max, self.constraints, bounds)
        return np.where(low <= high, low, np.inf)


def sensor_space(models: ModelSet, study: Study, table: HeightTable | None = None,
                 constraints: ForceConstraints | None = None, field_factor: float = 1.0,
                 read_factor: float = 1.0, shear_within: bool = True) -> SensorSpace:
    """The choices of ``study``'s sensor problem (``table``: a sweep over the H range, computed
    when not given; ``constraints``: the force constraints, default the study's, whose normal
    force is also the one the chip must read; ``shear_within``: ask the required shear among
    the loads within the normal force, :attr:`SensorSpace.F_r`)."""
    d = study.design
    if d.grades:
        grades = tuple(d.grades)
        M_z = np.array([catalogue_grade(g).M_z(MU0)[0] for g in grades])
    else:
        grades, M_z = (study.magnet.grade,), np.array([study.magnet.M_z])
    if d.standoff[1] > 0:
        lo, hi = d.standoff
        n = int(np.floor((hi - lo) / STANDOFF_STEP + 1e-9)) + 1
        standoffs = lo + STANDOFF_STEP * np.arange(n)
    else:
        standoffs = np.array([study.hall.standoff])
    if table is None:
        table = sweep(models, study)
    order = np.argsort(table.H)
    if constraints is None:
        constraints = force_constraints(models, study)
    F_z = constraints.F_z_c * (1.0 - constraints.tolerance)  # the force, not its tolerant bound
    # the shear where it occurs: the nominal unit's, as the verdict reads it (a worst corner's
    # problem moves the force constraints, not the requirement)
    F_r = max(float(study.requirements.F_r), 0.0) if shear_within else 0.0
    silicones, G_ranges = silicone_ranges(study)
    return SensorSpace(grades, M_z, standoffs, tuple(chip_options(study)), d.H, d.G,
                       table.take(order), constraints, F_z, field_factor, read_factor, F_r,
                       silicones, G_ranges)


def silicone_ranges(study: Study) -> tuple[tuple[str, ...], np.ndarray]:
    """The silicones of ``study``'s sensor problem that reach a G of its design range, and
    the G range [Pa] of each within it; G free (the study's silicone over the design range)
    where it names none."""
    from ..parts import SILICONES

    d = study.design
    lo, hi = d.G
    pairs = [(n, max(lo, SILICONES[n].G_range[0]), min(hi, SILICONES[n].G_range[1]))
             for n in d.silicones]
    pairs = [p for p in pairs if p[1] <= p[2]]
    if not pairs:
        pairs = [(study.material.silicone, lo, hi)]
    return tuple(p[0] for p in pairs), np.array([p[1:] for p in pairs], float)


@dataclass(frozen=True)
class SensorDesign:
    """One sensor: its parts and dimensions, evaluated on the sensor grid (SI).

    Attributes
    ----------
    H, G : float
        Base height [m], shear modulus [Pa].
    grade : str
        The magnet's grade (``custom``: the study's own magnetisation).
    M_z : float
        Magnetisation [A/m].
    standoff : float
        The chip's distance below the body [m].
    option : ChipOption
        The chip's setting: range, noise, rate.
    sigma_r, sigma_z : float
        Worst σ_F,r, σ_F,z [N] over the required loads.
    G_force, G_range : float
        The smallest G [Pa] that meets the force constraints, and that at which the chip
        reads the required loads (inf: none).
    F_saturation : float
        The smallest normal force [N] on the grid at which the chip has left its range (inf:
        never in the stable region).
    F_r_within : float
        The largest shear [N] on the grid among the loads within the required normal force.
    silicone : str
        The silicone the body is cast from (its G range holds G).
    """

    H: float
    G: float
    grade: str
    M_z: float
    standoff: float
    option: ChipOption
    sigma_r: float
    sigma_z: float
    G_force: float
    G_range: float
    F_saturation: float
    F_r_within: float = float("nan")
    silicone: str = "none"

    def sensor(self, study: Study):
        """This design as a :class:`magtact.Sensor` of ``study``: its magnet's grade and
        M_z, the chip at its standoff and setting, its silicone, the study's body."""
        from .._sensor import Sensor

        f = self.option.figures
        return replace(Sensor.of_study(study, self.H, self.G, self.M_z), grade=self.grade,
                       setting=None if f is None else f.setting, standoff=float(self.standoff),
                       silicone=self.silicone)

    @property
    def sigma(self) -> float:
        """√(σ_F,r² + σ_F,z²) [N]: the decision's objective."""
        return float(np.hypot(self.sigma_r, self.sigma_z))

    @property
    def feasible(self) -> bool:
        """Whether G meets the force constraints and the chip reads the required loads."""
        return bool(self.G >= max(self.G_force, self.G_range) * (1.0 - 1e-9))

    def to_json(self) -> dict:
        """The design in user units, each key naming its unit (:class:`SensorRecord`)."""
        return to_json(self.record())

    def record(self) -> SensorRecord:
        """The design as the files give it (:class:`SensorRecord`)."""
        o = self.option
        return SensorRecord(self.H, self.G, self.grade, self.M_z, float(self.standoff), o.words,
                            o.range_x, o.range_z, o.noise_x, o.noise_z, o.rate, self.sigma_r,
                            self.sigma_z, self.G_force, self.G_range, self.F_saturation,
                            self.F_r_within, self.feasible, self.silicone)


@dataclass(frozen=True)
class SensorRecord:
    """A sensor of the sensor problem as ``sensor.json`` and ``chosen.json`` give it (SI).

    Attributes
    ----------
    H, G, M_z, standoff : float
        Base height [m], shear modulus [Pa], magnetisation [A/m], the chip's standoff [m].
    grade, chip_setting, silicone : str
        The magnet's grade, the chip's setting in words, the silicone.
    range_x, range_z, noise_x, noise_z : float
        The chip's range [T] and RMS noise [T] per axis at its setting.
    sample_rate : float
        Its sample rate [Hz] (NaN, null in the file: not known).
    sigma_r, sigma_z : float
        Worst σ_F,r, σ_F,z [N] over the required loads.
    G_force, G_range, F_saturation, F_r_within : float
        As :class:`SensorDesign` (not finite: null in the file, NaN read back).
    feasible : bool
    """

    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    grade: str = entry("magnet_grade", kind=str)
    M_z: float = entry(unit="A_per_m")
    standoff: float = entry(unit="mm")
    chip_setting: str = entry(kind=str)
    range_x: float = entry(unit="mT")
    range_z: float = entry(unit="mT")
    noise_x: float = entry(unit="uT")
    noise_z: float = entry(unit="uT")
    sample_rate: float = entry(unit="Hz", null_nan=True)
    sigma_r: float = entry("sigma_Fr_mN", "mN")
    sigma_z: float = entry("sigma_Fz_mN", "mN")
    G_force: float = entry(unit="kPa", null_nan=True)
    G_range: float = entry(unit="kPa", null_nan=True)
    F_saturation: float = entry(unit="N", null_nan=True)
    F_r_within: float = entry(unit="N", null_nan=True)
    feasible: bool = entry(kind=bool)
    silicone: str = entry(kind=str)


def evaluate_designs(models: ModelSet, study: Study, space: SensorSpace, H, G, standoff,
                     grade, option, silicone=0) -> dict[str, np.ndarray]:
    """σ_F,r, σ_F,z [N], G [Pa], G_force, G_range [Pa], F_saturation and F_r_within [N] of
    designs given by arrays: H [m], G [Pa], and indices of the standoff level, grade, chip
    option and silicone. Where G is None, each design takes the G of least √(σ_r² + σ_z²)
    among those its silicone reaches (exact on the grid; inf σ where none is feasible)."""
    H = np.atleast_1d(np.asarray(H, float))
    standoff, grade, option = (np.atleast_1d(np.asarray(v, int)) for v in (standoff, grade,
                                                                            option))
    silicone = np.broadcast_to(np.asarray(silicone, int), H.shape)
    t_m, theta_m, f_r_min, f_z_max = space.box(H)
    G_force = np.empty(H.size)
    for j in np.unique(silicone):
        at = silicone == j
        G_force[at] = space.G_force(f_r_min[at], f_z_max[at], int(j))
    G = np.full(H.size, np.nan) if G is None else np.atleast_1d(np.asarray(G, float)).copy()
    free = np.isnan(G)
    M_z = space.M_z[grade]
    rx, rz, sx, sz = (np.array([getattr(space.options[k], a) for k in option])
                      for a in ("range_x", "range_z", "noise_x", "noise_z"))
    # every design in one grid, each with its chip at its own standoff
    grid = sensor_grid(models, study, H, t_m, theta_m, space.standoffs[standoff])
    G_range = grid.G_range(M_z * space.field_factor, rx, rz, space.F_z * space.read_factor)
    none = np.zeros(H.size, bool)  # designs with no G that meets the problem
    for j in np.unique(silicone[free]):  # the best G of each design, per silicone
        i = np.flatnonzero(free & (silicone == j))
        lo, hi = space.G_range_of(int(j))
        low = np.maximum(np.maximum(G_force[i], G_range[i]), lo)
        value, G[i] = _Noise(_Within(grid.take(i)), (sx[i], sz[i])).least(
            M_z[i], low, hi, space.F_z, space.F_r)
        none[i] = ~np.isfinite(value)
    sigma = grid.sigma(G, M_z, sx, sz, space.F_z)
    out = {k: np.where(none, np.inf, v) for k, v in zip(("sigma_r", "sigma_z"), sigma,
                                                        strict=True)}
    out["G_range"] = G_range
    out["F_saturation"] = grid.F_saturation(G, M_z, rx, rz)
    with np.errstate(invalid="ignore"):  # G may be inf where no G is feasible
        within = G[:, None, None] * grid.f_z <= space.F_z
        out["F_r_within"] = G * np.where(within, np.abs(grid.f_r), 0.0).max(axis=(1, 2))
    out["G"], out["G_force"] = G, G_force
    return out


def _design(space: SensorSpace, values: dict, H, s, g, k, j: int = 0, i: int = 0
            ) -> SensorDesign:
    return SensorDesign(float(np.atleast_1d(H)[i]), float(values["G"][i]), space.grades[g],
                        float(space.M_z[g]), float(space.standoffs[s]), space.options[k],
                        *(float(values[n][i]) for n in ("sigma_r", "sigma_z", "G_force",
                                                        "G_range", "F_saturation",
                                                        "F_r_within")),
                        silicone=space.silicones[j])


@dataclass(frozen=True)
class _Best:
    sigma: float
    H: float
    G: float
    s: int
    g: int
    k: int
    j: int = 0


class _Within:
    """Per height of a grid: its points sorted by their normal force per unit G, and the largest
    per-unit |f_r| among the first i of them (the shear the loads within a normal force include).

    Over G the points within the normal force F_z change only where G passes a point's
    F_z / f_z: on the piece G ∈ (F_z / f_i, F_z / f_(i−1)] (f sorted, f_(−1) = 0) they are the
    first i, for i = 0 … P (:meth:`pieces`). One per grid (kept, :func:`_within_of`), shared by
    every chip noise."""

    def __init__(self, grid: SensorGrid):
        n = grid.f_z.shape[0]
        self.grid = grid
        self.order = np.argsort(grid.f_z.reshape(n, -1), axis=1, kind="stable")
        self.f = np.take_along_axis(grid.f_z.reshape(n, -1), self.order, axis=1)
        with np.errstate(divide="ignore"):
            self.breaks = np.where(self.f > 0, 1.0 / np.where(self.f > 0, self.f, 1.0), np.inf)
        r = np.take_along_axis(np.abs(grid.f_r.reshape(n, -1)), self.order, axis=1)
        self.R = np.concatenate([np.zeros((n, 1)), np.maximum.accumulate(r, axis=1)], axis=1)
        self._kept: dict = {}  # the pieces' bounds per (F_z, F_r, G_high)
        self._open: dict = {}  # the pieces that may hold a G, per (F_z, F_r, G_high)
        self._squares: tuple | None = None
        self._noises: dict = {}  # _Noise per chip noise (σ_x, σ_z)

    def noise(self, noise_x: float, noise_z: float) -> _Noise:
        """The :class:`_Noise` of the chip noise (σ_x, σ_z) [T RMS] (scalars) over this grid;
        kept, with what it has computed, for the next solve on the same grid."""
        key = (float(noise_x), float(noise_z))
        if key not in self._noises:
            self._noises[key] = _Noise(self, key)
        return self._noises[key]

    def squares(self) -> tuple[np.ndarray, np.ndarray]:
        """(j_kx², j_kz²) of every point in this order, what every chip noise combines
        (:meth:`SensorGrid.unit_noise`), permuted once: each of shape (P, 2, n), point first
        and height last (k: F_r, F_z), so that a running maximum over the points runs along
        whole rows of heights."""
        if self._squares is None:
            n = self.order.shape[0]
            j = self.grid.j.reshape(n, -1, 2, 2)
            at = self.order[..., None]
            self._squares = tuple(
                np.ascontiguousarray(np.take_along_axis(j[..., c] ** 2, at, axis=1).transpose(
                    1, 2, 0)) for c in (0, 1))
        return self._squares

    def pieces(self, F_z: float) -> tuple[np.ndarray, np.ndarray]:
        """(start, end) [Pa] of the pieces i = 0 … P of G (shape (n, P + 1)): just above
        F_z / f_i (0 for i = P) and F_z / f_(i−1) (inf for i = 0)."""
        n = self.f.shape[0]
        start = np.concatenate([F_z * self.breaks * (1.0 + G_STEP), np.zeros((n, 1))], axis=1)
        end = np.concatenate([np.full((n, 1), np.inf), F_z * self.breaks], axis=1)
        return start, end

    def bounds(self, F_z: float, F_r: float, G_high: float) -> tuple[np.ndarray, np.ndarray]:
        """Per piece: the least G at which its loads include the shear F_r [N] (the larger of
        its start and F_r / R_i), and the largest G it may take (the lesser of its end and
        G_high); kept, since every chip noise and grade asks for the same."""
        key = (F_z, F_r, G_high)
        if key not in self._kept:
            start, end = self.pieces(F_z)
            with np.errstate(divide="ignore"):
                need = np.where(self.R > 0, F_r / self.R, np.inf) if F_r > 0 else 0.0
            self._kept[key] = (np.maximum(start, need), np.minimum(end, G_high))
        return self._kept[key]

    def open_pieces(self, F_z: float, F_r: float, G_high: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pieces that may hold a G (their least G at most their largest, :meth:`bounds`),
        in their order, per height: their indices i, least and largest G, each of shape
        (n, K) with K the most of any height; the rest of a row is padded with pieces that
        hold none (least G inf, largest −inf). Every other piece holds no G whatever the
        lower bound on G, so the least σ over G is the least over these; kept."""
        key = (F_z, F_r, G_high)
        if key not in self._open:
            lowest, cap = self.bounds(F_z, F_r, G_high)
            ok = lowest <= cap
            K = max(int(ok.sum(axis=1).max(initial=0)), 1)
            i = np.argsort(~ok, axis=1, kind="stable")[:, :K]  # the open ones first, in order
            held = np.take_along_axis(ok, i, axis=1)
            self._open[key] = (i, np.where(held, np.take_along_axis(lowest, i, axis=1), np.inf),
                               np.where(held, np.take_along_axis(cap, i, axis=1), -np.inf))
        return self._open[key]

    def most_shear(self, G_low, G_high: float, F_z: float) -> tuple[np.ndarray, np.ndarray]:
        """Per height: the largest shear [N] the loads within the normal force F_z [N] include
        over G ∈ [G_low, G_high] (G R_i grows with G on a piece: its largest is at the piece's
        end), and the G [Pa] where it is; 0 and NaN where the interval is empty."""
        start, end = self.pieces(F_z)
        G = np.minimum(end, G_high)
        low = np.broadcast_to(np.asarray(G_low, float), (self.f.shape[0],))[:, None]
        ok = (G >= np.maximum(start, low)) & np.isfinite(G)
        S = np.where(ok, G * self.R, 0.0)
        j = np.argmax(S, axis=1)
        rows = np.arange(S.shape[0])
        best = S[rows, j]
        return best, np.where(ok[rows, j], G[rows, j], np.nan)


#: The :class:`_Within` of the last grids the reduction solved on (grid, within), newest first:
#: the sensor problem solved again for a worst corner asks for the same grid
#: (:func:`magtact.chip.sensor_grid` keeps it) and the same chip noises.
_WITHINS: list = []
WITHINS_KEPT = 2


def _within_of(grid: SensorGrid) -> _Within:
    """The kept :class:`_Within` of ``grid`` (the same object, read only), else a new one."""
    for i, (g, within) in enumerate(_WITHINS):
        if g is grid:
            _WITHINS.insert(0, _WITHINS.pop(i))
            return within
    within = _Within(grid)
    _WITHINS.insert(0, (grid, within))
    del _WITHINS[WITHINS_KEPT:]
    return within


class _Noise:
    """One chip noise over a grid's :class:`_Within`: the worst per-unit √(σ_r² + σ_z²) among
    the first i points.

    The worst σ_k among the first i points is the square root of the largest σ_k² among them
    (the square root is monotone, also in floating point): the running maximum is taken of
    j_kx² σ_x² + j_kz² σ_z² (:meth:`_Within.squares`), and the root only at the pieces
    :meth:`least` compares. ``noise``: (σ_x, σ_z) [T RMS], scalars or one per height."""

    def __init__(self, within: _Within, noise: tuple):
        self.within = within
        self.noise = noise
        self._W: dict = {}  # W at the open pieces, per (F_z, F_r, G_high)

    def _running(self) -> np.ndarray:
        """q[i] = the largest σ_r², σ_z² per unit among the first i points, shape
        (P + 1, 2, n) (q[0] = 0: every σ² is ≥ 0)."""
        jx2, jz2 = self.within.squares()
        P, _, n = jx2.shape
        sx2, sz2 = (np.asarray(v, float).reshape(-1) ** 2 for v in self.noise)
        q = np.empty((P + 1, 2, n))
        q[0] = 0.0
        np.multiply(jx2, sx2, out=q[1:])
        q[1:] += jz2 * sz2
        return np.maximum.accumulate(q, axis=0, out=q)

    def W(self, F_z: float, F_r: float, G_high: float) -> np.ndarray:
        """The worst per-unit √(σ_r² + σ_z²) of the pieces :meth:`_Within.open_pieces`, shape
        (n, K); kept (the running maxima over all points are not: several MB a noise)."""
        key = (F_z, F_r, G_high)
        if key not in self._W:
            self.prepare(F_z, F_r, (G_high,))
        return self._W[key]

    def prepare(self, F_z: float, F_r: float, G_highs) -> None:
        """:meth:`W` of every upper bound of G in ``G_highs`` from one running maximum (the
        silicones of a solve ask for one each)."""
        todo = [G for G in dict.fromkeys(G_highs) if (F_z, F_r, G) not in self._W]
        if not todo:
            return
        q = self._running()
        n = q.shape[2]
        q = q.reshape(-1)
        for G_high in todo:
            i = self.within.open_pieces(F_z, F_r, G_high)[0]
            at = i * (2 * n) + np.arange(n)[:, None]  # piece i of height h: q[i, :, h]
            self._W[F_z, F_r, G_high] = np.hypot(np.sqrt(q[at]), np.sqrt(q[at + n]))

    def least(self, M_z: float, G_low: np.ndarray, G_high: float, F_z: float,
              F_r: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Per height: the least √(σ_r² + σ_z²) [N] over the G ∈ [G_low, G_high] at which the
        loads within the normal force F_z [N] include a shear of F_r [N], and its G (exact on
        the grid; see the module notes); inf (and G_low) where there is none. ``M_z`` [A/m]:
        a scalar or one per height; ``G_high`` finite.

        On piece i σ = G W_i / M_z grows with G, and the shear G R_i reaches F_r from
        G = F_r / R_i on: the piece's best G is the largest of its start, G_low and F_r / R_i,
        where that is within the piece and G_high. Only the pieces that may hold a G are
        compared (:meth:`_Within.open_pieces`); of equal values the first piece's is kept."""
        _, lowest, cap = self.within.open_pieces(F_z, F_r, G_high)
        W = self.W(F_z, F_r, G_high)
        n = W.shape[0]
        rows = np.arange(n)
        M = np.broadcast_to(np.asarray(M_z, float), (n,))
        G_low = np.broadcast_to(np.asarray(G_low, float), (n,))
        G = np.maximum(lowest, G_low[:, None])
        with np.errstate(invalid="ignore"):  # inf × 0 where no G is feasible: masked
            value = np.where(G <= cap, G * W, np.inf)
        j = np.argmin(value, axis=1)
        best = value[rows, j] / M
        return best, np.where(np.isfinite(best), G[rows, j], G_low)


def most_shear_within(models: ModelSet, study: Study, table: HeightTable, G_low, G_high: float,
                      F_z: float) -> tuple[np.ndarray, np.ndarray]:
    """Per height of ``table``: the largest shear [N] among the loads of its stable region
    within the normal force F_z [N], over G ∈ [G_low, G_high] [Pa] (``G_low``: one per height
    or a scalar), on the sensor problem's grid (the shear the sensor problem asks of the
    loads), and the G [Pa] where it is; 0 and NaN where the interval is empty."""
    grid = sensor_grid(models, study, table.H, table.t_m, table.theta_m)
    return _within_of(grid).most_shear(G_low, G_high, F_z)  # kept: asked once per G range


def exact_sensor_reduction(models: ModelSet, study: Study, space: SensorSpace
                           ) -> tuple[SensorDesign, int]:
    """The least √(σ_r² + σ_z²) over every grade, standoff level, chip option and silicone, on
    ``N_H`` heights (refined around the best), exact in G; the best-reading design where none
    is feasible. Returns it and the number of discrete combinations compared."""
    design, combos, _ = _reduction(models, study, space)
    return design, combos


def _reduction(models: ModelSet, study: Study, space: SensorSpace
               ) -> tuple[SensorDesign, int, tuple[SensorDesign | None, ...]]:
    """:func:`exact_sensor_reduction`, and the best design of each silicone on the heights'
    grid (the chosen one's refined; None where the silicone has no feasible design)."""
    H = np.linspace(*space.H_bounds, N_H)
    best, fallback, each = _reduce_heights(models, study, space, H,
                                           np.arange(space.standoffs.size))
    if best is None and space.F_r > 0:  # no sensor's loads include the shear: the problem
        return _reduction(models, study, replace(space, F_r=0.0))  # without it
    if best is not None:  # refine the height between the grid's neighbours
        step = H[1] - H[0]
        Hf = np.clip(np.linspace(best.H - step, best.H + step, 41), *space.H_bounds)
        best, fallback, _ = _reduce_heights(models, study, space, Hf, np.array([best.s]), best,
                                            fallback, only=(best.g, best.k, best.j))
    pick = best if best is not None else fallback
    if pick is None:  # no height reads and carries anything: nothing to report as the best
        raise InfeasibleError("no design of the sensor space carries the required forces and "
                              "keeps the chip in range")
    per = [pick if best is not None and j == pick.j else b for j, b in enumerate(each)]
    found = [j for j, b in enumerate(per) if b is not None]
    out = [None] * len(per)
    if found:  # every silicone's best in one evaluation
        b = [per[j] for j in found]
        values = evaluate_designs(models, study, space, [x.H for x in b], [x.G for x in b],
                                  [x.s for x in b], [x.g for x in b], [x.k for x in b],
                                  [x.j for x in b])
        for i, x in enumerate(b):
            out[x.j] = _design(space, values, [y.H for y in b], x.s, x.g, x.k, x.j, i)
    if best is not None:
        design = out[pick.j]
    else:
        values = evaluate_designs(models, study, space, pick.H, pick.G, pick.s, pick.g, pick.k,
                                  pick.j)
        design = _design(space, values, pick.H, pick.s, pick.g, pick.k, pick.j)
    combos = space.standoffs.size * space.M_z.size * len(space.options) * len(space.silicones)
    return design, combos, tuple(out)


def _reduce_heights(models, study, space, H, levels, best=None, fallback=None, only=None):
    """The best design over the heights ``H``, the standoff levels ``levels`` and every grade,
    chip option and silicone (``only``: one (grade, option, silicone)), all heights and levels
    in one grid; where none is feasible (and no ``best`` is known), the best-reading one; and
    the best of each silicone (None where it has none). Of equally good designs the first in
    the order (standoff, option, grade, silicone, height) is kept, and a design replaces
    ``best`` only when strictly better."""
    t_m, theta_m, f_r_min, f_z_max = space.box(H)
    n = H.size
    silicones = [(j, *space.G_range_of(j)) for j in range(len(space.silicones))
                 if only is None or j == only[2]]
    G_force = {j: np.tile(space.G_force(f_r_min, f_z_max, j), levels.size)
               for j, _, _ in silicones}
    each = [None] * len(space.silicones)
    if not any((G_force[j] <= hi).any() for j, _, hi in silicones):
        return best, fallback, tuple(each)  # no G carries the forces: no design, no grid
    rows_s = np.repeat(levels, n)  # rows: standoff level, then height
    grid = sensor_grid(models, study, np.tile(H, levels.size), np.tile(t_m, levels.size),
                       np.tile(theta_m, levels.size), space.standoffs[rows_s])
    keep = _undominated(space.options) if only is None else {only[1]}
    options = [(k, o) for k, o in enumerate(space.options) if k in keep]
    grades = [(g, M) for g, M in enumerate(space.M_z) if only is None or g == only[0]]
    within = _within_of(grid)
    reading = grid.read_order(space.F_z * space.read_factor)
    cands, falls = [], []
    for k, o in options:
        noise = within.noise(o.noise_x, o.noise_z)
        noise.prepare(space.F_z, space.F_r, [hi for _, _, hi in silicones])
        least = reading.least_limit(o.range_x, o.range_z)
        for g, M_z in grades:
            G_range = reading.G_range(least, M_z * space.field_factor)
            solved: dict = {}  # silicones of the same G range share the answer
            for j, lo, hi in silicones:
                G_low = np.maximum(np.maximum(G_force[j], G_range), lo)
                if not (G_low <= hi).any():  # no G of this silicone at any height
                    continue
                if (lo, hi) not in solved:
                    solved[lo, hi] = noise.least(M_z, G_low, hi, space.F_z, space.F_r)
                value, G = solved[lo, hi]
                # per standoff level: the first height of the least value
                v = value.reshape(levels.size, n)
                i = np.argmin(v, axis=1)
                for li, s in enumerate(levels):
                    r = li * n + i[li]
                    if np.isfinite(value[r]):
                        cands.append((float(value[r]), int(s), k, g, j, float(H[i[li]]),
                                      float(G[r])))
    if not cands and best is None:
        # where none reads the required loads: the design that reads the most, at the
        # stiffest G of its silicone
        for k, o in options:
            for g, M_z in grades:
                # the saturation force is G times its value per unit G
                unit = grid.F_saturation(np.ones(H.size * levels.size), M_z, o.range_x,
                                         o.range_z)
                for j, _, hi in silicones:
                    ok = np.isfinite(G_force[j]) & (G_force[j] <= hi)
                    F_sat = np.where(ok, hi * unit, -np.inf).reshape(levels.size, n)
                    m = np.argmax(F_sat, axis=1)
                    for li, s in enumerate(levels):
                        if ok[li * n + m[li]]:
                            falls.append((-float(F_sat[li, m[li]]), int(s), k, g, j,
                                          float(H[m[li]]), hi))
    for c in sorted(cands, key=lambda c: c[:5]):  # the best of each silicone
        if each[c[4]] is None:
            each[c[4]] = _Best(c[0], c[5], c[6], c[1], c[3], c[2], c[4])
    if cands:
        v, s, k, g, j, h, G = min(cands, key=lambda c: c[:5])
        if best is None or v < best.sigma:
            best = _Best(v, h, G, s, g, k, j)
    if falls:
        f, s, k, g, j, h, hi = min(falls, key=lambda c: c[:5])
        if fallback is None or -f > fallback.sigma:
            fallback = _Best(-f, h, hi, s, g, k, j)
    return best, fallback, tuple(each)


def _undominated(options: tuple) -> frozenset[int]:
    """The chip options no earlier option dominates: one with as wide a range on both axes and
    as little noise on both is at least as good for every design (its reading limit is no lower,
    so its least G no higher, and σ grows with the noise), and wins a tie by coming first, so
    the reduction's answer is the same without the dominated ones."""
    keep = set()
    for k, o in enumerate(options):
        if not any(p.range_x >= o.range_x and p.range_z >= o.range_z
                   and p.noise_x <= o.noise_x and p.noise_z <= o.noise_z
                   for p in options[:k]):
            keep.add(k)
    return frozenset(keep)


@dataclass(frozen=True)
class SensorPareto:
    """NSGA-II's feasible non-dominated sensor designs (arrays of shape (n,)): H [m], G [Pa],
    indices of the standoff level, grade and option, σ_F,r and σ_F,z [N], and of the
    silicone."""

    H: np.ndarray
    G: np.ndarray
    standoff: np.ndarray
    grade: np.ndarray
    option: np.ndarray
    sigma_r: np.ndarray
    sigma_z: np.ndarray
    seed: int
    generations: int
    evaluations: int
    silicone: np.ndarray | None = None


def same_designs():
    """pymoo's mixed-variable duplicate elimination, by hashing each design's variables instead
    of comparing every pair in Python: an individual is a duplicate where a later one of its
    population, or one of ``other``, equals it in every variable (the same marks as
    ``pymoo.core.mixed.MixedVariableDuplicateElimination``, in linear time)."""
    from pymoo.core.duplicate import DuplicateElimination

    class _SameDesigns(DuplicateElimination):
        def _do(self, pop, other, is_duplicate):
            keys = [tuple(sorted(x.items())) for x in pop.get("X")]
            if other is None:
                seen: set = set()
                for i in range(len(keys) - 1, -1, -1):
                    is_duplicate[i] = keys[i] in seen
                    seen.add(keys[i])
            else:
                known = {tuple(sorted(x.items())) for x in other.get("X")}
                for i, key in enumerate(keys):
                    is_duplicate[i] = is_duplicate[i] or key in known
            return is_duplicate

    return _SameDesigns()


def sensor_nsga2(models: ModelSet, study: Study, space: SensorSpace) -> SensorPareto | None:
    """NSGA-II over the mixed variables (see the module notes), seeded by ``optimise.seed``;
    None if it found no feasible design."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.mixed import MixedVariableMating, MixedVariableSampling
    from pymoo.core.problem import Problem
    from pymoo.core.variable import Integer, Real
    from pymoo.optimize import minimize

    o = study.optimise
    scale = 1e3  # objectives in mN
    NAMES = ("H", "standoff", "grade", "option", "silicone")
    highest = np.array([space.G_range_of(j)[1] for j in range(len(space.silicones))])

    class _Sensors(Problem):
        def __init__(self):
            super().__init__(vars={"H": Real(bounds=space.H_bounds),
                                   "standoff": Integer(bounds=(0, space.standoffs.size - 1)),
                                   "grade": Integer(bounds=(0, space.M_z.size - 1)),
                                   "option": Integer(bounds=(0, len(space.options) - 1)),
                                   "silicone": Integer(bounds=(0, len(space.silicones) - 1))},
                             n_obj=2, n_ieq_constr=1)

        def _evaluate(self, X, out, *args, **kwargs):
            v = {k: np.array([x[k] for x in X]) for k in NAMES}
            r = evaluate_designs(models, study, space, v["H"], None, v["standoff"],
                                 v["grade"], v["option"], v["silicone"])
            feasible = np.isfinite(r["sigma_r"]) & np.isfinite(r["sigma_z"])
            out["F"] = np.where(feasible[:, None],
                                np.stack([r["sigma_r"], r["sigma_z"]], axis=1) * scale, 1e6)
            low = np.maximum(r["G_force"], r["G_range"])
            with np.errstate(invalid="ignore", divide="ignore"):
                g = np.minimum(low / highest[v["silicone"]] - 1.0, 1e6)
            # a design whose loads never include the shear breaks the problem too
            out["G"] = np.where(feasible, g, np.maximum(g, 1.0))[:, None]

    dup = same_designs()
    algorithm = NSGA2(pop_size=o.sensor_population, sampling=MixedVariableSampling(),
                      mating=MixedVariableMating(eliminate_duplicates=dup),
                      eliminate_duplicates=dup)
    generations = o.sensor_generations
    res = minimize(_Sensors(), algorithm, ("n_gen", generations), seed=o.seed, verbose=False)
    opt = res.opt
    if opt is None:
        return None
    feasible = np.ravel(opt.get("CV")) <= 0
    if not feasible.any():
        return None
    X = [x for x, ok in zip(opt.get("X"), feasible, strict=True) if ok]
    F = np.atleast_2d(opt.get("F"))[feasible] / scale
    col = {k: np.array([x[k] for x in X]) for k in NAMES}
    col["G"] = evaluate_designs(models, study, space, col["H"], None, col["standoff"],
                                col["grade"], col["option"], col["silicone"])["G"]
    order = np.argsort(col["H"])
    return SensorPareto(col["H"][order], col["G"][order], col["standoff"][order].astype(int),
                        col["grade"][order].astype(int), col["option"][order].astype(int),
                        F[order, 0], F[order, 1], o.seed, generations,
                        int(res.algorithm.evaluator.n_eval),
                        col["silicone"][order].astype(int))


@dataclass(frozen=True)
class SensorOptimisation:
    """The sensor problem's answer (:func:`optimise_sensor`).

    Attributes
    ----------
    choice : SensorDesign
        The chosen sensor: NSGA-II's least √(σ_r² + σ_z²) where it agrees with the
        reduction's, else the reduction's.
    reduction_choice : SensorDesign
        The exact reduction's (the cross-check; the best-reading design where none is
        feasible).
    pareto : SensorPareto or None
        NSGA-II's feasible set (None where it found none).
    gap : float
        (σ NSGA-II − σ reduction) / σ reduction; NaN where either found no feasible design.
    combinations : int
        Discrete combinations (standoff levels × grades × chip options × silicones) the
        reduction compared.
    wall_time : float
        [s].
    per_silicone : tuple of SensorDesign or None
        The reduction's best sensor of each silicone of :attr:`silicones` (on its heights'
        grid; the chosen silicone's refined), None where a silicone has no feasible design.
    silicones : tuple of str
        The silicones the problem chose from.
    sizes : tuple of str
        The magnet sizes the problem chose from (catalogue names; empty: the study's magnet
        only).
    per_size : tuple of SensorDesign or None
        The reduction's best sensor of each size of :attr:`sizes` (nominal parts), None where
        the size has none; :attr:`size_notes` says why.
    size_notes : tuple of str
        Why a size of :attr:`sizes` has no sensor, or a caution on the one it has (its models
        a poor fit); "" where there is none.
    size : str
        The chosen size (of :attr:`sizes`; "" where it chose from none).
    """

    choice: SensorDesign
    reduction_choice: SensorDesign
    pareto: SensorPareto | None
    gap: float
    combinations: int
    wall_time: float
    per_silicone: tuple[SensorDesign | None, ...] = ()
    silicones: tuple[str, ...] = ()
    sizes: tuple[str, ...] = ()
    per_size: tuple[SensorDesign | None, ...] = ()
    size_notes: tuple[str, ...] = ()
    size: str = ""

    @property
    def feasible(self) -> bool:
        return self.choice.feasible

    def write(self, folder, design) -> list:
        """Write ``sensor.json`` (:meth:`to_json`) and ``chosen.json`` (the chosen sensor as
        flat values in user units, with ``design``'s extrema, a
        :class:`magtact.optimise.DesignResult` of the chosen sensor, for the report) into
        ``folder``; return the files."""
        from pathlib import Path

        from ._run import design_json

        folder = Path(folder)
        flat = design_json(design) | self.choice.to_json() | {"problem": "sensor"}
        return [write_json(folder / name, doc, indent=2)
                for name, doc in (("sensor.json", self.to_json()), ("chosen.json", flat))]

    def to_json(self) -> dict:
        """The answer in user units (``sensor.json``: :class:`SensorFile`)."""
        return to_json(self.record())

    def record(self) -> SensorFile:
        """The answer as ``sensor.json`` gives it (:class:`SensorFile`)."""
        p = self.pareto
        sizes = MagnetSizes(self.size, tuple(
            SizeRecord(name, None if d is None else d.record(), note or None)
            for name, d, note in zip(self.sizes, self.per_size, self.size_notes,
                                     strict=True))) if self.sizes else None
        return SensorFile(
            self.choice.record(), self.reduction_choice.record(), self.gap, self.combinations,
            self.wall_time, None if p is None else NSGA2Record(int(p.H.size), p.seed,
                                                               p.generations, p.evaluations),
            sizes)


@dataclass(frozen=True)
class NSGA2Record:
    """NSGA-II's run of the sensor problem: its feasible points, seed, generations and
    evaluations."""

    points: int = entry(kind=int)
    seed: int = entry(kind=int)
    generations: int = entry(kind=int)
    evaluations: int = entry(kind=int)


@dataclass(frozen=True)
class SizeRecord:
    """One magnet size of the answer: its name, its best sensor (None: none) and a note."""

    size: str = entry(kind=str)
    best: SensorRecord | None = entry(kind=SensorRecord, optional=True)
    note: str | None = entry(kind=str, optional=True)


@dataclass(frozen=True)
class MagnetSizes:
    """The magnet sizes an answer compared: the chosen size, and each size's best sensor."""

    magnet_size: str = entry(kind=str)
    magnet_sizes: tuple[SizeRecord, ...] = entry(kind=SizeRecord, levels=("list",))


@dataclass(frozen=True)
class SensorFile:
    """``sensor.json``: the sensor problem's answer (SI).

    Attributes
    ----------
    chosen, exact_reduction_choice : SensorRecord
        The chosen sensor and the exact reduction's.
    gap : float
        NSGA-II's σ_F over the reduction's, less one (NaN, null in the file: not run).
    combinations : int
        The parts' combinations the reduction enumerated.
    wall_time : float
        Seconds the problem took.
    nsga2 : NSGA2Record or None
    sizes : MagnetSizes or None
        The magnet sizes compared (their keys left out where the answer compared none).
    """

    chosen: SensorRecord = entry(kind=SensorRecord)
    exact_reduction_choice: SensorRecord = entry(kind=SensorRecord)
    gap: float = entry("gap_to_exact_reduction", null_nan=True)
    combinations: int = entry(kind=int)
    wall_time: float = entry(unit="s")
    nsga2: NSGA2Record | None = entry(kind=NSGA2Record, optional=True)
    sizes: MagnetSizes | None = entry(kind=MagnetSizes, inline=True, optional=True,
                                      omit="none", default=None)


def optimise_sensor(models: ModelSet, study: Study, table: HeightTable | None = None,
                    constraints: ForceConstraints | None = None, field_factor: float = 1.0,
                    read_factor: float = 1.0, *, nsga2: bool = True,
                    reduction: SensorOptimisation | None = None,
                    shear_within: bool = True) -> SensorOptimisation:
    """The sensor problem of ``study`` (see the module notes): the exact reduction and
    NSGA-II, the decision and their gap; ``field_factor`` and ``read_factor``: the chip's
    constraint at a worst corner (:class:`SensorSpace`). Without ``nsga2`` the reduction's
    answer alone (NSGA-II's cross-check left for the final problem); ``reduction``: that
    answer of this same problem, reused instead of solved again; ``shear_within``: ask the
    shear among the loads within the normal force (False where an earlier solve found that no
    sensor's loads include it).

    Warns
    -----
    SensorGapWarning
        If NSGA-II's choice lies more than ``WARN_GAP`` above the exact reduction's (the
        reduction's is kept).
    """
    t0 = time.perf_counter()
    space = sensor_space(models, study, table, constraints, field_factor, read_factor,
                         shear_within)
    if reduction is None:
        red, combos, per = _reduction(models, study, space)
    else:
        red, combos = reduction.reduction_choice, reduction.combinations
        per = reduction.per_silicone
        t0 -= reduction.wall_time
    if space.F_r > 0 and not red.F_r_within >= space.F_r * (1.0 - 1e-9):
        # no sensor's loads include the shear: the reduction answered the problem without it
        space = replace(space, F_r=0.0)
    pareto = sensor_nsga2(models, study, space) if red.feasible and nsga2 else None
    choice, gap = red, float("nan")
    if pareto is not None:
        i = int(np.argmin(np.hypot(pareto.sigma_r, pareto.sigma_z)))
        values = evaluate_designs(models, study, space, pareto.H[i], pareto.G[i],
                                  pareto.standoff[i], pareto.grade[i], pareto.option[i],
                                  pareto.silicone[i])
        nsga = _design(space, values, pareto.H[i], pareto.standoff[i], pareto.grade[i],
                       pareto.option[i], pareto.silicone[i])
        gap = (nsga.sigma - red.sigma) / red.sigma
        if gap > WARN_GAP:
            warnings.warn(
                f"NSGA-II's sensor (σ_F {from_si(nsga.sigma, 'mN'):.3g} mN) lies {gap:.3g} "
                f"above the exact reduction's ({from_si(red.sigma, 'mN'):.3g} mN), which is "
                "kept: raise [optimise] sensor_population and sensor_generations",
                SensorGapWarning, stacklevel=2)
        elif nsga.sigma < red.sigma:
            choice = nsga
    return SensorOptimisation(choice, red, pareto, gap, combos, time.perf_counter() - t0,
                              per, space.silicones)
