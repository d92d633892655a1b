"""Sensitivity of force to field, Γ = |∂F/∂B| (docs/method.md §6), from closed-form metamodels."""

from ._check import compare_with_data, gamma_from_data
from ._gamma import (
    PublishedResponsesAtH,
    Responses,
    ResponsesAtH,
    dF_dB,
    force_noise,
    gamma,
    row_norms,
    through_displacement,
)

__all__ = ["Responses", "compare_with_data", "dF_dB", "force_noise", "gamma"]
