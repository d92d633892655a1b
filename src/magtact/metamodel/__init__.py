"""Closed-form metamodels of the study's responses by genetic programming (docs/method.md §5)."""

from ._exact_field import ExactField
from ._field_force import ComposedForce, FieldForceModel
from ._fit import (
    MAX_OMITTED,
    Accuracy,
    FitReport,
    FitResult,
    accuracy,
    data_hash,
    fit_models,
    hall_features,
    holdout_paths,
)
from ._io import (
    load_field_models,
    load_model,
    load_models,
    save_model,
    save_models,
)
from ._model import Metamodel, ModelSet, Response
from ._outputs import write_fit_outputs
from ._parse import format_expression, parse_expression
from ._prefitted import (
    copy_prefitted,
    find_prefitted,
    find_shipped,
    prefitted_dir,
)
from ._quality import POOR_OVER_RANGE, POOR_R2, FitQuality, fit_quality, fit_quality_rows
from ._select import Selection, blended_metamodels, select_metamodels
from ._symbols import H, feature_jacobian, features, p, q, q_hessian, t, theta

__all__ = [
    "ExactField", "FitQuality", "FitResult", "Metamodel", "ModelSet", "Selection", "fit_models",
    "fit_quality", "holdout_paths", "load_models", "save_models", "select_metamodels",
    "write_fit_outputs",
]


def __getattr__(name: str):
    # the regressor needs scikit-learn (seconds to import): loaded when a fit asks for it
    if name == "SymbolicRegressor":
        from ._regressor import SymbolicRegressor

        return SymbolicRegressor
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
