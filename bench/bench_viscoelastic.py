"""The quasi-linear viscoelastic assumption of docs/method.md §15 against a finite-strain
viscoelastic FE path.

The half body of magtact's mechanics (``magtact.mechanics.build_model``, its contact, friction
and stepping unchanged) is given FElupe's multiplicative finite-strain viscoelastic branch
(Shutov, Landgraf, Ihlemann, CMAME 265 (2013) 213, the evolution FElupe ships as
``finite_strain_viscoelastic``) beside its long-time neo-Hookean solid:

    W = G_∞/2 (Ī_1 − 3) + G_1/2 (tr(Ĉ C_i⁻¹) − 3),   Ċ_i from the explicit update with
    η = G_1 τ (relaxation time τ at small strain),

plus the same volumetric penalty. The magnet and the upper plate follow a normal press (θ = 0)
to the load t_peak in T seconds and back in T. The same path of the elastic model (G_∞ only)
gives the elastic force history f(s) = F_el(s) / G_∞; the quasi-linear prediction is
F(t) = ∫ G(t − s) df(s) (``magtact.viscoelastic.hereditary_force``). Reported: both force
histories and their largest difference relative to the peak force, on the loading half, and on
the whole cycle while the predicted force stays positive.

A single-element check first: a cube stretched in one step and held relaxes as
G_∞ + G_1 exp(−t/τ) at small strain (which fixes η = G_1 τ).

    nice -n 10 python bench/bench_viscoelastic.py --levels 100   # bench/results/viscoelastic_t0.5.json
    nice -n 10 python bench/bench_viscoelastic.py --levels 100 --t-peak 0.9

Needs ``tensortrax`` (FElupe's automatic differentiation of the energy; not a magtact
dependency).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import felupe as fem
import numpy as np
import tensortrax.math as tm

from magtact.geometry import loading_path
from magtact.mechanics import build_model
from magtact.mechanics._simulate import stepping_of  # the study's own load stepping
from magtact.study import load_study
from magtact.viscoelastic import Prony, hereditary_force

RESULTS = Path(__file__).parent / "results"
#: The inelastic right Cauchy-Green tensor at rest (the identity), upper triangle.
IDENTITY6 = np.array([1.0, 0.0, 0.0, 1.0, 0.0, 1.0])


def energy(C, Cin, mu_inf, mu1, eta, dtime):
    """Long-time neo-Hookean plus one finite-strain Maxwell branch (isochoric parts)."""
    Chat = tm.linalg.det(C) ** (-1 / 3) * C
    Ci = tm.special.from_triu_1d(Cin, like=C) + (mu1 / eta * dtime) * Chat
    Ci = tm.linalg.det(Ci) ** (-1 / 3) * Ci
    W = mu_inf / 2 * (tm.trace(Chat) - 3) + mu1 / 2 * (tm.trace(Chat @ tm.linalg.inv(Ci)) - 3)
    return W, tm.special.triu_1d(Ci)


def viscous_umat(G_inf: float, G1: float, tau: float):
    return fem.Hyperelastic(energy, nstatevars=6, mu_inf=G_inf, mu1=G1, eta=G1 * tau,
                            dtime=1.0)


def _rest(solid) -> None:
    """Start the inelastic state at the identity (no prior deformation)."""
    sv = solid.results.statevars
    sv[...] = IDENTITY6.reshape((6,) + (1,) * (sv.ndim - 1))


def relaxation_check(G_inf: float, G1: float, tau: float, stretch: float = 1.001) -> dict:
    """A unit cube stretched along x in one step (lateral faces free, nearly incompressible)
    and held: its normalised force against (G_∞ + G_1 e^{−t/τ}) / (G_∞ + G_1)."""
    mesh = fem.Cube(n=2)
    region = fem.RegionHexahedron(mesh)
    field = fem.FieldContainer([fem.Field(region, dim=3)])
    umat = viscous_umat(G_inf, G1, tau)
    solid = fem.SolidBodyNearlyIncompressible(umat, field, bulk=5000 * G_inf)
    _rest(solid)
    lc = fem.dof.uniaxial(field, clamped=False, move=stretch - 1.0, return_loadcase=True)
    bounds, (dof0, dof1, ext0) = lc.boundaries, (lc.loadcase[k] for k in ("dof0", "dof1",
                                                                          "ext0"))
    times = np.linspace(0.0, 5 * tau, 501)  # steps of τ/100: the update is first order
    forces = []
    t_prev = 0.0
    for k, t in enumerate(times):
        umat.kwargs["dtime"] = tau * 1e-9 if k == 0 else t - t_prev  # a step, then the hold
        res = fem.newtonraphson(field, items=[solid], dof1=dof1, dof0=dof0, ext0=ext0, verbose=0,
                                tol=1e-8, maxiter=40)
        forces.append(float(np.sum(res.fun.reshape(-1, 3)[bounds["move"].points, 0])))
        t_prev = t
    forces = np.array(forces)
    G0 = G_inf + G1
    expected = (G_inf + G1 * np.exp(-times / tau)) / G0
    got = forces / forces[0]
    return {"times_s": times.tolist(), "force_over_first": got.tolist(),
            "expected": expected.tolist(),
            "largest_difference": float(np.max(np.abs(got - expected)))}


def fe_path(study, H: float, t_peak: float, T: float, levels: int, mesh: str,
            prony: Prony | None) -> dict:
    """A normal press to ``t_peak`` in ``T`` s and back, with the viscoelastic branch (``prony``)
    or the elastic model (None): the half body's F_z at every level (×2: the full body)."""
    G_inf = prony.G_inf if prony is not None else study.material.G_ref
    model = build_model(study, H, G=G_inf, mesh=mesh)
    if prony is not None:
        (G1,), (tau,) = prony.G, prony.tau
        umat = viscous_umat(G_inf, G1, tau)
        solid = fem.SolidBodyNearlyIncompressible(umat, model.field,
                                                  bulk=study.material.bulk_ratio * G_inf)
        _rest(solid)
        model.solid = solid
        model.items[0] = solid  # the contacts keep the elastic solid for their penalty scale
    s_levels = np.linspace(0.0, 1.0, 2 * levels + 1)[1:]
    done = {"s": 0.0}

    def path(s: float):
        # the inelastic update uses the time since the last converged step
        if prony is not None:
            last = model.log[-1] if model.log else (0.0, 0.0, 0)
            done["s"] = last[1] if last[2] >= 0 else last[0]
            umat.kwargs["dtime"] = max((s - done["s"]) * 2 * T, 1e-12)
        load = t_peak * (1.0 - abs(2.0 * s - 1.0))
        u_r, u_z = loading_path(study, load, 0.0, H)
        return float(u_r), float(u_z)

    t0 = time.perf_counter()
    out = model.solve_path(path, s_levels, stepping=stepping_of(study))
    F_z = 2 * out["lower"][:, 2]
    return {"s": np.concatenate([[0.0], s_levels]).tolist(),
            "time_s": (2 * T * np.concatenate([[0.0], s_levels])).tolist(),
            "load_t": (t_peak * (1 - np.abs(2 * np.concatenate([[0.0], s_levels]) - 1))
                       ).tolist(),
            "F_z_N": np.concatenate([[0.0], F_z]).tolist(), "steps": out["steps"],
            "cutbacks": out["cutbacks"], "wall_s": time.perf_counter() - t0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--H", type=float, default=3.0, help="base height [mm]")
    ap.add_argument("--mesh", default="coarse")
    ap.add_argument("--t-peak", type=float, default=0.5, help="largest load t of the press")
    ap.add_argument("--press-time", type=float, default=1.0, help="T [s], rest to peak")
    ap.add_argument("--g", type=float, default=0.5, help="G_1 / G_inf")
    ap.add_argument("--tau", type=float, default=1.0, help="relaxation time [s]")
    ap.add_argument("--levels", type=int, default=20, help="levels per half of the cycle")
    a = ap.parse_args()
    study = load_study("magone")
    G_inf = study.material.G_ref
    prony = Prony.from_ratios(G_inf, (a.g,), (a.tau,), "bench: one term")
    doc = {"H_mm": a.H, "mesh": a.mesh, "t_peak": a.t_peak, "press_time_s": a.press_time,
           "g": a.g, "tau_s": a.tau, "G_inf_kPa": G_inf / 1e3,
           "element": study.mechanics.element, "contact": study.mechanics.contact}
    doc["single_element"] = relaxation_check(G_inf, a.g * G_inf, a.tau)
    print("single element: largest difference from the exponential "
          f"{doc['single_element']['largest_difference']:.3g}", flush=True)
    H = a.H * 1e-3
    elastic = fe_path(study, H, a.t_peak, a.press_time, a.levels, a.mesh, None)
    print(f"elastic path: {elastic['wall_s']:.3g} s", flush=True)
    visco = fe_path(study, H, a.t_peak, a.press_time, a.levels, a.mesh, prony)
    print(f"viscoelastic path: {visco['wall_s']:.3g} s", flush=True)
    t = np.asarray(elastic["time_s"])
    f = np.asarray(elastic["F_z_N"]) / G_inf
    qlv = hereditary_force(prony, t, f)
    fe = np.asarray(visco["F_z_N"])
    peak = float(np.max(np.abs(fe)))
    half = len(t) // 2
    positive = qlv > 0
    doc |= {"elastic": elastic, "viscoelastic": visco, "qlv_F_z_N": qlv.tolist(),
            "peak_F_z_N": peak,
            "largest_difference_loading_over_peak":
                float(np.max(np.abs(qlv[: half + 1] - fe[: half + 1])) / peak),
            "largest_difference_while_positive_over_peak":
                float(np.max(np.abs(qlv[positive] - fe[positive])) / peak),
            "elastic_hysteresis_over_peak": None, "levels_per_half": a.levels}
    # the hysteresis of both at equal load (the press is symmetric in time)
    up, down = fe[: half + 1], fe[half:][::-1]
    q_up, q_down = qlv[: half + 1], qlv[half:][::-1]
    doc["fe_load_gap_over_peak"] = float(np.max(np.abs(up - down)) / peak)
    doc["qlv_load_gap_over_peak"] = float(np.max(np.abs(q_up - q_down)) / peak)
    e = np.asarray(elastic["F_z_N"])
    doc["elastic_hysteresis_over_peak"] = float(np.max(np.abs(e[: half + 1] - e[half:][::-1]))
                                               / np.max(np.abs(e)))
    out = RESULTS / f"viscoelastic_t{a.t_peak:g}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    print(json.dumps({k: v for k, v in doc.items() if not isinstance(v, (dict, list))},
                     indent=1))


if __name__ == "__main__":
    main()
