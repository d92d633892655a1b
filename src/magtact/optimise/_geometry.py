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
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._files import write_text
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


def _set_json(s: DesignSet) -> list[dict]:
    return [{f"{k}_{UNITS.get(k, 'mm')}": float(from_si(v[i], UNITS.get(k, "mm")))
             for k, v in s.values.items()}
            | {"Gamma_r_max_N_per_T": float(s.Gamma_r_max[i]),
               "Gamma_z_max_N_per_T": float(s.Gamma_z_max[i])} for i in range(len(s))]


def geometry_json(r: GeometryOptimisation) -> dict:
    """The result in user units (mm, kPa, A/m, N, N/T) as JSON-ready data."""
    def choice(c: GeometricChoice) -> dict:
        d = c.design
        return {"design": describe(c.values), "Gamma_r_max_N_per_T": d.Gamma_r_max,
                "Gamma_z_max_N_per_T": d.Gamma_z_max, "F_r_min_N": d.F_r_min,
                "F_z_max_N": d.F_z_max, "g_r_N": c.g_r, "g_z_N": c.g_z}

    return {"variables": list(r.design_variables),
            "constraints": {"F_r_c_N": r.constraints.F_r_c, "F_z_c_N": r.constraints.F_z_c,
                            "source": r.constraints.source},
            "choice": choice(r.choice), "exact_choice": choice(r.exact_choice),
            "gap_to_exact_front": r.gap, "nsga2_evaluations": r.evaluations,
            "exact_grid_mm": {k: [float(from_si(v, "mm")) for v in g]
                              for k, g in r.grid.items()},
            "exact_resolution_mm": {k: float(from_si(v, "mm")) for k, v in r.resolution.items()},
            "pareto": _set_json(r.pareto), "exact_front": _set_json(r.exact)}


def geometry_choice_json(data) -> dict | None:
    """The chosen design of ``geometry.json``'s document (:func:`geometry_json`) as the flat
    values of ``chosen.json``, with the constraints; None where it has none."""
    if not isinstance(data, dict) or not isinstance(data.get("choice"), dict):
        return None
    return data["choice"] | {"constraints": data.get("constraints")}


def write_geometry_outputs(result: GeometryOptimisation, folder, figures=None) -> list[Path]:
    """Write ``folder/geometry.json`` (and, with ``figures``, its figure: a callable
    ``figures(result, folder)`` returning its files); return the files written."""
    folder = Path(folder)
    files = [write_text(folder / "geometry.json",
                        json.dumps(geometry_json(result), indent=1) + "\n")]
    if figures is not None:
        files += figures(result, folder)
    return files
