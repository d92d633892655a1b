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
from ._app import StudyArg, app, check_out, console, get_study, outputs
from ._optimise import ModelsOpt

if TYPE_CHECKING:
    from ..budget import Budget

#: Range of a Hall chip's RMS field noise that ``--noise-uT`` accepts [T]: 1 nT to 10 mT.
NOISE_BOUNDS = (1e-9, 1e-2)
#: Largest seed study read by ``--seed-study`` [bytes] (magtact reproduce writes a few kB).
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
    """The seed study of ``--seed-study``, read through the size-capped reader and checked: the
    ``spread`` of each sensitivity definition, ``acc_f_r`` / ``acc_f_z`` with a finite ``max``
    >= 0 (a relative error) and an optional integer ``n``."""
    from .._files import UnreadableFile, read_json_capped

    if path is None:
        return None
    try:
        data = read_json_capped(path, MAX_SEEDS_BYTES)
    except UnreadableFile as exc:
        raise MagtactError(f"--seed-study {path}: {exc}") from None
    expected = "expected publication/publication.json of magtact reproduce"
    if not isinstance(data, dict) or not isinstance(data.get("spread"), dict):
        raise MagtactError(f"--seed-study {path}: not a seed study (no 'spread' table; {expected})")
    spread = {}
    for definition, entry in data["spread"].items():
        where = f"--seed-study {path}: spread.{definition}"
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


#: ``--H``, ``--G``, ``--grade``, ``--standoff-mm``, ``--setting``, ``--silicone``: the sensor a
#: command acts on, each changing only what it names in the chosen sensor.
HOpt = Annotated[float | None, typer.Option(
    "--H", help="Body height H [mm]; default: the chosen sensor's.")]
GOpt = Annotated[float | None, typer.Option(
    "--G", help="Shear modulus G [kPa]; default: the chosen sensor's.")]
GradeOpt = Annotated[str | None, typer.Option(
    "--grade", help="Magnet grade (N35 ... N52; sets M_z); default: the chosen sensor's.")]
StandoffOpt = Annotated[float | None, typer.Option(
    "--standoff-mm", help="The chip's distance below the body [mm]; default: the chosen "
                          "sensor's.")]
SettingOpt = Annotated[str | None, typer.Option(
    "--setting", metavar="FIELD=V,...",
    help="The chip's setting, e.g. GAIN_SEL=5,RES=2 (fields GAIN_SEL, RES, OSR, DIG_FILT; "
         "those not named keep the chosen sensor's); default: the chosen sensor's.")]
SiliconeOpt = Annotated[str | None, typer.Option(
    "--silicone", help="The silicone's catalogue name (e.g. 'Dragon Skin 10'; G stays as "
                       "given); default: the chosen sensor's.")]


def parse_setting(text: str) -> dict[str, int]:
    """``--setting FIELD=V,...`` → the fields named and their values.

    Raises
    ------
    MagtactError
        For a text that is not ``FIELD=V`` pairs of integers, an unknown or repeated field.
    """
    from .._sensor import SETTING_FIELDS

    values = {}
    for item in str(text).split(","):
        key, eq, value = item.partition("=")
        name = key.strip().lower()
        if not eq or name not in SETTING_FIELDS:
            raise MagtactError(f"--setting must be FIELD=V pairs separated by commas, the fields "
                               f"{', '.join(f.upper() for f in SETTING_FIELDS)} (e.g. "
                               f"GAIN_SEL=5,RES=2), got {text!r}")
        if name in values:
            raise MagtactError(f"--setting names {name.upper()} twice")
        try:
            values[name] = int(value)
        except ValueError:
            raise MagtactError(f"--setting: {name.upper()} must be an integer, got "
                               f"{value.strip()!r}") from None
    return values


def check_sensor_options(study, *, H=None, G=None, standoff=None, setting=None) -> None:
    """Refuse, before any work, a value out of its physical range, a height outside the
    data's domain, a ``--setting`` that is not ``FIELD=V`` pairs (the message names the
    option)."""
    from ..doe import check_design

    if H is not None:
        check_design(study, checked_si(H, "mm", "--H"))
    if G is not None:
        checked_si(G, "kPa", "--G")
    if standoff is not None:
        checked_si(standoff, "mm", "--standoff-mm", bounds=(0.0, 20e-3))
    if setting is not None:
        parse_setting(setting)


