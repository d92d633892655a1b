"""The error budget of a design: noise, temperature, stray fields, neighbours in an array,
fabrication and the model's own error, each as a false force ΔF = J ΔB (docs/method.md §12)."""

from ._array import (
    crosstalk,
    magnets_field,
    neighbour_offsets,
    smallest_pitch,
    worst_false_force,
)
from ._budget import (
    Budget,
    BudgetFile,
    BudgetRow,
    budget_card_rows,
    budget_json,
    error_budget,
    noise_given,
    write_budget_outputs,
    write_budgets,
)
from ._fabrication import linearised, monte_carlo, percentiles, responses, unit_context

__all__ = ["Budget", "budget_json", "error_budget", "write_budget_outputs"]
