"""`magtact budget`: the error budget of one design (docs/method.md §12)."""

from __future__ import annotations

import contextlib
import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .._errors import MagtactError
from ..study import checked_si, from_si, kpa, mm
from ._app import StudyArg, app, console, get_study, outputs
from ._optimise import ModelsOpt, study_models

if TYPE_CHECKING:
    from ..budget import Budget

#: Range of a Hall chip's RMS field noise that ``--noise-uT`` accepts [T]: 1 nT to 10 mT.
NOISE_BOUNDS = (1e-9, 1e-2)
#: Largest seed study read by ``--seeds`` [bytes] (magtact reproduce writes a few kB).
MAX_SEEDS_BYTES = 10_000_000


def parse_noise(text: str) -> tuple[float, float]:
    """``"X,Z"`` or ``"S"`` [µT RMS] → (σ_x, σ_z) [T]: the one form of ``--noise-uT`` in every
    command.

    Raises
    ------
    MagtactError
        If ``text`` is not one or two numbers within :data:`NOISE_BOUNDS`.
    """
    parts = str(text).split(",")
    values = []
    if len(parts) in (1, 2):
        for p in parts:
            try:
                values.append(float(p))
            except ValueError:
                break
    if len(values) != len(parts) or len(parts) not in (1, 2):
        raise MagtactError(f"--noise-uT must be 'X,Z' or one number for both axes, in µT RMS "
                           f"(e.g. 1.5,2.5 or 1.5), got {text!r}")
    if len(values) == 1:
        values *= 2
    return tuple(checked_si(v, "uT", "--noise-uT", bounds=NOISE_BOUNDS) for v in values)


def _seeds(path: Path | None) -> dict | None:
    """The seed study of ``--seeds``, read through the size-capped reader and checked: the
    ``spread`` of each sensitivity definition, ``acc_f_r`` / ``acc_f_z`` with a finite ``max``
    >= 0 (a relative error) and an optional integer ``n``."""
    from .._files import UnreadableFile, read_json_capped

    if path is None:
        return None
    try:
        data = read_json_capped(path, MAX_SEEDS_BYTES)
    except UnreadableFile as exc:
        raise MagtactError(f"--seeds {path}: {exc}") from None
    expected = "expected publication/publication.json of magtact reproduce"
    if not isinstance(data, dict) or not isinstance(data.get("spread"), dict):
        raise MagtactError(f"--seeds {path}: not a seed study (no 'spread' table; {expected})")
    spread = {}
    for definition, entry in data["spread"].items():
        where = f"--seeds {path}: spread.{definition}"
        if not isinstance(entry, dict):
            raise MagtactError(f"{where} must be a table ({expected})")
        clean = {}
        for key in ("acc_f_r", "acc_f_z"):
            if key not in entry:
                continue
            acc = entry[key]
            top = acc.get("max") if isinstance(acc, dict) else None
            if isinstance(top, bool) or not isinstance(top, int | float) \
                    or not 0 <= top <= 1e3:
                raise MagtactError(f"{where}.{key}.max must be a relative error between 0 and "
                                   f"1000, got {top!r}")
            n = acc.get("n", "?")
            if not (n == "?" or isinstance(n, int) and not isinstance(n, bool) and n >= 1):
                raise MagtactError(f"{where}.{key}.n must be a count of seeds, got {n!r}")
            clean[key] = {"max": float(top), "n": n}
        spread[str(definition)] = clean
    return {**data, "spread": spread}


@app.command("budget")
def budget_command(
    H: Annotated[float, typer.Option("--H", help="Base height H [mm].")],
    G: Annotated[float, typer.Option("--G", help="Shear modulus G [kPa].")],
    study: StudyArg = None,
    noise: Annotated[str | None, typer.Option(
        "--noise-uT", metavar="S|X,Z",
        help="RMS field noise [µT] of the chip, one value for both axes or X,Z; it replaces "
             "the chip's own figure, and the output says so.")] = None,
    seeds: Annotated[Path | None, typer.Option(
        "--seeds", help="A seed study (publication/publication.json of magtact reproduce) "
                        "for the seed-spread row.")] = None,
    models: ModelsOpt = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Also write OUT/budget.json and the figure.")] = None,
) -> None:
    """The error budget of design (H, G): every false force besides the load, in mN."""
    from ..budget import budget_card_rows, error_budget, write_budgets
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
        chip, said = noise_override(a.chip, sigma)
        b = error_budget(m, s, H_si, G_si, label="design", design=a.design, noise=sigma,
                         dataset=dataset, seeds=seed_data, chip=chip)
        if said is not None:
            b = replace(b, noise_source=said)
        if o is not None:
            write_budgets([b], s, o.folder, figures=budget_figures)
    print_budget(b)
    for name, text in budget_card_rows([b]):
        console.print(f"{escape(name)}: {escape(text)}", highlight=False)
    if o is not None:
        console.print(f"written to {o.out}", highlight=False)


def noise_override(chip, sigma):
    """The chip with the noise of ``--noise-uT`` (σ_x, σ_z) [T] in place of its own, and the
    sentence that says so (None, and the chip unchanged, without ``--noise-uT``)."""
    if sigma is None:
        return chip, None
    given = ", ".join(f"{from_si(v, 'uT'):.3g}" for v in sigma)
    own = (("that of the setting magtact picks per design" if chip.picked else "none")
           if chip.noise is None
           else ", ".join(f"{from_si(v, 'uT'):.3g}" for v in chip.noise) + f" µT at {chip.setting}")
    said = (f"given as --noise-uT {given} µT (x, z), in place of the chip's own figure "
            f"({chip.name}: {own})")
    console.print(f"noise: {escape(said)}", highlight=False)
    return replace(chip, noise_x=float(sigma[0]), noise_z=float(sigma[1])), said


def _dataset(study):
    """The bundled data set where it describes the study (its mesh error), else None."""
    from ..doe import bundled_for

    try:
        return bundled_for(study)
    except MagtactError:
        return None


def print_budget(b: Budget, stdout: Console | None = None) -> None:
    """Print one budget as a rich table (forces in mN, lengths in mm, G in kPa)."""
    table = Table(title=f"Error budget, H = {mm(b.H):.4g} mm, G = {kpa(b.G):.4g} kPa "
                        f"({b.chip}; noise: {b.noise_source})")
    for h, j in (("row", "left"), ("force", "left"), ("at rest [mN]", "right"),
                 ("worst [mN]", "right")):
        table.add_column(escape(h), justify=j)
    for r in b.rows:
        table.add_row(escape(r.name), r.component, _fmt(r.at_rest), _fmt(r.worst))
    (stdout or Console()).print(table)
    sp = b.array.get("smallest_pitch")
    (stdout or Console()).print(
        f"smallest {b.array.get('layout')} pitch for crosstalk below the resolution: "
        + ("unknown (no noise figure)" if sp is None else f"{mm(sp):.3g} mm"), highlight=False)
    for n in b.not_modelled:
        (stdout or Console()).print(f"not modelled: {escape(n)}", highlight=False)


def _fmt(force: float) -> str:
    """A force [N] in mN to 3 significant figures; a dash where there is none."""
    return "–" if not math.isfinite(force) else f"{from_si(force, 'mN'):.3g}"
