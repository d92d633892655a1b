"""`magtact validate`: compare repeat indentation tests with the model (docs/method.md §8)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from .._errors import MagtactError
from .._floor import RELATIVE_FLOOR
from ..study import PRESETS, Study, checked_si, mm, to_si
from ..validation import MAX_GRID, N_GRID
from ._app import MeshDensity, Solver, app, check_out, console, get_study, outputs, tables

#: Highest filter cut-off accepted (cycles per mm of u_z; the samples are far coarser).
MAX_CYCLES_PER_MM = 1e6


def split_study_and_data(args: list[str]) -> tuple[str | None, list[Path]]:
    """Split ``[STUDY] DATA...``: the first item is the study if it is a preset or a .toml file."""
    if args and (args[0] in PRESETS or args[0].lower().endswith(".toml")):
        return args[0], [Path(a) for a in args[1:]]
    return None, [Path(a) for a in args]


def path_model(study: Study, H: float, G: float, theta: float, models_file: Path | None,
               solver: str, mesh: str | None = None):
    """The model of the design: metamodels from ``models_file``, else a direct simulation."""
    from ..validation import PathModel

    if models_file is not None:
        from ..metamodel import ExactField, load_models

        exact = (ExactField(study, "B_r"), ExactField(study, "B_z"))
        models = load_models(models_file,
                             B_model=exact if study.metamodel.b_model == "exact" else None)
        return PathModel.from_metamodels(models, study, H, G, theta)
    from ..mechanics import PathFailed

    try:
        return PathModel.from_simulation(study, H, G, theta, solver=solver, mesh=mesh)
    except PathFailed as exc:  # a user-fixable situation: say what to try
        raise MagtactError(f"the direct simulation of the design failed ({exc}); try another "
                           "mesh (--mesh) or validate against fitted metamodels (--models DIR)"
                           ) from None


def print_table(validation) -> None:
    """Print the c_v / ε table (rich) on standard output."""
    table = Table(title=validation.title, caption=f"model: {validation.model_label}")
    for col in ("response", "c_v (%)", "at u_z (mm)", "ε (%)", "at u_z (mm)", "excluded from ε"):
        table.add_column(col, justify="left" if col.startswith(("resp", "excl")) else "right")
    for response, s in validation.stats.items():
        table.add_row(response, f"{s.c_v:.3g}", f"{mm(s.c_v_at):.3g}", f"{s.eps:.3g}",
                      f"{mm(s.eps_at):.3g}", validation.excluded(response))
    tables().print(table)
    for note in validation.notes:
        console.print(f"note: {note}", highlight=False)


@app.command("validate")
def validate_command(
    args: Annotated[list[str] | None, typer.Argument(
        metavar="[STUDY] DATA...",
        help="Optional study (preset or .toml), then CSV files of repeat tests; no files: the "
             "shipped SYNTHETIC example.")] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (created if needed).",
                                      callback=check_out)] = Path("validation"),
    H: Annotated[float | None, typer.Option("--H", help="Body height H [mm] of the tested "
                                            "design; default: the data's metadata.")] = None,
    G: Annotated[float | None, typer.Option("--G", help="Shear modulus G [kPa] of the tested "
                                            "design; default: the data's metadata.")] = None,
    models: Annotated[Path | None, typer.Option(
        "--models", help="Folder of metamodel files (B_r.json, B_z.json, f_r.json, f_z.json; "
                         "magtact fit); default: simulate the design directly (one structural "
                         "path).")] = None,
    solver: Annotated[Solver, typer.Option(
        "--solver", help="Field solver of the direct simulation: 'fe': axisymmetric finite "
                         "elements; 'exact': closed form.")] = Solver.exact,
    mesh: Annotated[MeshDensity | None, typer.Option(
        "--mesh", help="Mesh density of the direct simulation; default: the study's "
                       "mechanics.mesh.")] = None,
    f_lo: Annotated[float, typer.Option("--f-lo", help="Low cut-off (cycles per mm of u_z).")]
    = 0.0,
    f_hi: Annotated[float, typer.Option("--f-hi", help="High cut-off (cycles per mm of u_z); 0: no "
                                        "low-pass.")] = 2.0,
    n_grid: Annotated[int, typer.Option("--n-grid", min=2, max=MAX_GRID,
                                        help="Points of the common grid.")] = N_GRID,
    floor: Annotated[float, typer.Option(help="Ratios are evaluated where |denominator| > floor "
                                         "× its largest value.")] = RELATIVE_FLOOR,
) -> None:
    """Validate the model of a design against repeat indentation tests: c_v, ε and figures."""
    from ..report import validation_figures
    from ..validation import (
        FilterSettings,
        output_stem,
        read_experiment,
        synthetic_files,
        validate,
        write_outputs,
    )

    study_src, data = split_study_and_data(args or [])
    study = get_study(study_src)
    if not data:
        data = synthetic_files()
        console.print("no data files given: using the shipped SYNTHETIC example "
                      f"({len(data)} files)", highlight=False)
    H_m = None if H is None else checked_si(H, "mm", "--H")
    G_pa = None if G is None else checked_si(G, "kPa", "--G")
    solver = Solver(solver).value
    mesh = None if mesh is None else MeshDensity(mesh).value
    for name, value in (("--f-lo", f_lo), ("--f-hi", f_hi)):
        if not (math.isfinite(value) and 0.0 <= value <= MAX_CYCLES_PER_MM):
            raise MagtactError(f"{name} must be between 0 and {MAX_CYCLES_PER_MM:g} cycles per mm "
                               f"(--f-hi 0: no low-pass), got {value!r}")
    if not 0.0 <= floor < 1.0:
        raise MagtactError(f"--floor must be in [0, 1), got {floor!r}")
    if f_hi > 0 and not f_hi > f_lo:
        raise MagtactError(f"--f-hi ({f_hi:g} cycles per mm) must be above --f-lo ({f_lo:g} "
                           "cycles per mm), or 0 for no low-pass")
    filt = FilterSettings(f_lo=to_si(f_lo, "per_mm"),
                          f_hi=to_si(f_hi, "per_mm") if f_hi > 0 else None)
    experiment = read_experiment(data)
    H_m, G_pa = experiment.design(H_m, G_pa)
    stem = output_stem(experiment.synthetic)
    # the folder is checked (writable, nothing of the user's in the way) before the work
    with outputs("validate", out, f"{stem}.csv", f"{stem}.json") as o:
        model = path_model(study, H_m, G_pa, experiment.theta, models, solver, mesh)
        result = validate(experiment, model, filter=filt, n_grid=n_grid, floor=floor)
        written = write_outputs(result, o.folder, sources=data, figures=validation_figures)
        written = [o.final(p) for p in written]
    print_table(result)
    for path in written:
        console.print(f"wrote {path}", highlight=False)
