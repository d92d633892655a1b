"""Sensitivity of force to field, Γ = |∂F/∂B| (docs/method.md §6), from closed-form metamodels."""

from ._check import compare_with_data, gamma_from_data
from ._gamma import NAMES, PublishedResponsesAtH, Responses, ResponsesAtH, dF_dB, gamma

__all__ = ["NAMES", "PublishedResponsesAtH", "Responses", "ResponsesAtH", "compare_with_data",
           "dF_dB", "gamma", "gamma_from_data"]
