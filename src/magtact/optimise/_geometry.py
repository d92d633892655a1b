"""Optimisation over the geometric design variables besides H (R_m, H_m, R).

At a fixed geometry the problem is the (H, G, M_z) problem of :mod:`._pareto` with the models
bound to it (:meth:`magtact.metamodel.ModelSet.at`), so both answers are built from it
(docs/method.md §7):

* the **exact reduction**, generalised: the exact Pareto set over H (with the best G and M_z at
  each height) at every point of a grid over the geometric variables, then the non-dominated
  part of their union;
* **NSGA-II** over every design variable at once (H, G, M_z where it varies, and the geometric
  ones), each design evaluated exactly with the models bound to its geometry.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._files import write_json
from .._records import entry, from_json_lenient, to_json
from ..metamodel import ModelSet
from ..study import Study, from_si
from ._design import DesignResult, per_design
from ._pareto import (
    DesignProblem,
    ForceConstraints,
    InfeasibleError,
    curve_gap,
    decision_index,
    exact_reduction,
    force_constraints,
    nondominated,
    sweep,
)
from ._run import Limits

#: Newton iterations at most per per-height problem, in both answers over the geometry. A flat
#: valley of f_r keeps some problems iterating on round-off long after their values are
#: resolved. A cap of 15 instead of 100 changed the extrema of the tiny (H, R_m) study by
#: < 1e-12 (f_r,min, Γ) and 1.2e-4 (F_z,max, whose box follows the valley's ill-defined
#: minimum) relative; 20 leaves a margin above that. The chosen designs are evaluated again in full.
MAXITER = 20


@dataclass(frozen=True)
class DesignSet:
    """Designs over every design variable (arrays of shape (n,), SI).

    ``values`` maps ``H``, ``G``, ``M_z`` and each geometric variable to its values;
    ``Gamma_r_max, Gamma_z_max`` [N/T] the objectives.
    """

    values: dict[str, np.ndarray]
    Gamma_r_max: np.ndarray
    Gamma_z_max: np.ndarray

    @property
    def objectives(self) -> np.ndarray:
        """(Γ_r,max, Γ_z,max) [N/T], shape (n, 2)."""
        return np.stack([self.Gamma_r_max, self.Gamma_z_max], axis=1)

    def __len__(self) -> int:
        return self.Gamma_r_max.size

    def design(self, i: int) -> dict[str, float]:
        """Design ``i`` as a dict of SI values."""
        return {k: float(v[i]) for k, v in self.values.items()}


@dataclass(frozen=True)
class GeometricChoice:
    """The chosen design: ``values`` (SI, by variable) and its per-design result at its
    geometry (:func:`per_design` with the bound models)."""

    values: dict[str, float]
    design: DesignResult
    g_r: float
    g_z: float


@dataclass(frozen=True)
class GeometryOptimisation:
    """Both answers over the geometric design space and the decision on each.

    Attributes
    ----------
    variables : tuple of str
        The geometric design variables besides H.
    design_variables : tuple of str
        Every design variable: H, G, M_z (where it varies) and :attr:`variables`.
    constraints : ForceConstraints
    exact : DesignSet
        The exact Pareto set (generalised reduction, :attr:`grid` levels).
    pareto : DesignSet
        NSGA-II's Pareto set.
    choice, exact_choice : GeometricChoice
        The decision rule applied to NSGA-II's set (the answer) and to the exact set.
    gap : float
        Largest relative distance of NSGA-II's set from the exact front (:func:`curve_gap`).
    grid : dict of numpy.ndarray
        Levels of each geometric variable in the exact reduction's first grid [m].
    resolution : dict of float
        Its final spacing around the front, per geometric variable [m].
    evaluations : int
        NSGA-II's design evaluations.
    """

    variables: tuple[str, ...]
    design_variables: tuple[str, ...]
    constraints: ForceConstraints
    exact: DesignSet
    pareto: DesignSet
    choice: GeometricChoice
    exact_choice: GeometricChoice
    gap: float
    grid: dict[str, np.ndarray]
    evaluations: int
    resolution: dict[str, float]


def bound(models: ModelSet, study: Study, geometry: dict[str, float]) -> tuple[ModelSet, Study]:
    """The models and the study at one geometry (the (H, G, M_z) problem there)."""
    return models.at(**geometry), study.at(**geometry)


#: Refinement of the geometry grid around the exact front: at most this many halvings of its
#: spacing, until the front moves by less than :data:`REFINE_TOL` (relative, :func:`curve_gap`).
REFINE_ROUNDS = 8
REFINE_TOL = 1e-3


def _fronts(models: ModelSet, study: Study, constraints: ForceConstraints, names: tuple,
            points: list[tuple]) -> tuple[list[list], Exception | None]:
    """The exact front over H at each geometry of ``points`` (one batched sweep): rows
    (H, G*, M_z*, *geometry, Γ_r, Γ_z), and the last infeasibility met."""
    table = sweep(models, study, geometry={k: [p[i] for p in points]
                                           for i, k in enumerate(names)}, maxiter=MAXITER)
    n_H = study.optimise.sweep_n
    rows, last_error = [], None
    for j, values in enumerate(points):
        m, s = bound(models, study, dict(zip(names, values, strict=True)))
        try:
            red = exact_reduction(m, s, constraints, table.take(slice(j * n_H, (j + 1) * n_H)))
        except InfeasibleError as exc:
            last_error = exc
            continue
        rows += [[red.H[i], red.G_star[i], red.M_z_star[i], *values, red.Gamma_r[i],
                  red.Gamma_z[i]] for i in np.flatnonzero(red.front)]
    return rows, last_error


def exact_geometry(models: ModelSet, study: Study, constraints: ForceConstraints
                   ) -> tuple[DesignSet, dict[str, np.ndarray], dict[str, float]]:
    """The generalised exact reduction: the exact front over H at each point of a
    ``optimise.geometry_n`` grid per geometric variable, the non-dominated union, and the grid
    refined around it.

    Returns
    -------
    DesignSet, dict, dict
        The exact Pareto set; the grid's levels [m]; the final spacing [m] per variable.

    Raises
    ------
    InfeasibleError
        If no geometry of the grid admits a feasible design.

    Notes
    -----
    Each refinement halves the spacing and adds the neighbours (in every direction, at the new
    spacing) of the geometries on the current front; it stops when the front moved by less than
    ``REFINE_TOL`` or after ``REFINE_ROUNDS`` rounds.
    """
    ranges = study.geometric_variables
    names = tuple(ranges)
    grid = {k: np.linspace(lo, hi, study.optimise.geometry_n) for k, (lo, hi) in ranges.items()}
    step = {k: (hi - lo) / (study.optimise.geometry_n - 1) for k, (lo, hi) in ranges.items()}
    points = [tuple(float(v) for v in p) for p in itertools.product(*grid.values())]
    done = set(points)
    rows, last_error = _fronts(models, study, constraints, names, points)
    if not rows:
        raise InfeasibleError(f"no geometry of the grid admits a feasible design; at the last "
                              f"one: {last_error}")

    def front(rows):
        E = np.array(rows)
        E = E[nondominated(E[:, -2:])]
        return E[np.argsort(E[:, -2], kind="stable")]

    E = front(rows)
    for _ in range(REFINE_ROUNDS):
        step = {k: v / 2 for k, v in step.items()}
        new = set()
        for g in {tuple(r[3:3 + len(names)]) for r in E}:
            for d in itertools.product((-1, 0, 1), repeat=len(names)):
                p = tuple(float(np.clip(v + di * step[k], *ranges[k]))
                          for v, di, k in zip(g, d, names, strict=True))
                new.add(p)
        new -= done
        if not new:
            break
        done |= new
        more, _ = _fronts(models, study, constraints, names, sorted(new))
        rows += more
        E_new = front(rows)
        moved = curve_gap(E_new[:, -2:], E[:, -2:])
        E = E_new
        if moved <= REFINE_TOL:
            break
    all_names = ("H", "G", "M_z", *names)
    return (DesignSet({k: E[:, i] for i, k in enumerate(all_names)}, E[:, -2], E[:, -1]), grid,
            step)


def nsga2_geometry(models: ModelSet, study: Study, constraints: ForceConstraints
                   ) -> tuple[DesignSet, int]:
    """NSGA-II over (H, G[, M_z], geometric variables), each design evaluated exactly at its
    geometry (:class:`magtact.optimise.DesignProblem`, the same problem and constraints as over
    (H, G), the chip's range included), sorted by Γ_r,max.

    Raises
    ------
    InfeasibleError
        If NSGA-II finds no feasible design.
    """
    problem = DesignProblem(models, study, constraints, maxiter=MAXITER)
    X, n_eval = problem.solve()
    cols, obj, _, _ = problem.evaluate(X)
    order = np.argsort(obj[:, 0], kind="stable")
    values = {k: cols[k] for k in ("H", "G", "M_z", *study.geometric_variables)}
    return (DesignSet({k: np.asarray(v)[order] for k, v in values.items()}, obj[order, 0],
                      obj[order, 1]), n_eval)


def _choose(models: ModelSet, study: Study, designs: DesignSet,
            constraints: ForceConstraints) -> GeometricChoice:
    values = designs.design(decision_index(designs.objectives))
    m, s = bound(models, study, {k: values[k] for k in study.geometric_variables})
    d = per_design(m, values["H"], values["G"], s,
                   values["M_z"] if study.M_z_variable else None)
    g_r, g_z = (float(v) for v in constraints.margins(d.F_r_min, d.F_z_max))
    return GeometricChoice(values, d, g_r, g_z)


def optimise_geometry(models: ModelSet, study: Study,
                      constraints: ForceConstraints | None = None) -> GeometryOptimisation:
    """Optimise over H, G (M_z) and the study's geometric design variables (module notes).

    ``constraints``: default :func:`force_constraints` of the study (a reference design is
    evaluated at the study's own geometry, ``magnet.R_m`` ...).

    Raises
    ------
    ValueError
        If the study has no geometric design variable besides H.
    InfeasibleError
        If no design is feasible.
    """
    if not study.geometric_variables:
        raise ValueError("the study has no geometric design variable besides H; use optimise")
    if constraints is None:
        constraints = force_constraints(models, study)
    exact, grid, resolution = exact_geometry(models, study, constraints)
    pareto, n_eval = nsga2_geometry(models, study, constraints)
    geo = tuple(study.geometric_variables)
    return GeometryOptimisation(
        geo, ("H", "G", *(("M_z",) if study.M_z_variable else ()), *geo), constraints, exact,
        pareto,
        _choose(models, study, pareto, constraints), _choose(models, study, exact, constraints),
        curve_gap(pareto.objectives, exact.objectives), grid, n_eval, resolution)


#: User unit of each design variable (lengths in mm).
UNITS = {"G": "kPa", "M_z": "A_per_m"}


def describe(values: dict[str, float]) -> str:
    """A design in user units, one line."""
    return ", ".join(f"{k} = {from_si(v, UNITS.get(k, 'mm')):.4g} {UNITS.get(k, 'mm')}"
                     for k, v in values.items())


@dataclass(frozen=True)
class SetRecord:
    """A design of a set (:class:`DesignSet`) in ``geometry.json``'s ``pareto`` and
    ``exact_front``: every design variable (SI inside; mm, kPa, A/m in the file) and the
    objectives. A geometric variable that is not a design variable of the study is None and
    left out of the file."""

    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    M_z: float = entry(unit="A_per_m")
    R_m: float | None = entry(unit="mm", optional=True, omit="none", default=None)
    H_m: float | None = entry(unit="mm", optional=True, omit="none", default=None)
    R: float | None = entry(unit="mm", optional=True, omit="none", default=None)
    Gamma_r_max: float = entry(unit="N_per_T", kw_only=True)
    Gamma_z_max: float = entry(unit="N_per_T", kw_only=True)


@dataclass(frozen=True)
class GeometryChoiceRecord:
    """A chosen design (:class:`GeometricChoice`) in ``geometry.json``: the design in words, its
    objectives [N/T], force extrema and margins to the force constraints [N]. Its keys are
    ``chosen.json``'s (:class:`magtact.optimise.ChosenFile` reads it,
    :func:`geometry_choice_json`). A written choice has every value; a value that a partial
    file lacks reads (leniently) as None and is left out of the document again."""

    design: str | None = entry(kind=str, optional=True, omit="none")
    Gamma_r_max: float | None = entry(unit="N_per_T", optional=True, omit="none")
    Gamma_z_max: float | None = entry(unit="N_per_T", optional=True, omit="none")
    F_r_min: float | None = entry(unit="N", optional=True, omit="none")
    F_z_max: float | None = entry(unit="N", optional=True, omit="none")
    g_r: float | None = entry(unit="N", optional=True, omit="none")
    g_z: float | None = entry(unit="N", optional=True, omit="none")


@dataclass(frozen=True)
class GeometryFile:
    """``geometry.json``: the optimisation over the geometric design variables
    (:class:`GeometryOptimisation`) in user units (mm, kPa, A/m, N, N/T)."""

    variables: tuple[str, ...] = entry(kind=str, levels=("list",))
    constraints: Limits = entry(kind=Limits)
    choice: GeometryChoiceRecord = entry(kind=GeometryChoiceRecord)
    exact_choice: GeometryChoiceRecord = entry(kind=GeometryChoiceRecord)
    gap_to_exact_front: float = entry()
    nsga2_evaluations: int = entry(kind=int)
    exact_grid: dict[str, tuple[float, ...]] = entry(unit="mm", levels=("map", "list"))
    exact_resolution: dict[str, float] = entry(unit="mm", levels=("map",))
    pareto: tuple[SetRecord, ...] = entry(kind=SetRecord, levels=("list",))
    exact_front: tuple[SetRecord, ...] = entry(kind=SetRecord, levels=("list",))


@dataclass(frozen=True)
class GeometryChosen:
    """``geometry.json``'s choice as ``chosen.json`` holds a design (the document
    :meth:`magtact.optimise.ChosenFile.from_json` reads): the choice's values with the force
    constraints (None where the file has none)."""

    choice: GeometryChoiceRecord = entry(kind=GeometryChoiceRecord, inline=True)
    constraints: Limits | None = entry(kind=Limits, optional=True)


def _set_records(s: DesignSet) -> tuple[SetRecord, ...]:
    return tuple(SetRecord(**s.design(i), Gamma_r_max=float(s.Gamma_r_max[i]),
                           Gamma_z_max=float(s.Gamma_z_max[i])) for i in range(len(s)))


def _choice_record(c: GeometricChoice) -> GeometryChoiceRecord:
    d = c.design
    return GeometryChoiceRecord(describe(c.values), d.Gamma_r_max, d.Gamma_z_max, d.F_r_min,
                                d.F_z_max, c.g_r, c.g_z)


def geometry_record(r: GeometryOptimisation) -> GeometryFile:
    """``geometry.json``'s record of the result."""
    c = r.constraints
    return GeometryFile(tuple(r.design_variables), Limits(c.F_r_c, c.F_z_c, c.source),
                        _choice_record(r.choice), _choice_record(r.exact_choice), r.gap,
                        r.evaluations, r.grid, r.resolution, _set_records(r.pareto),
                        _set_records(r.exact))


def geometry_json(r: GeometryOptimisation) -> dict:
    """The result in user units (mm, kPa, A/m, N, N/T) as JSON-ready data
    (:class:`GeometryFile`)."""
    return to_json(geometry_record(r))


def geometry_choice_json(data) -> dict | None:
    """The chosen design of ``geometry.json``'s document (:func:`geometry_json`) as the flat
    values of ``chosen.json``, with the constraints (:class:`GeometryChosen`); None where it
    has none. The file is read leniently: a value it lacks or gives in another shape is left
    out."""
    record = from_json_lenient(GeometryFile, data)
    if record is None or record.choice is None:
        return None
    return to_json(GeometryChosen(record.choice, record.constraints))


def write_geometry_outputs(result: GeometryOptimisation, folder, figures=None) -> list[Path]:
    """Write ``folder/geometry.json`` (and, with ``figures``, its figure: a callable
    ``figures(result, folder)`` returning its files); return the files written."""
    folder = Path(folder)
    files = [write_json(folder / "geometry.json", geometry_json(result), indent=1)]
    if figures is not None:
        files += figures(result, folder)
    return files
