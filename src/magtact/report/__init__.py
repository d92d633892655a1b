"""Figures and the HTML report.

``fig_<name>`` draw one figure each; ``<stage>_figures`` draw all the figures of a stage and are
what the stages' writers accept as their ``figures`` argument (the stages themselves draw
nothing). :func:`build_report` turns a results folder into one self-contained HTML file.
"""

from ._card import (
    card_rows,
    infeasible_card,
    parts_list,
    read_card,
    silicone_table,
    size_table,
    write_card,
    write_infeasible_card,
)
from ._explorer import explorer_data, write_explorer
from ._fig_budget import budget_figures, budget_labels, draw_budget
from ._fig_calibration import (
    MINOR_TICK_DECADES,
    calibration_figure,
    calibration_figures,
    draw_calibration,
)
from ._fig_doe import fig_doe
from ._fig_geometry import draw_geometry_pareto, fig_geometry_pareto
from ._fig_mechanics import fig_deformed_body
from ._fig_time import draw_time
from ._html import build_report, report_document
from ._publication import publication_figures
from ._stages import (
    field_figures,
    fit_figures,
    optimise_figure_objects,
    optimise_figures,
    validation_figures,
)
from ._style import save, saved_in_background, style

__all__ = [
    "budget_figures", "build_report", "calibration_figures", "field_figures", "fit_figures",
    "optimise_figures", "publication_figures", "save", "style", "validation_figures",
]
