"""`magtact simulate`: one structural loading path (θ, H) of the sensor body."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from .._errors import MagtactError
from .._files import write_csv
from ._app import MeshDensity, OutOpt, StudyArg, app, console, get_study, outputs


@app.command("simulate")
def simulate_command(
    H: Annotated[float, typer.Option("--H", help="Body height H [mm].")],
    theta: Annotated[float, typer.Option("--theta", help="Shear angle θ [rad].")],
    study: StudyArg = None,
    out: OutOpt = Path("simulate"),
    G: Annotated[float | None, typer.Option(
        "--G", help="Shear modulus G [kPa]; default: the study's material.G_ref.")] = None,
    mesh: Annotated[MeshDensity | None, typer.Option(
        "--mesh", help="Mesh density; default: the study's mechanics.mesh.")] = None,
) -> None:
    """Solve one loading path; write OUT/forces.csv, the deformed mesh at t = 1 (VTU) and a
    figure of the deformed body (PNG, SVG)."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from ..mechanics import PathFailed, simulate_path
    from ..report import fig_deformed_body
    from ..study import checked_si, from_si

    s = get_study(study)
    H_si = checked_si(H, "mm", "--H")
    G_si = None if G is None else checked_si(G, "kPa", "--G")
    if not (math.isfinite(theta) and 0.0 <= theta < math.pi / 2):
        raise MagtactError(f"--theta must be in [0, π/2) rad, got {theta!r}")
    with outputs("simulate", out, "forces.csv", "deformed_t1.vtu") as o:
        folder = o.folder
        vtu = folder / "deformed_t1.vtu"
        t = s.t_levels
        with Progress(TextColumn("{task.description}"), BarColumn(),
                      TextColumn("t = {task.completed:.2f}"), TimeElapsedColumn(),
                      console=console, transient=True) as bar:
            task = bar.add_task(f"simulate H = {H:g} mm, θ = {theta:g} rad", total=1.0)
            try:
                res = simulate_path(s, H_si, theta, G=G_si, t=t, vtu=vtu,
                                    mesh=None if mesh is None else mesh.value,
                                    progress=lambda tt: bar.update(task, completed=tt))
            except PathFailed as exc:
                raise MagtactError(str(exc)) from exc
        write_csv(folder / "forces.csv", ["t", "u_r_mm", "u_z_mm", "F_r_N", "F_z_N"],
                  zip(res.t, from_si(res.u_r, "mm"), from_si(res.u_z, "mm"), res.F_r, res.F_z,
                      strict=True),
                  cell=lambda v: f"{v + 0.0:.10g}")  # + 0.0: no "-0"
        import meshio

        m = meshio.read(vtu)
        u = m.point_data["displacement"]
        fig_files = fig_deformed_body(
            m.points - u, m.cells[0].data, u, folder / "deformed_body",
            title=f"H = {H:g} mm, θ = {theta:.3f} rad, t = {res.t[-1]:g}: "
                  f"F_r = {res.F_r[-1]:.3g} N, F_z = {res.F_z[-1]:.3g} N "
                  f"(G = {from_si(res.G, 'kPa'):g} kPa)")
    console.print(
        f"simulate: {res.steps} steps, {res.newton_iterations} Newton iterations, "
        f"{res.cutbacks} cut-backs, {res.n_dofs} DOFs ({res.mesh} mesh, "
        f"{s.mechanics.element} cells, contact "
        f"{'over the faces' if s.mechanics.contact == 'faces' else 'node by node'}), "
        f"{res.wall_time:.1f} s; wrote {o.final(folder / 'forces.csv')}, {o.final(vtu)}, "
        + ", ".join(str(o.final(f)) for f in fig_files), highlight=False)
