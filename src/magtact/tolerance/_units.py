"""The figures of built units: each requirement's figure for units given by their values in
the tolerance box, all units at once (docs/method.md §16).

Per unit the field at its chip is the exact cylinder field of its magnet (remanence at its
temperature, its radius and height), at its body height and chip standoff, read with its
chip's gain and offset; the forces are the metamodels' at its body height, times its G and
over (1 + its FE bias). The magnet's size enters through the field only: the metamodels are
fitted at one magnet, and a size within its tolerance moves the mechanics far less than the
field. The stable region and the force extrema at the unit's height are interpolated between
the design's height and the box's ends (:func:`design_context`).

Along each of :data:`N_PATHS` paths over the unit's stable region the load at which the chip
leaves its range is root-found (:func:`magtact.chip.onset`), and the load at which the normal
force reaches the requirement by bisection; the figures follow as in the nominal verdict
(:mod:`magtact.designer`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..chip import onset
from ..geometry import loading_path, magnet_span
from ..magnetics import cylinder_field
from ..metamodel import ModelSet
from ..study import Study
from ._box import ToleranceBox

#: Paths over the stable region per unit, levels of the scan that brackets where the chip
#: leaves its range, and bisection steps (t to 2^-40 of a level).
N_PATHS, N_SCAN, N_BISECT = 11, 26, 40
#: Levels per path on which the largest shear is taken (the shear grows along a path).
N_SHEAR = 11


@dataclass(frozen=True)
class DesignContext:
    """A design and what its units share: the study (the problem: loading, magnet size,
    requirements), H, G [Pa], M_z [A/m], the chip's range (x, z) [T], the required forces F_z,
    F_r [N], the nominal worst σ_F over the required loads [N] (NaN: not known), the stable
    region and per-unit-G extrema at heights ``H_nodes`` (t_m, θ_m, f_r,min, f_z,max), and the
    chip's standoff [m]."""

    models: ModelSet
    study: Study
    H: float
    G: float
    M_z: float
    range: tuple[float, float]
    F_z: float
    F_r: float
    sigma: float
    H_nodes: np.ndarray
    t_m: np.ndarray
    theta_m: np.ndarray
    f_r_min: np.ndarray
    f_z_max: np.ndarray
    standoff: float = 0.0

    def at(self, H) -> tuple[np.ndarray, ...]:
        """(t_m, θ_m, f_r,min, f_z,max) at heights H [m], interpolated in the nodes."""
        return tuple(np.interp(H, self.H_nodes, v)
                     for v in (self.t_m, self.theta_m, self.f_r_min, self.f_z_max))


def design_context(models: ModelSet, answer, box: ToleranceBox) -> DesignContext:
    """The context of a designer's answer (:class:`magtact.designer.DesignAnswer`) with the
    models of its study (in the sensor problem, with the exact field)."""
    from ..optimise import force_extrema

    study, d, v, sensor = answer.study, answer.design, answer.verdict, answer.sensor
    dH = box.inputs[box.index("H")]
    H_nodes = np.array([d.H + dH.low, d.H, d.H + dH.high]) if dH.high > dH.low \
        else np.array([d.H])
    sigma = float("nan") if v is None else max(v.sigma_r, v.sigma_z)
    return DesignContext(models, study, d.H, d.G, sensor.M_z,
                         (answer.chip.range_x, answer.chip.range_z), study.requirements.F_z,
                         study.requirements.F_r, sigma, H_nodes,
                         *force_extrema(models, H_nodes, study), standoff=sensor.standoff)


