"""Closed-form metamodels of the study's responses by genetic programming (docs/method.md §5)."""

from ._exact_field import ExactField
from ._field_force import ComposedForce, FieldForceModel
from ._fit import (
    MAX_OMITTED,
    TRAIN_TARGET,
    TRANSFORMS,
    Accuracy,
    FitReport,
    FitResult,
    accuracy,
    data_hash,
    fit_models,
    fit_response,
    hall_features,
    holdout_paths,
)
from ._io import (
    load_field_models,
    load_model,
    load_models,
    model_from_dict,
    model_to_dict,
    save_model,
    save_models,
)
from ._model import RESPONSES, Metamodel, ModelSet, Response
from ._outputs import write_fit_outputs
from ._parse import OPERATOR_SETS, format_expression, parse_expression
from ._prefitted import (
    SHIPPED,
    copy_prefitted,
    find_prefitted,
    find_shipped,
    prefitted_dir,
    shipped_models,
)
from ._quality import POOR_OVER_RANGE, POOR_R2, FitQuality, fit_quality, fit_quality_rows
from ._select import Selection, select_metamodels
from ._symbols import H, feature_jacobian, features, p, q, q_hessian, t, theta

__all__ = [
    "MAX_OMITTED", "POOR_OVER_RANGE", "POOR_R2", "SHIPPED", "FitQuality", "fit_quality",
    "fit_quality_rows",
    "find_shipped", "shipped_models",
    "Accuracy", "ComposedForce", "ExactField", "FieldForceModel", "FitReport", "FitResult",
    "H", "Metamodel", "ModelSet", "OPERATOR_SETS", "RESPONSES", "Response", "Selection",
    "SymbolicRegressor", "TRAIN_TARGET", "TRANSFORMS", "accuracy", "copy_prefitted",
    "data_hash", "feature_jacobian", "features", "find_prefitted", "fit_models",
    "fit_response", "format_expression", "hall_features", "holdout_paths", "load_field_models",
    "load_model", "load_models", "model_from_dict", "model_to_dict", "p", "parse_expression",
    "prefitted_dir", "q", "q_hessian", "save_model", "save_models", "select_metamodels", "t",
    "theta", "write_fit_outputs",
]


def __getattr__(name: str):
    # the regressor needs scikit-learn (seconds to import): loaded when a fit asks for it
    if name == "SymbolicRegressor":
        from ._regressor import SymbolicRegressor

        return SymbolicRegressor
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
