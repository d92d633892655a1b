"""Which metamodels a study uses: the fit shipped with magtact when it matches, else a new fit.

The one place of that decision (the pipeline, the command line and :func:`magtact.design`
ask here).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..study import Study
from ._fit import FitResult, fit_models
from ._io import load_models
from ._model import ModelSet
from ._prefitted import find_prefitted


@dataclass(frozen=True)
class Selection:
    """The models of a study and where they come from.

    Attributes
    ----------
    models : ModelSet
    shipped : Path or None
        The shipped fit's folder when it was used (same data SHA-256 and settings).
    fit : FitResult or None
        The new fit when one was made.
    """

    models: ModelSet
    shipped: Path | None
    fit: FitResult | None

    @property
    def source(self) -> str:
        """In words: the shipped fit or a new fit."""
        return ("the fit shipped with magtact for this data set and these settings"
                if self.shipped is not None else "fitted now to the data set")


def select_metamodels(study: Study, ds, *, refit: bool = False,
                      log: Callable[[str], None] | None = None) -> Selection:
    """The shipped fit of ``ds`` if it was made with ``study``'s settings (and not ``refit``),
    else :func:`fit_models` (minutes with the default budget)."""
    shipped = None if refit else find_prefitted(study, ds)
    if shipped is not None:
        return Selection(load_models(shipped), shipped, None)
    if log:
        log("fitting the metamodels (no shipped fit matches this data set and these settings)")
    fit = fit_models(ds, study, log=log)
    return Selection(fit.model_set(study), None, fit)
