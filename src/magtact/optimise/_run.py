"""The whole optimisation stage: maps, exact reduction, NSGA-II, decision; and its files."""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import json_dict, json_number, json_text, significant, write_csv
from ..metamodel import ModelSet
from ..sensitivity import Responses
from ..study import Study, from_si, to_si
from ._conditioning import shear_bound_conditioning
from ._design import DesignMaps, DesignResult, as_responses, design_maps
from ._pareto import (
    Choice,
    ForceConstraints,
    ParetoSet,
    Reduction,
    choose,
    exact_reduction,
    force_constraints,
    front_gap,
    pareto_nsga2,
    reduction_set,
    sweep,
)
from ._setting import sigma_objective


@dataclass(frozen=True)
class Timings:
    """Wall times of the parts of :func:`optimise` [s]."""

    constraints: float
    sweep: float
    nsga2: float
    decision: float
    maps: float

    @property
    def total(self) -> float:
        """Sum of the parts [s]."""
        return self.constraints + self.sweep + self.nsga2 + self.decision + self.maps


#: Relative distance of NSGA-II's Pareto set from the exact front above which the two answers
#: disagree: a :class:`FrontGapWarning` (a gap that is not a number is an error).
WARN_FRONT_GAP = 0.05


#: What the objective columns (``Gamma_*``) of the tables hold, per ``[optimise] objective``.
OBJECTIVE_NOTE = {
    "gamma": "Gamma_* columns: the worst sensitivity Γ = |∂F/∂B| [N/T]",
    "sigma_F": "Gamma_* columns: the worst force noise σ_F [N] at the chip's setting "
               "(the noise-weighted Jacobian; their keys keep the Γ names)",
}


class FrontGapWarning(UserWarning):
    """NSGA-II's Pareto set lies off the exact front: its chosen design is not to be trusted
    (too small a budget, or design ranges far wider than the sensor's)."""


@dataclass(frozen=True)
class Optimisation:
    """Everything the optimisation stage computes for one study.

    Attributes
    ----------
    constraints : ForceConstraints
    maps : DesignMaps
        Per-design results on the ``grid_n × grid_n`` grid.
    reduction : Reduction
        The exact Pareto set over H.
    pareto : ParetoSet
        NSGA-II's Pareto set.
    choice : Choice
        The design the decision rule picks from NSGA-II's set (the stage's answer).
    reduction_choice : Choice
        The decision rule applied to the exact front (cross-check).
    gap : float
        :func:`front_gap` of NSGA-II's set from the exact front (relative).
    timings : Timings
    """

    study: Study
    constraints: ForceConstraints
    maps: DesignMaps
    reduction: Reduction
    pareto: ParetoSet
    choice: Choice
    reduction_choice: Choice
    gap: float
    timings: Timings

    def write(self, out: str | Path,
              figures: Callable[..., list[Path]] | None = None) -> list[Path]:
        """Write ``design.json``, ``pareto.csv``, ``reduction.csv``, ``maps.csv`` and, with
        ``figures``, the figures.

        ``figures(optimisation, out)`` draws them and returns the files
        (:func:`magtact.report.optimise_figures`). Returns the files written. Tables are in user
        units (mm, kPa, N, N/T).
        """
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        files = [self._write_json(out / "design.json"), self._write_pareto(out / "pareto.csv"),
                 self._write_reduction(out / "reduction.csv"), self.maps.to_csv(out / "maps.csv")]
        if figures is not None:
            files += figures(self, out)
        return files

    def _write_json(self, path: Path) -> Path:
        c = self.constraints
        doc = {
            "study": self.study.name,
            "sensitivity_definition": self.study.sensitivity.definition,
            "objective": self.study.optimise.objective,
            "objective_note": OBJECTIVE_NOTE[self.study.optimise.objective],
            "constraints": {
                "F_r_c_N": c.F_r_c, "F_z_c_N": c.F_z_c, "source": c.source,
                "reference": None if c.reference is None else _design_json(c.reference),
            },
            "chosen": _choice_json(self.choice),
            "exact_reduction_choice": _choice_json(self.reduction_choice),
            "pareto": {"points": int(self.pareto.H.size), "seed": self.pareto.seed,
                       "population": self.study.optimise.population,
                       "generations": self.pareto.generations,
                       "evaluations": self.pareto.evaluations,
                       "gap_to_exact_front": self.gap},
            "timings_s": {"constraints": self.timings.constraints, "sweep": self.timings.sweep,
                          "nsga2": self.timings.nsga2, "decision": self.timings.decision,
                          "maps": self.timings.maps, "total": self.timings.total},
        }
        path.write_text(json.dumps(doc, indent=2) + "\n")
        return path

    def _write_pareto(self, path: Path) -> Path:
        p = self.pareto
        g_r, g_z = self.constraints.margins(p.F_r_min, p.F_z_max)
        cols = [from_si(p.H, "mm"), from_si(p.G, "kPa"), *self._M_z(p.M_z), p.Gamma_r_max,
                p.Gamma_z_max, p.F_r_min, p.F_z_max, g_r, g_z]
        return _csv(path, ["H_mm", "G_kPa", *self._M_z(["M_z_A_per_m"]),
                           "Gamma_r_max_N_per_T", "Gamma_z_max_N_per_T", "F_r_min_N",
                           "F_z_max_N", "g_r_N", "g_z_N"], zip(*cols, strict=True))

    def _write_reduction(self, path: Path) -> Path:
        r = self.reduction
        t = r.table
        cols = [from_si(r.H, "mm"), from_si(r.G_star, "kPa"), *self._M_z(r.M_z_star), r.Gamma_r,
                r.Gamma_z, r.G_star * t.f_r_min, r.G_star * t.f_z_max, t.t_m, t.theta_m,
                r.front.astype(int)]
        return _csv(path, ["H_mm", "G_star_kPa", *self._M_z(["M_z_star_A_per_m"]),
                           "Gamma_r_max_N_per_T", "Gamma_z_max_N_per_T", "F_r_min_N",
                           "F_z_max_N", "t_m", "theta_m_rad", "on_front"], zip(*cols, strict=True))

    def _M_z(self, column) -> list:
        """``[column]`` where M_z is a design variable, else nothing."""
        return [column] if self.study.M_z_variable else []


