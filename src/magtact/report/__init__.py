"""Figures and the HTML report."""

from ._style import CMAP_DIV, CMAP_SEQ, save, style

__all__ = ["CMAP_DIV", "CMAP_SEQ", "save", "style"]
