"""Metamodel files: JSON, one file per response, read without executing anything.

File layout (``format = "magtact-metamodel/1"``)::

    {"format": ..., "name": "B_r", "units": "T",
     "variables": {"t": ..., "theta": ..., "H": ..., "p": ..., "q": ...},
     "expression": "<model in t, theta, H>", "expression_pq": "<model in p, q, H>",
     "latex": "<for reading only, never parsed>",
     "info": {"transform": ..., "accuracy": {...}, "settings": {...}, "data_hash": ..., ...}}

Both expressions are read by :func:`magtact.metamodel.parse_expression` (a whitelist grammar) and
checked to agree with each other where t > 0. The exact field as B model is written as
``{"format": "magtact-exact-field/1", "name", "units", "study_toml", "info"}`` (TOML read as data).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import sympy as sp

from .._errors import MagtactError, MissingFileError
from .._files import UnreadableFile, file_problem, read_text_capped, write_json
from ._field_force import FIELD_SYMBOLS, ComposedForce, FieldForceModel
from ._model import RESPONSES, Metamodel, ModelSet
from ._parse import format_expression, parse_expression
from ._symbols import GEOMETRY, PQH, TTH

FORMAT = "magtact-metamodel/1"
EXACT_FORMAT = "magtact-exact-field/1"
#: A force model of the published sensitivity definition, f̂(B_r, B_z, p, q, H).
FIELD_FORCE_FORMAT = "magtact-field-force/1"
FIELD_VARIABLES = {
    "B_r": "field component along the shear direction at the Hall point [T]",
    "B_z": "vertical field component at the Hall point [T]",
    "p": "feature p = t [-]",
    "q": "feature q = t tan(theta) [-]",
    "H": "base height of the body [m]",
}
VARIABLES = {
    "t": "non-dimensional load [-]",
    "theta": "shear angle [rad]",
    "H": "base height of the body [m]",
    "p": "feature p = t [-]",
    "q": "feature q = t tan(theta) [-]",
}


def model_to_dict(model: Metamodel) -> dict:
    """The JSON-ready content of a model file."""
    return {
        "format": FORMAT,
        "name": model.name,
        "units": model.units,
        "variables": VARIABLES,
        "expression": format_expression(model.expr),
        "expression_pq": format_expression(model.expr_pq),
        "latex": sp.latex(model.expr),
        "info": model.info,
    }


def model_from_dict(data: dict, source: str = "<dict>", check: bool = True) -> Metamodel:
    """A model from the content of a model file (see the module notes); ``check``: read
    through the grammar, its two forms checked to agree (False only for files of the package,
    which its tests read so: :meth:`Metamodel.from_text`).

    Raises
    ------
    MagtactError
        Wrong format tag, missing keys, an expression outside the grammar, or two expressions
        that disagree.
    """
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise MagtactError(f"{source}: not a magtact metamodel file (expected format {FORMAT!r})")
    for key in ("name", "units", "expression", "expression_pq"):
        if not isinstance(data.get(key), str):
            raise MagtactError(f"{source}: key {key!r} is missing or not a string")
    info = data.get("info", {})
    if not isinstance(info, dict):
        raise MagtactError(f"{source}: 'info' must be an object")
    if not check:  # a file of the package: its SymPy forms are built when asked for
        return Metamodel.from_text(data["name"], data["expression"], data["expression_pq"],
                                   data["units"], info)
    try:
        geo = tuple(g.name for g in GEOMETRY)  # a model over geometric design variables
        expr = parse_expression(data["expression"], ("t", "theta", "H", *geo))
        expr_pq = parse_expression(data["expression_pq"], ("p", "q", "H", *geo))
    except ValueError as exc:
        raise MagtactError(f"{source}: {exc}") from None
    _check_agree(expr, expr_pq, source)
    return Metamodel(name=data["name"], expr=expr, units=data["units"], expr_pq=expr_pq, info=info)


def _check_agree(expr, expr_pq, source, n: int = 16) -> None:
    """Both forms must give the same values at random points with t > 0."""
    rng = np.random.default_rng(0)
    tt, th, hh = rng.uniform(0.05, 1.0, n), rng.uniform(0.0, 0.6, n), rng.uniform(2e-3, 8e-3, n)
    geo = tuple(g for g in GEOMETRY if g in expr.free_symbols | expr_pq.free_symbols)
    gg = [rng.uniform(1e-3, 8e-3, n) for _ in geo]  # magnet and body dimensions [m]
    with np.errstate(all="ignore"):
        a = sp.lambdify(TTH + geo, expr, "numpy")(tt, th, hh, *gg)
        # the feature form at p = t, q = t tan θ, mapped in numbers (a symbolic substitution
        # costs more than both evaluations together)
        b = sp.lambdify(PQH + geo, expr_pq, "numpy")(tt, tt * np.tan(th), hh, *gg)
    a, b = np.broadcast_to(a, (n,)), np.broadcast_to(b, (n,))
    ok = np.isfinite(a) & np.isfinite(b)
    if not ok.any():
        raise MagtactError(f"{source}: the model is not finite at any of {n} sample points "
                         "(0.05 <= t <= 1, 0 <= theta <= 0.6 rad, 2 <= H <= 8 mm)")
    if not np.allclose(a[ok], b[ok], rtol=1e-9, atol=1e-12 * np.max(np.abs(a[ok]), initial=1.0)):
        raise MagtactError(f"{source}: 'expression' and 'expression_pq' describe different models")


def field_force_to_dict(model: FieldForceModel) -> dict:
    """The JSON-ready content of a field-force model file (published definition)."""
    return {
        "format": FIELD_FORCE_FORMAT,
        "definition": "published",
        "name": model.name,
        "units": model.units,
        "variables": FIELD_VARIABLES,
        "expression": format_expression(model.expr),
        "latex": sp.latex(model.expr),
        "info": model.info,
    }


def field_force_from_dict(data: dict, source: str = "<dict>") -> FieldForceModel:
    """A field-force model from the content of its file.

    Raises
    ------
    ValueError
        Wrong format tag, missing keys, or an expression outside the grammar.
    """
    if not isinstance(data, dict) or data.get("format") != FIELD_FORCE_FORMAT:
        raise MagtactError(f"{source}: not a field-force model file "
                         f"(expected format {FIELD_FORCE_FORMAT!r})")
    for key in ("name", "units", "expression"):
        if not isinstance(data.get(key), str):
            raise MagtactError(f"{source}: key {key!r} is missing or not a string")
    try:
        expr = parse_expression(data["expression"], FIELD_SYMBOLS)
    except ValueError as exc:
        raise MagtactError(f"{source}: {exc}") from None
    info = data.get("info", {})
    if not isinstance(info, dict):
        raise MagtactError(f"{source}: 'info' must be an object")
    return FieldForceModel(name=data["name"], expr=expr, units=data["units"], info=info)


def save_model(model: Metamodel | FieldForceModel, path: str | Path) -> Path:
    """Write one model file (JSON) and return its path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    content = (field_force_to_dict(model) if isinstance(model, FieldForceModel)
               else model_to_dict(model))
    return write_json(path, content, indent=2)


