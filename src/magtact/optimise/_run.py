"""The whole optimisation stage: maps, exact reduction, NSGA-II, decision; and its files."""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import MagtactError
from .._files import significant, write_csv, write_json
from .._records import declared, entry, from_json_lenient, keys, to_json
from ..metamodel import ModelSet
from ..sensitivity import Responses
from ..study import Study, from_si
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


@dataclass(frozen=True)
class TimingsRecord:
    """:class:`Timings` as ``design.json``'s ``timings_s`` holds it (seconds), with the
    total."""

    constraints: float = entry()
    sweep: float = entry()
    nsga2: float = entry()
    decision: float = entry()
    maps: float = entry()
    total: float = entry()


@dataclass(frozen=True)
class Extrema:
    """A design's variables and force extrema as the files hold them (the leading columns of
    ``pareto.csv``, the leading keys of a design in ``design.json`` and ``chosen.json``), in SI.

    ``M_z`` [A/m] is None (left out of the file) where it is not a design variable; the
    objectives ``Gamma_*`` [N/T] hold σ_F [N] where the study's objective is ``"sigma_F"``.
    """

    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    M_z: float | None = entry(unit="A_per_m", optional=True, omit="none", default=None,
                              kw_only=True)
    Gamma_r_max: float = entry(unit="N_per_T")
    Gamma_z_max: float = entry(unit="N_per_T")
    F_r_min: float = entry(unit="N")
    F_z_max: float = entry(unit="N")


@dataclass(frozen=True)
class DesignRecord(Extrema):
    """A design (:class:`DesignResult`) in the files: its extrema, the stable region's bounds
    t_m [1], θ_m [rad] and why the design is degenerate (None where it is not)."""

    t_m: float = entry()
    theta_m: float = entry(unit="rad")
    degenerate: str | None = entry(kind=str, optional=True)


@dataclass(frozen=True)
class ChoiceRecord(DesignRecord):
    """A chosen design (:class:`Choice`) in ``design.json``: the design, its margins to the
    force constraints [N] and the active constraints."""

    g_r: float = entry(unit="N")
    g_z: float = entry(unit="N")
    active_constraints: tuple[str, ...] = entry(kind=str, levels=("list",))


@dataclass(frozen=True)
class Limits:
    """The force constraints F_r,c, F_z,c [N] and where they come from."""

    F_r_c: float = entry(unit="N")
    F_z_c: float = entry(unit="N")
    source: str = entry(kind=str)


@dataclass(frozen=True)
class ConstraintsRecord(Limits):
    """The force constraints (:class:`ForceConstraints`) in ``design.json``, with the reference
    design they were taken from (None: given as values)."""

    reference: DesignRecord | None = entry(kind=DesignRecord, optional=True)


@dataclass(frozen=True)
class ParetoRecord:
    """The Pareto set's size and how it was found, in ``design.json``."""

    points: int = entry(kind=int)
    seed: int = entry(kind=int)
    population: int = entry(kind=int)
    generations: int = entry(kind=int)
    evaluations: int = entry(kind=int)
    gap_to_exact_front: float = entry()


@dataclass(frozen=True)
class DesignFile:
    """``design.json``: the optimisation stage's answer (:meth:`Optimisation.write`)."""

    study: str = entry(kind=str)
    sensitivity_definition: str = entry(kind=str)
    objective: str = entry(kind=str)
    objective_note: str = entry(kind=str)
    constraints: ConstraintsRecord = entry(kind=ConstraintsRecord)
    chosen: ChoiceRecord = entry(kind=ChoiceRecord)
    exact_reduction_choice: ChoiceRecord = entry(kind=ChoiceRecord)
    pareto: ParetoRecord = entry(kind=ParetoRecord)
    timings: TimingsRecord = entry("timings_s", kind=TimingsRecord)


@dataclass(frozen=True)
class ParetoRow(Extrema):
    """A row of ``pareto.csv``: a design of the Pareto set and its margins [N]."""

    g_r: float = entry(unit="N")
    g_z: float = entry(unit="N")


