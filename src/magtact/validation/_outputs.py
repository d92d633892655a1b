"""Files of a validation: the c_v / ε table (CSV, JSON) and, if asked, the figure."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .._files import write_text
from .._records import entry, to_json
from ._stats import Validation, ValidationRow


@dataclass(frozen=True)
class ValidationSummary:
    """``validation[_synthetic].json``: the validation's setting and its table, in SI.

    ``filter`` holds the band-pass's lower and upper cut-off [1/m] (None: no upper one);
    ``u_z_range`` the common grid's least and largest u_z [m].
    """

    title: str = entry(kind=str)
    synthetic: bool = entry(kind=bool)
    theta: float = entry(unit="rad")
    n_tests: int = entry(kind=int)
    sensors: tuple[str, ...] = entry(kind=str, levels=("list",))
    model: str = entry(kind=str)
    filter: tuple = entry("filter_cycles_per_mm", "per_mm", levels=("list",), null_nan=True)
    floor: float = entry()
    n_grid: int = entry(kind=int)
    u_z_range: tuple = entry(unit="mm", levels=("list",))
    notes: tuple[str, ...] = entry(kind=str, levels=("list",))
    sources: tuple[str, ...] = entry(kind=str, levels=("list",))
    rows: tuple[ValidationRow, ...] = entry(kind=ValidationRow, levels=("list",))


def output_stem(synthetic: bool) -> str:
    """The name (without suffix) of a validation's files: ``validation_synthetic`` for the
    shipped SYNTHETIC example, else ``validation``."""
    return "validation_synthetic" if synthetic else "validation"


def write_outputs(validation: Validation, out: str | Path, *, sources=(),
                  figures: Callable[..., list[Path]] | None = None) -> list[Path]:
    """Write ``validation[_synthetic].csv``, ``.json`` and, with ``figures``, the figure into
    ``out``.

    The names carry ``_synthetic`` for generated data, and so do the table's ``data`` column
    and the figure's title.

    Parameters
    ----------
    validation : Validation
        Result of :func:`magtact.validation.validate`.
    out : path
        Output folder (created).
    sources : sequence of path
        Data files, recorded in the JSON.
    figures : callable, optional
        ``figures(validation, path)`` draws the figure at ``path`` (``out/validation[_synthetic]``
        without suffix) and returns the files (:func:`magtact.report.validation_figures`).
        None: no figure.

    Returns
    -------
    list of Path
        Files written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    stem = output_stem(validation.synthetic)
    written = [validation.write_csv(out / f"{stem}.csv")]
    f = validation.filter
    summary = ValidationSummary(
        validation.title, validation.synthetic, validation.theta, validation.n_tests,
        tuple(validation.sensors), validation.model_label, (f.f_lo, f.f_hi),
        validation.floor, int(validation.u_z.size),
        (float(validation.u_z.min()), float(validation.u_z.max())), tuple(validation.notes),
        tuple(str(s) for s in sources), tuple(validation.row_records()))
    path = out / f"{stem}.json"
    write_text(path, json.dumps(to_json(summary), indent=2, ensure_ascii=False))
    written.append(path)
    if figures is not None:
        written += figures(validation, out / stem)
    return written
