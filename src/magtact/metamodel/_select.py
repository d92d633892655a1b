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
    #: (size name, weight) of the shipped fits blended across magnet sizes (empty: none).
    blend: tuple[tuple[str, float], ...] = ()

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
        if self.blend:
            from ..parts import SIZES

            parts = ", ".join(f"{name} mm × {w:.3g}" for name, w in self.blend)
            along = ("radius" if len({SIZES[name].H_m for name, _ in self.blend}) == 1
                     else "height and radius")
            return ("the shipped fits of the magnet sizes around it blended along the "
                    f"magnet's {along} ({parts})")
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


def blended_metamodels(study: Study, parts) -> Selection | None:
    """The models of ``study``'s magnet blended from the shipped fits of the sizes around it
    (``parts``: :func:`magtact.doe.bundled_blend`'s): f_r and f_z the weighted sums of the
    parts' force models (both forms, so values and derivatives blend alike), the
    field the exact one of ``study``'s magnet. None where a part has no shipped fit."""
    from ._exact_field import ExactField
    from ._model import Metamodel

    sets = []
    for _, _, ds, sub in parts:
        found = find_shipped(sub, ds)
        if found is None:
            return None
        sets.append(shipped_models(found[0], sub, ds, found[1]))
    weights = [w for _, w, _, _ in parts]
    heaviest = int(max(range(len(weights)), key=lambda k: abs(weights[k])))
    blend = tuple((name, w) for name, w, _, _ in parts)

    def blended(name):
        ms = [m[name] for m in sets]
        info = dict(ms[heaviest].info) | {"blended_from": dict(blend)}
        return Metamodel(name=name, units=ms[0].units, info=info,
                         expr=sum(w * m.expr for w, m in zip(weights, ms, strict=True)),
                         expr_pq=sum(w * m.expr_pq for w, m in zip(weights, ms, strict=True)))

    models = ModelSet(B_r=ExactField(study, "B_r"), B_z=ExactField(study, "B_z"),
                      f_r=blended("f_r"), f_z=blended("f_z"))
    return Selection(models, None, None, 1.0, blend)
