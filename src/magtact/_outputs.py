"""What is made of a :class:`magtact.Result` for people and files: the design card, the error
budgets of the chosen and the original design, the figures and the results folder.

These are functions of the record rather than members of it, so that the record needs none of
the report's code. The error budgets are a Monte-Carlo computation (about a second each): every
function here that needs them takes them as ``budgets=`` from a caller that has them already and
computes them only where they are not given, so that the card, ``budget.json`` and the figures
of one results folder share one computation.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ._front import calibrate, error_budget

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._card import Card
    from ._result import Result
    from .budget import Budget
    from .metamodel import ModelSet


def error_budgets(result: Result) -> tuple[Budget, Budget] | None:
    """The error budgets of the chosen and the original design of a result, with the mesh error
    of its data set (docs/method.md §12).

    Parameters
    ----------
    result : Result

    Returns
    -------
    (Budget, Budget) or None
        The chosen design's and the original design's (:func:`magtact.error_budget` of
        ``result.chosen`` and ``result.original`` with ``dataset=result.dataset``); None over
        geometric design variables (a budget belongs to one geometry).

    See Also
    --------
    error_budget : the budget of any one design, with other noise or seeds.

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design()                                   # doctest: +SKIP
    >>> chosen, original = magtact.error_budgets(result)            # doctest: +SKIP
    """
    if result.study.geometric_variables:
        return None
    return tuple(error_budget(result, a, dataset=result.dataset)
                 for a in (result.chosen, result.original))


def _extra_rows(models: ModelSet, budgets: tuple[Budget, Budget] | None) -> list[list[str]]:
    """The card's rows after the answers': a poor fit of the models, then the budgets'."""
    from .budget import budget_card_rows
    from .metamodel import fit_quality_rows  # a poor fit is said on the card

    return fit_quality_rows(models, 2) + ([] if budgets is None else budget_card_rows(budgets))


def card(result: Result, budgets: tuple[Budget, Budget] | None = None) -> Card:
    """The design card of a result: the chosen and the original design side by side, as in
    ``card.json``.

    Parameters
    ----------
    result : Result
    budgets : (Budget, Budget), optional
        :func:`error_budgets` of ``result`` where the caller has them (computed otherwise: a
        few seconds).

    Returns
    -------
    Card
        A dict (``header``, ``rows`` in words and units and, in the sensor problem,
        ``verdict`` and ``parts`` first) that prints as a few lines and shows as a table in a
        notebook (:func:`magtact.report.card_rows`).

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design()                                   # doctest: +SKIP
    >>> print(magtact.card(result))                                 # doctest: +SKIP
    """
    from ._card import Card, CardChoices
    from ._records import to_json
    from .report import card_rows, parts_list, silicone_table, size_table

    if budgets is None:
        budgets = error_budgets(result)
    header, rows = card_rows([result.chosen, result.original], result.constraints,
                             rtol=result.study.optimise.active_rtol)
    doc = {"header": header, "rows": rows + _extra_rows(result.models, budgets)}
    if result.chosen.verdict is not None:  # the verdict and the parts lead, as in card.json
        doc = {"verdict": result.chosen.verdict.to_json(),
               "parts": parts_list(result.chosen)} | doc
    doc |= to_json(CardChoices(silicone_table(result.sensor_design),
                               size_table(result.sensor_design)))
    return Card(doc)


def figures(result: Result, budgets: tuple[Budget, Budget] | None = None
            ) -> dict[str, Figure]:
    """The figures of a result as matplotlib figures, by name: the optimisation's and, where
    the study has one geometry, the chosen design's error budget (``budget_chosen``) and its
    calibration's error (``calibration``, computed here).

    Parameters
    ----------
    result : Result
    budgets : (Budget, Budget), optional
        :func:`error_budgets` of ``result`` where the caller has them (computed otherwise).

    Returns
    -------
    dict of str to matplotlib.figure.Figure

    Examples
    --------
    >>> import magtact
    >>> figs = magtact.figures(magtact.design())                    # doctest: +SKIP
    >>> figs["budget_chosen"].savefig("budget.png")                 # doctest: +SKIP
    """
    from .report import calibration_figure, draw_budget, optimise_figure_objects

    figs = dict(optimise_figure_objects(result.optimisation))
    if budgets is None:
        budgets = error_budgets(result)
    if budgets is not None:
        from .budget import budget_json

        figs["budget_chosen"] = draw_budget(budget_json(budgets[0]))
        figs["calibration"] = calibration_figure(calibrate(result))
    return figs


