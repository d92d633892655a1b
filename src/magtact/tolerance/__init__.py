"""A verdict that holds for every unit built (docs/method.md §16): the parts' tolerances as a
box (:func:`tolerance_box`: the grade's remanence range, the temperature, the chip's
sensitivity and offset, G, the body's height, the chip's standoff, the magnet's size and the
FE forces' bias), the figures of built units (:func:`unit_figures`), each requirement at the
worst corner of the box and as a yield with its confidence interval, and the tolerance that
limits it (:func:`robust_verdict`)."""

from ._box import (
    INPUTS,
    Tolerance,
    ToleranceBox,
    corners,
    tolerance_box,
)
from ._robust import (
    RobustRequirement,
    RobustVerdict,
    WorstFactors,
    robust_verdict,
    worst_factors,
    yield_factors,
)
from ._units import DesignContext, design_context, unit_figures

__all__ = [
    "RobustVerdict", "ToleranceBox", "WorstFactors", "design_context", "robust_verdict",
    "tolerance_box", "unit_figures", "worst_factors", "yield_factors",
]
