"""Design of experiments: parallel, cached, resumable runs of the field and mechanics stages."""

from ._cache import CacheCorruptWarning, CacheError, JobCache
from ._dataset import bundled_path, load_bundled, load_dataset, save_dataset, write_csv
from ._executor import default_workers
from ._run import DOEFailed, JobFailure, RunStats, run_doe

__all__ = [
    "CacheCorruptWarning", "CacheError", "DOEFailed", "JobCache", "JobFailure", "RunStats",
    "bundled_path", "default_workers", "load_bundled", "load_dataset", "run_doe", "save_dataset",
    "write_csv",
]
