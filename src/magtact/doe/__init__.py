"""Design of experiments: parallel, cached, resumable runs of the field and mechanics stages."""

from ._blend import bundled_blend, lagrange_weights
from ._cache import CacheCorruptWarning, CacheError, JobCache
from ._dataset import (
    BROAD_SIZES,
    bundled_for,
    bundled_path,
    differences,
    geometry_dims,
    load_bundled,
    load_dataset,
    matches_study,
    rescaled_for,
    save_dataset,
    write_csv,
)
from ._discretisation import (
    FINER_MESH,
    attach_discretisation_error,
    error_points,
)
from ._domain import Domain, check_design, domain_of
from ._run import DOEFailed, JobFailure, RunStats, run_doe

__all__ = [
    "DOEFailed", "JobCache", "bundled_blend", "bundled_for", "check_design", "load_bundled",
    "load_dataset", "run_doe", "save_dataset",
]
