"""Everything ``magtact fit`` writes: model files, ``metamodels.md`` and, if asked, figures."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..doe import geometry_dims
from ..study import Study
from ._fit import FitResult, _table, fit_models, holdout_mask
from ._io import save_models
from ._markdown import write_markdown


def write_fit_outputs(study: Study, ds, folder: str | Path, *, H: float | None = None,
                      G: float | None = None, log=None,
                      gamma_check: Callable[..., dict] | None = None,
                      figures: Callable[..., list[Path]] | None = None,
                      result: FitResult | None = None) -> tuple[FitResult, list[Path]]:
    """Fit the study's metamodels to ``ds`` and write them with their report.

    Writes ``<name>.json`` per response and ``metamodels.md`` (expressions, accuracy and,
    with ``gamma_check``, Γ against the data).

    Parameters
    ----------
    study : Study
    ds : xarray.Dataset
        The DOE data set.
    folder : path
        Output folder (created).
    H, G : float, optional
        Design [m], [Pa] of the figures; default: the original design.
    log : callable, optional
        Progress messages of the fit.
    gamma_check : callable, optional
        ``gamma_check(models, ds)`` compares the models' Γ with the data's
        (:func:`magtact.sensitivity.compare_with_data`); its result goes into
        ``metamodels.md``. None: no check.
    result : FitResult, optional
        A fit of ``ds`` already made (written, not fitted again).
    figures : callable, optional
        ``figures(study, models, table, test_mask, folder, H, G)`` draws the stage's figures
        (:func:`magtact.report.fit_figures`: ``force_map``, ``gamma``, ``parity``). None: no
        figures.

    Returns
    -------
    (FitResult, list of Path)
        The fit and the files written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    H = study.design.H_original if H is None else H
    G = study.design.G_original if G is None else G
    result = fit_models(ds, study, log=log) if result is None else result
    models = result.model_set(study)
    files = save_models(models, folder)
    # the data's finite-difference Γ is taken on a (t, θ, H) grid: not over magnet sizes
    check = None if gamma_check is None or geometry_dims(ds) else gamma_check(models, ds)
    files.append(write_markdown(result, folder / "metamodels.md",
                                title=f"Metamodels: {study.name}", gamma_check=check,
                                exact_B=study.metamodel.b_model == "exact"))
    if figures is not None:
        table = _table(ds)[0]
        files += figures(study, models, table, holdout_mask(table, result.holdout), folder, H, G)
    return result, files
