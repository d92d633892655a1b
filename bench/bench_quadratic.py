"""The quadratic structural routes (hex27, hex20): where the time goes, why Newton stalled.

Four parts, each writing a section of ``bench/results/quadratic.json``:

- ``penalty``: the normal contact multiplier λ_n against the mean diagonal stiffness of the
  contact nodes, with and without the volumetric term (hex8 ``coarse``/``default``, hex27
  ``coarse_x0.67``/``coarse``, H = 3 mm, reference configuration).
- ``tangent``: wall time of the solid's tangent integration, FElupe's einsum against the batched
  matrix products of :func:`grad_grad_values` (minimum of ``--repeat`` alternating calls, same
  state), of the whole tangent assembly with FElupe's solid and with one using those products,
  and of one PARDISO factorisation, on the hex8 ``default`` mesh and the
  hex27 ``coarse_x0.67`` and ``coarse`` meshes (H = 3 mm).
- ``newton``: one path at θ_max (``--element hex27`` or ``hex20``) with every Newton iteration
  logged (residual, line-search factor, contact points per plate and node class, points that
  changed contact, sliding points and those that switched between sticking and sliding, the
  nodes with the largest residual). ``--tol-cycling`` sets ``Stepping.tol_cycling`` (1e-6: the
  tolerance of the cycling mode equals the plain one, i.e. the model before that mode had its
  own); ``--penalty`` the contact penalty.
- ``uniaxial``: 20-node cells against the uniaxial closed form (contact at the nodes and over the
  faces), with the gaps of the top face's
  corner and mid-edge nodes to the plate (serendipity faces: node-wise contact lifts the
  corners).

    python bench/bench_quadratic.py tangent --repeat 4
    python bench/bench_quadratic.py penalty
    python bench/bench_quadratic.py newton --mesh coarse_x0.67 --H 3 --tol-cycling 1e-6
    python bench/bench_quadratic.py uniaxial

Wall times on a shared machine: the load average is recorded beside each.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import replace
from pathlib import Path

import bench_frontier  # noqa: F401  (registers the coarse_x0.67 and coarse_x1.5 densities)
import numpy as np

OUT = Path(__file__).parent / "results" / "quadratic.json"
NAMES = ("corner", "edge", "face")


import felupe as fem  # noqa: E402


def grad_grad_values(dhdX: np.ndarray, A: np.ndarray, dV: np.ndarray,
                     chunk: int = 8) -> np.ndarray:
    """Cell stiffness values K_aibk = Σ_q ∂_J h_a A_iJkL ∂_L h_b dV of a bilinear form in the
    gradients of one vector field, by two batched matrix products per cell .

    The same numbers as FElupe's einsum of the form, with the cells as the batch axis of
    ``np.matmul`` instead of the last (strided) axis of an einsum: about 20 times faster for
    27-node cells with 27 quadrature points; for 8-node cells FElupe's chunked einsum is faster
    (bench/results/quadratic.json).

    Parameters
    ----------
    dhdX : (a, J, q, c) ndarray
        Shape-function gradients of the a nodes at the q quadrature points of the c cells.
    A : (i, J, k, L, q, c) ndarray
        The fourth-order tangent ∂P_iJ / ∂F_kL (broadcast over q or c allowed).
    dV : (q, c) ndarray
        Quadrature weights times the Jacobian determinants.
    chunk : int
        Cells per batch.

    Returns
    -------
    (a, i, b, k, c) ndarray
        C-ordered values for FElupe's sparse assembly.
    """
    a, J, q, c = dhdX.shape
    d = A.shape[0]
    A = np.broadcast_to(A, (d, J, d, J, q, c))
    dV = np.broadcast_to(dV, (q, c))
    out = np.empty((a, d, a, d, c), dtype=np.result_type(dhdX, A, dV))
    for s in range(0, c, chunk):  # chunks of cells: the intermediates stay in the caches
        cs = slice(s, min(s + chunk, c))
        n = cs.stop - cs.start
        B = np.ascontiguousarray((dhdX[..., cs] * dV[:, cs]).transpose(3, 2, 0, 1))  # c q a J
        Bt = np.ascontiguousarray(dhdX[..., cs].transpose(3, 2, 1, 0))  # (c, q, L, b)
        F = np.ascontiguousarray(A[..., cs].transpose(5, 4, 1, 0, 3, 2))  # (c, q, J, i, L, k)
        X = np.matmul(B, F.reshape(n, q, J, d * J * d))  # (c, q, a, i L k)
        X = X.reshape(n, q, a, d, J, d).transpose(0, 2, 3, 5, 1, 4).reshape(n, a * d * d, q * J)
        K = np.matmul(X, Bt.reshape(n, q * J, a))  # (c, a i k, b)
        out[..., cs] = K.reshape(n, a, d, d, a).transpose(1, 2, 4, 3, 0)
    return out


class _BatchedForm(fem.IntegralForm):
    """FElupe's integral form whose single-field gradient–gradient bilinear form (the solid's
    tangent) of cells with more than 8 nodes is integrated by :func:`grad_grad_values`; every
    other form as FElupe does."""

    def integrate(self, parallel=False, out=None):
        if self.mode == 1 or len(self.forms) != 1:
            return super().integrate(parallel=parallel, out=out)
        form = self.forms[0]
        if not (form.grad_v and form.grad_u and type(form.v) is fem.Field
                and form.u.region is form.v.region and form.v.region.dhdX.shape[0] > 8):
            return super().integrate(parallel=parallel, out=out)
        values = grad_grad_values(form.v.region.dhdX, form.fun, form.dV)
        if out is not None and out[0] is not None and out[0].shape == values.shape:
            out[0][...] = values
            return out
        return [values]


class _NearlyIncompressibleSolid(fem.SolidBodyNearlyIncompressible):  # noqa: D101
    """FElupe's ``SolidBodyNearlyIncompressible`` with its tangent integrated by
    :func:`grad_grad_values` (same values, less time)."""

    def __init__(self, umat, field, bulk):
        super().__init__(umat, field, bulk=bulk)
        self._form = _BatchedForm


def _study(element: str, penalty: float | None = None):
    from magtact.study import load_study

    study = load_study("magone")
    mech = replace(study.mechanics, element=element, threads=1)
    if penalty is not None:
        mech = replace(mech, contact_penalty=penalty)
    return replace(study, mechanics=mech)


def tangent(repeat: int) -> dict:
    import felupe as fem

    from magtact.mechanics import build_model

    out = {"load_average_at_start": os.getloadavg(), "cases": []}
    for element, mesh in (("hex8", "default"), ("hex27", "coarse_x0.67"), ("hex27", "coarse")):
        m = build_model(_study(element), 3e-3, mesh=mesh)
        rng = np.random.default_rng(0)
        m.field[0].values[:] += 2e-5 * rng.standard_normal(m.field[0].values.shape)
        solids = [fem.SolidBodyNearlyIncompressible(fem.NeoHooke(mu=m.G), m.field, bulk=5e3 * m.G),
                  _NearlyIncompressibleSolid(fem.NeoHooke(mu=m.G), m.field, bulk=5e3 * m.G)]
        times = [[], [], [], []]
        region = m.field.region
        for _ in range(repeat):
            for k, s in enumerate(solids):
                t0 = time.perf_counter()
                K = s.assemble.matrix(m.field)
                times[k].append(time.perf_counter() - t0)
            A = solids[0].results.elasticity[0]  # the integration alone, both ways
            t0 = time.perf_counter()
            fem.IntegralForm([A], m.field, region.dV, u=m.field).integrate()
            times[2].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            grad_grad_values(region.dhdX, A, region.dV)
            times[3].append(time.perf_counter() - t0)
        K0, K1 = (s.results.stiffness for s in solids)
        m._jacobian()
        t0 = time.perf_counter()
        m._linear.factorize(m._linear.A)
        t_fact = time.perf_counter() - t0
        out["cases"].append({
            "element": element, "mesh": mesh, "n_dofs": m.n_dofs, "n_cells": m.bmesh.n_cells,
            "nnz": int(K.nnz), "felupe_einsum_s": min(times[2]), "batched_s": min(times[3]),
            "tangent_assembly_stock_s": min(times[0]), "tangent_assembly_batched_s": min(times[1]),
            "max_relative_difference": float(abs(K1 - K0).max() / abs(K0).max()),
            "factorisation_s": t_fact})
        print(out["cases"][-1], flush=True)
    out["load_average_at_end"] = os.getloadavg()
    return out


def penalty_scale() -> dict:
    """The normal contact multiplier against the contact nodes' mean diagonal stiffness, with
    and without the volumetric term (a shear-only solid: bulk modulus 0), upper plate, H = 3 mm,
    reference configuration."""
    import felupe as fem

    from magtact.mechanics import build_model

    out = []
    for element, mesh in (("hex8", "coarse"), ("hex8", "default"), ("hex27", "coarse_x0.67"),
                          ("hex27", "coarse")):
        m = build_model(_study(element), 3e-3, mesh=mesh)
        c = m.contacts[1]
        dofs = 3 * c.points + 2
        shear = fem.SolidBodyNearlyIncompressible(fem.NeoHooke(mu=m.G), m.field, bulk=0.0)
        diag_shear = np.asarray(shear.assemble.matrix().tocsr()[dofs, dofs]).ravel()
        diag_full = np.asarray(m.solid.assemble.matrix().tocsr()[dofs, dofs]).ravel()
        lam = c.contact_multipliers().normal
        out.append({"element": element, "mesh": mesh, "penalty": c.multiplier,
                    "lambda_n_over_G_m": lam / m.G,
                    "mean_diagonal_over_G_m": float(diag_full.mean() / m.G),
                    "mean_shear_diagonal_over_G_m": float(diag_shear.mean() / m.G),
                    "lambda_n_over_mean_shear_diagonal": float(lam / diag_shear.mean())})
        print(out[-1], flush=True)
    return {"cases": out}


def newton(mesh: str, H_mm: float, tol_cycling: float, penalty: float | None,
           element: str = "hex27") -> dict:
    from magtact.geometry import loading_path
    from magtact.mechanics import build_model
    from magtact.mechanics._model import NewtonFailed
    from magtact.mechanics._simulate import stepping_of

    study = _study(element, penalty)
    H, theta = H_mm * 1e-3, study.loading.theta_max
    m = build_model(study, H, mesh=mesh)
    bm = m.bmesh
    cls = np.full(bm.n_points, -1)
    for lo, hi, c in ((0, 8, 0), (8, 20, 1), (20, 26, 2)):
        cls[np.unique(bm.cells[:, lo:hi])] = c
    surface = set(bm.surface.tolist())
    steps, state = [], {"its": []}
    line_search, solve_step = m._line_search, m._newton

    def logged_line_search(u, du, halvings, below=np.inf):
        u0 = u.copy()
        f, fnorm = line_search(u, du, halvings, below)
        k = int(np.argmax(np.abs(du)))
        rec = {"residual": fnorm, "alpha": float((u[k] - u0[k] + du[k]) / du[k]),
               "du_max_m": float(np.abs(du[m.dof1]).max())}
        for name, c in zip(("lower", "upper"), m.contacts, strict=True):
            act, cl = c.results.active, cls[c.points]
            rec[f"{name}_in_contact"] = {NAMES[j]: int(np.sum(act & (cl == j))) for j in range(3)}
            prev = state.get(name)
            if prev is not None and np.any(act != prev):
                ch = act != prev
                rec[f"{name}_changed"] = {NAMES[j]: int(np.sum(ch & (cl == j))) for j in range(3)}
                rec[f"{name}_changed_gaps_um"] = [
                    round(float(g) * 1e6, 4) for g in c._kinematics(c._gap_vectors())[0][ch][:8]]
            state[name] = act.copy()
            slip = np.asarray(c.results.slip, dtype=bool) & act  # sliding, not sticking
            rec[f"{name}_sliding"] = int(slip.sum())
            prev = state.get(f"{name}_slip")
            if prev is not None and np.any(slip != prev):
                rec[f"{name}_slip_changed_nodes"] = [int(n) for n in c.points[slip != prev][:8]]
            state[f"{name}_slip"] = slip.copy()
        r = np.zeros(m.n_dofs)
        r[m.dof1] = f[m.dof1]
        node = np.abs(r.reshape(-1, 3)).max(axis=1)
        rec["largest_residual_nodes"] = [
            {"node": int(n), "class": NAMES[cls[n]] if n < bm.n_points else "plate",
             "on_surface": n in surface, "residual_N": float(node[n])}
            for n in np.argsort(node)[::-1][:3]]
        state["its"].append(rec)
        return f, fnorm

    def logged_step(u_r, u_z, st):
        state["its"] = []
        try:
            n = solve_step(u_r, u_z, replace(st, tol_cycling=tol_cycling))
        except NewtonFailed as exc:
            steps.append({"converged": False, "reason": str(exc), "iterations": state["its"]})
            raise
        steps.append({"converged": True, "iterations": state["its"]})
        return n

    m._line_search, m._newton = logged_line_search, logged_step
    t0, status = time.perf_counter(), "completed"
    load = os.getloadavg()
    try:
        res = m.solve_path(lambda tt: tuple(float(v) for v in loading_path(study, tt, theta, H)),
                           study.t_levels, stepping=stepping_of(study))
        forces = {"F_z_t1_N": 2 * float(res["lower"][-1, 2]),
                  "F_r_min_N": 2 * float(res["lower"][:, 0].min())}
    except Exception as exc:  # noqa: BLE001  (the failure is the result)
        status, forces = str(exc), {}
    for s, (ta, tb, _) in zip(steps, m.log, strict=True):
        s["t"] = [ta, tb]
    return {"element": element, "mesh": mesh, "H_mm": H_mm, "tol_cycling": tol_cycling,
            "contact_penalty": study.mechanics.contact_penalty, "status": status,
            "wall_time_s": time.perf_counter() - t0, "load_average_at_start": load,
            "load_average_at_end": os.getloadavg(), "n_dofs": m.n_dofs,
            "newton_iterations": m.iterations, "jacobians": m.jacobians,
            "timings_s": dict(m.timings), **forces, "steps": steps}


def uniaxial() -> dict:
    """hex20 against the uniaxial closed form F = G A0 (λ⁻² − λ): a plain cylinder (R = h = 6 mm)
    between frictionless plates, base sliding, with the gaps of the top face's corner and
    mid-edge nodes to the upper plate at the end (negative: off the plate); contact node-wise and
    integrated over the faces."""
    import math

    from magtact.geometry import half_cylinder_mesh
    from magtact.mechanics import HalfBodyModel
    from magtact.mechanics._model import StepFailure, Stepping

    R = h = 6e-3
    G = 10e3
    cases = []
    for contact, density, lam in (("nodes", "coarse", 0.9), ("nodes", "default", 0.9),
                                  ("nodes", "coarse", 0.7), ("faces", "coarse", 0.9),
                                  ("faces", "default", 0.9), ("faces", "coarse", 0.7)):
        bm = half_cylinder_mesh(R, h, density=density, order=2, serendipity=True)
        model = HalfBodyModel(bm, G, 5000.0, 0.0, base="sliding", contact=contact)
        rec = {"contact": contact, "density": density, "lambda": lam, "n_dofs": model.n_dofs,
               "load_average_at_start": os.getloadavg()}
        t0 = time.perf_counter()
        try:
            out = model.solve_path(lambda t, lam=lam: (0.0, -(1 - lam) * h * t), [1.0],
                                   stepping=Stepping(dt_initial=1.0 if lam > 0.85 else 0.25,
                                                     dt_max=1.0))
            F = 2 * out["lower"][-1, 2]
            rec |= {"completed": True,
                    "relative_error": F / (G * math.pi * R**2 * (lam**-2 - lam)) - 1}
            t_end = 1.0
        except StepFailure as exc:
            rec |= {"completed": False, "failed_at_t": exc.t, "error": exc.reason}
            t_end = exc.t_converged
        rec["wall_time_s"] = time.perf_counter() - t0
        z = bm.points[:, 2] + model.displacement[:, 2]
        plate = h - (1 - lam) * h * t_end
        top = bm.surface[np.isclose(bm.points[bm.surface, 2], h)]
        for name, nodes in (("corner", top[top < bm.n_corners]),
                            ("mid_edge", top[top >= bm.n_corners])):
            gap = plate - z[nodes]  # > 0: below the upper plate, i.e. off it
            rec[f"top_{name}_gap_um"] = {"min": -1e6 * float(gap.max()),
                                         "mean": -1e6 * float(gap.mean()),
                                         "max": -1e6 * float(gap.min())}
        cases.append(rec)
        print(rec)
    return {"element": "hex20", "cases": cases,
            "note": "gap sign: negative = off the plate, positive = into it"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("tangent")
    t.add_argument("--repeat", type=int, default=4)
    sub.add_parser("penalty")
    sub.add_parser("uniaxial")
    n = sub.add_parser("newton")
    n.add_argument("--mesh", default="coarse_x0.67")
    n.add_argument("--H", type=float, default=3.0)
    n.add_argument("--tol-cycling", type=float, default=1e-5)
    n.add_argument("--penalty", type=float, default=None)
    n.add_argument("--element", choices=("hex20", "hex27"), default="hex27")
    args = ap.parse_args()
    data = json.loads(OUT.read_text()) if OUT.is_file() else {}
    if args.cmd == "tangent":
        data["tangent"] = tangent(args.repeat)
    elif args.cmd == "penalty":
        data["penalty_scale"] = penalty_scale()
    elif args.cmd == "uniaxial":
        data["uniaxial_hex20"] = uniaxial()
    else:
        rec = newton(args.mesh, args.H, args.tol_cycling, args.penalty, args.element)
        key = ("" if args.element == "hex27" else f"{args.element}_") + (
            f"newton_{args.mesh}_H{args.H:g}_tolcycling{args.tol_cycling:g}") + (
            f"_penalty{args.penalty:g}" if args.penalty is not None else "")
        data[key] = rec
        print({k: v for k, v in rec.items() if k != "steps"})
    OUT.write_text(json.dumps(data, indent=1, default=float))


if __name__ == "__main__":
    main()
