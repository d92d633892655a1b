"""The tolerance box of a design: each input a built unit may differ in, its range and its
distribution (docs/method.md §16).

Inputs, in the order of the columns of a unit's values:

- ``B_r``: the magnet's remanence over the nominal one (the grade's catalogue range, uniform;
  a custom magnet: ``[tolerances] remanence``, normal);
- ``temperature`` [°C]: ``[tolerances] temperature_C``, uniform; the remanence follows the
  grade's coefficient from 20 °C;
- ``chip_sensitivity``: the chip's gain over its nominal one minus 1, ± the datasheet's band,
  uniform;
- ``G``: the shear modulus over the nominal one minus 1 (``[tolerances] G``, normal);
- ``H``, ``standoff``, ``R_m``, ``H_m`` [m]: the body's height, the chip's distance below it,
  the magnet's radius (half the diameter's spread) and height, each minus the nominal (normal);
- ``chip_offset``: the chip's offset in units of its band (± 1 on x and z together), uniform;
- ``fe_bias``: how far the FE forces lie above the true ones, [0, ``fe_force_bias``]: a
  property of the model, common to every unit (the yield takes it at its adverse end).

A normal spread is truncated at ±``coverage`` standard deviations: the box holds every unit
the verdict speaks for, so that its worst corner bounds every sampled unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..study import ROOM_C, Study, StudyError

#: The inputs, in column order.
INPUTS = ("B_r", "temperature", "chip_sensitivity", "G", "H", "standoff", "R_m", "H_m",
          "chip_offset", "fe_bias")
#: The inputs that scale the chip's reading (the field's strength): the reading's worst end is
#: the same for each of them (monotone, see :func:`corners`).
FIELD_SCALE = ("B_r", "temperature", "chip_sensitivity")
#: Words for each input (the verdict's "limited by").
WORDS = {"B_r": "B_r", "temperature": "temperature", "chip_sensitivity": "chip sensitivity",
         "G": "G", "H": "body height", "standoff": "standoff", "R_m": "magnet diameter",
         "H_m": "magnet height", "chip_offset": "chip offset", "fe_bias": "FE force bias"}


@dataclass(frozen=True)
class Tolerance:
    """One input: nominal value, the box [low, high], the distribution (``"uniform"`` over
    the box or ``"normal"`` with ``sigma`` truncated to it) and where its figure comes from."""

    name: str
    nominal: float
    low: float
    high: float
    distribution: str
    sigma: float
    source: str

    def ppf(self, u) -> np.ndarray:
        """Values at probabilities u ∈ [0, 1] (inverse of the distribution function)."""
        u = np.asarray(u, float)
        if self.high <= self.low:
            return np.full(u.shape, self.nominal)
        if self.distribution == "uniform":
            return self.low + u * (self.high - self.low)
        a, b = (self.low - self.nominal) / self.sigma, (self.high - self.nominal) / self.sigma
        return self.nominal + self.sigma * stats.truncnorm.ppf(u, a, b)


@dataclass(frozen=True)
class ToleranceBox:
    """The inputs of a design (:data:`INPUTS` order), the remanence's temperature
    coefficient α [1/K] and the chip's offset band (x, z) [T]."""

    inputs: tuple[Tolerance, ...]
    alpha: float
    offset: tuple[float, float]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.inputs)

    @property
    def nominal(self) -> np.ndarray:
        return np.array([t.nominal for t in self.inputs])

    @property
    def low(self) -> np.ndarray:
        return np.array([t.low for t in self.inputs])

    @property
    def high(self) -> np.ndarray:
        return np.array([t.high for t in self.inputs])

    def index(self, name: str) -> int:
        return self.names.index(name)

    def sample(self, u: np.ndarray) -> np.ndarray:
        """Units at points u (n, d) of the unit cube, one column per input."""
        return np.column_stack([t.ppf(u[:, k]) for k, t in enumerate(self.inputs)])


