"""Everything ``magtact fit`` writes: model files, ``metamodels.md``, figures."""

from __future__ import annotations

from pathlib import Path

from ..study import Study
from ._fit import FitResult, _table, fit_models, holdout_mask
from ._io import save_models
from ._markdown import write_markdown


def write_fit_outputs(study: Study, ds, folder: str | Path, *, H: float | None = None,
                      G: float | None = None, log=None) -> tuple[FitResult, list[Path]]:
    """Fit the study's metamodels to ``ds`` and write them with their report and figures.

    Writes ``<name>.json`` per response, ``metamodels.md`` (expressions, accuracy, Γ check
    against the data) and the figures ``force_map``, ``gamma`` (at design H [m], G [Pa];
    default: the original design) and ``parity`` (PNG and SVG).

    Returns
    -------
    (FitResult, list of Path)
        The fit and the files written.
    """
    from ..report._fig_metamodel import fig_force_map, fig_gamma, fig_parity
    from ..sensitivity import compare_with_data

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    H = study.design.H_original if H is None else H
    G = study.design.G_original if G is None else G
    result = fit_models(ds, study, log=log)
    models = result.model_set(study)
    files = save_models(models, folder)
    check = compare_with_data(models, ds)
    files.append(write_markdown(result, folder / "metamodels.md",
                                title=f"Metamodels: {study.name}", gamma_check=check,
                                exact_B=study.metamodel.b_model == "exact"))
    table, _, _ = _table(ds)
    files += fig_force_map(models, study, H, G, folder / "force_map")
    files += fig_gamma(models, study, H, G, folder / "gamma")
    files += fig_parity(models, table, holdout_mask(table, result.holdout), folder / "parity")
    return result, files
