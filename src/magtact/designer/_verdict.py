"""The verdict on a design: each requirement of the study met or not, with its margin
(docs/method.md §10).

The requirements name a load envelope: every load on the loading paths inside the design's
stable region whose normal force is at most F_z,req, with the shear that comes with it up to
F_r,req (the shear requirement at the loads where it occurs under the normal range). The
sensor reads 0 to F_z,req normal when the body carries F_z,req stably and the chip stays
inside its setting's range on every path up to F_z,req: the normal force at which it first
leaves its range (root-found along each path, :func:`magtact.chip.saturation`) lies above
F_z,req. It carries and reads the shear when the body is stable up to F_r,req and the paths
reach a shear of F_r,req within the normal range before the chip leaves its range; else the
answer names the largest shear read within F_z,req ("reads shear up to 0.23 N within 5 N
normal"). The chip's y axis has the x axis's range and, by the body's symmetry, sees on a
shear along y what x sees on a shear along x: the x check holds for both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..chip import field_ratio, onset, saturation, sensor_grid
from ..metamodel import ModelSet
from ..optimise import DesignResult
from ..study import HallChip, Study, from_si

#: Load levels and shear angles of the grid on which the verdict takes σ_F over the required
#: loads; the shear envelope's paths take N_FINE[1] angles and N_FINE[0] levels each.
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
    #: The largest shear [N] on the paths within the normal range F_z ≤ F_z,req that the body
    #: carries stably, and that the chip reads (before it leaves its range).
    shear_within: float = float("nan")
    shear_read: float = float("nan")

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
        """Each requirement met or not with its margin, σ_F and saturation (≤ 25 lines)."""
        from .._display import text_block, verdict_rows

        return text_block(*verdict_rows(self))

    def _repr_html_(self) -> str:
        from .._display import html_block, verdict_rows

        return html_block(*verdict_rows(self))


def _n(x: float) -> str:
    """A number to 3 significant figures, written as short as it reads (5 N, not 5.00 N)."""
    from .._display import short

    return short(float(x))


#: A design chosen on a force constraint's boundary (G where it is just met) meets it to the
#: precision of G's computation (about 1e-8 relative): a force this close to the requirement
#: meets it.
BOUNDARY_RTOL = 1e-6


def verdict(models: ModelSet, study: Study, design: DesignResult, chip: HallChip, *,
            M_z: float | None = None, standoff: float | None = None) -> Verdict:
    """The verdict on ``design`` with ``chip`` at its setting, against ``[requirements]``, with
    the design's magnetisation ``M_z`` [A/m] and the chip at ``standoff`` [m] (default: the
    study's; see the module notes)."""
    req = study.requirements
    grid = sensor_grid(models, study, design.H, design.t_m, design.theta_m, standoff,
                       n=N_FINE)
    M_z = study.magnet.M_z if M_z is None else float(M_z)
    sat = saturation(study, models, design.H, design.G, chip, design.t_m, design.theta_m,
                     M_z=M_z, standoff=standoff)
    F_sat = math.inf if sat.F_z is None else sat.F_z
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
    within, read = shear_envelope(models, study, design, chip, req.F_z, M_z=M_z,
                                  standoff=standoff)
    stable = shear >= req.F_r * (1.0 - BOUNDARY_RTOL)
    occurs = within >= req.F_r * (1.0 - BOUNDARY_RTOL)
    read_all = read >= req.F_r * (1.0 - BOUNDARY_RTOL)
    if not stable:
        text = f"no: shear turns unstable at {_n(shear)} N"
    elif not occurs:
        text = (f"no: the body carries at most {_n(within)} N of shear within {_n(req.F_z)} N "
                "normal")
    elif not read_all:
        text = f"no: reads shear up to {_n(read)} N within {_n(req.F_z)} N normal"
    else:
        text = f"yes, stable up to {_n(shear)} N"
    items.append(Requirement("shear", stable and occurs and read_all,
                             f"carries and reads 0–{_n(req.F_r)} N shear", text,
                             min(shear, read) - req.F_r, "N"))
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
        items.append(footprint(study))
    return Verdict(tuple(items), s_r, s_z, F_sat, within, read)


def footprint(study: Study) -> Requirement:
    """The footprint requirement: the body's radius within ``[requirements] R_max_mm``."""
    R, R_max = study.body.R, study.requirements.R_max
    return Requirement("footprint", R <= R_max,
                       f"fits a body radius of {_n(from_si(R_max, 'mm'))} mm",
                       f"{'yes' if R <= R_max else 'no'}, {_n(from_si(R, 'mm'))} mm",
                       R_max - R, "m")


def shear_envelope(models: ModelSet, study: Study, design: DesignResult, chip: HallChip,
                   F_z: float, n: tuple[int, int] = N_FINE, *, M_z: float | None = None,
                   standoff: float | None = None) -> tuple[float, float]:
    """The largest shear |F_r| [N] on the paths of the stable region within the normal force
    F_z [N]: that the body carries (every load up to F_z on each path), and that the chip
    reads (the loads before it leaves its range on each path).

    On each of ``n[1]`` paths θ ∈ [0, θ_m] the load at which the normal force reaches F_z and
    the load at which the chip leaves its range are root-found; |F_r| is taken on ``n[0]``
    levels up to each (both ends included).
    """
    H, G, t_m = design.H, design.G, design.t_m
    th = np.linspace(0.0, design.theta_m, n[1])
    t_F = np.full(th.size, t_m)  # where G f_z reaches F_z (f_z grows along a path)
    below = np.asarray(models.forces(t_m, th, H, G)[1], float) > F_z
    if below.any():
        lo, hi = np.zeros(int(below.sum())), np.full(int(below.sum()), t_m)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            over = np.asarray(models.forces(mid, th[below], H, G)[1], float) > F_z
            hi, lo = np.where(over, mid, hi), np.where(over, lo, mid)
        t_F[below] = lo
    t_on = onset(field_ratio(study, H, chip, M_z=M_z, standoff=standoff), th, t_m)
    t_read = np.where(np.isnan(t_on), t_F, np.minimum(t_F, t_on))
    s = np.linspace(0.0, 1.0, n[0])[:, None]
    F_r_body = np.abs(np.asarray(models.forces(s * t_F, th, H, G)[0], float))
    # the chip reads up to (not at) the load where it leaves its range
    F_r_read = np.abs(np.asarray(models.forces(s * t_read, th, H, G)[0], float))
    return float(F_r_body.max()), float(F_r_read.max())
