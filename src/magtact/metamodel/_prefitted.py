"""Metamodels fitted once to the bundled DOEs and shipped with magtact.

A fit of the default budget takes minutes; the bundled data sets never change between
installations, so their fits are shipped too (``data/magone/`` for the MagOne data set, written
by ``magtact fit --out src/magtact/metamodel/data/magone``; ``data/broad/`` for the broad one
over (H, R_m, H_m), ``bench/bench_broad.py``). A shipped fit is used only for the very data and
settings it was fitted with: every shipped model file records the SHA-256 of its training data
and the fit settings, and both must match, or the data set must be an exact rescaling of the
shipped one to the study's G levels and magnetisation (``magtact.doe.rescaled_for``, checked by
recomputing it), whose field models are then scaled by M_z / M_z,data.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict
from importlib import resources
from pathlib import Path

from ..doe import BROAD_SIZES
from ..study import Study, magone
from ._fit import data_hash
from ._io import load_models, save_model
from ._model import RESPONSES, Metamodel, ModelSet

#: Settings that do not change a fit's result (the GP is deterministic in its thread count).
_NEUTRAL = {"threads"}
#: Shipped fits: folder under ``data/`` -> the bundled data set (``magtact.doe``) they fit.
SHIPPED = {"magone": "magone_doe.nc",
           **{f"broad_{size}": f"broad_{size}_doe.nc" for size in BROAD_SIZES}}


def prefitted_dir(name: str = "magone") -> Path:
    """Folder of a shipped fit (default: that of the bundled MagOne DOE)."""
    return Path(str(resources.files("magtact.metamodel").joinpath("data", name)))


def _infos(folder: Path) -> dict | None:
    infos = {}
    for name in RESPONSES:
        path = folder / f"{name}.json"
        if not path.is_file():
            return None
        infos[name] = json.loads(path.read_text("utf-8")).get("info", {})
    return infos


def _settings_match(study: Study, infos: dict, geometric: bool, own: bool) -> bool:
    """True if the shipped fit with ``infos`` serves ``study``'s fit settings: the same
    settings, or, for a fit shipped for a data set other than the MagOne one (``own`` False),
    a study that leaves the fit settings at magtact's defaults (that data set's fit is then
    the one magtact made for it)."""
    # over geometric data the field is the exact one whatever b_model asks (docs/method.md §7)
    ignore = _NEUTRAL | ({"b_model"} if geometric else set())
    wanted = {k: v for k, v in asdict(study.metamodel).items() if k not in ignore}
    default = not own and wanted == {k: v for k, v in asdict(magone().metamodel).items()
                                     if k not in ignore}
    for name, info in infos.items():
        if "settings" not in info and name in ("B_r", "B_z"):
            continue  # the exact field: nothing fitted
        settings = {k: v for k, v in info.get("settings", {}).items() if k not in ignore}
        if settings != wanted and not default:
            return False
        if name in ("f_r", "f_z") and \
                info.get("definition", "jacobian") != study.sensitivity.definition:
            return False
    return True


def find_shipped(study: Study, ds) -> tuple[Path, float] | None:
    """The shipped fit folder made from ``ds`` (or from the bundled data set ``ds`` is an exact
    rescaling of) with ``study``'s settings, and the factor M_z / M_z,data its field models
    take; None when no shipped fit serves."""
    from ..doe import geometry_dims, load_bundled, rescaled_for

    digest = None
    source = ds.attrs.get("rescaled_from", "")
    for folder_name, data_name in SHIPPED.items():
        folder = prefitted_dir(folder_name)
        infos = _infos(folder)
        if infos is None or not _settings_match(study, infos, bool(geometry_dims(ds)),
                                                own=folder_name == "magone"):
            continue
        hashes = {info.get("data_hash") for info in infos.values() if "data_hash" in info}
        digest = digest or data_hash(ds)
        if hashes == {digest}:
            return folder, 1.0
        if source == data_name:
            original = load_bundled(data_name)
            if {data_hash(original)} == hashes and data_hash(rescaled_for(original, study)) \
                    == digest:
                return folder, float(ds.attrs.get("field_scale", 1.0))
    return None


def find_prefitted(study: Study, ds) -> Path | None:
    """The shipped fit folder if it was made from ``ds`` (or the bundled data set it rescales)
    with ``study``'s settings, else None (:func:`find_shipped`)."""
    found = find_shipped(study, ds)
    return None if found is None else found[0]


def shipped_models(folder: Path, study: Study, ds, field_scale: float = 1.0) -> ModelSet:
    """The models of a shipped fit for ``study``: fitted field models scaled by
    ``field_scale`` (B ∝ M_z), the exact field of the study's magnet where the fit has it, and
    the force models bound to the study's magnet or body where the data set has a geometric
    dimension the study keeps fixed."""
    from ..doe import geometry_dims
    from ._exact_field import ExactField

    infos = _infos(folder) or {}
    exact = any("settings" not in infos.get(k, {}) for k in ("B_r", "B_z"))
    B = (ExactField(study, "B_r"), ExactField(study, "B_z")) if exact else None
    # the shipped files' two forms agree: tests/test_prefitted.py checks every one
    models = load_models(folder, B_model=B, definition=study.sensitivity.definition,
                         check=False)
    if not exact and field_scale != 1.0:
        models = ModelSet(**{k: _scaled(m, field_scale) if k in ("B_r", "B_z") else m
                             for k, m in models.items()})
    fixed = {k: getattr(study.magnet if k != "R" else study.body, k)
             for k in geometry_dims(ds) if k not in study.geometric_variables}
    return models.at(**fixed) if fixed else models


def _scaled(model, k: float):
    if not isinstance(model, Metamodel):
        return model
    info = dict(model.info)
    info["field_scale"] = k  # B = k x the fitted field (B proportional to M_z)
    return Metamodel.from_expr(model.name, model.expr_pq * k, model.units, info)


def copy_prefitted(folder: Path, out: str | Path, models: ModelSet | None = None
                   ) -> tuple[ModelSet, list[Path]]:
    """Copy a shipped fit (models, ``metamodels.md``, figures) to ``out``; load its models.

    With ``models`` (the study's models made from it, :func:`shipped_models`) the fitted field
    models written are those (scaled to the study's M_z) and those are returned.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for src in sorted(folder.iterdir()):
        if src.suffix in (".json", ".md", ".png", ".svg"):
            files.append(Path(shutil.copy2(src, out / src.name)))
    if models is None:
        return load_models(out), files
    for k in ("B_r", "B_z"):
        m = models[k]
        if isinstance(m, Metamodel) and m.info.get("field_scale", 1.0) != 1.0:
            save_model(m, out / f"{k}.json")
    return models, files
