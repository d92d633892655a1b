"""Optimisation over designs (docs/method.md §7.2): constraints, NSGA-II, exact reduction, choice.

Problem (published study, Eq. 19)::

    minimise (Γ_r,max(H, G), Γ_z,max(H, G))
    subject to H ∈ [H_lo, H_hi], G ∈ [G_lo, G_hi],
               g_r = F_r,min − F_r,c ≤ 0,   g_z = F_z,c − F_z,max ≤ 0,
               and, with ``[constraints] chip_range``, the Hall chip within its range over the
               stable region (a condition on H alone: :func:`chip_margin`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .._errors import MagtactError
from ..chip import chip_margin
from ..doe import check_design
from ..metamodel import ModelSet
from ..sensitivity import Responses
from ..study import Study, from_si, hall_chip
from ._design import DesignResult, HeightTable, as_responses, heights_batch, per_design


class InfeasibleError(MagtactError):
    """No design within the bounds satisfies the force constraints."""


@dataclass(frozen=True)
class ForceConstraints:
    """Force constraints F_r,min ≤ F_r,c and F_z,max ≥ F_z,c [N].

    ``source`` is ``"values"`` (numbers given) or ``"reference"`` (those of ``reference``, a
    design whose F_r,min and F_z,max were computed).
    """

    F_r_c: float
    F_z_c: float
    source: str = "values"
    reference: DesignResult | None = None
    #: Fabrication tolerance δ of G the numbers include: F_r,c and F_z,c are the forces required
    #: at G (1 − δ), divided by 1 − δ (docs/method.md §7).
    tolerance: float = 0.0

    def margins(self, F_r_min, F_z_max) -> tuple[np.ndarray, np.ndarray]:
        """(g_r, g_z) = (F_r,min − F_r,c, F_z,c − F_z,max) [N]; ≤ 0 is feasible."""
        return np.asarray(F_r_min) - self.F_r_c, self.F_z_c - np.asarray(F_z_max)

    def active(self, F_r_min: float, F_z_max: float, rtol: float) -> tuple[str, ...]:
        """``"F_r"`` and/or ``"F_z"``: the constraints with |margin| ≤ ``rtol`` |limit|."""
        g_r, g_z = (float(v) for v in self.margins(F_r_min, F_z_max))
        return tuple(name for name, g, lim in (("F_r", g_r, self.F_r_c), ("F_z", g_z, self.F_z_c))
                     if abs(g) <= rtol * max(abs(lim), 1e-300))


def force_constraints(models: Responses | ModelSet, study: Study, *, F_r_c: float | None = None,
                      F_z_c: float | None = None,
                      reference: tuple[float, float] | None = None) -> ForceConstraints:
    """The force constraints to use.

    Parameters
    ----------
    models : Responses or ModelSet
        Needed when the constraints come from a reference design.
    study : Study
        Its ``[constraints]`` table is the default: numbers (``source = "values"``) or the
        original design ``design.H_original, G_original`` (``source = "reference"``).
    F_r_c, F_z_c : float, optional
        Numbers [N] overriding the study's (a missing one is taken from the study).
    reference : (H [m], G [Pa]), optional
        Use this design's F_r,min and F_z,max as F_r,c and F_z,c (at the study's own geometry
        where it has geometric design variables).

    Notes
    -----
    With ``[constraints] G_tolerance`` δ > 0 the forces must be reached by the softest body,
    G (1 − δ): since F ∝ G, that is F(G) against F_c / (1 − δ).

    Raises
    ------
    MagtactError
        If both numbers and a reference design are given.
    """
    given = F_r_c is not None or F_z_c is not None
    if given and reference is not None:
        raise MagtactError("give either constraint values (F_r_c, F_z_c) or a reference design, "
                         "not both")
    c = study.constraints
    if reference is None and not given and c.source == "reference":
        reference = (study.design.H_original, study.design.G_original)
    k = 1.0 / (1.0 - c.G_tolerance)  # every force scales with G: F(G (1 − δ)) = (1 − δ) F(G)
    if reference is not None:
        if study.geometric_variables:  # a reference design has the study's own geometry
            geometry = study.geometry()
            models, study = as_responses(models).models.at(**geometry), study.at(**geometry)
        check_design(study, reference[0])  # a reference outside the data: extrapolated
        d = per_design(models, reference[0], reference[1], study)
        return ForceConstraints(k * d.F_r_min, k * d.F_z_max, "reference", d, c.G_tolerance)
    return ForceConstraints(k * (c.F_r_c if F_r_c is None else float(F_r_c)),
                            k * (c.F_z_c if F_z_c is None else float(F_z_c)), "values",
                            tolerance=c.G_tolerance)


def feasible_G(f_r_min, f_z_max, constraints: ForceConstraints,
               G_bounds: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Interval [G_low, G_high] of feasible shear moduli at each height (empty if low > high).

    Notes
    -----
    With a = f_r,min(H) and b = f_z,max(H) (per unit G), G a ≤ F_r,c and G b ≥ F_z,c give
    G ≥ F_r,c / a where a < 0 (G ≤ F_r,c / a where a > 0; for a = 0 feasible iff F_r,c ≥ 0) and
    G ≥ F_z,c / b where b > 0 (G ≤ F_z,c / b where b < 0; for b = 0 feasible iff F_z,c ≤ 0).
    With F_r,c < 0 and f_r,min < 0 the first bound is the positive ratio F_r,c / f_r,min.
    """
    a, b = np.asarray(f_r_min, float), np.asarray(f_z_max, float)
    low = np.full(np.broadcast(a, b).shape, float(G_bounds[0]))
    high = np.full(low.shape, float(G_bounds[1]))
    cr, cz = constraints.F_r_c, constraints.F_z_c
    with np.errstate(divide="ignore", invalid="ignore"):
        low = np.where(a < 0, np.maximum(low, cr / a), low)
        high = np.where(a > 0, np.minimum(high, cr / a), high)
        low = np.where(b > 0, np.maximum(low, cz / b), low)
        high = np.where(b < 0, np.minimum(high, cz / b), high)
    impossible = (a == 0) & (cr < 0) | (b == 0) & (cz > 0)
    high = np.where(impossible, -np.inf, high)
    return low, high


