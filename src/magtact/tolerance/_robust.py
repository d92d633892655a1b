"""The robust verdict: each requirement at the worst corner of the tolerance box and as a
yield, the fraction of built units that meet it, with its confidence interval, and the
tolerance that limits it (docs/method.md §16).

The yield is a randomised quasi-Monte Carlo estimate: ``[tolerances] robust_replicates``
independently scrambled Sobol sets (:class:`scipy.stats.qmc.Sobol`) of
``robust_samples / robust_replicates`` units each; the mean over the sets is the yield and
their spread gives a Student-t 95 % interval (where every set gives the same fraction, the
Clopper–Pearson interval of all units instead). The FE bias is a property of the model, not
of a unit: the yield takes it at its adverse end.

What limits a requirement: at its worst corner, each input alone moved from its nominal
value to the corner's, the others nominal; the input whose move costs the most margin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats
from scipy.stats import qmc

from ..metamodel import ModelSet
from ._box import WORDS, ToleranceBox, corners, tolerance_box
from ._units import design_context, unit_figures

#: A figure this close to its requirement meets it (the nominal verdict's rule).
BOUNDARY_RTOL = 1e-6
#: Confidence of the yield's interval.
CONFIDENCE = 0.95


def _n(x: float) -> str:
    return f"{x:.3g}"


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"


@dataclass(frozen=True)
class RobustRequirement:
    """One requirement over the built units.

    Attributes
    ----------
    key, statement : str
        As the nominal verdict's (:class:`magtact.designer.Requirement`).
    met : bool
        Whether the unit at the worst corner of the box meets it (then every unit in the box
        does).
    yield_fraction : float
        The fraction of units that meet it.
    interval : (float, float)
        Its 95 % confidence interval.
    worst : float
        The requirement's figure at the worst corner (a force [N]; σ_F [N] for the
        resolution); ``worst_words`` says it in words.
    nominal : float
        The same figure of the nominal unit (the tolerance model's).
    margin : float
        ``worst`` beyond the requirement (negative: short of it) [N].
    limited_by : str
        The input that limits it (:data:`magtact.tolerance.INPUTS`; "" where none moves it).
    contributions : dict of float
        Each input's share: the margin it costs alone at the worst corner [N].
    corner : dict of float
        The worst corner's values by input.
    """

    key: str
    statement: str
    met: bool
    yield_fraction: float
    interval: tuple[float, float]
    worst: float
    worst_words: str
    nominal: float
    margin: float
    limited_by: str
    contributions: dict[str, float]
    corner: dict[str, float]

    @property
    def answer(self) -> str:
        """Whether the worst case meets it, and the fraction of units that does: "no at the
        worst case; 97.7 % of units meet it (95 % CI 97–98.4 %; the worst case saturates at
        3.03 N; limited by G)"."""
        lo, hi = self.interval
        limit = f"; limited by {WORDS[self.limited_by]}" if self.limited_by else ""
        return (f"{'yes' if self.met else 'no'} at the worst case; "
                f"{_pct(self.yield_fraction)} of units meet it (95 % CI {_pct(lo)}–{_pct(hi)}; "
                f"the worst case {self.worst_words}{limit})")

    @property
    def text(self) -> str:
        return f"{self.statement}: {self.answer}"

    def to_json(self) -> dict:
        return {"requirement": self.key, "met_worst_case": self.met, "text": self.text,
                "statement": self.statement, "answer": self.answer,
                "yield": self.yield_fraction, "yield_interval": list(self.interval),
                "worst": None if math.isinf(self.worst) else self.worst,
                "worst_words": self.worst_words,
                "nominal": None if math.isinf(self.nominal) else self.nominal,
                "margin": None if math.isinf(self.margin) else self.margin,
                "limited_by": self.limited_by or None, "contributions": self.contributions,
                "worst_corner": self.corner}


@dataclass(frozen=True)
class RobustVerdict:
    """Every tolerance-dependent requirement of a design over its built units.

    Attributes
    ----------
    requirements : tuple of RobustRequirement
    yield_fraction, interval : float, (float, float)
        The fraction of units that meet all of them, and its 95 % interval.
    samples, replicates : int
        Units of the quasi-Monte Carlo and the scrambled sets they come in.
    box : ToleranceBox
    sigma_nominal, sigma_worst : float
        σ_F [N] over the required loads of the nominal unit and at the worst corner (NaN:
        the chip's noise is not known).
    corner_bounds_samples : bool
        Whether no sampled unit is worse than the worst corner in any requirement (the
        corners' search holds).
    """

    requirements: tuple[RobustRequirement, ...]
    yield_fraction: float
    interval: tuple[float, float]
    samples: int
    replicates: int
    box: ToleranceBox
    sigma_nominal: float
    sigma_worst: float
    corner_bounds_samples: bool

    @property
    def met(self) -> bool:
        """Whether the worst corner meets every requirement."""
        return all(r.met for r in self.requirements)

    def __getitem__(self, key: str) -> RobustRequirement:
        for r in self.requirements:
            if r.key == key:
                return r
        raise KeyError(f"no requirement {key!r}; requirements: "
                       f"{[r.key for r in self.requirements]}")

    def to_json(self) -> dict:
        return {"requirements": [r.to_json() for r in self.requirements],
                "yield": self.yield_fraction, "yield_interval": list(self.interval),
                "samples": self.samples, "replicates": self.replicates,
                "sigma_F_nominal_N": None if math.isnan(self.sigma_nominal)
                else self.sigma_nominal,
                "sigma_F_worst_N": None if math.isnan(self.sigma_worst) else self.sigma_worst,
                "corner_bounds_samples": self.corner_bounds_samples,
                "tolerances": [{"input": t.name, "nominal": t.nominal, "low": t.low,
                                "high": t.high, "distribution": t.distribution,
                                "source": t.source} for t in self.box.inputs]}

    def __str__(self) -> str:
        return "\n".join(r.text for r in self.requirements) + (
            f"\nall requirements: {_pct(self.yield_fraction)} of units (95 % CI "
            f"{_pct(self.interval[0])}–{_pct(self.interval[1])})")


def _margins(fig: dict, F_z: float, F_r: float, resolution: float) -> dict[str, np.ndarray]:
    """Each requirement's margin (≥ 0: met) from the units' figures."""
    tol_z, tol_r = F_z * BOUNDARY_RTOL, F_r * BOUNDARY_RTOL
    carries = fig["F_z_max"] - F_z + tol_z
    reads = np.where(np.isinf(fig["F_sat"]), np.inf, fig["F_sat"] - F_z)
    out = {"normal": np.minimum(carries, np.where(reads > 0, reads, reads - tol_z)),
           "shear": np.minimum(fig["shear_stable"], fig["shear_read"]) - F_r + tol_r}
    if resolution > 0 and np.isfinite(fig["sigma"]).all():
        out["resolution"] = resolution - fig["sigma"]
    return out


def _words(key: str, fig: dict, i: int, F_z: float, F_r: float) -> tuple[float, str]:
    """The figure of requirement ``key`` of unit i, and in words."""
    if key == "normal":
        F_max, F_sat = fig["F_z_max"][i], fig["F_sat"][i]
        if F_max < F_sat:
            return F_max, f"carries {_n(F_max)} N stably"
        return F_sat, ("never saturates in the stable region" if math.isinf(F_sat)
                       else f"saturates at {_n(F_sat)} N")
    if key == "shear":
        stable, within, read = (fig[k][i] for k in ("shear_stable", "shear_within",
                                                    "shear_read"))
        if stable < read:
            return stable, f"shear turns unstable at {_n(stable)} N"
        if read >= within * (1 - 1e-9) and within < F_r:
            return read, (f"the body carries at most {_n(within)} N of shear within "
                          f"{_n(F_z)} N normal")
        return read, f"reads shear up to {_n(read)} N within {_n(F_z)} N normal"
    s = fig["sigma"][i]
    return s, f"σ_F {_n(1e3 * s)} mN"


def _interval(per_set: np.ndarray, met: np.ndarray) -> tuple[float, float]:
    """The yield's 95 % interval from the fractions of the scrambled sets (Student t), or the
    Clopper–Pearson interval of all units where the sets agree."""
    R = per_set.size
    mean, sd = float(per_set.mean()), float(per_set.std(ddof=1))
    if sd > 0:
        h = stats.t.ppf(0.5 + CONFIDENCE / 2, R - 1) * sd / math.sqrt(R)
        return max(0.0, mean - h), min(1.0, mean + h)
    ci = stats.binomtest(int(met.sum()), met.size).proportion_ci(CONFIDENCE, "exact")
    return float(ci.low), float(ci.high)


def sobol_units(box: ToleranceBox, samples: int, replicates: int, seed: int) -> np.ndarray:
    """``replicates`` scrambled Sobol sets of units (replicates × 2^m rows, 2^m ≥
    samples / replicates), the FE bias at its adverse (high) end."""
    m = max(1, math.ceil(math.log2(max(samples / replicates, 2))))
    free = [k for k, n in enumerate(box.names) if n != "fe_bias"]
    rng = np.random.default_rng(seed)
    sets = []
    for _ in range(replicates):
        u = qmc.Sobol(len(free), scramble=True, seed=rng).random_base2(m)
        full = np.full((u.shape[0], len(box.names)), 0.5)
        full[:, free] = u
        X = box.sample(full)
        X[:, box.index("fe_bias")] = box.inputs[box.index("fe_bias")].high
        sets.append(X)
    return np.concatenate(sets)


def robust_verdict(models: ModelSet, answer, box: ToleranceBox | None = None, *,
                   samples: bool = True) -> RobustVerdict:
    """The robust verdict of a designer's answer (:class:`magtact.designer.DesignAnswer`;
    ``models``: those of its study, in the sensor problem with the exact field, as
    :meth:`magtact.Result.of` gives them) over ``box`` (default: its study's,
    :func:`tolerance_box`). See the module notes. Without ``samples``, the worst corners
    alone: each requirement's ``met`` (with ``[tolerances] yield_target`` 0), worst and
    nominal figures and what limits it, the yields NaN (what a solve needs to decide, at a
    fraction of the cost)."""
    study = answer.study
    box = tolerance_box(study, answer.sensor.grade) if box is None else box
    ctx = design_context(models, answer, box)
    tol, req = study.tolerances, study.requirements
    target = tol.yield_target
    if not samples and target > 0:
        raise ValueError("a yield target is judged on the samples")
    X_s = (sobol_units(box, tol.robust_samples, tol.robust_replicates, tol.seed) if samples
           else np.empty((0, len(box.names))))
    X_c = corners(box)
    X_0 = box.nominal[None, :]
    fig = unit_figures(ctx, box, np.concatenate([X_0, X_c, X_s]))
    M = _margins(fig, req.F_z, req.F_r, req.resolution)
    nc, ns = X_c.shape[0], X_s.shape[0]
    corner_rows, sample_rows = slice(1, 1 + nc), slice(1 + nc, 1 + nc + ns)
    # each requirement's worst corner, then each input alone at it
    worst = {k: 1 + int(np.argmin(m[corner_rows])) for k, m in M.items()}
    alone = []
    for k in M:
        x_w = np.concatenate([X_0, X_c])[worst[k]]
        for i in range(len(box.names)):
            x = box.nominal.copy()
            x[i] = x_w[i]
            alone.append(x)
    fig_alone = unit_figures(ctx, box, np.array(alone))
    M_alone = _margins(fig_alone, req.F_z, req.F_r, req.resolution)
    d = len(box.names)
    statements = {r.key: r.statement for r in answer.verdict.requirements} \
        if answer.verdict is not None else {}
    out, bounds = [], True
    met_all = np.ones(ns, bool)
    for j, (k, m) in enumerate(M.items()):
        met = m[sample_rows] >= 0
        met_all &= met
        per_set = met.reshape(tol.robust_replicates, -1).mean(axis=1) if ns else \
            np.full(tol.robust_replicates, np.nan)
        i_w = worst[k]
        if ns:
            bounds &= bool(m[sample_rows].min() >= m[i_w] - 1e-9 * max(1.0, abs(m[i_w])))
        cost = {box.names[i]: float(M_alone[k][j * d + i] - m[0]) for i in range(d)}
        cost = {n: (0.0 if not np.isfinite(v) else v) for n, v in cost.items()}
        limited = min(cost, key=cost.get)
        value, words = _words(k, fig, i_w, req.F_z, req.F_r)
        nominal, _ = _words(k, fig, 0, req.F_z, req.F_r)
        out.append(RobustRequirement(
            k, statements.get(k, k),
            bool(m[i_w] >= 0) if target <= 0 else bool(per_set.mean() >= target),
            float(per_set.mean()),
            _interval(per_set, met) if ns else (math.nan, math.nan), float(value), words,
            float(nominal), float(m[i_w]),
            limited if cost[limited] < 0 else "", cost,
            {n: float(v) for n, v in zip(box.names, np.concatenate([X_0, X_c])[i_w],
                                         strict=True)}))
    s_nom = float(fig["sigma"][0])
    s_worst = float(fig["sigma"][corner_rows].max())
    if not ns:
        return RobustVerdict(tuple(out), math.nan, (math.nan, math.nan), 0,
                             tol.robust_replicates, box, s_nom, s_worst, bounds)
    per_set = met_all.reshape(tol.robust_replicates, -1).mean(axis=1)
    return RobustVerdict(tuple(out), float(per_set.mean()), _interval(per_set, met_all), ns,
                         tol.robust_replicates, box, s_nom, s_worst, bounds)




@dataclass(frozen=True)
class WorstFactors:
    """A design's tolerances as factors the optimiser's constraints can take
    (:func:`worst_factors`, :func:`yield_factors`): the chip's reading over the nominal one
    (``field``, ≥ 1), the forces the body must carry over the nominal ones (``force``, ≤ 1) and
    the normal force the chip must read at the nominal parts over the required one (``read``,
    ≥ 1)."""

    field: float
    force: float
    read: float = float("nan")

    def __post_init__(self):
        if math.isnan(self.read):
            object.__setattr__(self, "read", 1.0 / self.force)


def worst_factors(models: ModelSet, answer, box: ToleranceBox | None = None
                  ) -> WorstFactors:
    """The worst corner of ``answer``'s box for reading the required normal force, as factors.

    The forces' factor is exact: every force ∝ G, so the softest body with the FE forces at
    their bias gives (1 + G_low) / (1 + bias). The field's factor is the magnetisation scale
    at which the nominal unit, its forces times that factor, saturates at the worst corner's
    saturation force (brentq): it folds the remanence, temperature, sensitivity, offset,
    standoff, body height and magnet size into one scale, exact for this design and close
    for its neighbours (the robust verdict of the design the optimiser returns says whether
    it holds).
    """
    from scipy.optimize import brentq

    box = tolerance_box(answer.study, answer.sensor.grade) if box is None else box
    ctx = design_context(models, answer, box)
    g, b = box.inputs[box.index("G")], box.inputs[box.index("fe_bias")]
    force = (1.0 + g.low) / (1.0 + b.high)
    F_worst = float(unit_figures(ctx, box, corners(box))["F_sat"].min())
    i = box.index("B_r")

    def excess(k):
        x = box.nominal.copy()
        x[i] = k
        return float(unit_figures(ctx, box, x[None, :])["F_sat"][0]) * force - F_worst

    if not np.isfinite(F_worst) or excess(1.0) <= 0:
        return WorstFactors(1.0, force)
    hi = 1.5
    while excess(hi) > 0 and hi < 64:
        hi *= 2
    return WorstFactors(float(brentq(excess, 1.0, hi, xtol=1e-6)), force)


def yield_factors(models: ModelSet, answer, target: float, box: ToleranceBox | None = None
                  ) -> WorstFactors:
    """The factors at which a design's units meet the normal requirement with the fraction
    ``target``: the (1 − target)-quantiles, over the quasi-Monte Carlo's units, of their
    saturation force and of the normal force they carry, each over the nominal unit's; the
    chip must then read F_z,req over the first at the nominal parts, the body carry it over
    the second. Calibrated on this design (its units' spread relative to its nominal unit).
    """
    box = tolerance_box(answer.study, answer.sensor.grade) if box is None else box
    ctx = design_context(models, answer, box)
    tol = answer.study.tolerances
    X = np.concatenate([box.nominal[None, :],
                        sobol_units(box, tol.robust_samples, tol.robust_replicates, tol.seed)])
    fig = unit_figures(ctx, box, X)
    with np.errstate(invalid="ignore"):
        sat = np.where(np.isinf(fig["F_sat"]), 1.0, fig["F_sat"] / fig["F_sat"][0])[1:]
    carry = fig["F_z_max"][1:] / fig["F_z_max"][0]
    q = 1.0 - target
    # where that many units saturate at rest, no nominal part reads for the target: inf
    low = float(np.quantile(sat, q))
    return WorstFactors(1.0, min(1.0, float(np.quantile(carry, q))),
                        max(1.0, 1.0 / low) if low > 0 else math.inf)


__all__ = ["RobustRequirement", "RobustVerdict", "WorstFactors", "robust_verdict",
           "sobol_units", "worst_factors", "yield_factors"]