def _csv(path: Path, header: list[str], rows) -> Path:
    return write_csv(path, header, rows, cell=significant(12))


def design_json(d: DesignResult) -> dict:
    """A design's variables and extrema in user units, each key naming its unit."""
    return _design_json(d)


def _design_json(d: DesignResult) -> dict:
    out = {"H_mm": from_si(d.H, "mm"), "G_kPa": from_si(d.G, "kPa")}
    if d.M_z is not None:  # a design variable
        out["M_z_A_per_m"] = from_si(d.M_z, "A_per_m")
    return out | {"Gamma_r_max_N_per_T": d.Gamma_r_max, "Gamma_z_max_N_per_T": d.Gamma_z_max,
                  "F_r_min_N": d.F_r_min, "F_z_max_N": d.F_z_max, "t_m": d.t_m,
                  "theta_m_rad": d.theta_m, "degenerate": d.degenerate}


def _choice_json(c: Choice) -> dict:
    return {**_design_json(c.design), "g_r_N": c.g_r, "g_z_N": c.g_z,
            "active_constraints": list(c.active)}


@dataclass(frozen=True)
class ChosenFile:
    """``chosen.json`` read back, in SI: the chosen design as :func:`write_optimise_outputs`,
    :meth:`magtact.optimise.SensorOptimisation.write` and (its ``choice``) ``geometry.json``
    write it. A field the file does not give (or gives with the wrong type) is None.

    Attributes
    ----------
    design : str or None
        The design in words (over geometric design variables).
    H, G, M_z : float or None
        Base height [m], shear modulus [Pa], magnetisation [A/m].
    Gamma_r_max, Gamma_z_max : float or None
        The objectives: worst Γ [N/T], or worst σ_F [N] where ``objective`` is ``"sigma_F"``.
    F_r_min, F_z_max : float or None
        Force extrema [N].
    t_m, theta_m : float or None
        The stable region's bounds [1, rad].
    g_r, g_z : float or None
        Margins to the force constraints [N] (≤ 0: met).
    F_r_c, F_z_c : float or None
        The force constraints [N]; ``constraints_source`` where they come from; all None where
        the file has no constraints.
    active_constraints, degenerate, sensitivity_definition, objective : str or None
    """

    design: str | None = None
    H: float | None = None
    G: float | None = None
    M_z: float | None = None
    Gamma_r_max: float | None = None
    Gamma_z_max: float | None = None
    F_r_min: float | None = None
    F_z_max: float | None = None
    t_m: float | None = None
    theta_m: float | None = None
    g_r: float | None = None
    g_z: float | None = None
    F_r_c: float | None = None
    F_z_c: float | None = None
    constraints_source: str | None = None
    has_constraints: bool = False
    active_constraints: str | None = None
    degenerate: str | None = None
    sensitivity_definition: str | None = None
    objective: str | None = None

    @classmethod
    def from_json(cls, data) -> ChosenFile | None:
        """The chosen design of ``chosen.json``'s document; None for anything but a non-empty
        JSON object."""
        if not isinstance(data, dict) or not data:
            return None

        def num(key: str, unit: str | None = None) -> float | None:
            v = json_number(data.get(key))
            return v if v is None or unit is None else to_si(v, unit)

        def text(key: str) -> str | None:
            v = data.get(key)
            return None if v is None else json_text(v)

        c = data.get("constraints")
        given = isinstance(c, dict)
        c = json_dict(c)
        active = data.get("active_constraints")
        return cls(design=text("design"), H=num("H_mm", "mm"), G=num("G_kPa", "kPa"),
                   M_z=num("M_z_A_per_m", "A_per_m"), Gamma_r_max=num("Gamma_r_max_N_per_T"),
                   Gamma_z_max=num("Gamma_z_max_N_per_T"), F_r_min=num("F_r_min_N"),
                   F_z_max=num("F_z_max_N"), t_m=num("t_m"), theta_m=num("theta_m_rad"),
                   g_r=num("g_r_N"), g_z=num("g_z_N"), F_r_c=json_number(c.get("F_r_c_N")),
                   F_z_c=json_number(c.get("F_z_c_N")),
                   constraints_source=None if c.get("source") is None
                   else json_text(c.get("source")), has_constraints=given,
                   active_constraints=None if active is None else json_text(
                       ", ".join(map(str, active)) if isinstance(active, list) else active),
                   degenerate=text("degenerate"),
                   sensitivity_definition=text("sensitivity_definition"),
                   objective=text("objective"))


