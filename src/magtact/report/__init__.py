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
    write_card,
    write_infeasible_card,
)
from ._explorer import explorer_data, write_explorer
from ._fig_budget import budget_figures, budget_labels, draw_budget, fig_budget
from ._fig_calibration import (
    calibration_figure,
    calibration_figures,
    draw_calibration,
    fig_calibration,
)
from ._fig_doe import fig_doe
from ._fig_field import fig_field
from ._fig_geometry import draw_geometry_pareto, fig_geometry_pareto
from ._fig_mechanics import fig_deformed_body
from ._fig_metamodel import fig_force_map, fig_gamma, fig_parity
from ._fig_optimise import draw_maps, draw_pareto, fig_maps, fig_pareto
from ._fig_time import draw_time, time_figures
from ._fig_validation import fig_validation
from ._html import build_report, report_document
from ._publication import publication_figures
from ._stages import (
    field_figures,
    fit_figures,
    optimise_figure_objects,
    optimise_figures,
    validation_figures,
)
from ._style import CMAP_DIV, CMAP_SEQ, save, style

__all__ = [
    "budget_figures", "budget_labels", "draw_budget", "fig_budget", "calibration_figures",
    "draw_calibration", "fig_calibration", "report_document", "calibration_figure",
    "explorer_data", "write_explorer", "parts_list", "infeasible_card", "write_infeasible_card",
    "CMAP_DIV", "CMAP_SEQ", "build_report", "card_rows", "draw_geometry_pareto", "draw_maps",
    "draw_pareto", "optimise_figure_objects",
    "field_figures", "fig_deformed_body", "fig_doe", "fig_field", "fig_force_map", "fig_gamma",
    "fig_geometry_pareto", "fig_maps", "fig_pareto", "fig_parity", "fig_validation",
    "fit_figures", "optimise_figures", "publication_figures", "read_card", "save", "style",
    "validation_figures", "write_card", "draw_time", "time_figures",
]
