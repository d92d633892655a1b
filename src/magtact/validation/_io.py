"""Reading repeat indentation tests from CSV files (docs/method.md §8).

File format
-----------
Plain comma-separated text. Leading lines starting with ``#`` form a metadata header of
``key = value`` (or ``key: value``) pairs; then one header row of column names, then one row per
sample, in the order the samples were taken. Blank lines are ignored. Columns (any order; other
columns, e.g. ``time_s``, are ignored):

=================  ========================================================================
``u_z_mm``         vertical magnet displacement [mm], ≤ 0 downwards (or ``u_z_m`` in metres);
                   strictly monotonic within one test. Required.
``u_r_mm``         shear displacement along +x [mm] (or ``u_r_m``). Optional: when absent it
                   follows from the loading path, u_r = −u_z tan θ.
``B_r_T, B_z_T``   measured Hall field [T], B_r along the shear direction. Required.
``F_r_N, F_z_N``   measured reaction force [N]. Required.
``theta_rad``      shear angle [rad] (or ``theta_deg``), or the metadata key of the same name.
``sensor``         sensor label; default: metadata ``sensor``, else the file name.
``repeat``         repeat label; default: metadata ``repeat``, else ``1``.
=================  ========================================================================

One file may hold one test (one sensor × repeat) or many (a long table with ``sensor`` and
``repeat`` columns). All tests of one validation share one shear angle. Metadata ``synthetic =
true`` marks generated data: it is carried through to every table and figure.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._errors import MagtactError, MissingFileError
from .._files import UnreadableFile, file_problem, read_text_capped
from .._numbers import parse_float
from ..study import check_si, mm, to_si

#: The measured responses and the unit suffix of their columns.
RESPONSES: tuple[str, ...] = ("B_r", "B_z", "F_r", "F_z")
UNITS: dict[str, str] = {"B_r": "T", "B_z": "T", "F_r": "N", "F_z": "N"}
#: Unit suffixes accepted for displacement and shear angle columns (converted by
#: :func:`magtact.study.to_si`).
_LENGTH = ("mm", "m")
_ANGLE = ("rad", "deg")
#: Fewest samples a test must have.
MIN_SAMPLES = 4
#: Two shear angles closer than this [rad] are the same.
THETA_TOL = 1e-6


#: Largest data file read [bytes].
MAX_FILE_BYTES = 200_000_000
#: Longest message of a :class:`DataError` [characters] (cells are quoted, and may be huge).
MAX_MESSAGE = 1000
#: Physical range in SI of each kind of column: displacements within ±1 m, shear angles in
#: [0, π/2], Hall fields within ±100 T, forces within ±1 MN.
PHYSICAL_RANGE: dict[str, tuple[float, float, str]] = {
    "length": (-1.0, 1.0, "m"), "angle": (0.0, math.pi / 2, "rad"),
    "T": (-100.0, 100.0, "T"), "N": (-1e6, 1e6, "N"),
}


class DataError(MagtactError):
    """Malformed validation data; the message names the file, line and column."""

    def __init__(self, message: str):
        if not message.isprintable():  # cells and labels quoted from a file hold any character
            message = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
        super().__init__(_clip(message, MAX_MESSAGE))


def _clip(text: str, n: int = 60) -> str:
    return text if len(text) <= n else text[:n] + f"... ({len(text)} characters)"


@dataclass(frozen=True)
class Curve:
    """One indentation test (one sensor, one repeat), in SI units.

    Attributes
    ----------
    sensor, repeat : str
        Labels of the sensor and of the repeat.
    source : str
        File the test was read from; ``line`` is the line number of its first sample.
    u_z : numpy.ndarray
        Vertical magnet displacement [m], shape (n,), strictly monotonic.
    u_r : numpy.ndarray or None
        Measured shear displacement [m], shape (n,), or None when the file has none.
    values : dict[str, numpy.ndarray]
        ``B_r, B_z`` [T] and ``F_r, F_z`` [N], each of shape (n,).
    """

    sensor: str
    repeat: str
    source: str
    line: int
    u_z: np.ndarray
    u_r: np.ndarray | None
    values: dict[str, np.ndarray]


@dataclass(frozen=True)
class Experiment:
    """Repeat indentation tests at one shear angle.

    Attributes
    ----------
    curves : tuple[Curve, ...]
        The tests (at least two).
    theta : float
        Shear angle [rad].
    synthetic : bool
        True if any file declares ``synthetic = true`` in its metadata.
    metadata : dict[str, str]
        Metadata of the first file (keys lower case).
    """

    curves: tuple[Curve, ...]
    theta: float
    synthetic: bool = False
    metadata: dict[str, str] = field(default_factory=dict)

    @property
    def sensors(self) -> tuple[str, ...]:
        """Distinct sensor labels, in order of appearance."""
        return tuple(dict.fromkeys(c.sensor for c in self.curves))

    def design(self, H: float | None = None, G: float | None = None) -> tuple[float, float]:
        """The tested design (H, G) [m, Pa]: the arguments, else metadata ``design_H_mm`` and
        ``design_G_kPa`` of the first file.

        Raises
        ------
        MagtactError
            If a value is neither given nor in the metadata, or the metadata is not a number.
        """
        return (H if H is not None else self._meta_si("design_h_mm", "H", "mm"),
                G if G is not None else self._meta_si("design_g_kpa", "G", "kPa"))

    def _meta_si(self, key: str, name: str, unit: str) -> float:
        where = self.sources[0] if self.curves else "the data"
        if key not in self.metadata:
            raise MagtactError(f"give the design's {name} (--{name}): {where} has no metadata "
                             f"'{key}'")
        text = self.metadata[key]
        try:
            value = parse_float(text)
        except ValueError:
            raise MagtactError(f"{where}: metadata '{key}' is not a number: "
                             f"{_clip(text)!r}") from None
        return check_si(to_si(value, unit), unit, f"{where}: metadata '{key}'", value)

    @property
    def sources(self) -> tuple[str, ...]:
        """Distinct source files, in order of appearance."""
        return tuple(dict.fromkeys(c.source for c in self.curves))


def read_experiment(paths) -> Experiment:
    """Read repeat indentation tests from one or more CSV files (format: module docstring).

    Parameters
    ----------
    paths : str, Path or sequence of them
        CSV files; each holds one test or a long table of several.

    Returns
    -------
    Experiment
        All tests, SI units.

    Raises
    ------
    DataError
        On malformed input, naming the file, the line (1-based, as in a text editor) and the
        column.
    MissingFileError
        If a file does not exist.
    """
    if isinstance(paths, (str, Path)):
        paths = [paths]
    paths = [Path(p) for p in paths]
    if not paths:
        raise DataError("no data files given")
    curves: list[Curve] = []
    thetas: list[tuple[float, str, str]] = []  # (theta, where, what)
    synthetic = False
    first_meta: dict[str, str] = {}
    seen: dict[tuple[str, str], str] = {}
    for path in paths:
        file_curves, theta, where, meta = _read_file(path)
        if not first_meta:
            first_meta = meta
        synthetic |= meta.get("synthetic", "").strip().lower() in ("true", "yes", "1")
        thetas.append((theta, where, str(path)))
        for c in file_curves:
            key = (c.sensor, c.repeat)
            if key in seen:
                raise DataError(f"{path}: line {c.line}, columns 'sensor', 'repeat': test "
                                f"(sensor {c.sensor!r}, repeat {c.repeat!r}) appears twice "
                                f"(also in {seen[key]})")
            seen[key] = f"{c.source}, line {c.line}"
            curves.append(c)
    theta0, where0, _ = thetas[0]
    for theta, where, _ in thetas[1:]:
        if abs(theta - theta0) > THETA_TOL:
            raise DataError(f"mixed shear angles: {where} gives theta = {theta:.6g} rad but "
                            f"{where0} gives {theta0:.6g} rad; validate one shear angle at a time")
    if len(curves) < 2:
        c = curves[0]
        raise DataError(f"{c.source}: column 'repeat': only one test (sensor {c.sensor!r}, "
                        f"repeat {c.repeat!r}); the statistics need at least 2 repeats")
    return Experiment(curves=tuple(curves), theta=theta0, synthetic=synthetic,
                      metadata=first_meta)


def read_cell(path: Path, line: int, column: str, cell: str) -> float:
    """A table cell as a finite number, under the usual float grammar.

    Raises
    ------
    DataError
        Naming the file, line and column of an empty, non-numeric or non-finite cell.
    """
    try:
        value = parse_float(cell)
    except ValueError:
        what = "empty cell" if not cell else f"not a number: {cell!r}"
        raise DataError(f"{path}: line {line}, column {column!r}: {what}") from None
    if not math.isfinite(value):
        raise DataError(f"{path}: line {line}, column {column!r}: {cell!r} is not a finite "
                        "number")
    return value


def read_table_lines(path: Path, what: str, hint: str) -> tuple[list[str], dict, dict, int]:
    """The lines of a CSV table with ``# key = value`` metadata lines at its top.

    Returns
    -------
    lines, metadata (lower-case key → value), the line number of each key, and the index of
    the header row (the first line that is neither metadata nor blank).

    Raises
    ------
    MissingFileError
        If ``path`` does not exist (``what`` names the kind of file).
    DataError
        If it is not a readable UTF-8 file of at most ``MAX_FILE_BYTES`` (``hint`` says what to
        give instead of something that is not a file), a metadata line is not ``key = value``,
        or no header row follows.
    """
    problem = file_problem(path)
    if problem == "not found":
        raise MissingFileError(f"{path}: no such {what}")
    if problem is not None:
        raise DataError(f"{path}: not a file: it is {problem} ({hint})")
    try:
        text = read_text_capped(path, MAX_FILE_BYTES)
    except UnreadableFile as exc:
        raise DataError(f"{path}: {exc}") from None
    lines = text.splitlines()
    meta: dict[str, str] = {}
    meta_line: dict[str, int] = {}
    i = 0
    while i < len(lines) and (lines[i].lstrip().startswith("#") or not lines[i].strip()):
        body = lines[i].lstrip().lstrip("#").strip()
        if body:
            sep = "=" if "=" in body else (":" if ":" in body else None)
            if sep is None:
                raise DataError(f"{path}: line {i + 1}: metadata must read 'key = value', "
                                f"got {body!r}")
            key, value = (s.strip() for s in body.split(sep, 1))
            if key.lower() in meta:  # two values of one setting: neither is taken
                raise DataError(f"{path}: line {i + 1}: {key} is given twice (also on line "
                                f"{meta_line[key.lower()]}); keep one")
            meta[key.lower()] = value
            meta_line[key.lower()] = i + 1
        i += 1
    if i >= len(lines):
        raise DataError(f"{path}: empty file (no header row of column names)")
    return lines, meta, meta_line, i


def _read_file(path: Path):
    """Parse one file → (curves, theta, where theta was read, metadata)."""
    lines, meta, meta_line, i = read_table_lines(path, "data file", "give CSV files")
    header_line = i + 1
    header = [h.strip() for h in _cells(path, lines[i], i + 1)]
    columns = _columns(path, header, header_line)
    rows: list[tuple[int, list[str]]] = []
    for j in range(i + 1, len(lines)):
        if not lines[j].strip() or lines[j].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in _cells(path, lines[j], j + 1)]
        if len(cells) != len(header):
            raise DataError(f"{path}: line {j + 1}: {len(cells)} cells, the header on line "
                            f"{header_line} has {len(header)} columns")
        rows.append((j + 1, cells))
    if not rows:
        raise DataError(f"{path}: line {header_line}: header but no data rows")

    numeric = {name: _numbers(path, rows, header, col) for name, col in columns.items()
               if name not in ("sensor", "repeat")}
    theta, where = _theta(path, rows, header, columns, numeric, meta, meta_line)

    def labels(name: str, default: str) -> list[str]:
        if name in columns:
            k = header.index(columns[name])
            out = []
            for line, cells in rows:
                if not cells[k]:
                    raise DataError(f"{path}: line {line}, column {columns[name]!r}: empty label")
                out.append(cells[k])
            return out
        return [meta.get(name, default)] * len(rows)

    sensors = labels("sensor", path.stem)
    repeats = labels("repeat", "1")
    groups: dict[tuple[str, str], list[int]] = {}
    for k, key in enumerate(zip(sensors, repeats, strict=True)):
        groups.setdefault(key, []).append(k)
    curves = []
    for (sensor, repeat), idx in groups.items():
        idx = np.asarray(idx)
        line_nos = [rows[k][0] for k in idx]
        if len(idx) < MIN_SAMPLES:
            raise DataError(f"{path}: line {line_nos[0]}: test (sensor {sensor!r}, repeat "
                            f"{repeat!r}) has {len(idx)} samples; at least {MIN_SAMPLES} needed")
        u_z = numeric["u_z"][idx]
        _monotonic(path, u_z, line_nos, columns["u_z"])
        curves.append(Curve(
            sensor=sensor, repeat=repeat, source=str(path), line=line_nos[0], u_z=u_z,
            u_r=numeric["u_r"][idx] if "u_r" in numeric else None,
            values={r: numeric[r][idx] for r in RESPONSES},
        ))
    return curves, theta, where, meta


def read_row(path: Path, text: str, line: int) -> list[str]:
    """The cells of one CSV line. A quote left open (``"0.5``) or text after a closing quote
    is refused rather than read as if closed (the csv module's strict mode); its other errors,
    e.g. a cell over its size limit, become a DataError naming the line too."""
    try:
        return next(csv.reader([text], strict=True), [])
    except csv.Error as exc:
        raise DataError(f"{path}: line {line}: not a CSV row ({exc}; a quoted cell must "
                        "close its quote on the same line)") from None


_cells = read_row


def _columns(path: Path, header: list[str], line: int) -> dict[str, str]:
    """Map quantity → column name; check required columns and duplicates."""
    for k, h in enumerate(header):
        if not h:
            raise DataError(f"{path}: line {line}, column {k + 1}: empty column name")
        if header.index(h) != k:
            raise DataError(f"{path}: line {line}, column {h!r}: column name appears twice")
    columns: dict[str, str] = {}
    for r in RESPONSES:
        name = f"{r}_{UNITS[r]}"
        if name not in header:
            raise DataError(f"{path}: line {line}: missing column {name!r} (the header has "
                            f"{', '.join(header)})")
        columns[r] = name
    for q, units, required in (("u_z", _LENGTH, True), ("u_r", _LENGTH, False),
                               ("theta", _ANGLE, False)):
        found = [f"{q}_{u}" for u in units if f"{q}_{u}" in header]
        if len(found) > 1:
            raise DataError(f"{path}: line {line}, columns {found}: give {q} once, in one unit")
        if found:
            columns[q] = found[0]
        elif required:
            raise DataError(f"{path}: line {line}: missing column 'u_z_mm' (or 'u_z_m'): the "
                            "vertical displacement")
    for q in ("sensor", "repeat"):
        if q in header:
            columns[q] = q
    return columns


def _numbers(path: Path, rows, header: list[str], column: str) -> np.ndarray:
    """One column as SI floats; every cell must be a finite number."""
    k = header.index(column)
    unit = column.rsplit("_", 1)[1]
    kind = "length" if unit in _LENGTH else "angle" if unit in _ANGLE else unit
    lo, hi, si = PHYSICAL_RANGE.get(kind, (-math.inf, math.inf, ""))
    out = np.empty(len(rows))
    for n, (line, cells) in enumerate(rows):
        cell = cells[k]
        out[n] = to_si(read_cell(path, line, column, cell), unit)
        if not lo <= out[n] <= hi:
            raise DataError(f"{path}: line {line}, column {column!r}: {cell} is outside the "
                            f"physical range [{lo:g}, {hi:g}] {si} (in SI)")
    return out


def _theta(path, rows, header, columns, numeric, meta, meta_line):
    """The file's shear angle [rad] from its column or its metadata, and where it was read."""
    from_meta = None
    for unit in _ANGLE:
        key = f"theta_{unit}"
        if key in meta:
            try:
                from_meta = to_si(parse_float(meta[key]), unit)
            except ValueError:
                raise DataError(f"{path}: line {meta_line[key]}, metadata {key!r}: not a number: "
                                f"{meta[key]!r}") from None
            if not 0.0 <= from_meta <= math.pi / 2:
                raise DataError(f"{path}: line {meta_line[key]}, metadata {key!r}: shear angle "
                                f"{meta[key]} is outside [0, π/2] rad")
            meta_where = f"{path}, line {meta_line[key]} (metadata {key!r})"
    if "theta" in numeric:
        values = numeric["theta"]
        col = columns["theta"]
        bad = np.flatnonzero(np.abs(values - values[0]) > THETA_TOL)
        if bad.size:
            raise DataError(f"{path}: line {rows[bad[0]][0]}, column {col!r}: shear angle "
                            f"{values[bad[0]]:.6g} rad differs from {values[0]:.6g} rad on line "
                            f"{rows[0][0]}; one file holds one shear angle")
        if from_meta is not None and abs(from_meta - values[0]) > THETA_TOL:
            raise DataError(f"{path}: line {rows[0][0]}, column {col!r}: shear angle "
                            f"{values[0]:.6g} rad disagrees with {meta_where}: {from_meta:.6g} rad")
        return float(values[0]), f"{path}, line {rows[0][0]} (column {col!r})"
    if from_meta is None:
        raise DataError(f"{path}: no shear angle: add a column 'theta_rad' (or 'theta_deg') or "
                        "a metadata line '# theta_rad = ...'")
    return from_meta, meta_where


def _monotonic(path: Path, u_z: np.ndarray, line_nos: list[int], column: str) -> None:
    """u_z must be strictly monotonic within a test; name the first line that breaks it."""
    d = np.diff(u_z)
    sign = np.sign(d[np.flatnonzero(d)[0]]) if np.any(d) else 0.0
    bad = np.flatnonzero(np.sign(d) != sign) if sign else np.array([0])
    if bad.size:
        k = bad[0] + 1
        raise DataError(f"{path}: line {line_nos[k]}, column {column!r}: displacement is not "
                        f"strictly monotonic ({mm(u_z[k - 1]):.6g} mm on line "
                        f"{line_nos[k - 1]}, then {mm(u_z[k]):.6g} mm); give the loading "
                        "branch only, one sample per displacement")