def design_file_definition(data) -> str | None:
    """The sensitivity definition recorded in ``design.json``'s document (None if none)."""
    v = data.get("sensitivity_definition") if isinstance(data, dict) else None
    return None if v is None else json_text(v)


def optimise(models: Responses | ModelSet, study: Study,
             constraints: ForceConstraints | None = None) -> Optimisation:
    """Run the optimisation stage: constraints, sweep + exact reduction, NSGA-II, choice, maps.

    In the sensor problem (``optimise.problem = "sensor"``) the (H, G) problem is the
    publication's, kept beside the whole sensor for the report: its Pareto set is the exact
    reduction's front (:func:`reduction_set`) and NSGA-II is not run (NSGA-II cross-checks the
    sensor problem itself, :func:`optimise_sensor`).

    Parameters
    ----------
    models : Responses or ModelSet
    study : Study
    constraints : ForceConstraints, optional
        Default: :func:`force_constraints` from the study's ``[constraints]`` table.

    Raises
    ------
    InfeasibleError
        If no design in the bounds meets the constraints (with the best reachable values).
    """
    if isinstance(models, ModelSet) and study.optimise.objective == "sigma_F":
        R = sigma_objective(models, study).responses  # the force-noise objective (§10)
    else:
        R = as_responses(models)
    R.models.check_finite(study)  # no NaN or inf from a model into the results
    clock = time.perf_counter
    t0 = clock()
    constraints = force_constraints(R, study) if constraints is None else constraints
    t1 = clock()
    table = sweep(R, study)
    reduction = exact_reduction(R, study, constraints, table)
    t2 = clock()
    pareto: ParetoSet = (reduction_set(reduction, study) if study.optimise.problem == "sensor"
                         else pareto_nsga2(R, study, constraints, table))
    t3 = clock()
    choice = choose(R, study, pareto)
    reduction_choice = choose(R, study, reduction)
    gap = front_gap(pareto, reduction)
    if not gap <= WARN_FRONT_GAP:  # NSGA-II and the exact reduction must tell the same story
        e, d = reduction_choice.design, choice.design
        text = (f"NSGA-II's Pareto set lies {gap:.3g} (relative) from the exact reduction's "
                f"front, more than {WARN_FRONT_GAP:g}: its choice H = {from_si(d.H, 'mm'):.4g} "
                f"mm, G = {from_si(d.G, 'kPa'):.4g} kPa disagrees with the exact reduction's "
                f"H = {from_si(e.H, 'mm'):.4g} mm, G = {from_si(e.G, 'kPa'):.4g} kPa; check the "
                "design ranges or raise [optimise] population and nsga2_generations")
        if not np.isfinite(gap):
            raise MagtactError(text)
        warnings.warn(text, FrontGapWarning, stacklevel=2)
    t4 = clock()
    maps = design_maps(R, study)
    t5 = clock()
    return Optimisation(study, constraints, maps, reduction, pareto, choice, reduction_choice,
                        gap, Timings(t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4))