def tolerance_box(study: Study, grade: str | None = None) -> ToleranceBox:
    """The tolerance box of a design of ``study`` with a magnet of ``grade`` (default: the
    study's; ``"custom"``: the study's remanence tolerance) and the study's chip (see the
    module notes).

    Raises
    ------
    StudyError
        Naming ``tolerances.temperature_C`` for a range whose ends are reversed.
    """
    from ..parts import chip_part
    from ..parts import grade as catalogue_grade

    tol = study.tolerances
    grade = study.magnet.grade if grade is None else grade
    k = tol.coverage

    def normal(name, sigma, source, scale=1.0):
        s = sigma * scale
        return Tolerance(name, 0.0, -k * s, k * s, "normal", s, source)

    if grade != "custom":
        g = catalogue_grade(grade)
        B_r = Tolerance("B_r", 1.0, g.B_r_min / g.B_r, g.B_r_max / g.B_r, "uniform", 0.0,
                        f"grade {g.name}: {g.B_r_min:g}–{g.B_r_max:g} T ({g.source})")
        alpha = g.alpha
    else:
        B_r = normal("B_r", tol.remanence, "tolerances.remanence_pct (a custom magnet)")
        B_r = Tolerance("B_r", 1.0, 1.0 + B_r.low, 1.0 + B_r.high, "normal", B_r.sigma,
                        B_r.source)
        alpha = study.environment.remanence_tc
    lo_T, hi_T = tol.temperature_C
    if lo_T > hi_T:
        raise StudyError("tolerances.temperature_C", f"[{lo_T:g}, {hi_T:g}] °C: give the "
                                                     "lowest temperature first")
    temperature = Tolerance("temperature", ROOM_C, lo_T, hi_T, "uniform", 0.0,
                            "tolerances.temperature_C (assumed working range)")
    gain, off_x, off_z, chip_source = tol.chip_sensitivity, tol.chip_offset_x, \
        tol.chip_offset_z, "tolerances.chip_*"
    data = chip_part(study.hall.chip).tolerance()
    if data is not None:
        gain = gain or data[0]
        off_x, off_z = off_x or data[1], off_z or data[2]
        chip_source = f"{study.hall.chip} datasheet: {data[3]}"
    inputs = (
        B_r, temperature,
        Tolerance("chip_sensitivity", 0.0, -gain, gain, "uniform", 0.0, chip_source),
        normal("G", tol.G, "tolerances.G_pct (batch and cure; assumed)"),
        normal("H", tol.body_height, "tolerances.body_height_mm (assumed)"),
        normal("standoff", tol.chip_vertical, "tolerances.chip_vertical_mm (assumed)"),
        normal("R_m", tol.magnet_diameter, "tolerances.magnet_diameter_mm (half of it)", 0.5),
        normal("H_m", tol.magnet_height, "tolerances.magnet_height_mm"),
        Tolerance("chip_offset", 0.0, -1.0 if off_x or off_z else 0.0,
                  1.0 if off_x or off_z else 0.0, "uniform", 0.0, chip_source),
        Tolerance("fe_bias", 0.0, 0.0, tol.fe_force_bias, "uniform", 0.0,
                  "tolerances.fe_force_bias_pct (docs/verification.md)"),
    )
    return ToleranceBox(inputs, alpha, (off_x, off_z))


def corners(box: ToleranceBox) -> np.ndarray:
    """The corners of the box the worst case is searched over, one unit per row.

    The reading's strength (B_r, temperature, the chip's sensitivity) is monotone in each
    requirement: a stronger field leaves the range earlier at every load and a weaker one
    gives a larger σ_F, so these take their two joint ends (strong: B_r and sensitivity high,
    temperature low as α < 0; weak: the opposite); the FE bias lowers every force, so it takes
    its high end. The other inputs (G, H, standoff, the magnet's size, the offset) are not
    monotone in every requirement and take every combination of their ends: 2 × 2^6 units.
    """
    names = box.names
    free = [i for i, n in enumerate(names) if n not in FIELD_SCALE and n != "fe_bias"]
    grid = np.array(np.meshgrid(*[[0, 1]] * len(free), indexing="ij")).reshape(len(free), -1).T
    rows = []
    for strong in (True, False):
        base = box.nominal.copy()
        for n in ("B_r", "chip_sensitivity"):
            i = box.index(n)
            base[i] = box.high[i] if strong else box.low[i]
        i = box.index("temperature")  # α < 0: the cold end is the strong one
        base[i] = box.low[i] if strong == (box.alpha <= 0) else box.high[i]
        base[box.index("fe_bias")] = box.inputs[box.index("fe_bias")].high
        for g in grid:
            u = base.copy()
            u[free] = np.where(g == 1, box.high[free], box.low[free])
            rows.append(u)
    return np.unique(np.array(rows), axis=0)
