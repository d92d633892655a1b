"""Field stage outputs: the Hall-point field over the DOE grid (CSV), and figures if asked."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..study import Study, from_si
from ._hall import hall_field

#: Columns of ``field.csv`` (SI except H in mm, the user unit).
CSV_COLUMNS = ("t", "theta_rad", "H_mm", "B_r_T", "B_z_T")


def field_grid(study: Study, solver: str | None = None) -> dict[str, np.ndarray]:
    """B at the Hall point over the study's DOE grid of (t, θ, H).

    Parameters
    ----------
    study : Study
        Its levels ``t_levels``, ``theta_levels``, ``H_levels`` span the grid.
    solver : {"fe", "exact"}, optional
        Field solver (default ``study.magnetics.solver``).

    Returns
    -------
    dict of numpy.ndarray
        ``t`` [-], ``theta`` [rad], ``H`` [m], ``B_r``, ``B_z`` [T], each of shape
        (n_t, n_theta, n_H) (index order t, θ, H).
    """
    t, theta, H = np.meshgrid(study.t_levels, study.theta_levels, study.H_levels, indexing="ij")
    B_r, B_z = hall_field(study, t, theta, H, solver)
    return {"t": t, "theta": theta, "H": H, "B_r": B_r, "B_z": B_z}


def write_field_csv(grid: dict[str, np.ndarray], path: str | Path) -> Path:
    """Write a :func:`field_grid` result as CSV with columns ``t,theta_rad,H_mm,B_r_T,B_z_T``.

    One row per grid point, t varying slowest and H fastest; 15 significant digits.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    table = np.column_stack([grid["t"].ravel(), grid["theta"].ravel(),
                             from_si(grid["H"].ravel(), "mm"), grid["B_r"].ravel(),
                             grid["B_z"].ravel()])
    np.savetxt(path, table, fmt="%.15g", delimiter=",", header=",".join(CSV_COLUMNS),
               comments="")
    return path


def write_field_outputs(study: Study, folder: str | Path, *, solver: str | None = None,
                        progress: Callable[[str], None] | None = None,
                        figures: Callable[..., list[Path]] | None = None) -> list[Path]:
    """Run the field stage: ``folder/field.csv`` and, with ``figures``, its figures.

    Parameters
    ----------
    study : Study
        The study.
    folder : path
        Output folder (created if needed).
    solver : {"fe", "exact"}, optional
        Field solver (default ``study.magnetics.solver``).
    progress : callable, optional
        Called with a short description before each step (mesh and solve, table, figures).
    figures : callable, optional
        ``figures(study, folder, solver)`` draws the stage's figures into ``folder`` and returns
        the files (:func:`magtact.report.field_figures`: the B_r, B_z maps). None: no figures.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from ._fe import solve_fe

    def step(text: str) -> None:
        if progress is not None:
            progress(text)

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    solver = study.magnetics.solver if solver is None else solver
    if solver == "fe":
        step("meshing and solving the axisymmetric FE field")
        solve_fe(study)
    n = study.doe.n_t * study.doe.n_theta * study.doe.n_H
    step(f"field at {n:,} Hall points")
    files = [write_field_csv(field_grid(study, solver), folder / "field.csv")]
    if figures is not None:
        step("figures")
        files += figures(study, folder, solver)
    return files