def load_model(path: str | Path) -> Metamodel:
    """Read one model file written by :func:`save_model` (restricted parser, no code execution).

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MagtactError
        If it is not valid JSON or not a valid model file.
    """
    path = Path(path)
    return model_from_dict(_read_json(path), str(path))


#: Largest model file read [bytes] (a fitted model file is a few kilobytes).
MAX_FILE_BYTES = 1_000_000


def _read_json(path: Path):
    """The JSON content of a model file; every way it can fail is one ValueError naming it."""
    problem = file_problem(path)
    if problem == "not found":
        raise MissingFileError(f"metamodel file not found: {path}")
    if problem is not None:
        raise MagtactError(f"{path}: not a model file: it is {problem}")
    try:
        text = read_text_capped(path, MAX_FILE_BYTES)
    except UnreadableFile as exc:
        raise MagtactError(f"{path}: {exc}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise MagtactError(f"{path}: not valid JSON ({exc})") from None
    except ValueError as exc:  # e.g. an integer of more digits than Python converts
        raise MagtactError(f"{path}: not a model file (a number it holds cannot be read: "
                           f"{str(exc).split(':')[0]})") from None
    except (RecursionError, MemoryError):
        raise MagtactError(f"{path}: not a model file (JSON nested too deeply)") from None


def save_models(models: ModelSet, folder: str | Path) -> list[Path]:
    """Write ``<folder>/<name>.json`` for each response; return the paths.

    A closed-form :class:`Metamodel` is written as a model file; the exact field
    (:class:`magtact.metamodel.ExactField`) as ``format = "magtact-exact-field/1"`` with the
    study (TOML text) that defines its geometry.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, m in models.items():
        path = folder / f"{k}.json"
        if isinstance(m, ComposedForce):
            save_model(m.model, path)
        elif isinstance(m, Metamodel):
            save_model(m, path)
        else:
            write_json(path, {"format": EXACT_FORMAT, "name": k, "units": "T",
                              "study_toml": m.study.to_toml(), "info": m.info}, indent=2)
        paths.append(path)
    return paths


def _load_any(path: Path, name: str, check: bool = True):
    data = _read_json(path)
    if isinstance(data, dict) and data.get("format") == EXACT_FORMAT and name in ("B_r", "B_z"):
        import tomllib

        from ..study import study_from_dict
        from ._exact_field import ExactField

        try:
            study = study_from_dict(tomllib.loads(data["study_toml"]), str(path))
        except (KeyError, TypeError, ValueError, RecursionError) as exc:
            raise MagtactError(f"{path}: exact-field file without a valid study ({exc})") from None
        return ExactField(study, name)
    if isinstance(data, dict) and data.get("format") == FIELD_FORCE_FORMAT:
        return field_force_from_dict(data, str(path))
    return model_from_dict(data, str(path), check)


def _read_response(folder: Path, k: str, check: bool = True):
    """The model of response ``k`` from ``folder/<k>.json``, checked to hold that response."""
    path = folder / f"{k}.json"
    m = _load_any(path, k, check)
    if m.name != k or m.units != RESPONSES[k]:
        raise MagtactError(f"{path}: holds {m.name!r} [{m.units}], "
                           f"expected {k!r} [{RESPONSES[k]}]")
    return m


def load_field_models(folder: str | Path) -> tuple:
    """Read only ``B_r.json`` and ``B_z.json`` of a model folder (fitted or exact field).

    Raises
    ------
    MissingFileError, MagtactError
        As :func:`load_models`.
    """
    return tuple(_read_response(Path(folder), k) for k in ("B_r", "B_z"))


def load_models(folder: str | Path, B_model=None, definition: str | None = None, *,
                check: bool = True) -> ModelSet:
    """Read ``B_r, B_z, f_r, f_z`` from ``<folder>/<name>.json`` (see :func:`save_models`).

    Parameters
    ----------
    folder : path
    B_model : tuple, optional
        ``(B_r, B_z)`` models to use instead of the folder's field files (e.g. the exact field);
        then only ``f_r.json`` and ``f_z.json`` are read.
    definition : {"jacobian", "published"}, optional
        The sensitivity definition the study asks for; the force files must be of it.
    check : bool
        Read each expression through the grammar of :func:`parse_expression` and check that
        each model's two forms (in (t, θ) and in the features (p, q)) agree; False only for the
        fits shipped with magtact, which their tests read and check so: their SymPy forms are
        then built when first asked for (:meth:`Metamodel.from_text`).

    Raises
    ------
    MissingFileError
        If a file is missing.
    MagtactError
        If a file is not a valid model file, holds another response, or serves another
        sensitivity definition than ``definition``.
    """
    folder = Path(folder)
    models = {}
    if B_model is not None:
        models["B_r"], models["B_z"] = B_model
    for k in RESPONSES:
        if k not in models:
            models[k] = _read_response(folder, k, check)
    for k in ("f_r", "f_z"):
        if isinstance(models[k], FieldForceModel):
            models[k] = ComposedForce(models[k], models["B_r"], models["B_z"])
    out = ModelSet(**models)
    if definition is not None and out.definition != definition:
        raise MagtactError(
            f"{folder}: the force models serve the {out.definition!r} sensitivity definition, "
            f"but the study's [sensitivity] definition is {definition!r}: fit models for it "
            f"(magtact fit) or set definition = {out.definition!r}")
    return out
