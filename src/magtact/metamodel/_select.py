"""Which metamodels a study uses: a fit shipped with magtact when it serves, else a new fit.

The one place of that decision (the pipeline, the command line and :func:`magtact.design`
ask here).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..study import Study
from ._fit import FitResult, fit_models
from ._model import ModelSet
from ._prefitted import find_shipped, shipped_models
from ._quality import FitQuality, fit_quality


@dataclass(frozen=True)
class Selection:
    """The models of a study and where they come from.

    Attributes
    ----------
    models : ModelSet
    shipped : Path or None
        The shipped fit's folder when it was used (same data SHA-256, or an exact rescaling of
        its data, and the same settings).
    fit : FitResult or None
        The new fit when one was made.
    field_scale : float
        M_z / M_z,data: the factor on the shipped fit's field models (1 unless the study's
        magnet is magnetised otherwise than the data's).
    """

    models: ModelSet
    shipped: Path | None
    fit: FitResult | None
    field_scale: float = 1.0

    @property
    def quality(self) -> FitQuality:
        """The models' held-out accuracy and whether the answer rests on a poor fit."""
        return fit_quality(self.models)

    @property
    def poor_fit(self) -> bool:
        """True when a model's held-out accuracy is below the thresholds
        (:data:`magtact.metamodel.POOR_R2`, :data:`magtact.metamodel.POOR_OVER_RANGE`)."""
        return self.quality.is_poor

    @property
    def source(self) -> str:
        """In words: the shipped fit or a new fit (and the verdict when the fit is poor)."""
        text = ("the fit shipped with magtact for this data set and these settings"
                if self.shipped is not None else "fitted now to the data set")
        if self.shipped is not None and self.field_scale != 1.0:
            text += f" (field × {self.field_scale:.6g}: the study's M_z over the data's)"
        return text + (f"; {self.quality.message()}" if self.poor_fit else "")


def select_metamodels(study: Study, ds, *, refit: bool = False,
                      log: Callable[[str], None] | None = None) -> Selection:
    """The shipped fit of ``ds`` if it was made with ``study``'s settings (and not ``refit``),
    else :func:`fit_models` (minutes with the default budget)."""
    found = None if refit else find_shipped(study, ds)
    if found is not None:
        folder, scale = found
        return Selection(shipped_models(folder, study, ds, scale), folder, None, scale)
    if log:
        log("fitting the metamodels (no shipped fit matches this data set and these settings)")
    fit = fit_models(ds, study, log=log)
    return Selection(fit.model_set(study), None, fit)
