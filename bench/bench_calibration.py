"""The field-to-force calibration on the shipped MagOne models and the bundled DOE.

Usage::

    nice -n 10 python bench/bench_calibration.py

Measures, and writes ``bench/results/calibration.json`` (docs/method.md §13):

- the round trip F → B → F over the stable region of the chosen (H = 3 mm, G = 22.57 kPa) and
  the original (H = 3 mm, G = 29.4 kPa) designs, relative to the force range, and the time per
  reading of B → F;
- B → F against the DOE's held-out FE paths (the 4 (θ, H) paths the fit never saw): the map
  of design (H of the path, G = 22.57 kPa) read with the FE field, against the FE forces, in
  mN; and the metamodels' own error at the same points (the map cannot be better);
- the firmware approximation of both designs against their resolution σ_F with σ_B = 1 µT
  per axis (an assumed noise, not a datasheet's): every candidate's size, multiplications and
  largest held-out error, and the choice;
- a built unit: synthetic units with G −15 %, remanence +3 %, chip offset (0.2, 0, 0.1) mm,
  from 8 presses; (a) presses of the models themselves, exact and with noise, (b) presses
  made from the FE paths at H = 3 mm; recovered parameters and the corrected map's force error
  on about 1,000 other readings, against 2 σ_F; and the refusal of all-normal presses for a
  shear (field) offset;
- the FE force source (docs/method.md §13.4): the map whose forces are the DOE's FE paths at
  H = 3 mm, interpolated: its round trip, its leave-one-θ-path-out error at every height of
  the DOE (the map's model error between paths) beside the FE paths' own scatter about a
  smooth curve in θ and the metamodels' error at the same points; FE-made units fitted with it
  (exact presses and noisy ones); the same unit fitted with one interior path held out of the
  map and read on that path (the error of a calibrated map between paths); its firmware
  frontier; and the refusal of a height without FE paths.
"""

from __future__ import annotations

import json
import platform
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from magtact import MagtactError
from magtact.calibration import (
    OK,
    PARAMETERS,
    Presses,
    UnitParameters,
    calibrate_unit,
    fe_forces,
    fe_readings,
    firmware_approximation,
    force_model_error,
    path_holdout,
    round_trip_error,
    sensor_map,
)
from magtact.designer import resolution
from magtact.doe import load_bundled
from magtact.metamodel import holdout_paths, load_models, prefitted_dir
from magtact.optimise import per_design
from magtact.study import HallChip, load_study

RESULTS = Path(__file__).resolve().parent / "results" / "calibration.json"
H0, G_CHOSEN, G_ORIGINAL = 3e-3, 22.57e3, 29.4e3
NOISE = 1e-6  # T per axis: σ_F "per µT", the README's unit
TRUE = UnitParameters(0.85, 1.03, (2e-4, 0.0, 1e-4))
PRESSES = [(0.0, 0), (0.4, 0), (0.8, 0), (1.0, 0), (0.5, 4), (0.9, 4), (0.7, 2), (1.0, 4)]


def sigma_F(models, study, design):
    chip = HallChip("given", NOISE, NOISE, 1.0, 1.0, "1 uT per axis", "assumed")
    r = resolution(models, study, design, chip)
    return r.sigma_r_worst, r.sigma_z_worst



def unit_readings(ds, smap, n_azimuths: int):
    """Readings of the FE-made unit TRUE: all (B, F) with their loads L, the presses' indices
    k, and the other FE points, each at ``n_azimuths`` random azimuths (Bo, Fo)."""
    B, F, L = fe_readings(ds, smap, TRUE, seed=3)
    k = pick(L, PRESSES)
    others = np.setdiff1d(np.arange(len(B)), k)
    Bo, Fo = [], []
    for s in range(n_azimuths):
        b, f, _ = fe_readings(ds, smap, TRUE, seed=100 + s)
        Bo.append(b[others])
        Fo.append(f[others])
    return B, F, L, k, np.concatenate(Bo), np.concatenate(Fo)


def pick(L, presses):
    th = np.unique(L[:, 1])
    return np.array([np.flatnonzero(np.isclose(L[:, 0], t) & (L[:, 1] == th[k]))[0]
                     for t, k in presses])


