"""What the default mesh's discretisation error does to the study's answer (issues 3 and 5).

Compares the bundled MagOne DOE (``default`` mesh) with the same DOE solved on a finer mesh:
per (θ, H) path the relative change of F_z(t = 1) and of min F_r over t, the roughness of f_r
per path, and the chosen design of both (metamodels fitted with the study's settings,
then :func:`magtact.optimise.optimise`). Writes ``bench/results/mesh_effect.json``.

    magtact doe bench/magone_accurate.toml --out ACC --workers 2    # about 1 h on 2 cores
    cp ACC/doe.nc bench/results/doe_accurate.nc
    python bench/bench_mesh_effect.py [--data bench/results/doe_accurate.nc]

The Γ check of the finer DOE's fit is ``bench/bench_fit.py --data bench/results/doe_accurate.nc
--out bench/results/fit_accurate.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from bench_fit import roughness

from magtact.doe import load_bundled, load_dataset
from magtact.metamodel import find_prefitted, fit_models, load_models
from magtact.optimise import optimise
from magtact.optimise._run import _design_json
from magtact.study import load_study

RESULTS = Path(__file__).parent / "results"


def _forces(ds) -> dict[str, np.ndarray]:
    """F_z(t = 1) and min over t of F_r per (θ, H) [N], at the first G level."""
    F = {k: ds[k].transpose("t", "theta", "H", "G").values[..., 0] for k in ("F_z", "F_r")}
    return {"F_z_t1": F["F_z"][-1], "F_r_min": F["F_r"].min(axis=0)}


def _design(models, study) -> dict[str, float]:
    d = _design_json(optimise(models, study).choice.design)
    return {k: v for k, v in d.items() if isinstance(v, float)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=RESULTS / "doe_accurate.nc")
    ap.add_argument("--out", type=Path, default=RESULTS / "mesh_effect.json")
    args = ap.parse_args()
    study = load_study(None)
    base, fine = load_bundled(), load_dataset(args.data)
    mesh = {"default": base.attrs["mesh"], "finer": fine.attrs["mesh"]}
    fb, ff = _forces(base), _forces(fine)
    # min F_r at θ = 0 is zero up to solver tolerance: no relative change there
    shear = base["theta"].values > 0
    change = {"F_z_t1": fb["F_z_t1"] / ff["F_z_t1"] - 1,
              "F_r_min": fb["F_r_min"][shear] / ff["F_r_min"][shear] - 1}
    t0 = time.perf_counter()
    designs = {"default": _design(load_models(find_prefitted(study, base)), study),
               "finer": _design(fit_models(fine, study).model_set(study), study)}
    out = {
        "data": {"default": "bundled", "finer": str(args.data)},
        "mesh": mesh,
        "theta_rad": base["theta"].values.tolist(), "H_mm": (base["H"].values * 1e3).tolist(),
        "change_default_vs_finer": {
            "F_z_t1_theta_by_H": change["F_z_t1"].tolist(),
            "F_z_t1_range": [float(change["F_z_t1"].min()), float(change["F_z_t1"].max())],
            "F_r_min_theta_gt_0_range": [float(change["F_r_min"].min()),
                                         float(change["F_r_min"].max())],
        },
        "f_r_roughness_per_path_poly6": {"default": roughness(base)["f_r"],
                                          "finer": roughness(fine)["f_r"]},
        "chosen_design": designs,
        "chosen_design_change": {k: designs["finer"][k] / designs["default"][k] - 1
                                 for k in ("H_mm", "G_kPa", "Gamma_r_max_N_per_T",
                                           "Gamma_z_max_N_per_T", "F_r_min_N", "F_z_max_N")},
        "fit_and_optimise_time_s": time.perf_counter() - t0,
    }
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps({k: out[k] for k in ("chosen_design", "chosen_design_change")}, indent=1))


if __name__ == "__main__":
    main()
