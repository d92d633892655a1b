"""`magtact budget`: the error budget of one design (docs/method.md §12)."""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .._errors import MagtactError
from ..study import checked_si
from ._app import StudyArg, app, console, get_study, outputs
from ._optimise import ModelsOpt, study_models


def parse_noise(text: str) -> tuple[float, float]:
    """``"X,Z"`` or ``"S"`` [µT RMS] → (σ_x, σ_z) [T].

    Raises
    ------
    MagtactError
        If ``text`` is not one or two positive numbers up to 1000 µT.
    """
    parts = text.split(",")
    try:
        if len(parts) not in (1, 2):
            raise ValueError
        values = [float(p) for p in parts]
    except ValueError:
        raise MagtactError(f"--noise-uT must be 'X,Z' or one number in µT RMS (e.g. 1.5,2.5), "
                           f"got {text!r}") from None
    if len(values) == 1:
        values *= 2
    return tuple(checked_si(v, "uT", "--noise-uT", bounds=(1e-9, 1e-3)) for v in values)


def _seeds(path: Path | None) -> dict | None:
    if path is None:
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise MagtactError(f"--seeds {path}: not a readable JSON file ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("spread"), dict):
        raise MagtactError(f"--seeds {path}: not a seed study (no 'spread' table; expected "
                           "publication/publication.json of magtact reproduce)")
    return data


@app.command("budget")
def budget_command(
    H: Annotated[float, typer.Option("--H", help="Base height H [mm].")],
    G: Annotated[float, typer.Option("--G", help="Shear modulus G [kPa].")],
    study: StudyArg = None,
    noise: Annotated[str | None, typer.Option(
        "--noise-uT", metavar="X,Z",
        help="RMS field noise [µT] of the chip where the study's [hall] gives none.")] = None,
    seeds: Annotated[Path | None, typer.Option(
        "--seeds", help="A seed study (publication/publication.json of magtact reproduce) "
                        "for the seed-spread row.")] = None,
    models: ModelsOpt = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Also write OUT/budget.json and the figure.")] = None,
) -> None:
    """The error budget of design (H, G): every false force besides the load, in mN."""
    from ..budget import budget_card_rows, budget_json, error_budget, write_budgets
    from ..designer import answer
    from ..report import budget_figures

    s = get_study(study)
    H_si = checked_si(H, "mm", "--H")
    G_si = checked_si(G, "kPa", "--G")
    sigma = None if noise is None else parse_noise(noise)
    seed_data = _seeds(seeds)
    written = outputs("budget", out, "budget.json") if out is not None else None
    with written or contextlib.nullcontext() as o:
        m, _ = study_models(s, models)
        dataset = _dataset(s) if models is None else None
        a = answer(m, s, H_si, G_si)  # the chip at this design's setting
        b = error_budget(m, s, H_si, G_si, label="design", design=a.design, noise=sigma,
                         dataset=dataset, seeds=seed_data, chip=a.chip)
        if o is not None:
            write_budgets([b], s, o.folder, figures=budget_figures)
    print_budget(budget_json(b))
    for name, text in budget_card_rows([b]):
        console.print(f"{escape(name)}: {escape(text)}", highlight=False)
    if o is not None:
        console.print(f"written to {o.out}", highlight=False)


def _dataset(study):
    """The bundled data set where it describes the study (its mesh error), else None."""
    from ..doe import bundled_for

    try:
        return bundled_for(study)
    except MagtactError:
        return None


def print_budget(doc: dict, stdout: Console | None = None) -> None:
    """Print one budget (a :func:`magtact.budget.budget_json` entry) as a rich table."""
    table = Table(title=f"Error budget, H = {doc['H_mm']:.4g} mm, G = {doc['G_kPa']:.4g} kPa "
                        f"({doc['chip']}; noise: {doc['noise_source']})")
    for h, j in (("row", "left"), ("force", "left"), ("at rest [mN]", "right"),
                 ("worst [mN]", "right")):
        table.add_column(escape(h), justify=j)
    for r in doc["rows"]:
        table.add_row(escape(r["name"]), r["component"], _fmt(r["at_rest_mN"]),
                      _fmt(r["worst_mN"]))
    (stdout or Console()).print(table)
    sp = doc["array"]["smallest_pitch_mm"]
    (stdout or Console()).print(
        f"smallest {doc['array']['layout']} pitch for crosstalk below the resolution: "
        + ("unknown (no noise figure)" if sp is None else f"{sp:.3g} mm"), highlight=False)
    for n in doc["not_modelled"]:
        (stdout or Console()).print(f"not modelled: {escape(n)}", highlight=False)


def _fmt(v) -> str:
    return "–" if v is None else f"{v:.3g}"