def unit_result(cal, true, B_other, F_other, sigma):
    u = cal.unit
    r = cal.corrected.force(B_other)
    ok = r.flag == OK
    err = np.abs(r.F - F_other)
    return {
        "G_scale": u.G_scale, "B_scale": u.B_scale,
        "chip_offset_mm": [1e3 * v for v in u.chip_offset],
        "G_scale_err_rel": u.G_scale / true.G_scale - 1,
        "B_scale_err_rel": u.B_scale / true.B_scale - 1,
        "chip_offset_err_mm": [1e3 * (a - b) for a, b in zip(u.chip_offset, true.chip_offset,
                                                              strict=True)],
        "std": cal.to_json()["std"],
        "other_readings": int(len(B_other)), "other_in_region": int(ok.sum()),
        "force_err_max_mN": {"xy": 1e3 * float(err[ok, :2].max()),
                             "z": 1e3 * float(err[ok, 2].max())},
        "force_err_rms_mN": {"xy": 1e3 * float(np.sqrt(np.mean(err[ok, :2] ** 2))),
                             "z": 1e3 * float(np.sqrt(np.mean(err[ok, 2] ** 2)))},
        "two_sigma_F_mN": {"r": 2e3 * sigma[0], "z": 2e3 * sigma[1]},
        "within_2_sigma_F": bool(err[ok, :2].max() <= 2 * sigma[0]
                                 and err[ok, 2].max() <= 2 * sigma[1]),
    }


def fe_scatter(ds, H, G):
    """The FE paths' scatter about a smooth curve in θ: at each load t > 0, the largest
    residual [mN] of a least-squares quadratic in sin²θ through the 5 paths' F_z, and of a
    linear one in sin²θ through the 4 sheared paths' F_r / tan θ (times tan θ)."""
    d = ds.sel(H=H)
    t, th = d["t"].values, d["theta"].values
    scale = G / float(d["G"].values[0])
    v = np.sin(th) ** 2
    Fz = d["F_z"].values[1:, :, 0] * scale
    Fr = d["F_r"].values[1:, 1:, 0] * scale
    A = np.vander(v, 3)
    rz = Fz - (A @ np.linalg.lstsq(A, Fz.T, rcond=None)[0]).T
    psi = Fr / np.tan(th[1:])
    A1 = np.vander(v[1:], 2)
    rr = (psi - (A1 @ np.linalg.lstsq(A1, psi.T, rcond=None)[0]).T) * np.tan(th[1:])
    return {"F_z_quadratic_in_sin2theta_max_residual_mN": 1e3 * float(np.abs(rz).max()),
            "F_r_linear_in_sin2theta_max_residual_mN": 1e3 * float(np.abs(rr).max()),
            "loads": int(len(t) - 1)}


def interpolant_choice(ds, H, G):
    """Why the FE interpolant is a spline along t and PCHIP along sin²θ: the largest error [mN]
    of F_z, F_r on a held-out interior path (along θ: a global cubic in sin²θ, the not-a-knot
    spline of 4 paths, against PCHIP) and on a held-out load 0.1 ≤ t ≤ 0.95 (along t: the
    not-a-knot spline against PCHIP), each through the other nodes."""
    from scipy.interpolate import CubicSpline, PchipInterpolator

    d = ds.sel(H=H)
    t, th = d["t"].values, d["theta"].values
    scale = G / float(d["G"].values[0])
    Fz, Fr = d["F_z"].values[..., 0] * scale, d["F_r"].values[..., 0] * scale
    out: dict = {}
    kinds = {"cubic_not_a_knot": lambda x, y: CubicSpline(x, y, axis=0),
             "pchip": lambda x, y: PchipInterpolator(x, y, axis=0)}
    for name, make in kinds.items():
        ez = er = 0.0
        for j in (1, 2, 3):  # along θ, in v = sin²θ
            keep = [i for i in range(len(th)) if i != j]
            v = np.sin(th[keep]) ** 2
            phi = make(v, (Fz[1:, keep] / t[1:, None]).T)(np.sin(th[j]) ** 2)
            ez = max(ez, float(np.abs(t[1:] * phi - Fz[1:, j]).max()))
            sh = [i for i in keep if i > 0]
            psi = make(np.sin(th[sh]) ** 2,
                       (Fr[1:, sh] / (t[1:, None] * np.tan(th[sh]))).T)(np.sin(th[j]) ** 2)
            er = max(er, float(np.abs(t[1:] * np.tan(th[j]) * psi - Fr[1:, j]).max()))
        ez_t = er_t = 0.0
        for i in range(2, len(t) - 1):  # along t, one load left out
            keep = [k for k in range(1, len(t)) if k != i]
            phi = make(t[keep], Fz[keep] / t[keep, None])(t[i])
            psi = make(t[keep], Fr[keep, 1:] / t[keep, None])(t[i])
            ez_t = max(ez_t, float(np.abs(t[i] * phi - Fz[i]).max()))
            er_t = max(er_t, float(np.abs(t[i] * psi - Fr[i, 1:]).max()))
        out[name] = {"held_out_path_F_r_mN": 1e3 * er, "held_out_path_F_z_mN": 1e3 * ez,
                     "held_out_load_F_r_mN": 1e3 * er_t, "held_out_load_F_z_mN": 1e3 * ez_t}
    return out