def _infeasible_message(table: HeightTable, constraints: ForceConstraints, study: Study) -> str:
    """Why no design is feasible: the best reachable value of each constraint on its own."""
    G_lo, G_hi = study.design.G
    H_lo, H_hi = study.design.H
    Fr = np.stack([table.f_r_min * G_lo, table.f_r_min * G_hi])  # (2, n)
    Fz = np.stack([table.f_z_max * G_lo, table.f_z_max * G_hi])
    ir = np.unravel_index(np.argmin(Fr), Fr.shape)
    iz = np.unravel_index(np.argmax(Fz), Fz.shape)
    Gs = (G_lo, G_hi)

    def at(i):
        return f"H = {from_si(table.H[i[1]], 'mm'):.3f} mm, G = {from_si(Gs[i[0]], 'kPa'):.2f} kPa"

    best_r, best_z = Fr[ir], Fz[iz]
    alone = best_r <= constraints.F_r_c and best_z >= constraints.F_z_c
    return (f"no design with H in [{from_si(H_lo, 'mm'):g}, {from_si(H_hi, 'mm'):g}] mm and "
            f"G in [{from_si(G_lo, 'kPa'):g}, {from_si(G_hi, 'kPa'):g}] kPa satisfies "
            f"F_r,min <= {constraints.F_r_c:.4g} N and F_z,max >= {constraints.F_z_c:.4g} N. "
            f"Best reachable: F_r,min = {best_r:.4g} N ({at(ir)}); "
            f"F_z,max = {best_z:.4g} N ({at(iz)})"
            + ("; each is reachable alone but not both in one design." if alone else "."))


def _chip_message(table: HeightTable, study: Study) -> str:
    """Why the chip's range leaves no feasible design: where it comes closest."""
    chip = hall_chip(study)
    m = chip_margin(study, table.H, table.t_m, table.theta_m)
    k = int(np.argmin(m))
    return (f"the force constraints can be met, but the {chip.name} (range "
            f"{from_si(chip.range_x, 'mT'):g} / {from_si(chip.range_z, 'mT'):g} mT, x / z) "
            "saturates inside the stable region of every feasible height "
            "([constraints] chip_range = true); the field exceeds the range least at "
            f"H = {from_si(table.H[k], 'mm'):.3f} mm, by {m[k]:.1%}: widen hall.range_x_mT / "
            "hall.range_z_mT, choose another chip, or set constraints.chip_range = false")