def chosen_or_given(result, *, H=None, G=None, grade=None, standoff=None, setting=None,
                    silicone=None):
    """The sensor a command acts on: the result's chosen sensor with what the options name
    changed (user units: mm, kPa; ``setting``: ``FIELD=V,...``), and whether any was given.

    Raises
    ------
    MagtactError
        For a value out of its physical range, a grade or silicone not in the catalogue, a
        setting the chip does not have (the message names the option).
    """
    from ..parts import SettingError, chip_table

    sensor = result.sensor
    if sensor is None:
        raise MagtactError("the result holds no chosen sensor")
    chip = None
    if setting is not None:
        if sensor.setting is None:
            raise MagtactError(f"--setting: the {sensor.chip} has no settings to choose")
        chip = replace(sensor.setting, **parse_setting(setting))
        try:  # a setting the chip has and permits
            chip_table(sensor.chip).check(chip)
        except SettingError as exc:
            raise MagtactError(f"--setting: {exc.reason}") from None
    given = {"H": None if H is None else checked_si(H, "mm", "--H"),
             "G": None if G is None else checked_si(G, "kPa", "--G"),
             "standoff": None if standoff is None else checked_si(
                 standoff, "mm", "--standoff-mm", bounds=(0.0, 20e-3)),
             "setting": chip}
    try:
        changed = sensor.changed(grade=grade, silicone=silicone, **given)
        changed.check(result.study, free=result.study.geometric_variables)  # its silicone
    except MagtactError as exc:
        option = "--grade" if str(exc).startswith("grade") else "--silicone"
        raise MagtactError(f"{option}: {str(exc).partition(': ')[2]}") from None
    return changed, changed != sensor


def print_sensor_line(sensor, given: bool, to=None) -> None:
    """The sensor a command acts on, first in its output; ``to``: the console of the
    command's other messages (default: this module's)."""
    what = "the chosen sensor with the options given" if given else "the chosen sensor"
    (console if to is None else to).print(f"{what}: {escape(sensor.words())}",
                                          highlight=False)


@app.command("budget")
def budget_command(
    study: StudyArg = None,
    H: HOpt = None,
    G: GOpt = None,
    grade: GradeOpt = None,
    standoff: StandoffOpt = None,
    setting: SettingOpt = None,
    silicone: SiliconeOpt = None,
    noise: Annotated[str | None, typer.Option(
        "--noise-uT", metavar="S|X,Z",
        help="RMS field noise [µT] of the chip, one value for both axes or X,Z; it replaces "
             "the chip's own figure, and the output says so.")] = None,
    seeds: Annotated[Path | None, typer.Option(
        "--seed-study", help="A seed study (publication/publication.json of magtact reproduce) "
                        "for the seed-spread row.")] = None,
    models: ModelsOpt = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", callback=check_out,
        help="Output folder (created if needed) for budget.json and the figure; default: "
             "print only.")] = None,
) -> None:
    """The error budget of the chosen sensor (magtact.error_budget), or of it with the parts
    the options name changed: every false force besides the load, in mN."""
    from .. import design, error_budget
    from ..budget import budget_card_rows, write_budgets
    from ..report import budget_figures

    s = get_study(study)
    sigma = None if noise is None else parse_noise(noise)
    seed_data = _seeds(seeds)
    check_sensor_options(s, H=H, G=G, standoff=standoff, setting=setting)
    written = outputs("budget", out, "budget.json") if out is not None else None
    with written or contextlib.nullcontext() as o:
        with console.status("choosing the sensor"):
            result = design(s, models=models, log=lambda m: console.print(m, highlight=False))
        sensor, given = chosen_or_given(result, H=H, G=G, grade=grade, standoff=standoff,
                                        setting=setting, silicone=silicone)
        print_sensor_line(sensor, given)
        if sigma is not None:
            noise_override(sigma)
        b = error_budget(result, sensor if given else None, noise=sigma,
                         dataset=result.dataset, seeds=seed_data)
        if o is not None:
            write_budgets([b], result.study, o.folder, figures=budget_figures)
    print_budget(b)
    for name, text in budget_card_rows([b]):
        console.print(f"{escape(name)}: {escape(text)}", highlight=False)
    if o is not None:
        console.print(f"written to {o.out}", highlight=False)


def noise_override(sigma) -> None:
    """Say that ``--noise-uT`` (σ_x, σ_z) [T] replaces the chip's own figure."""
    given = ", ".join(f"{from_si(v, 'uT'):.3g}" for v in sigma)
    console.print(f"noise: given as --noise-uT {given} µT (x, z), in place of the chip's own "
                  "figure at the sensor's setting", highlight=False)


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
