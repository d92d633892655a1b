"""Sensitivity of force to field, Γ = |∂F/∂B| (SPEC section 6), from closed-form metamodels."""

from ._gamma import NAMES, Responses, ResponsesAtH, dF_dB, gamma

__all__ = ["NAMES", "Responses", "ResponsesAtH", "dF_dB", "gamma"]
