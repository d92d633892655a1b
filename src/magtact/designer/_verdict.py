"""The verdict on a design: each requirement of the study met or not, with its margin
(docs/method.md §10).

The chip's reading is checked on a fine grid over the design's stable region
(:data:`N_FINE` load levels × shear angles): the sensor reads 0 to F_z,req normal when the body
carries F_z,req stably and no grid point whose normal force is at most F_z,req lies outside the
range of the chip's setting; it carries and reads the shear force when, besides, its stable
shear reaches F_r,req.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..chip import sensor_grid
from ..metamodel import ModelSet
from ..optimise import DesignResult
from ..study import HallChip, Study, from_si

#: Load levels and shear angles of the grid on which the verdict checks the chip's reading.
N_FINE = (201, 21)


@dataclass(frozen=True)
class Requirement:
    """One requirement and how a design meets it.

    ``met`` is None where it cannot be known (a chip without a sample rate in magtact's data);
    ``margin`` is how far the design is beyond the requirement in ``unit`` (negative: short of
    it; NaN: not known).
    """

    key: str
    met: bool | None
    #: What is required ("reads 0–5 N normal without saturating") and the design's answer
    #: ("yes, saturates at 6.2 N").
    statement: str
    answer: str
    margin: float
    unit: str

    @property
    def text(self) -> str:
        """The requirement and the answer in one line."""
        return f"{self.statement}: {self.answer}"

    def to_json(self) -> dict:
        return {"requirement": self.key, "met": self.met, "text": self.text,
                "statement": self.statement, "answer": self.answer,
                "margin": None if math.isnan(self.margin) else self.margin, "unit": self.unit}


@dataclass(frozen=True)
class Verdict:
    """Every requirement of the study for one design, in the order a specification lists
    them; also the σ_F over the required loads and where the chip saturates."""

    requirements: tuple[Requirement, ...]
    #: Worst σ_F,r, σ_F,z [N] over the required loads (G f_z ≤ F_z,req).
    sigma_r: float
    sigma_z: float
    #: Smallest normal force [N] at which the chip has left its range (inf: never in the
    #: stable region).
    F_saturation: float

    @property
    def met(self) -> bool:
        """Whether every requirement is met (an unknown one counts as not met)."""
        return all(r.met is True for r in self.requirements)

    @property
    def failed(self) -> tuple[str, ...]:
        """Keys of the requirements not met (or not known)."""
        return tuple(r.key for r in self.requirements if r.met is not True)

    def __getitem__(self, key: str) -> Requirement:
        for r in self.requirements:
            if r.key == key:
                return r
        raise KeyError(f"no requirement {key!r}; requirements: "
                       f"{[r.key for r in self.requirements]}")

    def to_json(self) -> list[dict]:
        return [r.to_json() for r in self.requirements]

    def __str__(self) -> str:
        return "\n".join(r.text for r in self.requirements)


def _n(x: float) -> str:
    return f"{x:.3g}"


#: A design chosen on a force constraint's boundary (G where it is just met) meets it to the
#: precision of G's computation (about 1e-8 relative): a force this close to the requirement
#: meets it.
BOUNDARY_RTOL = 1e-6


def verdict(models: ModelSet, study: Study, design: DesignResult, chip: HallChip) -> Verdict:
    """The verdict on ``design`` with ``chip`` at its setting, against ``[requirements]``
    (``study`` holds the design's magnet and the chip's standoff)."""
    req = study.requirements
    grid = sensor_grid(models, study, design.H, design.t_m, design.theta_m, n=N_FINE)
    M_z = study.magnet.M_z
    F_sat = float(grid.F_saturation(design.G, M_z, chip.range_x, chip.range_z)[0])
    if chip.noise is None:
        s_r = s_z = math.nan
    else:
        s_r, s_z = (float(v[0]) for v in grid.sigma(design.G, M_z, *chip.noise, req.F_z))
    carries = design.F_z_max >= req.F_z * (1.0 - BOUNDARY_RTOL)
    reads = F_sat > req.F_z
    items = []
    if not carries:
        text = f"no: the body carries {_n(design.F_z_max)} N stably"
    elif not reads:
        text = f"no: the chip saturates at {_n(F_sat)} N"
    elif math.isinf(F_sat):
        text = f"yes, never saturates in the stable region (up to {_n(design.F_z_max)} N)"
    else:
        text = f"yes, saturates at {_n(F_sat)} N"
    items.append(Requirement("normal", carries and reads,
                             f"reads 0–{_n(req.F_z)} N normal without saturating", text,
                             min(design.F_z_max, F_sat) - req.F_z, "N"))
    shear = -design.F_r_min
    stable = shear >= req.F_r * (1.0 - BOUNDARY_RTOL)
    if not stable:
        text = f"no: shear turns unstable at {_n(shear)} N"
    elif not reads:
        text = "no: the chip saturates within the required loads"
    else:
        text = f"yes, stable up to {_n(shear)} N"
    items.append(Requirement("shear", stable and reads,
                             f"carries and reads 0–{_n(req.F_r)} N shear", text,
                             shear - req.F_r, "N"))
    if req.rate > 0:
        rate = None if chip.figures is None else chip.figures.rate
        if rate is None:
            items.append(Requirement("rate", None, f"samples at {_n(req.rate)} Hz or faster",
                                     f"not known (magtact has no sample rate for the "
                                     f"{chip.name})", math.nan, "Hz"))
        else:
            items.append(Requirement("rate", rate >= req.rate,
                                     f"samples at {_n(req.rate)} Hz or faster",
                                     f"{'yes' if rate >= req.rate else 'no'}, {_n(rate)} Hz",
                                     rate - req.rate, "Hz"))
    if req.resolution > 0:
        sigma = max(s_r, s_z)
        ok = bool(sigma <= req.resolution) if not math.isnan(sigma) else None
        word = "not known (the chip's noise is not known)" if ok is None else (
            f"{'yes' if ok else 'no'}, σ_F {_n(from_si(sigma, 'mN'))} mN")
        items.append(Requirement("resolution", ok,
                                 f"resolves {_n(from_si(req.resolution, 'mN'))} mN (σ_F, worst "
                                 "over the required loads)", word, req.resolution - sigma,
                                 "N"))
    if req.R_max > 0:
        R = study.body.R
        items.append(Requirement("footprint", R <= req.R_max,
                                 f"fits a body radius of {_n(from_si(req.R_max, 'mm'))} mm",
                                 f"{'yes' if R <= req.R_max else 'no'}, "
                                 f"{_n(from_si(R, 'mm'))} mm", req.R_max - R, "m"))
    return Verdict(tuple(items), s_r, s_z, F_sat)
