"""The figures of each stage, in the form the stages' writers accept as ``figures``.

Stages compute and write data; they draw nothing themselves. Each writer takes an optional
``figures`` callable, and these are the ones magtact's command line and pipeline pass:

=========================================  ==============================================
writer                                      figures
=========================================  ==============================================
``magtact.magnetics.write_field_outputs``   :func:`field_figures`
``magtact.metamodel.write_fit_outputs``     :func:`fit_figures`
``magtact.optimise.write_optimise_outputs`` :func:`optimise_figures`
``magtact.validation.write_outputs``        :func:`validation_figures`
=========================================  ==============================================

Every function writes PNG and SVG files and returns the paths written;
:func:`optimise_figure_objects` returns the optimisation's figures as objects instead.
"""

from __future__ import annotations

from pathlib import Path

from ._fig_field import fig_field
from ._fig_geometry import draw_geometry_pareto
from ._fig_metamodel import fig_force_map, fig_gamma, fig_parity
from ._fig_optimise import draw_maps, draw_pareto, fig_maps, fig_pareto
from ._fig_validation import fig_validation


def field_figures(study, folder: str | Path, solver: str | None = None) -> list[Path]:
    """The B_r, B_z maps of the field stage: ``folder/field_maps.{png,svg}``.

    Parameters
    ----------
    study : magtact.study.Study
    folder : path
        Output folder of the field stage.
    solver : {"fe", "exact"}, optional
        Field solver (default ``study.magnetics.solver``).
    """
    return fig_field(study, Path(folder) / "field_maps", solver=solver)


def fit_figures(study, models, table: dict, test_mask, folder: str | Path, H: float,
                G: float) -> list[Path]:
    """The figures of the metamodel stage: ``force_map``, ``gamma`` and ``parity``.

    Parameters
    ----------
    study : magtact.study.Study
    models : magtact.metamodel.ModelSet
    table : dict of numpy.ndarray
        The flattened DOE data the models were fitted to (``t, theta, H`` and the responses).
    test_mask : numpy.ndarray of bool
        Points of ``table`` held out of the fit.
    folder : path
        Output folder of the metamodel stage.
    H, G : float
        Design [m], [Pa] of the force map and the sensitivity figure.
    """
    folder = Path(folder)
    # over geometric design variables the maps are drawn at the study's own magnet and body
    at = models.at(**study.geometry()) if study.geometric_variables else models
    return (fig_force_map(at, study, H, G, folder / "force_map")
            + fig_gamma(at, study, H, G, folder / "gamma")
            + fig_parity(models, table, test_mask, folder / "parity"))


def optimise_figures(optimisation, folder: str | Path) -> list[Path]:
    """The figures of the optimisation stage: ``maps_objectives``, ``maps_constraints`` and
    ``pareto_set``.

    Parameters
    ----------
    optimisation : magtact.optimise.Optimisation
    folder : path
        Output folder of the optimisation stage.
    """
    folder = Path(folder)
    return (fig_maps(optimisation.maps, optimisation.constraints, folder)
            + fig_pareto(optimisation, folder / "pareto_set"))


def optimise_figure_objects(optimisation) -> dict:
    """The optimisation's figures as matplotlib Figures by name (not saved): those of
    :func:`optimise_figures`, or ``geometry_pareto`` over geometric design variables.

    Parameters
    ----------
    optimisation : magtact.optimise.Optimisation or GeometryOptimisation
    """
    if hasattr(optimisation, "maps"):
        return (draw_maps(optimisation.maps, optimisation.constraints)
                | {"pareto_set": draw_pareto(optimisation)})
    return {"geometry_pareto": draw_geometry_pareto(optimisation)}


def validation_figures(validation, path: str | Path) -> list[Path]:
    """The figure of a validation, mean ± std of the tests against the model, at ``path``
    (without suffix).

    Parameters
    ----------
    validation : magtact.validation.Validation
    path : path
        File name without suffix (the writer passes ``validation[_synthetic]``).
    """
    return fig_validation(validation, path)
