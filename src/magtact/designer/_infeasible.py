"""The answer to a specification no design meets: each requirement with the best figure a design
of the study's space reaches, the requirement that binds, and the smallest change of one
requirement that makes the specification feasible (docs/method.md §10).

With a = f_r,min(H) < 0 and b = f_z,max(H) > 0 per unit G (the sweep over the H range), a design
(H, G) carries F_z,req normal when G b ≥ F_z,req and F_r,req shear when −G a ≥ F_r,req; both
grow with G, so the best a height offers is at the stiffest G of the range. The shear must also
occur within the normal range (the verdict's reading): the largest |F_r| among the loads with
F_z ≤ F_z,req, which over G is largest at the end of one of the pieces the sensor problem
splits G into (:func:`magtact.optimise.most_shear_within`). The best shear with the normal
requirement met is max over the heights where G_hi b ≥ F_z,req of the lesser of −G_hi a and
that shear over G ∈ [F_z,req / b, G_hi], and the best normal force with the shear requirement
met is max over the heights where −G_hi a ≥ F_r,req of G_hi b (at that force every load of the
stable region is within the normal range, so the shear occurs). The
requirement that binds is the one whose relaxation to that figure is the smaller relative
change; the relaxed figure is rounded down to 3 significant figures, so that it is met.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..metamodel import ModelSet
from ..optimise import (
    ForceConstraints,
    InfeasibleError,
    most_shear_within,
    silicone_ranges,
    sweep,
)
from ..study import Study, from_si
from ._verdict import Requirement, _n, footprint


class InfeasibleSpecification(InfeasibleError):
    """No design of the study's space meets its requirements; ``answer`` (an
    :class:`Infeasible`) says what binds and what to relax."""

    def __init__(self, message: str, answer: Infeasible):
        super().__init__(message)
        self.answer = answer


@dataclass(frozen=True)
class Relaxation:
    """The smallest change of one requirement that makes the specification feasible: the
    requirement's key, its required and relaxed values (SI, ``unit``) and the study key to
    change."""

    key: str
    required: float
    relaxed: float
    unit: str
    setting: str

    @property
    def text(self) -> str:
        scale = {"N": ("N", 1.0)}.get(self.unit, (self.unit, 1.0))
        return (f"{self.setting} = {_n(self.relaxed * scale[1])} (from "
                f"{_n(self.required * scale[1])} {scale[0]})")

    def to_json(self) -> dict:
        return {"requirement": self.key, "required": self.required, "relaxed": self.relaxed,
                "unit": self.unit, "setting": self.setting, "text": self.text}


@dataclass(frozen=True)
class Infeasible:
    """The answer to a specification no design meets.

    Attributes
    ----------
    requirements : tuple of Requirement
        Each requirement with the best figure reached (``met`` False for those no design meets
        together with the others, None where no design is there to judge it).
    binding : str
        Key of the requirement that binds.
    relaxation : Relaxation or None
        The smallest change of one requirement that makes it feasible (None: no change of one
        force requirement does; the message says why).
    message : str
        What the optimisation found, in words.
    """

    requirements: tuple[Requirement, ...]
    binding: str
    relaxation: Relaxation | None
    message: str
    #: The study's name.
    study: str = ""

    met = False

    @property
    def failed(self) -> tuple[str, ...]:
        return tuple(r.key for r in self.requirements if r.met is not True)

    def to_json(self) -> dict:
        return {"verdict": [r.to_json() for r in self.requirements], "binding": self.binding,
                "relaxation": None if self.relaxation is None else self.relaxation.to_json(),
                "message": self.message}

    def __str__(self) -> str:
        from .._display import infeasible_rows, text_block

        return text_block(*infeasible_rows(self.to_json()))

    def _repr_html_(self) -> str:
        from .._display import html_block, infeasible_rows

        return html_block(*infeasible_rows(self.to_json()))


def _floor_sig(x: float, digits: int = 3) -> float:
    """``x`` > 0 rounded down to ``digits`` significant figures."""
    e = math.floor(math.log10(x)) - digits + 1
    return math.floor(x / 10.0**e) * 10.0**e


def infeasibility(models: ModelSet, study: Study, constraints: ForceConstraints,
                  message: str) -> Infeasible:
    """The answer to ``study``'s infeasible force requirements (``constraints``: F_r,c ≤ 0 and
    F_z,c > 0 as :func:`magtact.optimise.force_constraints` gives them)."""
    table = sweep(models, study)
    # the G the silicones to choose from reach (the design range where none is named)
    ranges = silicone_ranges(study)[1] if study.optimise.problem == "sensor" else \
        np.array([study.design.G], float)
    G_hi = float(ranges[:, 1].max())
    # the forces every unit reaches: with a tolerance δ of G, the softest body's, (1 − δ) times
    # the nominal; the constraints hold the required forces over (1 − δ)
    k = 1.0 - constraints.tolerance
    shear = -k * G_hi * np.asarray(table.f_r_min, float)  # best shear [N] at each height
    normal = k * G_hi * np.asarray(table.f_z_max, float)
    F_r, F_z = -k * constraints.F_r_c, k * constraints.F_z_c

    def best(values, where):
        ok = where & np.isfinite(values)
        if not ok.any():
            return math.nan, -1
        i = int(np.flatnonzero(ok)[np.argmax(values[ok])])
        return float(values[i]), i

    # the shear where it occurs: among the loads within the normal force F_z (the verdict's
    # reading), over the G that carry F_z, [F_z / f_z,max, G_hi] for the softest unit
    with np.errstate(divide="ignore"):
        G_normal = np.where(table.f_z_max > 0, F_z / np.asarray(table.f_z_max, float), np.inf)
    envelope, G_envelope = np.zeros(table.H.shape), np.full(table.H.shape, np.nan)
    for lo, hi in ranges:  # the most over every silicone's G range
        e, G_e = most_shear_within(models, study, table, np.maximum(G_normal, k * lo), k * hi,
                                   F_z)
        more = e > envelope
        envelope, G_envelope = np.where(more, e, envelope), np.where(more, G_e, G_envelope)
    shear_within = np.minimum(shear, envelope)
    G_shear = np.where(envelope < shear, G_envelope / k, G_hi)  # the nominal unit's G
    shear_with, i_r = best(shear_within, normal >= F_z)
    normal_with, i_z = best(normal, shear >= F_r)
    shear_alone, _ = best(shear, np.ones(shear.shape, bool))
    normal_alone, _ = best(normal, np.ones(normal.shape, bool))

    def at(i, G=None):
        G = G_hi if G is None else float(G[i])
        return (f"H {_n(from_si(table.H[i], 'mm'))} mm, G {_n(from_si(G, 'kPa'))} kPa"
                if i >= 0 else "no height")

    # the setting to change: the study's requirement, or the force constraint given instead
    req = study.requirements
    own = math.isclose(F_r, req.F_r, rel_tol=1e-9) and math.isclose(F_z, req.F_z, rel_tol=1e-9)
    names = (("requirements.F_r_N", "requirements.F_z_N") if own
             else ("the shear force constraint |F_r,c| [N]",
                   "the normal force constraint F_z,c [N]"))
    options = []
    if math.isfinite(shear_with) and shear_with > 0:
        options.append(((F_r - shear_with) / F_r, Relaxation(
            "shear", F_r, _floor_sig(shear_with), "N", names[0])))
    if math.isfinite(normal_with) and normal_with > 0:
        options.append(((F_z - normal_with) / F_z, Relaxation(
            "normal", F_z, _floor_sig(normal_with), "N", names[1])))
    relaxation = min(options, key=lambda o: o[0])[1] if options else None
    binding = relaxation.key if relaxation is not None else (
        "shear" if shear_alone < F_r else "normal")

    items = [_force("normal", f"reads 0–{_n(F_z)} N normal without saturating", F_z,
                    normal_with, at(i_z), normal_alone, f"{_n(F_r)} N shear"),
             _force("shear", f"carries and reads 0–{_n(F_r)} N shear", F_r, shear_with,
                    at(i_r, G_shear), shear_alone, f"{_n(F_z)} N normal")]
    if req.rate > 0:
        items.append(_rate(study))
    if req.resolution > 0:
        items.append(Requirement("resolution", None,
                                 f"resolves {_n(from_si(req.resolution, 'mN'))} mN (σ_F, worst "
                                 "over the required loads)",
                                 "not judged: no design carries the required forces",
                                 math.nan, "N"))
    if req.R_max > 0:
        items.append(footprint(study))
    return Infeasible(tuple(items), binding, relaxation, message, study.name)


def _force(key: str, statement: str, required: float, together: float, where: str,
           alone: float, other: str) -> Requirement:
    """A force requirement: the best figure reached with the other force requirement met
    (``together``, NaN where no design meets the other), else on its own (no margin: it is not
    reached together)."""
    if math.isfinite(together):  # short of it: else the specification would be feasible
        return Requirement(key, False, statement, f"no: up to {_n(together)} N with {other} "
                           f"({where})", together - required, "N")
    return Requirement(key, False, statement,
                       f"no: up to {_n(alone)} N alone, not with {other}", math.nan, "N")


def _rate(study: Study) -> Requirement:
    """The rate requirement against the chip's fastest setting the study allows."""
    from ..study import candidate_settings, hall_chip, setting_figures

    req = study.requirements
    statement = f"samples at {_n(req.rate)} Hz or faster"
    chip = hall_chip(study)
    if chip.picked:
        rates = [setting_figures(study, s).rate for s in candidate_settings(study)]
    else:
        rates = [chip.figures.rate] if chip.figures is not None else []
    rates = [r for r in rates if math.isfinite(r)]
    if not rates:
        return Requirement("rate", None, statement, "not known (no sample rate in magtact's "
                           "data for this chip)", math.nan, "Hz")
    top = max(rates)
    return Requirement("rate", top >= req.rate, statement,
                       f"{'yes' if top >= req.rate else 'no'}, up to {_n(top)} Hz",
                       top - req.rate, "Hz")
