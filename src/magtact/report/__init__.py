"""Figures and the HTML report.

Stage figure functions live in ``_fig_<stage>.py`` and are imported from there by their stage
(importing them here would make ``magtact.report`` depend on every stage).
"""

from ._fig_validation import fig_validation
from ._html import build_report
from ._publication import publication_figures
from ._style import CMAP_DIV, CMAP_SEQ, save, style

__all__ = ["CMAP_DIV", "CMAP_SEQ", "build_report", "fig_validation", "publication_figures",
           "save", "style"]