#: Captions of the stage's figures and tables (read by the HTML report).
CAPTIONS = {
    "maps_objectives": "Objectives over the design space: Γ_r,max (solid) and Γ_z,max (dashed) "
                       "[N/T], per-design extrema on the map grid.",
    "maps_constraints": "Constraints over the design space: F_r,min (solid) and F_z,max "
                        "(dashed) [N]; bold lines at the limits F_r,c and F_z,c.",
    "pareto_set": "Pareto set of NSGA-II (points) and of the exact reduction (grey line) in "
              "objective, constraint and design space; the chosen design is the star.",
    "pareto": "NSGA-II's Pareto set (H, G, objectives, constraints).",
    "maps": "Per-design extrema on the (H, G) map grid.",
    "reduction": "Exact reduction: smallest feasible G*(H) and the objectives along it.",
    "shear_bound": "How well-posed the stable-shear bound is, per height (G cancels): t_m "
                   "(grid minimum of F_r), the smallest t at which F_r is within 1 % of its "
                   "range of that minimum, and how much F_z,max drops between the two.",
}


#: The captions that change where the Pareto set is the exact reduction's (the sensor problem).
EXACT_CAPTIONS = {
    "pareto_set": "Pareto set of the exact reduction (points and grey line) in objective, "
                  "constraint and design space; the chosen design is the star.",
    "pareto": "The exact reduction's Pareto set (H, G, objectives, constraints).",
}


def write_optimise_outputs(result: Optimisation, models: Responses | ModelSet,
                           folder: str | Path, *,
                           figures: Callable[..., list[Path]] | None = None) -> list[Path]:
    """Write an optimisation's files into ``folder``; return the files written.

    Besides :meth:`Optimisation.write` (which receives ``figures``), writes ``chosen.json``
    (the chosen design as flat values in user units, for the report), ``shear_bound.csv``
    (how well-posed the stable-shear bound is per height, from ``models``) and
    ``captions.json``.
    """
    folder = Path(folder)
    study = result.study
    files = result.write(folder, figures=figures)
    cond = shear_bound_conditioning(models, study, np.linspace(*study.design.H, 9))
    files.append(_csv(folder / "shear_bound.csv",
                      ["H_mm", "t_m", "t_within_1_percent", "F_z_max_drop_percent"],
                      zip(from_si(cond.H, "mm"), cond.t_m, cond.t_tol, 100 * cond.dF_z_rel,
                          strict=True)))
    c = result.choice
    flat = {k: v for k, v in _choice_json(c).items() if k != "active_constraints"}
    flat["active_constraints"] = ", ".join(c.active) or "none"
    flat["sensitivity_definition"] = study.sensitivity.definition
    flat["objective"] = study.optimise.objective
    flat["constraints"] = {"F_r_c_N": result.constraints.F_r_c,
                           "F_z_c_N": result.constraints.F_z_c,
                           "source": result.constraints.source}
    captions = CAPTIONS if result.pareto.generations else CAPTIONS | EXACT_CAPTIONS
    for name, doc in (("chosen.json", flat), ("captions.json", captions)):
        (folder / name).write_text(json.dumps(doc, indent=2) + "\n")
        files.append(folder / name)
    return files
