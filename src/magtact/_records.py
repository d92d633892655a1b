"""Records of the JSON files magtact writes: one declaration per key, for writer and reader.

A record is a dataclass whose fields are declared with :func:`entry`: the field's metadata
names its JSON key, its user unit and the shape of its value, as the study's settings do for
the study file (:func:`magtact.study._model.setting`). :func:`to_json` writes a record from
these declarations and :func:`from_json` reads it back, so that a key is spelled once, where
its field is declared, and its writer and reader cannot spell it apart.

Values are SI inside and user units only in the document: a number is written as
:func:`magtact.study.from_si` of its unit and read back as the SI value that writes the same
number again (the nearest float of :func:`magtact.study.to_si` that does), so a file read and
written again is the same file.

Reading is strict: a document that is not the record (a missing key, a value of another type)
raises :class:`RecordError`, whose message names the file or record, the key's path in the
document and what was found. A reader that takes a damaged file for none uses
:func:`from_json_or_none`. A reader that shows what a partial or forged file holds, field by
field, uses :func:`from_json_lenient`: each value the document gives in its declared shape is
read, every other field takes its default.

Declarations
------------
``entry(key=None, unit="", kind=float, ...)``
    ``key``: the JSON key (default: the field's name, followed by ``_<unit>`` when it has a
    unit). ``kind``: ``float``, ``int``, ``bool``, ``str``, ``object`` (any JSON, kept as is)
    or a record type (nested). ``levels``: the containers around each value, outermost first:
    ``"list"`` (a JSON array, a tuple inside; a numpy array with ``array=True``) or ``"map"``
    (a JSON object of names, a dict inside). Further options: see :func:`entry`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from contextlib import contextmanager
from dataclasses import MISSING, dataclass, field, fields, is_dataclass
from typing import Any, TypeVar

from ._errors import MagtactError

R = TypeVar("R")

#: Units that name a key but convert nothing (SI in the file too): the conversions of
#: :func:`magtact.study.to_si` cover the others.
SUFFIX_ONLY = frozenset({"N_per_T", "per_T", "N_per_m"})

_META = "magtact_json"


class RecordError(MagtactError):
    """A JSON document that is not the record asked for; the message names the file or the
    record, the path of the key and what is wrong."""


@dataclass(frozen=True)
class Entry:
    """The declaration of one field of a record (see :func:`entry`)."""

    key: str | None
    unit: str
    kind: Any
    levels: tuple[str, ...]
    optional: bool
    null_nan: bool
    omit: str | None
    shape: str | type | None
    inline: bool
    array: bool
    key_units: Mapping[str, str] | None
    doc: str
    fallback: Any = MISSING


def entry(key: str | None = None, unit: str = "", *, kind=float, levels=(),
          optional: bool = False, null_nan: bool = False, omit: str | None = None,
          shape: str | type | None = None, inline: bool = False, array: bool = False,
          key_units: Mapping[str, str] | None = None, default=MISSING,
          default_factory=MISSING, kw_only=MISSING, doc: str = "", fallback=MISSING):
    """A field of a record with its JSON key.

    Parameters
    ----------
    key : str, optional
        The JSON key; default: the field's name, followed by ``_<unit>`` where ``unit`` is
        given.
    unit : str
        The user unit of the numbers in the file (a unit of :func:`magtact.study.to_si`, or
        one of :data:`SUFFIX_ONLY`); the field holds SI.
    kind : type
        ``float``, ``int``, ``bool``, ``str``, ``object`` (any JSON value, as is) or a record
        type (a dataclass declared with :func:`entry`).
    levels : sequence of {"list", "map"}
        The containers around each value, outermost first.
    optional : bool
        The field may be None, written as null (and null read as None).
    null_nan : bool
        A number that is not finite is written as null, and null read as NaN.
    omit : {None, "none", "empty"}
        Leave the key out of the document when the value is None (``"none"``) or empty
        (``"empty"``); a document without the key reads as the field's default.
    shape : {None, "tuple", "dict"} or type
        A nested record held as the tuple of its fields' values, as the dict of its fields'
        names and values (an empty dict is an empty JSON object), or as another type made of
        (and read through) the attributes that the record's fields name.
    inline : bool
        A nested record whose keys stand in the enclosing record's object (an optional one
        writes them as null and reads as None where all are null; with ``omit`` its keys are
        left out, and a document without any of them reads as the field's default). With
        ``levels=("map",)``: a dict whose entries stand in the enclosing object, read back from
        the keys that no other field declares.
    array : bool
        A list of numbers held as a numpy array.
    key_units : mapping of str to str, optional
        For a ``"map"`` level of numbers: the unit of each name, written as a suffix of the
        key (``unit`` for the names not listed).
    default, default_factory, kw_only
        As :func:`dataclasses.field`; a field with a default may be missing from a document.
    doc : str
        What the value is (for the reader of the declaration).
    fallback : optional
        The value a lenient read (:func:`from_json_lenient`) gives where the document lacks the
        key or gives a value of another shape (default: the field's default).
    """
    meta = Entry(key, unit, kind, tuple(levels), optional, null_nan, omit, shape, inline,
                 array, key_units, doc, fallback)
    extra = {} if kw_only is MISSING else {"kw_only": kw_only}
    return field(default=default, default_factory=default_factory, metadata={_META: meta},
                 **extra)


def declared(cls) -> list[tuple[Any, Entry]]:
    """The fields of the record type ``cls`` with their declarations (undeclared fields left
    out: they are not in the file)."""
    return [(f, f.metadata[_META]) for f in fields(cls) if _META in f.metadata]


def key_of(f, e: Entry) -> str:
    """The JSON key of a declared field."""
    if e.key is not None:
        return e.key
    return f"{f.name}_{e.unit}" if e.unit else f.name


def keys(cls) -> tuple[str, ...]:
    """The JSON keys of a record type, in the order they are written (inlined records' keys
    in their place)."""
    out: list[str] = []
    for f, e in declared(cls):
        if e.inline and e.levels:
            continue  # entries of a map: the keys of no declaration
        out += list(keys(e.kind)) if e.inline else [key_of(f, e)]
    return tuple(out)


# ---- units -----------------------------------------------------------------------------------
def _check_unit(unit: str) -> None:
    from .study import to_si

    if unit and unit not in SUFFIX_ONLY:
        try:
            to_si(1.0, unit)
        except KeyError:
            raise KeyError(f"unknown unit {unit!r} in a record declaration") from None


def user_value(si, unit: str):
    """An SI number in the user unit ``unit`` for a file (:func:`magtact.study.from_si`)."""
    if not unit or unit in SUFFIX_ONLY:
        return si
    from .study import from_si

    return from_si(si, unit)


def si_value(user: float, unit: str) -> float:
    """A file's number in ``unit`` back in SI: the float nearest to
    :func:`magtact.study.to_si` of it that :func:`user_value` writes as the same number."""
    if not unit or unit in SUFFIX_ONLY:
        return user
    from .study import from_si, to_si

    si = to_si(user, unit)
    if not math.isfinite(si) or from_si(si, unit) == user:
        return si
    for direction in (math.inf, -math.inf):
        near = math.nextafter(si, direction)
        for _ in range(2):
            if from_si(near, unit) == user:
                return near
            near = math.nextafter(near, direction)
    return si


# ---- writing ---------------------------------------------------------------------------------
def to_json(record, *, null_nan: bool = True) -> dict:
    """The JSON document (a dict) of a record, every number in its user unit.

    Parameters
    ----------
    record : dataclass instance
        A record declared with :func:`entry`.
    null_nan : bool
        Write a number that is not finite as null where its field is declared ``null_nan``;
        False keeps every number as it is (the rows of a table, where NaN is a cell).

    Returns
    -------
    dict
        Keys in the order of the declarations.
    """
    out: dict = {}
    for f, e in declared(type(record)):
        value = getattr(record, f.name)
        if e.omit == "none" and value is None or e.omit == "empty" and _empty(value):
            continue
        if e.inline and e.levels:
            out |= {k: _write(v, e, 1, e.unit, null_nan) for k, v in value.items()}
            continue
        if e.inline:
            inner = _inner_record(e, value)
            out |= (dict.fromkeys(keys(e.kind)) if inner is None
                    else to_json(inner, null_nan=null_nan))
            continue
        out[key_of(f, e)] = _write(value, e, 0, e.unit, null_nan)
    return out


def _empty(value) -> bool:
    if value is None:
        return True
    if hasattr(value, "__len__"):
        return len(value) == 0
    return False


def _inner_record(e: Entry, value):
    """The nested record of a value held as a tuple, a dict or another type (None stays
    None)."""
    if value is None or isinstance(value, e.kind):
        return value
    if e.shape == "tuple":
        return e.kind(*value)
    if e.shape == "dict":
        return e.kind(**value) if value else None
    return e.kind(**{f.name: getattr(value, f.name) for f, _ in declared(e.kind)})


def _write(value, e: Entry, depth: int, unit: str, null_nan: bool = True):
    if depth < len(e.levels):
        if value is None and e.optional and depth == 0:
            return None
        if e.levels[depth] == "map":
            units = e.key_units or {}
            out = {}
            for name, v in value.items():
                u = units.get(name, unit) if e.key_units is not None and depth == 0 else unit
                k = f"{name}_{u}" if e.key_units is not None and depth == 0 and u else name
                out[k] = _write(v, e, depth + 1, u, null_nan)
            return out
        return [_write(v, e, depth + 1, unit, null_nan) for v in value]
    if value is None and (e.optional or e.null_nan):
        return None
    if is_dataclass(e.kind):
        if e.shape == "dict" and not value:
            return {}
        return to_json(_inner_record(e, value), null_nan=null_nan)
    if e.kind is float:
        if e.null_nan and null_nan and not math.isfinite(value):
            return None
        return user_value(value, unit)
    return value


# ---- reading ---------------------------------------------------------------------------------
def from_json(cls: type[R], doc, where: str | None = None) -> R:
    """The record of type ``cls`` that :func:`to_json` wrote as ``doc``, back in SI.

    Parameters
    ----------
    cls : type
        A record type declared with :func:`entry`.
    doc : object
        A parsed JSON document.
    where : str, optional
        The file the document comes from (for the message of an error); default: the
        record's type.

    Returns
    -------
    cls

    Raises
    ------
    RecordError
        If ``doc`` is not such a record: a key missing, a value of another type, a record
        that its type refuses; the message names ``where``, the key's path and what was found.
    """
    return _record(cls, doc, where or cls.__name__, "")


def from_json_or_none(cls: type[R], doc, where: str | None = None) -> R | None:
    """:func:`from_json`, or None where ``doc`` is not such a record."""
    try:
        return from_json(cls, doc, where)
    except RecordError:
        return None


def from_json_lenient(cls: type[R], doc) -> R | None:
    """The record of type ``cls`` read field by field from a document that may be partial or
    forged.

    Each field whose key ``doc`` gives with a value of the declared shape is read as
    :func:`from_json` reads it (a nested record leniently too, and a list or map of records
    keeps the items that read as records); a field whose key is missing or whose value has
    another shape takes its ``fallback``, else its default, and a field without either None.
    ``cls`` and ``doc`` as :func:`from_json`; None where ``doc`` is not a JSON object or the
    values read make no ``cls``.
    """
    try:
        return _record(cls, doc, cls.__name__, "", lenient=True)
    except RecordError:
        return None


def _default(f, e: Entry | None = None):
    """The value of a field that a lenient read does not find: its declared fallback, else its
    default (None where it has neither)."""
    if e is not None and e.fallback is not MISSING:
        return e.fallback
    if f.default is not MISSING:
        return f.default
    if f.default_factory is not MISSING:
        return f.default_factory()
    return None


def _fail(where: str, path: str, problem: str):
    raise RecordError(f"{where}: {path or 'the document'}: {problem}")


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _record(cls, doc, where: str, path: str, lenient: bool = False):
    if not isinstance(doc, dict):
        _fail(where, path, f"expected a JSON object ({cls.__name__}), got {_shown(doc)}")
    values = {}
    for f, e in declared(cls):
        try:
            if e.inline and e.levels:
                others = keys(cls)
                values[f.name] = {k: _read(v, e, 1, e.unit, where, f"{path}.{k}", lenient)
                                  for k, v in doc.items() if k not in others}
                continue
            if e.inline:
                if e.omit is not None and not any(k in doc for k in keys(e.kind)):
                    continue  # an inline record left out: the field's default
                values[f.name] = _inline(e, doc, where, path, lenient)
                continue
            key = key_of(f, e)
            here = f"{path}.{key}" if path else key
            if key not in doc:
                if not _has_default(f) or lenient and e.fallback is not MISSING:
                    _fail(where, path, f"missing key {key!r} ({cls.__name__})")
                continue
            values[f.name] = _read(doc[key], e, 0, e.unit, where, here, lenient)
        except RecordError:
            if not lenient:
                raise
            values[f.name] = _default(f, e)
    try:
        return cls(**values)
    except (TypeError, ValueError) as exc:
        _fail(where, path, f"not a {cls.__name__}: {exc}")


def _has_default(f) -> bool:
    return f.default is not MISSING or f.default_factory is not MISSING


def _inline(e: Entry, doc: dict, where: str, path: str, lenient: bool = False):
    inner = keys(e.kind)
    required = {key for g, d in declared(e.kind) if not _has_default(g)
                for key in (keys(d.kind) if d.inline else (key_of(g, d),))}
    missing = [k for k in inner if k not in doc and k in required]
    if missing and not lenient:
        _fail(where, path, f"missing key {missing[0]!r} ({e.kind.__name__})")
    if e.optional and all(doc.get(k) is None for k in inner):
        return None
    record = _record(e.kind, {k: doc[k] for k in inner if k in doc}, where, path, lenient)
    return _shaped(record, e)


def _shaped(record, e: Entry):
    if e.shape == "tuple":
        return tuple(getattr(record, f.name) for f in fields(record))
    if e.shape == "dict":
        return {f.name: getattr(record, f.name) for f in fields(record)}
    if e.shape is not None:
        return e.shape(**{f.name: getattr(record, f.name) for f in fields(record)})
    return record


@contextmanager
def _skipped(skip: bool):
    """Leave out an item of a list or map that is not the record asked for (``skip``: a
    lenient read), else let its error through."""
    try:
        yield
    except RecordError:
        if not skip:
            raise


_KINDS = {float: "a number", int: "an integer", bool: "true or false", str: "text"}


def _read(value, e: Entry, depth: int, unit: str, where: str, path: str,
          lenient: bool = False):
    if value is None and e.optional and depth in (0, len(e.levels)):
        return None
    if depth < len(e.levels):
        if e.levels[depth] == "map":
            if not isinstance(value, dict):
                _fail(where, path, f"expected a JSON object, got {_shown(value)}")
            units = e.key_units if depth == 0 else None
            out = {}
            for k, v in value.items():
                name, u = _name_unit(k, units, unit)
                with _skipped(lenient and is_dataclass(e.kind)):
                    out[name] = _read(v, e, depth + 1, u, where, f"{path}.{k}", lenient)
            return out
        if not isinstance(value, list):
            _fail(where, path, f"expected a JSON array, got {_shown(value)}")
        items = []
        for i, v in enumerate(value):
            with _skipped(lenient and is_dataclass(e.kind)):
                items.append(_read(v, e, depth + 1, unit, where, f"{path}[{i}]", lenient))
        if e.array and depth == 0:
            import numpy as np

            try:
                return np.asarray(items, dtype=float)
            except ValueError:  # rows of unequal length
                _fail(where, path, "expected an array of rows of equal length")
        return tuple(items)
    if is_dataclass(e.kind):
        if e.shape == "dict" and value == {}:
            return {}
        return _shaped(_record(e.kind, value, where, path, lenient), e)
    if e.kind is object:
        return value
    if e.kind is float:
        if value is None and e.null_nan:
            return math.nan
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            _fail(where, path, f"expected {_KINDS[float]}"
                  f"{f' ({unit})' if unit else ''}, got {_shown(value)}")
        return si_value(value, unit)
    if not isinstance(value, e.kind) or e.kind is int and isinstance(value, bool):
        _fail(where, path, f"expected {_KINDS.get(e.kind, e.kind.__name__)}, got "
                           f"{_shown(value)}")
    return value


def _name_unit(key: str, units: Mapping[str, str] | None, unit: str) -> tuple[str, str]:
    """The name and the unit of a key of a map whose keys carry their unit."""
    if units is None:
        return key, unit
    for name, u in units.items():
        if key == (f"{name}_{u}" if u else name):
            return name, u
    suffix = f"_{unit}" if unit else ""
    if suffix and key.endswith(suffix):
        return key[: -len(suffix)], unit
    return key, unit


def check_declarations(cls) -> None:
    """Raise KeyError for a declaration with an unknown unit (records' tests call it)."""
    for _, e in declared(cls):
        _check_unit(e.unit)
        for u in (e.key_units or {}).values():
            _check_unit(u)
        if is_dataclass(e.kind):
            check_declarations(e.kind)