def nondominated(objectives: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of ``objectives`` (n, 2), both minimised.

    Of identical rows only the first is kept.
    """
    obj = np.asarray(objectives, float)
    order = np.lexsort((obj[:, 1], obj[:, 0]))
    keep = np.zeros(obj.shape[0], bool)
    best = np.inf
    for k in order:
        if obj[k, 1] < best:
            keep[k] = True
            best = obj[k, 1]
    return keep


@dataclass(frozen=True)
class Reduction:
    """Exact reduction of the design problem to a curve over H (docs/method.md §7).

    Attributes
    ----------
    table : HeightTable
        Per-unit-G extrema on the sweep of heights.
    G_star : numpy.ndarray, shape (n,)
        Smallest feasible G at each height [Pa] (NaN where none is feasible).
    M_z_star : numpy.ndarray, shape (n,)
        Best magnetisation at each height [A/m]: the largest in range the chip allows (the
        magnet's own where M_z is not a design variable).
    Gamma_r, Gamma_z : numpy.ndarray, shape (n,)
        Objectives at (H, G*(H), M_z*(H)) [N/T] (NaN where infeasible).
    front : numpy.ndarray of bool, shape (n,)
        The non-dominated feasible heights: the exact Pareto set.
    constraints : ForceConstraints
    """

    table: HeightTable
    G_star: np.ndarray
    Gamma_r: np.ndarray
    Gamma_z: np.ndarray
    front: np.ndarray
    constraints: ForceConstraints
    M_z_star: np.ndarray | None = None

    @property
    def H(self) -> np.ndarray:
        """Heights of the sweep [m]."""
        return self.table.H

    @property
    def feasible(self) -> np.ndarray:
        """Heights at which some G in the bounds is feasible."""
        return np.isfinite(self.G_star)


def sweep(models: Responses | ModelSet, study: Study, geometry: dict | None = None,
          maxiter: int = 100) -> HeightTable:
    """Per-unit-G extrema on ``sweep_n`` equally spaced heights over the H bounds.

    ``sweep_coarse`` heights are solved from full start grids; the others start from the
    bracketing coarse heights' optima (and a coarse grid) (see :func:`heights_batch`).
    With ``geometry`` (values [m] of geometric design variables by name, arrays of one
    length), the sweep is done at each of these geometries, all in one batch: the rows are
    ordered by geometry, then height. ``maxiter``: Newton iterations at most per problem.
    """
    o = study.optimise
    geometry = {k: np.atleast_1d(np.asarray(v, float)) for k, v in (geometry or {}).items()}
    n_geo = len(next(iter(geometry.values()))) if geometry else 1

    def rows(n):
        H = np.tile(np.linspace(*study.design.H, n), n_geo)
        return H, {k: np.repeat(v, n) for k, v in geometry.items()}

    H, geo = rows(o.sweep_coarse)
    coarse = heights_batch(models, H, study, geometry=geo, maxiter=maxiter)
    H, geo = rows(o.sweep_n)
    return heights_batch(models, H, study, warm=coarse, geometry=geo, maxiter=maxiter)


def exact_reduction(models: Responses | ModelSet, study: Study, constraints: ForceConstraints,
                    table: HeightTable | None = None) -> Reduction:
    """The Pareto set by a 1D sweep over H: G*(H) = smallest feasible G.

    Parameters
    ----------
    table : HeightTable, optional
        A precomputed :func:`sweep` (computed when not given).

    Raises
    ------
    InfeasibleError
        If no height admits a feasible G; the message gives the best reachable F_r,min and
        F_z,max.

    Notes
    -----
    Γ_r,max = G γ_r,max(H) and Γ_z,max = G γ_z,max(H) grow with G, and the feasible G at a
    height form an interval (:func:`feasible_G`), so only its lower end
    G*(H) = max(G_lo, F_r,c / f_r,min(H), F_z,c / f_z,max(H)) (with the signs of the defaults)
    can be Pareto-optimal. The Pareto set is the non-dominated part of the curve
    H ↦ (G* γ_r,max, G* γ_z,max).

    With M_z a design variable the sensitivities scale as M_z,0 / M_z (B ∝ M_z; M_z,0 the
    magnet's own, at which the models hold) and the forces do not depend on it, so the best
    M_z is the largest the chip allows (:func:`best_magnetisation`).
    """
    table = sweep(models, study) if table is None else table
    low, high = feasible_G(table.f_r_min, table.f_z_max, constraints, study.design.G)
    ok = low <= high
    if not ok.any():
        raise InfeasibleError(_infeasible_message(table, constraints, study))
    M_star = best_magnetisation(study, table)
    ok &= np.isfinite(M_star)
    if not ok.any():
        raise InfeasibleError(_chip_message(table, study))
    G_star = np.where(ok, low, np.nan)
    k = study.magnet.M_z / M_star
    Gr, Gz = G_star * table.gamma_r_max * k, G_star * table.gamma_z_max * k
    front = np.zeros(ok.size, bool)
    idx = np.flatnonzero(ok)
    front[idx[nondominated(np.stack([Gr[idx], Gz[idx]], axis=1))]] = True
    return Reduction(table, G_star, Gr, Gz, front, constraints, M_star)


def best_magnetisation(study: Study, table: HeightTable) -> np.ndarray:
    """The largest magnetisation in range at each height of ``table`` that the chip allows
    (NaN where none does) [A/m].

    Notes
    -----
    Γ ∝ 1 / M_z, so without ``[constraints] chip_range`` it is the top of the range. With it,
    the field's margin over the stable region scales as (M_z / M_z,0)(1 + m_0(H)) − 1, m_0 the
    :func:`chip_margin` at the magnet's own M_z,0, so M_z ≤ M_z,0 / (1 + m_0(H)).
    """
    lo, hi = study.M_z_bounds
    M = np.full(table.H.shape, float(hi))
    if study.constraints.chip_range:
        m0 = chip_margin(study, table.H, table.t_m, table.theta_m)
        # at a fixed M_z,0 (lo = hi) this keeps exactly the heights with m_0 ≤ 0
        M = np.minimum(M, study.magnet.M_z / (1.0 + m0))
        M = np.where(M >= lo, M, np.nan)
    return M


@dataclass(frozen=True)
class ParetoSet:
    """NSGA-II's Pareto set over designs (H, G), sorted by H (arrays of shape (n,)).

    ``H`` [m], ``G`` [Pa], ``Gamma_r_max, Gamma_z_max`` [N/T], ``F_r_min, F_z_max`` [N];
    ``constraints`` used; ``seed``, ``generations`` and ``evaluations`` of the run; ``M_z``
    [A/m] (the magnet's own where it is not a design variable).
    """

    H: np.ndarray
    G: np.ndarray
    Gamma_r_max: np.ndarray
    Gamma_z_max: np.ndarray
    F_r_min: np.ndarray
    F_z_max: np.ndarray
    constraints: ForceConstraints
    seed: int
    generations: int
    evaluations: int
    M_z: np.ndarray | None = None

    @property
    def objectives(self) -> np.ndarray:
        """(Γ_r,max, Γ_z,max) [N/T], shape (n, 2)."""
        return np.stack([self.Gamma_r_max, self.Gamma_z_max], axis=1)


class DesignProblem:
    """NSGA-II's design problem for every kind of study (a pymoo ``Problem`` via
    :meth:`problem`).

    Variables: H, G, M_z where it is a design variable, and the study's geometric design
    variables (R_m, H_m, R), each scaled to [0, 1] over its bounds. Objectives
    (Γ_r,max, Γ_z,max) [N/T]; inequality constraints g_r / |F_r,c| ≤ 0 and g_z / |F_z,c| ≤ 0
    (1 N where a limit is zero, so both weigh alike in the constraint violation) and, with
    ``[constraints] chip_range``, the chip's relative margin over the stable region
    (:func:`chip_margin`; the field scales with M_z). These are the constraints the exact
    reduction applies, so the two answers solve one problem.

    Parameters
    ----------
    models : Responses or ModelSet
    study : Study
    constraints : ForceConstraints
    warm : HeightTable, optional
        A dense :func:`sweep` of a study without geometric variables: NSGA-II's search reads
        each design's per-height extrema off it (:meth:`HeightTable.at`, linear between the
        ``sweep_n`` heights: the per-height extrema depend on H alone, and the exact reduction
        uses the same sweep), and the set it returns is evaluated exactly, each height's
        problems started from the optima at the bracketing swept heights
        (:func:`heights_batch`); the chip's margin is read off it.
    maxiter : int
        Newton iterations at most per per-height problem.
    """

    def __init__(self, models: Responses | ModelSet, study: Study,
                 constraints: ForceConstraints, warm: HeightTable | None = None,
                 maxiter: int = 100):
        self.R = models if study.geometric_variables else as_responses(models)
        self.study, self.constraints, self.warm, self.maxiter = study, constraints, warm, maxiter
        bounds = {"H": study.design.H, "G": study.design.G}
        if study.M_z_variable:
            bounds["M_z"] = study.M_z_bounds
        bounds |= study.geometric_variables
        self.names = tuple(bounds)
        self.geometric = tuple(study.geometric_variables)
        self.lo = np.array([float(b[0]) for b in bounds.values()])
        self.hi = np.array([float(b[1]) for b in bounds.values()])
        self.scale = (abs(constraints.F_r_c) or 1.0, abs(constraints.F_z_c) or 1.0)
        self.chip_range = bool(study.constraints.chip_range)
        self._search = False  # NSGA-II searching: read the sweep
        self._known: dict[float, int] = {}  # height -> its row in self._solved
        self._solved: HeightTable | None = None
        self._chip_on_sweep = (chip_margin(study, warm.H, warm.t_m, warm.theta_m)
                               if self.chip_range and warm is not None and not self.geometric
                               else None)

    def _heights(self, H: np.ndarray) -> HeightTable:
        """The per-height extrema at ``H``, warm-started from the sweep; each height is solved
        once (the extrema do not depend on G, and offspring often keep a parent's H)."""
        if self._search:
            return self.warm.at(H)
        new = np.unique(H[[h not in self._known for h in H.tolist()]])
        if new.size:
            tab = heights_batch(self.R, new, self.study, warm=self.warm, coarse_start=False,
                                maxiter=self.maxiter)
            start = 0 if self._solved is None else self._solved.H.size
            self._solved = tab if self._solved is None else HeightTable(
                *(np.concatenate([getattr(self._solved, f.name), getattr(tab, f.name)])
                  for f in fields(HeightTable)[:-1]))
            self._known.update(zip(new.tolist(), range(start, start + new.size), strict=True))
        return self._solved.take(np.array([self._known[h] for h in H.tolist()], dtype=int))

    def values(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Scaled variables ``x`` (n, n_var) → SI values by name (M_z always present)."""
        v = self.lo + np.atleast_2d(x) * (self.hi - self.lo)
        cols = dict(zip(self.names, v.T, strict=True))
        cols.setdefault("M_z", np.full(v.shape[0], self.study.magnet.M_z))
        return cols

    def evaluate(self, x: np.ndarray):
        """(values, objectives (n, 2) [N/T], constraint columns (n, n_constr), table)."""
        cols = self.values(x)
        H, G, M = cols["H"], cols["G"], cols["M_z"]
        geo = {k: cols[k] for k in self.geometric}
        if self.warm is not None and not geo:
            tab = self._heights(H)
        else:
            tab = heights_batch(self.R, H, self.study, geometry=geo or None,
                                maxiter=self.maxiter)
        k = G * self.study.magnet.M_z / M  # Γ ∝ G / M_z
        objectives = np.stack([k * tab.gamma_r_max, k * tab.gamma_z_max], axis=1)
        g_r, g_z = self.constraints.margins(G * tab.f_r_min, G * tab.f_z_max)
        g = [g_r / self.scale[0], g_z / self.scale[1]]
        if self.chip_range:
            if self._chip_on_sweep is not None:
                m0 = np.interp(H, self.warm.H, self._chip_on_sweep)
            else:
                m0 = chip_margin(self.study, H, tab.t_m, tab.theta_m, geometry=geo)
            g.append(M / self.study.magnet.M_z * (1.0 + m0) - 1.0)
        return cols, objectives, np.stack(g, axis=1), tab

    def problem(self):
        """The pymoo ``Problem`` over the scaled variables."""
        from pymoo.core.problem import Problem

        outer = self

        class _Designs(Problem):
            def __init__(self):
                n = outer.lo.size
                super().__init__(n_var=n, n_obj=2, n_ieq_constr=2 + outer.chip_range,
                                 xl=np.zeros(n), xu=np.ones(n))

            def _evaluate(self, x, out, *args, **kwargs):
                _, out["F"], out["G"], _ = outer.evaluate(x)

        return _Designs()

    def solve(self) -> tuple[np.ndarray, int]:
        """Run NSGA-II (pymoo, population ``optimise.population``, ``nsga2_generations``
        generations, seed ``optimise.seed``: the same seed gives the same set).

        Returns
        -------
        numpy.ndarray, int
            The scaled variables of the feasible non-dominated designs (m, n_var), and the
            number of design evaluations.

        Raises
        ------
        InfeasibleError
            If NSGA-II found no feasible design.
        """
        from pymoo.algorithms.moo.nsga2 import NSGA2
        from pymoo.optimize import minimize

        o = self.study.optimise
        self._search = self.warm is not None and not self.geometric
        try:
            res = minimize(self.problem(), NSGA2(pop_size=o.population),
                           ("n_gen", o.nsga2_generations), seed=o.seed, verbose=False)
        finally:
            self._search = False
        opt = res.opt  # None when no feasible design was found
        feasible = np.zeros(0, bool) if opt is None else np.ravel(opt.get("CV")) <= 0
        if not feasible.any():
            raise InfeasibleError("NSGA-II found no feasible design; increase "
                                  "optimise.nsga2_generations or optimise.population")
        return np.atleast_2d(opt.get("X"))[feasible], int(res.algorithm.evaluator.n_eval)


def pareto_nsga2(models: Responses | ModelSet, study: Study, constraints: ForceConstraints,
                 table: HeightTable | None = None) -> ParetoSet:
    """NSGA-II over (H, G[, M_z]) minimising (Γ_r,max, Γ_z,max) under the constraints
    (:class:`DesignProblem`).

    Parameters
    ----------
    table : HeightTable, optional
        A dense :func:`sweep`; each design's per-height problems start from the optimum at the
        nearest swept height (see :func:`heights_batch`). Computed when not given.

    Raises
    ------
    InfeasibleError
        If no design is feasible (message from :func:`exact_reduction` where it explains).
    """
    R = as_responses(models)
    o = study.optimise
    table = sweep(R, study) if table is None else table
    problem = DesignProblem(R, study, constraints, warm=table)
    try:
        X, n_eval = problem.solve()
    except InfeasibleError:
        exact_reduction(R, study, constraints, table)  # raises the informative error
        raise
    X = X[np.argsort(X[:, 0], kind="stable")]
    cols, obj, _, tab = problem.evaluate(X)
    G = cols["G"]
    return ParetoSet(cols["H"], G, obj[:, 0], obj[:, 1], G * tab.f_r_min, G * tab.f_z_max,
                     constraints, o.seed, o.nsga2_generations, n_eval, cols["M_z"])


def curve_gap(points: np.ndarray, front: np.ndarray, joined: np.ndarray | None = None) -> float:
    """Largest relative distance of ``points`` (n, 2) from the curve through ``front`` (m, 2).

    For each point P the distance is min over the curve Q of max_i |P_i − Q_i| / Q_i; the curve
    is ``front`` refined by linear interpolation (20 points per segment) between neighbours
    ``k, k + 1`` where ``joined[k]`` (default: all of them).
    """
    Q = np.asarray(front, float)
    if Q.shape[0] > 1:
        joined = np.ones(Q.shape[0] - 1, bool) if joined is None else joined
        s = np.linspace(0, 1, 20, endpoint=False)
        segs = [Q[k] + s[:, None] * (Q[k + 1] - Q[k]) for k in range(Q.shape[0] - 1)
                if joined[k]]
        Q = np.concatenate(segs + [Q], axis=0)
    P = np.asarray(points, float)
    d = np.max(np.abs(P[:, None, :] - Q[None, :, :]) / np.abs(Q[None, :, :]), axis=2)
    return float(np.max(np.min(d, axis=1)))


def reduction_set(reduction: Reduction, study: Study) -> ParetoSet:
    """The exact reduction's Pareto set as a :class:`ParetoSet` (the front's heights at their
    least feasible G; ``generations`` and ``evaluations`` 0: no NSGA-II run).

    The sensor problem answers with the whole sensor; the publication's (H, G) problem beside
    it is read from its exact front, which NSGA-II would only approach."""
    idx = np.flatnonzero(reduction.front)
    t, G = reduction.table, reduction.G_star[idx]
    M = None if reduction.M_z_star is None else reduction.M_z_star[idx]
    return ParetoSet(t.H[idx], G, reduction.Gamma_r[idx], reduction.Gamma_z[idx],
                     G * t.f_r_min[idx], G * t.f_z_max[idx], reduction.constraints,
                     study.optimise.seed, 0, 0, M)


def front_gap(pareto: ParetoSet, reduction: Reduction) -> float:
    """Largest relative distance of NSGA-II's set from the exact Pareto curve in objective space
    (:func:`curve_gap`, the curve joining neighbouring front heights only)."""
    idx = np.flatnonzero(reduction.front)
    Q = np.stack([reduction.Gamma_r[idx], reduction.Gamma_z[idx]], axis=1)
    return curve_gap(pareto.objectives, Q, np.diff(idx) == 1)


def decision_index(objectives: np.ndarray) -> int:
    """Index of the chosen point: objectives normalised to [0, 1] over the set, equal weights,
    smallest sum (an objective constant over the set contributes 0)."""
    obj = np.asarray(objectives, float)
    lo, hi = obj.min(axis=0), obj.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return int(np.argmin(np.sum((obj - lo) / span, axis=1)))


@dataclass(frozen=True)
class Choice:
    """The chosen design and its constraints.

    Attributes
    ----------
    design : DesignResult
        Re-evaluated with the per-design method (grid, multistart trust region).
    index : int
        Its position in the set it was chosen from.
    constraints : ForceConstraints
    g_r, g_z : float
        Constraint values F_r,min − F_r,c and F_z,c − F_z,max [N] (≤ 0 feasible).
    active : tuple of str
        ``"F_r"`` and/or ``"F_z"``: constraints with |g| ≤ ``active_rtol`` |limit|.
    """

    design: DesignResult
    index: int
    constraints: ForceConstraints
    g_r: float
    g_z: float
    active: tuple[str, ...]


def choose(models: Responses | ModelSet, study: Study, candidates: ParetoSet | Reduction
           ) -> Choice:
    """Apply the decision rule to NSGA-II's set or to the exact front (:func:`decision_index`)."""
    if isinstance(candidates, Reduction):
        idx = np.flatnonzero(candidates.front)
        obj = np.stack([candidates.Gamma_r[idx], candidates.Gamma_z[idx]], axis=1)
        k = decision_index(obj)
        H, G, index = candidates.H[idx[k]], candidates.G_star[idx[k]], int(idx[k])
        M = None if candidates.M_z_star is None else candidates.M_z_star[index]
    else:
        index = decision_index(candidates.objectives)
        H, G = candidates.H[index], candidates.G[index]
        M = None if candidates.M_z is None else candidates.M_z[index]
    c = candidates.constraints
    M = float(M) if M is not None and study.M_z_variable else None
    d = per_design(models, float(H), float(G), study, M)
    g_r, g_z = (float(v) for v in c.margins(d.F_r_min, d.F_z_max))
    return Choice(d, index, c, g_r, g_z,
                  c.active(d.F_r_min, d.F_z_max, study.optimise.active_rtol))


#: Quantities of :func:`compare`: attribute, label, unit.
COMPARED: tuple[tuple[str, str, str], ...] = (
    ("Gamma_r_max", "Γ_r,max", "N/T"), ("Gamma_z_max", "Γ_z,max", "N/T"),
    ("F_r_min", "F_r,min", "N"), ("F_z_max", "F_z,max", "N"),
)


@dataclass(frozen=True)
class Comparison:
    """Two designs side by side; ``rows`` gives (label, unit, first, second, change %)."""

    first: DesignResult
    second: DesignResult

    def change(self, attr: str) -> float:
        """Percentage change of ``attr`` from the first design to the second:
        (v₂ − v₁) / v₁ × 100 (for negative F_r,min, growth in magnitude is positive)."""
        v1, v2 = getattr(self.first, attr), getattr(self.second, attr)
        return (v2 - v1) / v1 * 100.0 if v1 != 0 else float("nan")

    @property
    def rows(self) -> list[tuple[str, str, float, float, float]]:
        """(label, unit, value of first, value of second, change %) per compared quantity."""
        return [(label, unit, getattr(self.first, a), getattr(self.second, a), self.change(a))
                for a, label, unit in COMPARED]


def compare(first: DesignResult, second: DesignResult) -> Comparison:
    """Percentage changes of Γ_r,max, Γ_z,max, F_r,min, F_z,max from ``first`` to ``second``."""
    return Comparison(first, second)
