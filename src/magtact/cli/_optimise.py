"""`magtact optimise` (docs/method.md §7) and `magtact compare` (two designs side by side)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .._display import sig
from .._errors import MagtactError
from ..study import Study, checked_si, from_si
from ._app import ModelsOpt, OutOpt, StudyArg, app, console, get_study, outputs, renamed, tables

#: Files ``magtact optimise`` always writes (:func:`magtact.write_results`).
OPTIMISE_OUTPUTS = ("design.json", "pareto.csv", "reduction.csv", "maps.csv", "card.json",
                    "chosen.json", "sensor.json")


def parse_design(text: str, what: str) -> tuple[float, float]:
    """``"H_MM,G_KPA"`` → (H [m], G [Pa]).

    Raises
    ------
    MagtactError
        If ``text`` is not two comma-separated positive numbers.
    """
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        H_mm, G_kPa = (float(p) for p in parts)
    except ValueError:
        raise MagtactError(f"{what} must be 'H_MM,G_KPA' (two numbers, e.g. 3,29.4), "
                           f"got {text!r}") from None
    if not (H_mm > 0 and G_kPa > 0):
        raise MagtactError(f"{what}: H and G must be positive, got {text!r}")
    return checked_si(H_mm, "mm", f"{what}: H"), checked_si(G_kPa, "kPa", f"{what}: G")


def study_models(study: Study, models: Path | None):
    """The metamodels (:func:`magtact.models_for`): from ``models`` (a ``magtact fit`` output
    folder) if given, else the shipped fit or a new fit to the bundled DOE data set."""
    from .. import models_for

    return models_for(study, models=models,
                      log=lambda m: console.print(m, highlight=False))[:2]


@app.command("optimise")
def optimise_command(
    study: StudyArg = None,
    out: OutOpt = Path("optimise"),
    Frc: Annotated[float | None, typer.Option(
        "--Frc", help="Shear constraint F_r,c [N]: F_r,min must be at most this.")] = None,
    Fzc: Annotated[float | None, typer.Option(
        "--Fzc", help="Normal constraint F_z,c [N]: F_z,max must be at least this.")] = None,
    constraints_from: Annotated[str | None, typer.Option(
        "--constraints-from", metavar="H_MM,G_KPA",
        help="Take F_r,c and F_z,c from this reference design.")] = None,
    models: ModelsOpt = None,
) -> None:
    """Sensitivity-optimal design: maps, Pareto set (NSGA-II + exact reduction), chosen design.

    Writes OUT/design.json, pareto.csv, reduction.csv, maps.csv, card.json and the figures
    (OUT/geometry.json and its figure with geometric design variables).
    """
    from .. import card, error_budgets, solve, write_results_into
    from ..designer import check_rest_field
    from ..optimise import force_constraints

    s = get_study(study)
    Frc = None if Frc is None else checked_si(Frc, "N", "--Frc")
    Fzc = None if Fzc is None else checked_si(Fzc, "N", "--Fzc")
    reference = (parse_design(constraints_from, "--constraints-from")
                 if constraints_from is not None else None)
    own = s.geometry()
    check_rest_field(s.at(**own) if own else s)  # a chip that reads nothing: before the work
    # the folder is checked (writable, nothing of the user's in the way) before the work
    with outputs("optimise", out, *OPTIMISE_OUTPUTS) as o:
        m, source = study_models(s, models)
        constraints = force_constraints(m, s, F_r_c=Frc, F_z_c=Fzc, reference=reference)
        with console.status("optimising"):
            result = solve(m, s, constraints, models_source=source)
        budgets = error_budgets(result)  # once, for card.json, budget.json and the card shown
        write_results_into(result, o.folder, budgets=budgets)
    print_choice(result)
    print_card(card(result, budgets))
    console.print(f"written to {o.out}", highlight=False)


def print_card(card: dict | None, stdout: Console | None = None) -> None:
    """Print the design card (rows of :func:`magtact.report.card_rows`) as a rich table."""
    if not card:
        return
    table = Table(title="Design card", show_lines=False)
    for k, h in enumerate(card["header"]):
        table.add_column(escape(h or "answer"), justify="left", overflow="fold",
                         ratio=2 if k == 0 else 1)
    for row in card["rows"]:
        table.add_row(*(escape(str(c)) for c in row))
    (stdout or tables()).print(table)


def print_sensor(result, stdout: Console | None = None) -> None:
    """Print the chosen sensor of the sensor problem beside the exact reduction's (rich table
    on standard output)."""
    sd = result.sensor_design
    r = result.study.requirements
    table = Table(title=f"Chosen sensor ({result.study.name})",
                  caption=f"requirements: 0–{r.F_z:.3g} N normal, 0–{r.F_r:.3g} N shear, "
                          f"{r.rate:.3g} Hz; NSGA-II {100 * sd.gap:.2g} % from the exact "
                          "reduction" if sd.gap == sd.gap else "")
    table.add_column("quantity", justify="left")
    table.add_column("chosen", justify="right")
    table.add_column("exact reduction", justify="right")
    rows = (("H [mm]", lambda d: sig(from_si(d.H, "mm"))),
            ("G [kPa]", lambda d: sig(from_si(d.G, "kPa"))),
            ("magnet grade", lambda d: d.grade),
            ("chip standoff [mm]", lambda d: sig(from_si(d.standoff, "mm"))),
            ("chip setting", lambda d: d.option.words),
            ("σ_F,r over the required loads [mN]", lambda d: sig(from_si(d.sigma_r, "mN"))),
            ("σ_F,z over the required loads [mN]", lambda d: sig(from_si(d.sigma_z, "mN"))))
    for label, cell in rows:
        table.add_row(escape(label), cell(sd.choice), cell(sd.reduction_choice))
    (stdout or tables()).print(table)


def print_choice(result, stdout: Console | None = None) -> None:
    """Print the chosen design of a :class:`magtact.Result` beside the exact reduction's
    choice, and the constraints used (rich table on standard output); in the sensor problem
    the chosen sensor (:func:`print_sensor`)."""
    if getattr(result, "sensor_design", None) is not None:
        print_sensor(result, stdout)
        return
    opt, c = result.optimisation, result.constraints
    table = Table(title=f"Chosen design ({result.study.name}; "
                        f"{result.study.sensitivity.definition} Γ)",
                  caption=f"constraints ({c.source}): F_r,min <= {c.F_r_c:.4g} N, "
                          f"F_z,max >= {c.F_z_c:.4g} N; active: "
                          f"{', '.join(result.active_constraints) or 'none'}")
    table.add_column("quantity", justify="left")
    table.add_column("NSGA-II + decision", justify="right")
    table.add_column("exact reduction", justify="right")
    if result.study.geometric_variables:
        a, b = opt.choice.values, opt.exact_choice.values
        names = [k for k in a if k != "M_z" or result.study.M_z_variable]
    else:
        d, e = opt.choice.design, opt.reduction_choice.design
        a = {"H": d.H, "G": d.G, "M_z": d.M_z}
        b = {"H": e.H, "G": e.G, "M_z": e.M_z}
        names = ["H", "G"] + (["M_z"] if d.M_z is not None and e.M_z is not None else [])
    unit = {"G": ("kPa", "kPa"), "M_z": ("MA_per_m", "MA/m")}
    rows = [(f"{k} [{unit.get(k, ('mm', 'mm'))[1]}]", from_si(a[k], unit.get(k, ("mm",))[0]),
             from_si(b[k], unit.get(k, ("mm",))[0])) for k in names]
    d, e = opt.choice.design, (opt.exact_choice if result.study.geometric_variables
                               else opt.reduction_choice).design
    if result.study.optimise.objective == "sigma_F":  # the objective: σ_F [N] → mN
        rows += [("σ_Fr,max (objective) [mN]", 1e3 * d.Gamma_r_max, 1e3 * e.Gamma_r_max),
                 ("σ_Fz,max (objective) [mN]", 1e3 * d.Gamma_z_max, 1e3 * e.Gamma_z_max)]
    else:
        rows += [("Γ_r,max [N/T]", d.Gamma_r_max, e.Gamma_r_max),
                 ("Γ_z,max [N/T]", d.Gamma_z_max, e.Gamma_z_max)]
    rows += [("F_r,min [N]", d.F_r_min, e.F_r_min), ("F_z,max [N]", d.F_z_max, e.F_z_max)]
    for label, x, y in rows:
        table.add_row(escape(label), f"{x:.5g}", f"{y:.5g}")
    (stdout or tables()).print(table)


@app.command("compare")
def compare_command(
    first: Annotated[str, typer.Argument(metavar="H1,G1", help="First design, mm,kPa.")],
    second: Annotated[str, typer.Argument(metavar="H2,G2", help="Second design, mm,kPa.")],
    study: StudyArg = None,
    models: ModelsOpt = None,
    _old_study: Annotated[str | None, renamed(
        "--study", "an argument", "an argument: magtact compare H1,G1 H2,G2 STUDY")] = None,
) -> None:
    """Percentage changes of Γ_r,max, Γ_z,max, F_r,min, F_z,max from design 1 to design 2."""
    from .._sensor import Sensor
    from ..designer import answer
    from ..optimise import compare

    d1 = parse_design(first, "first design")
    d2 = parse_design(second, "second design")
    s = get_study(study)
    m, _ = study_models(s, models)
    # each with the study's parts, the chip at its own setting
    a1, a2 = (answer(m, s, Sensor.of_study(s, *d)) for d in (d1, d2))
    cmp = compare(a1.design, a2.design)
    table = Table(title=f"{first} → {second} (mm,kPa)")
    for col in ("quantity", "design 1", "design 2", "change (%)"):
        table.add_column(col, justify="left" if col == "quantity" else "right")
    for label, unit, v1, v2, pct in cmp.rows:
        table.add_row(escape(f"{label} [{unit}]"), sig(v1), sig(v2), f"{pct:+.2f}")
    r1, r2 = a1.resolution, a2.resolution
    if r1 is None or r2 is None:
        table.caption = (f"resolution with the {a1.chip.name}: give "
                         f"{' and '.join(a1.chip.missing)} in the study (RMS noise, µT)")
    else:
        for label, a, b in (("σ_Fr at t = 0", r1.sigma_r_0, r2.sigma_r_0),
                            ("σ_Fz at t = 0", r1.sigma_z_0, r2.sigma_z_0),
                            ("σ_Fr, worst in the stable region", r1.sigma_r_worst,
                             r2.sigma_r_worst),
                            ("σ_Fz, worst in the stable region", r1.sigma_z_worst,
                             r2.sigma_z_worst)):
            v1, v2 = from_si(a, "mN"), from_si(b, "mN")
            table.add_row(escape(f"{label} [mN]"), sig(v1), sig(v2),
                          f"{100 * (v2 - v1) / v1:+.2f}")
        table.caption = (f"σ_F with the {a1.chip.name}: design 1 at {a1.chip.setting}, "
                         f"design 2 at {a2.chip.setting}")
    tables().print(table)
