"""Metamodels fitted once to the bundled MagOne DOE and shipped with magtact.

A fit of the default budget takes minutes; the bundled data set never changes between
installations, so its fit is shipped too (``data/magone/``, written by
``magtact fit --out src/magtact/metamodel/data/magone``). It is used only for the very data
and settings it was fitted with: every shipped model file records the SHA-256 of its training
data and the fit settings, and both must match.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict
from importlib import resources
from pathlib import Path

from ..study import Study
from ._fit import data_hash
from ._io import load_models
from ._model import RESPONSES, ModelSet

#: Settings that do not change a fit's result (the GP is deterministic in its thread count).
_NEUTRAL = {"threads"}


def prefitted_dir() -> Path:
    """Folder of the shipped fit of the bundled MagOne DOE."""
    return Path(str(resources.files("magtact.metamodel").joinpath("data", "magone")))


def find_prefitted(study: Study, ds) -> Path | None:
    """The shipped fit folder if it was made from ``ds`` with ``study``'s settings, else None."""
    folder = prefitted_dir()
    wanted = {k: v for k, v in asdict(study.metamodel).items() if k not in _NEUTRAL}
    digest = None
    for name in RESPONSES:
        path = folder / f"{name}.json"
        if not path.is_file():
            return None
        info = json.loads(path.read_text("utf-8")).get("info", {})
        settings = {k: v for k, v in info.get("settings", {}).items() if k not in _NEUTRAL}
        if settings != wanted:
            return None
        if name in ("f_r", "f_z") and \
                info.get("definition", "jacobian") != study.sensitivity.definition:
            return None
        digest = digest or data_hash(ds)
        if info.get("data_hash") != digest:
            return None
    return folder


def copy_prefitted(folder: Path, out: str | Path) -> tuple[ModelSet, list[Path]]:
    """Copy a shipped fit (models, ``metamodels.md``, figures) to ``out``; load its models."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for src in sorted(folder.iterdir()):
        if src.suffix in (".json", ".md", ".png", ".svg"):
            files.append(Path(shutil.copy2(src, out / src.name)))
    return load_models(out), files
