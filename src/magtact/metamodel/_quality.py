"""Whether an answer rests on a poor fit: the held-out accuracy each model records.

Every fitted model keeps its accuracy on the held-out (θ, H) paths in ``info["accuracy"]
["test"]`` (shipped fits, new fits and model files alike), so the verdict needs the models only.
A fit is poor when a held-out R² falls below :data:`POOR_R2` or a held-out error exceeds
:data:`POOR_OVER_RANGE` of the response's range over the data set. Both are far outside what
the default budget gives (on the bundled MagOne data: R² ≥ 0.998 and at most 0.95 % of the
range), and well inside what a fit stopped after a few generations gives (R² 0.19 for f_r after
5 generations).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Held-out R² below which a model is a poor fit.
POOR_R2 = 0.99
#: Held-out largest error over the response's range above which a model is a poor fit.
POOR_OVER_RANGE = 0.05


@dataclass(frozen=True)
class FitQuality:
    """The held-out accuracy of a model set and the verdict.

    Attributes
    ----------
    held_out : dict of str to (float, float, float)
        Per fitted response: held-out R², largest error over the response's range, largest
        relative error (where |y| exceeds 5 % of its largest magnitude).
    poor : tuple of str
        The responses whose held-out R² is below :data:`POOR_R2` or whose error over the range
        exceeds :data:`POOR_OVER_RANGE`.
    unchecked : tuple of str
        Fitted responses that record no held-out accuracy (a fit without held-out paths).
    """

    held_out: dict[str, tuple[float, float, float]]
    poor: tuple[str, ...]
    unchecked: tuple[str, ...] = ()

    @property
    def is_poor(self) -> bool:
        """True when some model is a poor fit."""
        return bool(self.poor)

    @property
    def worst_rel_err(self) -> float:
        """The largest held-out relative error over the fitted responses (NaN without any)."""
        return max((v[2] for v in self.held_out.values()), default=float("nan"))

    def message(self) -> str:
        """One sentence: the verdict with the held-out figures of the poor models."""
        if not self.poor:
            return ("the metamodels' held-out accuracy is within the thresholds (R² ≥ "
                    f"{POOR_R2:g}, error ≤ {POOR_OVER_RANGE:.0%} of the range)")
        parts = [f"{k}: held-out R² {self.held_out[k][0]:.4g}, error "
                 f"{self.held_out[k][1]:.3g} of the range" for k in self.poor]
        return ("the answer rests on a poor fit (" + "; ".join(parts) + f"; thresholds R² ≥ "
                f"{POOR_R2:g}, error ≤ {POOR_OVER_RANGE:.0%} of the range): fit again with a "
                "larger budget (metamodel.generations) before trusting it")


def fit_quality(models) -> FitQuality:
    """The held-out accuracy recorded in each fitted model of ``models`` (a ModelSet) and
    whether the set is a poor fit (:data:`POOR_R2`, :data:`POOR_OVER_RANGE`). Models without a
    fit record (the exact field) are left out."""
    held, poor, unchecked = {}, [], []
    for name, model in models.items():
        info = getattr(model, "info", None) or {}
        if "accuracy" not in info:
            continue  # the exact field: nothing fitted
        test = (info.get("accuracy") or {}).get("test")
        if not test:
            unchecked.append(name)
            continue
        r2, over, rel = (float(test[k]) for k in ("r2", "max_abs_err_over_range", "max_rel_err"))
        held[name] = (r2, over, rel)
        if not (r2 >= POOR_R2 and over <= POOR_OVER_RANGE):  # NaN counts as poor
            poor.append(name)
    return FitQuality(held, tuple(poor), tuple(unchecked))


def fit_quality_rows(models, columns: int) -> list[list[str]]:
    """The design card's row for a poor fit (none when the fit is within the thresholds):
    the verdict in each of ``columns`` answer cells."""
    q = fit_quality(models)
    if not q.is_poor:
        return []
    cell = "poor fit: " + ", ".join(f"{k} held-out R² {q.held_out[k][0]:.4g}" for k in q.poor)
    return [["metamodels (the answer rests on a poor fit; fit again with a larger budget)",
             *([cell] * columns)]]
