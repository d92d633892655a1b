"""The SYNTHETIC example data set shipped with magtact (docs/method.md §8).

It is generated, not measured: 4 sensors × 2 repeats of the fabricated design (H = 4.1 mm,
G = 29.4 kPa) at θ = θ_max, from the model (exact field of the magnet, FE forces of one direct
structural simulation on the study's default mesh), with noise, drift and sensor-to-sensor
scatter added. Its file names start with ``synthetic_``, its metadata says ``synthetic = true``,
and every table and figure made from it says SYNTHETIC. Regenerate it with::

    python -m magtact.validation --out src/magtact/validation/data
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..geometry import shear_displacement
from ..study import MESH_DENSITIES, Study, kpa, load_study, mm, to_si
from ._io import RESPONSES, UNITS
from ._model import PathModel

#: Folder of the shipped example files.
SYNTHETIC_DIR = Path(__file__).parent / "data"

#: Base height of the example's sensor [m]: the height of the sensor fabricated in de Boer et
#: al., Sensors 17 (2017) 2539 (its material is the study's original design).
SYNTHETIC_H = to_si(4.1, "mm")

#: Noise model (SI): standard deviations of each effect.
NOISE = {
    "field_gain_sensor": 0.02,      # magnetisation / placement scatter between sensors [-]
    "field_offset_sensor": 0.3e-3,  # Hall offset per sensor [T]
    "force_gain_sensor": 0.03,      # elastomer modulus scatter between sensors [-]
    "gain_repeat": 0.005,           # repeat-to-repeat change (Mullins effect, seating) [-]
    "field_white": 0.05e-3,         # Hall noise per sample [T]
    "force_white": 5e-3,            # load cell noise per sample [N]
    "field_drift": 0.1e-3,          # field drift over one test [T]
    "force_drift": 10e-3,           # load cell drift over one test [N]
    "u_jitter": 1e-6,               # displacement read-out noise [m]
}


def synthetic_files() -> list[Path]:
    """The shipped SYNTHETIC example files, sorted."""
    return sorted(SYNTHETIC_DIR.glob("synthetic_*.csv"))


def make_synthetic(model: PathModel, u_z_end: float, *, n_sensors: int = 4, n_repeats: int = 2,
                   n_samples: int = 241, seed: int = 20240607) -> list[dict]:
    """Generate noisy repeat tests from a model.

    Parameters
    ----------
    model : PathModel
        The model of the design at its shear angle.
    u_z_end : float
        Deepest vertical displacement [m] (< 0).
    n_sensors, n_repeats : int
        Sensors and repeats per sensor.
    n_samples : int
        Samples per test, uniform in commanded displacement.
    seed : int
        Seed of the random generator (reproducible).

    Returns
    -------
    list of dict
        One per test: ``sensor, repeat, u_z, u_r`` and the four responses, arrays (n_samples,)
        in SI.

    Notes
    -----
    Per sensor s, repeat j and sample k (fraction s_k ∈ [0, 1] of the test):
    B = g_s g_sj B_model + b_s + d_sj s_k + e_k, F = h_s g_sj F_model + c_sj s_k + e'_k, with gains
    g, h, offsets b, drifts d, c and white noise e, e' drawn from normal laws of the standard
    deviations in :data:`NOISE`; the recorded u_z carries read-out noise of σ = 1 µm.
    """
    rng = np.random.default_rng(seed)
    n = NOISE
    commanded = np.linspace(0.0, u_z_end, n_samples)
    step = abs(commanded[1] - commanded[0])
    tests = []
    for s in range(1, n_sensors + 1):
        g_B = 1.0 + n["field_gain_sensor"] * rng.standard_normal()
        g_F = 1.0 + n["force_gain_sensor"] * rng.standard_normal()
        offset = {r: n["field_offset_sensor"] * rng.standard_normal() for r in ("B_r", "B_z")}
        for j in range(1, n_repeats + 1):
            g_j = 1.0 + n["gain_repeat"] * rng.standard_normal()
            jitter = np.clip(n["u_jitter"] * rng.standard_normal(n_samples), -step / 4, step / 4)
            u_z = commanded + jitter
            clean = model(commanded)
            frac = np.linspace(0.0, 1.0, n_samples)
            test = {"sensor": f"S{s}", "repeat": str(j), "u_z": u_z,
                    "u_r": shear_displacement(u_z, model.theta)}
            for r in RESPONSES:
                if r.startswith("B"):
                    y = (g_B * g_j * clean[r] + offset[r]
                         + n["field_drift"] * rng.standard_normal() * frac
                         + n["field_white"] * rng.standard_normal(n_samples))
                else:
                    y = (g_F * g_j * clean[r] + n["force_drift"] * rng.standard_normal() * frac
                         + n["force_white"] * rng.standard_normal(n_samples))
                test[r] = y
            tests.append(test)
    return tests


def write_synthetic(out: str | Path, study: Study | None = None, *, seed: int = 20240607,
                    solver: str = "exact", mesh: str | None = None,
                    H: float = SYNTHETIC_H) -> list[Path]:
    """Simulate the fabricated design and write the SYNTHETIC example files.

    Parameters
    ----------
    out : path
        Folder for ``synthetic_S<sensor>_r<repeat>.csv``.
    study : Study, optional
        Default: the built-in MagOne study.
    H : float
        Base height of the simulated sensor [m]; default :data:`SYNTHETIC_H` (the fabricated
        sensor's); its shear modulus is the study's original design's.
    seed : int
        Random seed.
    solver : {"exact", "fe"}
        Field solver of the model.
    mesh : {"coarse", "default", "accurate", "fine"}, optional
        Structural mesh; default ``study.mechanics.mesh``.

    Returns
    -------
    list of Path
        Files written.
    """
    from ..geometry import loading_path

    study = load_study(None) if study is None else study
    theta = study.loading.theta_max
    mesh = study.mechanics.mesh if mesh is None else mesh
    G = study.design.G_original
    model = PathModel.from_simulation(study, H, G, theta, solver=solver, mesh=mesh)
    u_z_end = float(loading_path(study, 1.0, theta, H)[1])
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for test in make_synthetic(model, u_z_end, seed=seed):
        path = out / f"synthetic_{test['sensor']}_r{test['repeat']}.csv"
        header = [
            "# synthetic = true",
            "# description = SYNTHETIC example data generated by magtact from its model "
            "(not a measurement)",
            f"# model = {model.label}, {mesh} structural mesh",
            f"# design_H_mm = {mm(H):g}",
            f"# design_G_kPa = {kpa(G):g}",
            f"# theta_rad = {theta:.10g}",
            f"# sensor = {test['sensor']}",
            f"# repeat = {test['repeat']}",
            f"# seed = {seed}",
            "# noise = " + ", ".join(f"{k} {v:g}" for k, v in NOISE.items()),
            "u_z_mm,u_r_mm," + ",".join(f"{r}_{UNITS[r]}" for r in RESPONSES),
        ]
        rows = [f"{mm(test['u_z'][k]):.6f},{mm(test['u_r'][k]):.6f},"
                + ",".join(f"{test[r][k]:.6e}" for r in RESPONSES)
                for k in range(test["u_z"].size)]
        path.write_text("\n".join(header + rows) + "\n", encoding="utf-8")
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> None:
    """Command line: regenerate the SYNTHETIC example files."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(SYNTHETIC_DIR), help="output folder")
    parser.add_argument("--seed", type=int, default=20240607)
    parser.add_argument("--solver", default="exact", choices=("exact", "fe"))
    parser.add_argument("--mesh", default=None, choices=MESH_DENSITIES)
    args = parser.parse_args(argv)
    for path in write_synthetic(args.out, seed=args.seed, solver=args.solver, mesh=args.mesh):
        print(path)


if __name__ == "__main__":
    main()