def fe_source(models, study, ds, design, sig) -> dict:
    """The map with the FE force source at H = 3 mm (docs/method.md §13.4)."""
    res: dict = {}
    t0 = time.perf_counter()
    fmap = sensor_map(models, study, H0, G_CHOSEN, design=design, force_source="fe",
                      dataset=ds)
    res["build_s"] = time.perf_counter() - t0
    res["t_m"], res["theta_m_rad"] = fmap.t_m, fmap.theta_m
    res["round_trip_rel"] = round_trip_error(fmap, n=5000, seed=2)
    res["folds"] = {k: int(v.size) for k, v in fmap.folds.items()}
    L = fmap.region_samples(10000, seed=1)
    B, F = fmap.at_load(L[:, 0], L[:, 1], L[:, 2])
    t0 = time.perf_counter()
    r = fmap.force(B)
    res["B_to_F_us_per_reading"] = 1e6 * (time.perf_counter() - t0) / len(B)
    rng = np.array([fmap.ranges[0], fmap.ranges[0], fmap.ranges[1]])
    res["B_to_F_rel_10000"] = float(np.max(np.abs(r.F - F) / rng))
    # the model error: between paths (held out), the FE scatter, the metamodels' at H
    res["model_error_fe"] = force_model_error(fmap, ds)
    res["model_error_metamodels"] = force_model_error(
        sensor_map(models, study, H0, G_CHOSEN, design=design), ds)
    res["held_out_paths_every_H"] = {}
    res["fe_scatter_every_H"] = {}
    for H in ds["H"].values:
        paths = path_holdout(ds, float(H), G_CHOSEN)
        inner = [p for p in paths if p.interior]
        res["held_out_paths_every_H"][f"{1e3 * H:g}"] = {
            "interior_max_F_r_mN": 1e3 * max(p.err_r for p in inner),
            "interior_max_F_z_mN": 1e3 * max(p.err_z for p in inner),
            "paths": [p.to_json() for p in paths]}
        res["fe_scatter_every_H"][f"{1e3 * H:g}"] = fe_scatter(ds, float(H), G_CHOSEN)
    res["interpolant_choice_H_3_mm"] = interpolant_choice(ds, H0, G_CHOSEN)
    print("interpolant choice", json.dumps(res["interpolant_choice_H_3_mm"]))
    print("FE source", json.dumps({k: res[k] for k in ("round_trip_rel", "B_to_F_rel_10000",
                                                         "model_error_metamodels")}))
    print("held out", json.dumps({k: (v["interior_max_F_r_mN"], v["interior_max_F_z_mN"])
                                  for k, v in res["held_out_paths_every_H"].items()}))
    print("scatter", json.dumps(res["fe_scatter_every_H"]))

    # FE-made units fitted with the FE source
    B, F, Lfe, k, Bo, Fo = unit_readings(ds, fmap, 11)
    rng = np.random.default_rng(17)
    units = []
    for nB, nF in ((0.0, 0.0), (0.1e-6, 0.05e-3), (1e-6, 1e-3), (5e-6, 2e-3)):
        p = Presses(B[k] + rng.normal(0, nB, (8, 3)), F[k] + rng.normal(0, nF, (8, 3)),
                    sigma_B=max(nB, 1e-7), sigma_F=max(nF, 5e-5))
        t0 = time.perf_counter()
        try:
            cal = calibrate_unit(fmap, p)
            u = {"fit_s": time.perf_counter() - t0, **unit_result(cal, TRUE, Bo, Fo, sig)}
        except MagtactError as exc:
            u = {"refused": str(exc)}
        units.append({"press_noise_B_uT": 1e6 * nB, "press_noise_F_mN": 1e3 * nF, **u})
        print("FE unit, FE source", json.dumps(units[-1]))
    res["unit_from_fe"] = units

    # one interior path held out of the map; the unit's readings on that path
    d = ds.sel(H=H0)
    th = d["theta"].values
    between = []
    for j in (1, 2, 3):
        held = replace(fmap, fe=fe_forces(ds, H0, drop_theta=float(th[j])))
        presses = [(t, kk if kk != j else (3 if j != 3 else 1)) for t, kk in PRESSES]
        kp = pick(Lfe, presses)
        cal = calibrate_unit(held, Presses(B[kp], F[kp]))
        on = np.flatnonzero(np.isclose(Lfe[:, 1], th[j]) & (Lfe[:, 0] > 0))
        Bh, Fh = [], []
        for s in range(10):
            b, f, _ = fe_readings(ds, fmap, TRUE, seed=200 + s)
            Bh.append(b[on])
            Fh.append(f[on])
        between.append({"held_out_theta_rad": float(th[j]),
                        **unit_result(cal, TRUE, np.concatenate(Bh), np.concatenate(Fh), sig)})
        print("between paths", json.dumps(between[-1]))
    res["unit_between_paths"] = between

    t0 = time.perf_counter()
    choice = firmware_approximation(fmap, sig)
    a = choice.chosen
    res["firmware"] = {"kind": a.kind, "degree_or_n": a.degree, "transform": a.transform,
                       "bytes": a.bytes, "multiplies": a.multiplies,
                       "max_error_F_r_mN": 1e3 * a.err_r, "max_error_F_z_mN": 1e3 * a.err_z,
                       "reached": choice.reached, "rule": choice.rule,
                       "wall_time_s": time.perf_counter() - t0, "frontier": choice.frontier()}
    print("FE firmware", json.dumps({k: v for k, v in res["firmware"].items()
                                     if k != "frontier"}))
    try:
        sensor_map(models, study, 3.5e-3, G_CHOSEN, force_source="fe", dataset=ds)
        res["refusal_H_3_5_mm"] = "NOT refused"
    except MagtactError as exc:
        res["refusal_H_3_5_mm"] = str(exc)
    return res