def unit_figures(ctx: DesignContext, box: ToleranceBox, X: np.ndarray) -> dict[str, np.ndarray]:
    """Each requirement's figure of units with values ``X`` (n, d) (:data:`INPUTS` columns),
    arrays of shape (n,):

    ``F_z_max`` the normal force the body carries stably, ``F_sat`` the normal force at which
    the chip leaves its range (inf: not in the stable region), ``shear_stable`` the shear the
    body carries stably, ``shear_within`` and ``shear_read`` the largest shear on the paths
    within the required normal force that the body carries and that the chip reads [N];
    ``sigma`` the worst σ_F over the required loads [N] (the nominal one scaled by G / M_z
    and the FE bias: σ_F = |∂F/∂B| σ_B with F ∝ G, B ∝ M_z; the geometry's share of the
    Jacobian is not followed).
    """
    X = np.atleast_2d(np.asarray(X, float))
    c = {name: X[:, k] for k, name in enumerate(box.names)}
    s, m = ctx.study, ctx.study.magnet
    rem = c["B_r"] * (1.0 + box.alpha * (c["temperature"] - box.inputs[1].nominal))
    gain = 1.0 + c["chip_sensitivity"]
    force = ctx.G * (1.0 + c["G"]) / (1.0 + c["fe_bias"])  # the unit's G as the models see it
    H = ctx.H + c["H"]
    standoff = np.maximum(ctx.standoff + c["standoff"], 0.0)
    R_m, H_m, M_z = m.R_m + c["R_m"], m.H_m + c["H_m"], ctx.M_z * rem
    off_x, off_z = c["chip_offset"] * box.offset[0], c["chip_offset"] * box.offset[1]
    t_m, theta_m, f_r_min, f_z_max = ctx.at(H)
    rx, rz = ctx.range
    col = (slice(None), None)  # per unit, broadcast over its paths

    def ratio(t, theta):
        u_r, u_z = loading_path(s, t, theta, H[col])
        low, high = magnet_span(s, H[col])
        z = -(0.5 * (low + high) + u_z + standoff[col])
        x = -u_r
        B_rho, B_z = cylinder_field(np.abs(x), z, R_m[col], H_m[col], M_z[col])
        bx = gain[col] * np.sign(x) * B_rho + off_x[col]
        bz = gain[col] * B_z + off_z[col]
        return np.maximum(np.abs(bx) / rx, np.abs(bz) / rz)

    th = np.linspace(0.0, 1.0, N_PATHS)[None, :] * theta_m[col]
    t_max = np.broadcast_to(t_m[col], th.shape)
    t_on = onset(ratio, th, t_max, n_scan=N_SCAN, iterations=N_BISECT)
    F_on = force[col] * np.asarray(ctx.models.forces(np.nan_to_num(t_on), th, H[col], 1.0)[1])
    F_sat = np.where(np.isnan(t_on), np.inf, F_on).min(axis=1)
    # where the normal force reaches the requirement on each path (f_z grows along a path)
    lo, hi = np.zeros(th.shape), t_max.copy()
    for _ in range(N_BISECT):
        mid = 0.5 * (lo + hi)
        over = force[col] * np.asarray(ctx.models.forces(mid, th, H[col], 1.0)[1]) > ctx.F_z
        hi, lo = np.where(over, mid, hi), np.where(over, lo, mid)
    t_F = np.where(force[col] * np.asarray(ctx.models.forces(t_max, th, H[col], 1.0)[1])
                   > ctx.F_z, lo, t_max)
    t_read = np.where(np.isnan(t_on), t_F, np.minimum(t_F, t_on))
    lv = np.linspace(0.0, 1.0, N_SHEAR)[:, None, None]

    def largest_shear(t_end):
        F_r = ctx.models.forces(lv * t_end, th, H[col], 1.0)[0]
        return force * np.abs(np.asarray(F_r)).max(axis=(0, 2))

    sigma = ctx.sigma * (1.0 + c["G"]) / (1.0 + c["fe_bias"]) / rem
    return {"F_z_max": force * f_z_max, "F_sat": F_sat, "shear_stable": -force * f_r_min,
            "shear_within": largest_shear(t_F), "shear_read": largest_shear(t_read),
            "sigma": sigma}


def nominal_unit(box: ToleranceBox) -> np.ndarray:
    """The nominal unit's values (1, d)."""
    return box.nominal[None, :]


def with_values(box: ToleranceBox, base: np.ndarray, names: dict[str, float]) -> np.ndarray:
    """``base`` (d,) with some inputs set by name."""
    out = np.array(base, float)
    for k, v in names.items():
        out[box.index(k)] = v
    return out


__all__ = ["N_PATHS", "DesignContext", "design_context", "nominal_unit", "unit_figures",
           "with_values"]
