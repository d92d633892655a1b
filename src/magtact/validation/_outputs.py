"""Files of a validation: the c_v / ε table (CSV, JSON) and, if asked, the figure."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

from .._files import write_text
from ..study import from_si, mm
from ._stats import Validation


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
    summary = {
        "title": validation.title,
        "synthetic": validation.synthetic,
        "theta_rad": validation.theta,
        "n_tests": validation.n_tests,
        "sensors": list(validation.sensors),
        "model": validation.model_label,
        "filter_cycles_per_mm": [from_si(validation.filter.f_lo, "per_mm"),
                                 None if validation.filter.f_hi is None
                                 else from_si(validation.filter.f_hi, "per_mm")],
        "floor": validation.floor,
        "n_grid": int(validation.u_z.size),
        "u_z_range_mm": [float(mm(validation.u_z.min())), float(mm(validation.u_z.max()))],
        "notes": list(validation.notes),
        "sources": [str(s) for s in sources],
        "rows": [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                  for k, v in row.items()} for row in validation.rows()],
    }
    path = out / f"{stem}.json"
    write_text(path, json.dumps(summary, indent=2, ensure_ascii=False))
    written.append(path)
    if figures is not None:
        written += figures(validation, out / stem)
    return written