def main() -> None:
    t_start = time.perf_counter()
    models, study, ds = load_models(prefitted_dir()), load_study(None), load_bundled()
    out: dict = {"noise_B_uT": 1e6 * NOISE,
                 "noise_note": "sigma_F for 1 uT of field noise per axis (assumed, not a "
                               "datasheet figure)"}
    design = per_design(models, H0, G_CHOSEN, study)
    maps = {}
    for name, G in (("chosen", G_CHOSEN), ("original", G_ORIGINAL)):
        d = replace(design, G=G) if G != G_CHOSEN else design
        smap = sensor_map(models, study, H0, G, design=d)
        maps[name] = smap
        sig = sigma_F(models, study, per_design(models, H0, G, study))
        L = smap.region_samples(10000, seed=1)
        B, F = smap.at_load(L[:, 0], L[:, 1], L[:, 2])
        t0 = time.perf_counter()
        r = smap.force(B)
        dt = time.perf_counter() - t0
        rng = np.array([smap.ranges[0], smap.ranges[0], smap.ranges[1]])
        t0 = time.perf_counter()
        choice = firmware_approximation(smap, sig)
        t_fw = time.perf_counter() - t0
        a = choice.chosen
        out[name] = {
            "H_mm": 1e3 * H0, "G_kPa": 1e-3 * G, "t_m": smap.t_m, "theta_m_rad": smap.theta_m,
            "F_r_range_N": smap.ranges[0], "F_z_range_N": smap.ranges[1],
            "round_trip_rel": round_trip_error(smap, n=5000, seed=2),
            "B_to_F_rel_10000": float(np.max(np.abs(r.F - F) / rng)),
            "B_to_F_flags_ok": int((r.flag == OK).sum()),
            "B_to_F_us_per_reading": 1e6 * dt / len(B),
            "sigma_F_r_mN": 1e3 * sig[0], "sigma_F_z_mN": 1e3 * sig[1],
            "firmware": {"kind": a.kind, "degree_or_n": a.degree, "transform": a.transform,
                         "bytes": a.bytes, "multiplies": a.multiplies,
                         "max_error_F_r_mN": 1e3 * a.err_r, "max_error_F_z_mN": 1e3 * a.err_z,
                         "reached": choice.reached, "rule": choice.rule,
                         "wall_time_s": t_fw, "frontier": choice.frontier()},
        }
        print(name, json.dumps({k: v for k, v in out[name].items() if k != "firmware"}),
              json.dumps({k: v for k, v in out[name]["firmware"].items() if k != "frontier"}))

    # B -> F on the held-out FE paths (the map at the path's height, G = 22.57 kPa)
    held = []
    paths = holdout_paths(ds["theta"].values, ds["H"].values, study.metamodel.holdout_paths)
    G_level = float(ds["G"].values[0])
    for theta, H in paths:
        smap = sensor_map(models, study, H, G_CHOSEN)
        d = ds.sel(theta=theta, H=H)
        B = np.stack([d["B_r"].values, np.zeros_like(d["B_r"].values), d["B_z"].values], -1)
        F = np.stack([d["F_r"].values[:, 0], np.zeros(len(B)), d["F_z"].values[:, 0]], -1)
        F *= G_CHOSEN / G_level
        r = smap.force(B)
        t = d["t"].values
        inside = smap.inside(smap.features(t, theta))
        ok = (r.flag == OK) & inside
        Fm = np.stack(models.forces(t, theta, H, G_CHOSEN), -1)
        held.append({
            "theta_rad": theta, "H_mm": 1e3 * H, "t_m": smap.t_m, "theta_m_rad": smap.theta_m,
            "points_in_region": int(inside.sum()), "points_read": int(ok.sum()),
            "flagged_in_region": int((inside & (r.flag != OK)).sum()),
            "map_err_max_mN": {"r": 1e3 * float(np.abs(r.F[ok, 0] - F[ok, 0]).max()),
                               "z": 1e3 * float(np.abs(r.F[ok, 2] - F[ok, 2]).max())},
            "model_err_max_mN": {"r": 1e3 * float(np.abs(Fm[inside, 0] - F[inside, 0]).max()),
                                 "z": 1e3 * float(np.abs(Fm[inside, 1] - F[inside, 2]).max())},
            "F_z_max_N": float(F[inside, 2].max()),
        })
        print("held-out", json.dumps(held[-1]))
    out["held_out_paths"] = held

    # a built unit
    smap = maps["chosen"]
    sig = (out["chosen"]["sigma_F_r_mN"] * 1e-3, out["chosen"]["sigma_F_z_mN"] * 1e-3)
    unit_map = replace(smap, field_source="exact").with_unit(TRUE)
    rng = np.random.default_rng(7)
    th = smap.theta_m
    loads = np.array([[t, th * k / 4, rng.uniform(-np.pi, np.pi)] for t, k in PRESSES])
    Bp, Fp = unit_map.at_load(loads[:, 0], loads[:, 1], loads[:, 2])
    L = smap.region_samples(1000, seed=8)
    Bo, Fo = unit_map.at_load(0.98 * L[:, 0], 0.98 * L[:, 1], L[:, 2])
    model_units = []
    for nB, nF in ((0.0, 0.0), (0.1e-6, 0.05e-3), (1e-6, 1e-3), (5e-6, 2e-3)):
        p = Presses(Bp + rng.normal(0, nB, Bp.shape), Fp + rng.normal(0, nF, Fp.shape),
                    sigma_B=max(nB, 1e-7), sigma_F=max(nF, 5e-5))
        try:
            cal = calibrate_unit(smap, p)
            res = unit_result(cal, TRUE, Bo, Fo, sig)
        except MagtactError as exc:
            res = {"refused": str(exc)}
        model_units.append({"press_noise_B_uT": 1e6 * nB, "press_noise_F_mN": 1e3 * nF, **res})
        print("model unit", json.dumps(model_units[-1]))
    out["unit_from_models"] = model_units

    B, F, Lfe, k, Bo, Fo = unit_readings(ds, smap, 10)
    fe_units = []
    for nB, nF in ((5e-6, 2e-3), (1e-6, 1e-3)):
        cal = calibrate_unit(smap, Presses(B[k], F[k], sigma_B=nB, sigma_F=nF))
        fe_units.append({"weights_sigma_B_uT": 1e6 * nB, "weights_sigma_F_mN": 1e3 * nF,
                         "press_loads_t_theta": [[float(a), float(b)] for a, b, _ in Lfe[k]],
                         **unit_result(cal, TRUE, Bo, Fo, sig)})
        print("FE unit", json.dumps(fe_units[-1]))
    # the same with the force models' own error in the weights: 1 % of |F| per axis, the order
    # of f_z's largest relative error in its fit report (0.98 %)
    eps = (0.01, 0.01)
    p = Presses(B[k], F[k], sigma_B=5e-6, sigma_F=2e-3)
    try:
        calibrate_unit(smap, p, model_error=eps)
        refusal = None
    except MagtactError as exc:
        refusal = str(exc)
    cal_eps = calibrate_unit(smap, p, model_error=eps,
                             tolerance={n: 1.0 for n in PARAMETERS})
    fe_units.append({"weights_sigma_B_uT": 5.0, "weights_sigma_F_mN": 2.0,
                     "model_error_rel": list(eps), "default_tolerance_refusal": refusal,
                     **unit_result(cal_eps, TRUE, Bo, Fo, sig)})
    print("FE unit, model error", json.dumps(fe_units[-1]))
    out["unit_from_fe"] = fe_units
    # the firmware export of the fitted unit (its map is not axisymmetric: two stages only)
    choice = firmware_approximation(cal.corrected, sig)
    a = choice.chosen
    out["unit_firmware"] = {"kind": a.kind, "degree_or_n": a.degree, "transform": a.transform,
                            "bytes": a.bytes, "multiplies": a.multiplies,
                            "max_error_F_r_mN": 1e3 * a.err_r,
                            "max_error_F_z_mN": 1e3 * a.err_z, "reached": choice.reached,
                            "frontier": choice.frontier()}
    print("unit firmware", json.dumps({k: v for k, v in out["unit_firmware"].items()
                                       if k != "frontier"}))
    # the same FE readings through the exact unit map (true parameters): the models' own error
    truth = unit_map.force(Bo)
    ok = truth.flag == OK
    out["unit_from_fe_true_parameters_err_max_mN"] = {
        "xy": 1e3 * float(np.abs(truth.F[ok, :2] - Fo[ok, :2]).max()),
        "z": 1e3 * float(np.abs(truth.F[ok, 2] - Fo[ok, 2]).max()), "in_region": int(ok.sum())}

    normal = pick(Lfe, [(t, 0) for t in (0.0, 0.2, 0.3, 0.4, 0.6, 0.8, 0.9, 1.0)])
    fit = PARAMETERS[:2] + ("chip_offset_x", "chip_offset_y", "field_offset_x",
                            "field_offset_y")
    try:
        calibrate_unit(smap, Presses(B[normal], F[normal]), fit=fit)
        out["all_normal_refusal"] = "NOT refused"
    except MagtactError as exc:
        out["all_normal_refusal"] = str(exc)
    print(out["all_normal_refusal"])
    out["fe_source"] = fe_source(models, study, ds, design, sig)
    out["wall_time_s"] = time.perf_counter() - t_start
    out["machine"] = {"python": platform.python_version(), "machine": platform.machine()}
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {RESULTS} in {out['wall_time_s']:.0f} s")


if __name__ == "__main__":
    main()
