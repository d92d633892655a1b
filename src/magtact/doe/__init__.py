"""Design of experiments: parallel, cached, resumable runs of the field and mechanics stages."""

from ._cache import CacheCorruptWarning, CacheError, JobCache
from ._dataset import (
    BROAD_SIZES,
    BUNDLED_NAMES,
    DOE_SECTIONS,
    FORCE_SETTINGS,
    GEOMETRY_NAMES,
    bundled_for,
    bundled_path,
    data_study,
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
    ERROR_VARIABLES,
    FINER_MESH,
    attach_discretisation_error,
    error_points,
)
from ._domain import Domain, check_design, domain_of
from ._executor import default_workers
from ._run import DOEFailed, JobFailure, RunStats, run_doe

__all__ = [
    "Domain", "check_design", "domain_of", "BROAD_SIZES", "BUNDLED_NAMES", "FORCE_SETTINGS",
    "data_study", "rescaled_for",
    "DOE_SECTIONS", "ERROR_VARIABLES", "GEOMETRY_NAMES", "FINER_MESH", "CacheCorruptWarning",
    "CacheError", "DOEFailed", "JobCache", "JobFailure", "RunStats",
    "attach_discretisation_error", "bundled_for", "differences", "error_points", "geometry_dims",
    "bundled_path", "default_workers", "load_bundled", "load_dataset", "matches_study",
    "run_doe", "save_dataset", "write_csv",
]