def write_results(result: Result, out: str | Path, *, figures: bool = True,
                  budget: bool = True, budgets: tuple[Budget, Budget] | None = None
                  ) -> list[Path]:
    """Write a result into the results folder ``out``: the optimisation's tables, the design
    card (``card.json``), the error budgets (``budget.json``) and the figures.

    ``out`` has the rules of ``magtact`` commands (docs/method.md §14): its lock is held while
    writing, the files appear only once all are complete, and a file there that magtact did
    not write is never replaced.

    Parameters
    ----------
    result : Result
    out : path
        The results folder (made if missing).
    figures : bool
        Draw the figures (PNG and SVG).
    budget : bool
        Write ``budget.json`` (where the study has one geometry).
    budgets : (Budget, Budget), optional
        :func:`error_budgets` of ``result`` where the caller has them; computed once otherwise
        (the card holds their largest rows even without ``budget``).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    MagtactError
        If another process is writing ``out``, or an output would replace a file that is
        not magtact's (the message names the files).

    See Also
    --------
    write_results_into : the same into a folder the caller already holds.

    Examples
    --------
    >>> import magtact
    >>> magtact.write_results(magtact.design(), "design")         # doctest: +SKIP
    """
    from ._runfolder import command_outputs

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with command_outputs(out, "magtact.write_results") as o:
        files = write_results_into(result, o.folder, figures=figures, budget=budget,
                                   budgets=budgets)
    return [o.final(p) for p in files]


def write_results_into(result: Result, out: str | Path, *, figures: bool = True,
                       budget: bool = True, explorer: bool = False,
                       budgets: tuple[Budget, Budget] | None = None) -> list[Path]:
    """:func:`write_results` straight into ``out``, for a caller that already holds the
    folder (a command's or a run's staging folder): no lock, no check of what is there.

    Parameters
    ----------
    result : Result
    out : path
        The folder (it must exist).
    figures, budget, budgets
        As :func:`write_results`.
    explorer : bool
        Also the report's design explorer (``explorer.json``, a grid of
        ``result.evaluate``).

    Returns
    -------
    list of Path
        The files written.
    """
    from .budget import write_budgets
    from .optimise import write_geometry_outputs, write_optimise_outputs
    from .report import (
        budget_figures,
        fig_geometry_pareto,
        optimise_figures,
        silicone_table,
        size_table,
        write_card,
        write_explorer,
    )

    out = Path(out)
    if budgets is None:  # once, for the card and budget.json
        budgets = error_budgets(result)
    if result.study.geometric_variables:
        files = write_geometry_outputs(result.optimisation, out,
                                       figures=fig_geometry_pareto if figures else None)
    else:
        files = write_optimise_outputs(result.optimisation, result.models, out,
                                       figures=optimise_figures if figures else None)
    if result.sensor_design is not None:  # the whole sensor is the chosen design
        written = result.sensor_design.write(out, result.chosen.design)
        files = [f for f in files if f.name != "chosen.json"] + written
    files.append(write_card([result.chosen, result.original], out, result.constraints,
                            rtol=result.study.optimise.active_rtol, study=result.study,
                            extra_rows=_extra_rows(result.models, budgets),
                            silicones=silicone_table(result.sensor_design),
                            sizes=size_table(result.sensor_design)))
    grid = write_explorer(result, out) if explorer else None  # for the report's explorer
    if grid is not None:
        files.append(grid)
    if budget and budgets is not None:
        files.append(write_budgets(budgets, result.study, out,
                                   figures=budget_figures if figures else None))
    return files
