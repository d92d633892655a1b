"""Per-path estimate of the structural forces' discretisation error (docs/method.md §3).

A DOE computed on one mesh is compared with the same paths solved on the next finer mesh. Per
(θ, H) path two numbers describe the change the finer mesh makes:

* ``err_F_z``: F_z(t = 1) / F_z,finer(t = 1) − 1;
* ``err_F_r``: min_t F_r / min_t F_r,finer − 1, the force the stable-shear bound limits (NaN at
  θ = 0, where F_r vanishes by symmetry).

Paths solved on both meshes record the measured value. The others record a bilinear model of
the change over (θ, H), least squares on the measured paths: the change is smooth over the design
space (it follows from the mesh, which scales with the body), which the leave-one-out check in
the attributes quantifies. Both ratios are independent of G (forces scale exactly with G).
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from .._errors import MagtactError

#: The next finer mesh density of each density (the refinement the estimate measures).
FINER_MESH = {"coarse": "default", "default": "accurate", "accurate": "fine"}
#: The data variables the estimate adds: name -> (force, long name).
ERROR_VARIABLES = {
    "err_F_z": ("F_z", "relative change of F_z(t=1) against the next finer mesh "
                       "(this mesh / finer - 1)"),
    "err_F_r": ("F_r", "relative change of min over t of F_r against the next finer mesh "
                       "(this mesh / finer - 1); NaN at theta = 0"),
}


def error_points(theta: np.ndarray, H: np.ndarray, n: int) -> list[tuple[float, float]]:
    """The (θ, H) paths to solve on the finer mesh when ``n`` of them are affordable.

    The corners of the sheared part of the grid (smallest non-zero θ and θ_max, each H bound)
    first, then its centre, then the rest of the grid from the centre outwards: the first four
    fix a bilinear model, the centre checks it.
    """
    theta, H = np.asarray(theta, float), np.asarray(H, float)
    sheared = theta[theta > 0] if (theta > 0).any() else theta
    corners = [(sheared[0], H[0]), (sheared[0], H[-1]), (sheared[-1], H[0]),
               (sheared[-1], H[-1])]
    centre = [(sheared[len(sheared) // 2], H[len(H) // 2])]
    rest = sorted(((a, b) for a in theta for b in H),
                  key=lambda p: (abs(p[0] - centre[0][0]) / np.ptp(theta)
                                 if np.ptp(theta) else 0.0)
                  + (abs(p[1] - centre[0][1]) / np.ptp(H) if np.ptp(H) else 0.0))
    chosen: list[tuple[float, float]] = []
    for p in corners + centre + rest:
        p = (float(p[0]), float(p[1]))
        if p not in chosen:
            chosen.append(p)
    return chosen[:max(0, n)]


def _basis(theta: np.ndarray, H: np.ndarray, n_points: int) -> np.ndarray:
    """Bilinear basis in (θ, H), reduced to what ``n_points`` measurements can fix."""
    full = np.stack([np.ones_like(theta), theta, H, theta * H], axis=-1)
    return full[..., :4 if n_points >= 4 else 3 if n_points == 3 else 1]


def _model(theta: np.ndarray, H: np.ndarray, y: np.ndarray, measured: np.ndarray,
           ) -> tuple[np.ndarray, float]:
    """The fitted change on the whole grid, and its leave-one-out maximum error (NaN if < 5)."""
    ok = measured & np.isfinite(y)
    n = int(ok.sum())
    if n == 0:
        return np.full_like(y, np.nan), float("nan")

    def fit(mask):
        coef, *_ = np.linalg.lstsq(_basis(theta[mask], H[mask], int(mask.sum())), y[mask],
                                   rcond=None)
        return _basis(theta, H, int(mask.sum())) @ coef

    loo = float("nan")
    if n >= 5:
        errs = []
        for k in zip(*np.nonzero(ok), strict=True):
            mask = ok.copy()
            mask[k] = False
            errs.append(abs(fit(mask)[k] - y[k]))
        loo = float(max(errs))
    return fit(ok), loo


def attach_discretisation_error(ds: xr.Dataset, finer: xr.Dataset) -> xr.Dataset:
    """``ds`` with the per-path estimate of its forces' discretisation error (module doc).

    Parameters
    ----------
    ds : xarray.Dataset
        A DOE data set.
    finer : xarray.Dataset
        The same study's paths on a finer mesh: same t and G levels, (θ, H) levels a subset of
        ``ds``'s (paths it lacks, or holds as NaN, are modelled).

    Returns
    -------
    xarray.Dataset
        A copy of ``ds`` with ``err_F_z``, ``err_F_r`` (θ, H) [1], ``err_measured`` (θ, H) [1]
        (1: solved on both meshes, 0: modelled), and ``discretisation_*`` attributes.

    Raises
    ------
    MagtactError
        If the two data sets do not share t, or no path of ``finer`` is usable.
    """
    if not np.array_equal(ds["t"].values, finer["t"].values):
        raise MagtactError("the finer data set has other t levels than the DOE")
    theta, H = ds["theta"].values, ds["H"].values
    tt, HH = np.meshgrid(theta, H, indexing="ij")
    values, measured = {}, np.zeros(tt.shape, bool)
    for name, (force, _) in ERROR_VARIABLES.items():
        coarse = _path_measure(ds, force)
        fine = _path_measure(finer, force).reindex(theta=theta, H=H, method="nearest",
                                                   tolerance=1e-12)
        y = (coarse / fine - 1).values
        have = np.isfinite(y)
        if name == "err_F_z":
            measured = have
        elif (theta > 0).any():
            y[theta == 0, :] = np.nan
        model, loo = _model(tt, HH, y, have)
        out = np.where(have, y, model)
        if name == "err_F_r":
            out[theta == 0, :] = np.nan
        values[name] = (out, loo)
    if not measured.any():
        raise MagtactError("the finer data set has no path of the DOE's (theta, H) grid")
    out = ds.copy()
    for name, (_, long_name) in ERROR_VARIABLES.items():
        out[name] = (("theta", "H"), values[name][0], {"units": "1", "long_name": long_name})
    out["err_measured"] = (("theta", "H"), measured.astype(np.int8),
                           {"units": "1", "long_name": "1: path solved on both meshes, "
                                                       "0: change modelled (bilinear in theta, H)"})
    jobs = json.loads(finer.attrs.get("jobs", "[]"))
    times = [j["wall_time"] for j in jobs if j.get("wall_time") is not None]
    out.attrs.update({
        "discretisation_mesh": str(ds.attrs.get("mesh", "")),
        "discretisation_finer_mesh": str(finer.attrs.get("mesh", "")),
        "discretisation_paths_measured": int(measured.sum()),
        "discretisation_loo_max_err_F_z": values["err_F_z"][1],
        "discretisation_loo_max_err_F_r": values["err_F_r"][1],
        "discretisation_finer_wall_time_s": float(np.mean(times)) if times else float("nan"),
        "discretisation_method": (
            "err_F_z, err_F_r: per (theta, H) path, the DOE's F_z(t=1) and min_t F_r "
            "divided by the same path's on the finer mesh, minus 1; measured where "
            "err_measured = 1, elsewhere a bilinear least-squares model in (theta, H) of the "
            "measured paths (leave-one-out maximum error in discretisation_loo_max_*); "
            "docs/method.md section 3 relates this change to the converged forces"),
    })
    return out


def _path_measure(ds: xr.Dataset, force: str) -> xr.DataArray:
    """F_z at the last t, or min over t of F_r, per (θ, H), at the first G level."""
    F = ds[force].isel(G=0)
    return (F.isel(t=-1) if force == "F_z" else F.min("t", skipna=False)).transpose("theta", "H")