@dataclass(frozen=True)
class ReductionRow:
    """A row of ``reduction.csv``: a height of the exact reduction, its smallest feasible
    G*(H) and M_z*(H) (None where M_z is not a design variable), the objectives and extrema
    along it and whether it is on the front."""

    H: float = entry(unit="mm")
    G_star: float = entry(unit="kPa")
    M_z_star: float | None = entry(unit="A_per_m", optional=True, omit="none", default=None,
                                   kw_only=True)
    Gamma_r_max: float = entry(unit="N_per_T")
    Gamma_z_max: float = entry(unit="N_per_T")
    F_r_min: float = entry(unit="N")
    F_z_max: float = entry(unit="N")
    t_m: float = entry()
    theta_m: float = entry(unit="rad")
    on_front: int = entry(kind=int)


@dataclass(frozen=True)
class ShearBoundRow:
    """A row of ``shear_bound.csv``: at a height, t_m, the smallest t within 1 % of the range
    of F_r's minimum, and F_z,max's relative drop between the two."""

    H: float = entry(unit="mm")
    t_m: float = entry()
    t_within_1_percent: float = entry()
    dF_z_rel: float = entry("F_z_max_drop_percent", "pct")


def _table(path: Path, cls, rows) -> Path:
    """Write records of type ``cls`` as the rows of a CSV table, their keys as the header
    (a key left out of the records, left out of the table)."""
    docs = [to_json(r) for r in rows]
    header = list(docs[0]) if docs else list(keys(cls))
    return write_csv(path, header, ([d[k] for k in header] for d in docs),
                     cell=significant(12))


def _design_record(d, cls=DesignRecord, **more):
    """The record ``cls`` (:class:`DesignRecord` or one that extends it) of a design ``d``
    (a :class:`DesignResult`) with the further fields ``more``."""
    return cls(**{f.name: getattr(d, f.name) for f, _ in declared(DesignRecord)}, **more)


def _choice_record(c: Choice) -> ChoiceRecord:
    return _design_record(c.design, ChoiceRecord, g_r=c.g_r, g_z=c.g_z,
                          active_constraints=tuple(c.active))


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
                 self._write_reduction(out / "reduction.csv"), self._write_maps(out / "maps.csv")]
        if figures is not None:
            files += figures(self, out)
        return files

    def record(self) -> DesignFile:
        """``design.json``'s record of this optimisation."""
        c, p, study = self.constraints, self.pareto, self.study
        reference = None if c.reference is None else _design_record(c.reference)
        return DesignFile(
            study.name, study.sensitivity.definition, study.optimise.objective,
            OBJECTIVE_NOTE[study.optimise.objective],
            ConstraintsRecord(c.F_r_c, c.F_z_c, c.source, reference),
            _choice_record(self.choice), _choice_record(self.reduction_choice),
            ParetoRecord(int(p.H.size), p.seed, study.optimise.population, p.generations,
                         p.evaluations, self.gap),
            TimingsRecord(**{f.name: getattr(self.timings, f.name)
                             for f, _ in declared(TimingsRecord)}))

    def _write_json(self, path: Path) -> Path:
        return write_json(path, to_json(self.record()), indent=2)

    def _write_pareto(self, path: Path) -> Path:
        p = self.pareto
        g_r, g_z = self.constraints.margins(p.F_r_min, p.F_z_max)
        M_z = p.M_z if self.study.M_z_variable else [None] * p.H.size
        return _table(path, ParetoRow, (
            ParetoRow(*row[:2], *row[3:], M_z=row[2])
            for row in zip(p.H, p.G, M_z, p.Gamma_r_max, p.Gamma_z_max, p.F_r_min, p.F_z_max,
                           g_r, g_z, strict=True)))

    def _write_maps(self, path: Path) -> Path:
        return write_maps(self.maps, path)

    def _write_reduction(self, path: Path) -> Path:
        r = self.reduction
        t = r.table
        M_z = r.M_z_star if self.study.M_z_variable else [None] * r.H.size
        return _table(path, ReductionRow, (
            ReductionRow(*row[:2], *row[3:], M_z_star=row[2])
            for row in zip(r.H, r.G_star, M_z, r.Gamma_r, r.Gamma_z, r.G_star * t.f_r_min,
                           r.G_star * t.f_z_max, t.t_m, t.theta_m, r.front.astype(int),
                           strict=True)))


def write_maps(maps, path: Path) -> Path:
    """``maps.csv``: one row per design of the map grid (:class:`DesignMaps`), as the files
    hold a design (:class:`DesignRecord`), in user units (mm, kPa, N, N/T, rad)."""
    return _table(path, DesignRecord, (_design_record(maps.design(i, j))
                                       for i in range(maps.H.size) for j in range(maps.G.size)))


def design_json(d: DesignResult) -> dict:
    """A design's variables and extrema in user units, each key naming its unit
    (:class:`DesignRecord`)."""
    return to_json(_design_record(d))


@dataclass(frozen=True)
class ChosenFile(DesignRecord):
    """``chosen.json``: the chosen design as flat values, in SI, as
    :func:`write_optimise_outputs` writes it; read back (:meth:`from_json`) also from the
    ``chosen.json`` of :meth:`magtact.optimise.SensorOptimisation.write` and from the choice of
    ``geometry.json``. A field the file does not give (or gives with the wrong type) reads as
    None.

    Attributes
    ----------
    H, G, M_z : float or None
        Base height [m], shear modulus [Pa], magnetisation [A/m].
    Gamma_r_max, Gamma_z_max : float or None
        The objectives: worst Γ [N/T], or worst σ_F [N] where ``objective`` is ``"sigma_F"``.
    F_r_min, F_z_max : float or None
        Force extrema [N].
    t_m, theta_m : float or None
        The stable region's bounds [1, rad].
    degenerate : str or None
    g_r, g_z : float or None
        Margins to the force constraints [N] (≤ 0: met).
    active_constraints, sensitivity_definition, objective : str or None
    constraints : Limits or None
        The force constraints (None where the file has none).
    design : str or None
        The design in words (over geometric design variables; not written here).
    """

    g_r: float | None = entry(unit="N")
    g_z: float | None = entry(unit="N")
    active_constraints: str | None = entry(kind=str)
    sensitivity_definition: str | None = entry(kind=str)
    objective: str | None = entry(kind=str)
    constraints: Limits | None = entry(kind=Limits, optional=True, default=None)
    design: str | None = entry(kind=str, optional=True, omit="none", default=None)

    @property
    def has_constraints(self) -> bool:
        """Whether the file gives the force constraints."""
        return self.constraints is not None

    @property
    def F_r_c(self) -> float | None:
        """The shear force constraint [N] (None where the file has none)."""
        return None if self.constraints is None else self.constraints.F_r_c

    @property
    def F_z_c(self) -> float | None:
        """The normal force constraint [N] (None where the file has none)."""
        return None if self.constraints is None else self.constraints.F_z_c

    @property
    def constraints_source(self) -> str | None:
        """Where the force constraints come from (None where the file has none)."""
        return None if self.constraints is None else self.constraints.source

    @classmethod
    def from_json(cls, data) -> ChosenFile | None:
        """The chosen design of ``chosen.json``'s document, field by field; None for anything
        but a non-empty JSON object."""
        if not isinstance(data, dict) or not data:
            return None
        return from_json_lenient(cls, data)


def design_file_definition(data) -> str | None:
    """The sensitivity definition recorded in ``design.json``'s document (None if none)."""
    record = from_json_lenient(DesignFile, data)
    return None if record is None else record.sensitivity_definition


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
    files.append(_table(folder / "shear_bound.csv", ShearBoundRow, (
        ShearBoundRow(*row) for row in zip(cond.H, cond.t_m, cond.t_tol, cond.dF_z_rel,
                                           strict=True))))
    c, limits = result.choice, result.constraints
    chosen = _design_record(
        c.design, ChosenFile, g_r=c.g_r, g_z=c.g_z,
        active_constraints=", ".join(c.active) or "none",
        sensitivity_definition=study.sensitivity.definition, objective=study.optimise.objective,
        constraints=Limits(limits.F_r_c, limits.F_z_c, limits.source))
    captions = CAPTIONS if result.pareto.generations else CAPTIONS | EXACT_CAPTIONS
    files.append(write_json(folder / "chosen.json", to_json(chosen), indent=2))
    files.append(write_json(folder / "captions.json", captions, indent=2))
    return files
