"""Fabrication tolerances by seeded Monte Carlo (docs/method.md §12).

Each unit off the line differs from the nominal design by independent normal deviations of
G, the remanence, the magnet's diameter and height, the chip's position under the magnet and
the magnet's tilt (``[tolerances]``, each a standard deviation). Per unit the field at its chip
and its derivatives with respect to the magnet's displacement come from magpylib's cylinder
(a tilted magnet over an off-axis chip has no axisymmetric solution); the force's derivatives
from the metamodels, scaled by the unit's G. Everything is evaluated at rest (t = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import hall_from_magnet_centre, loading_path
from ..metamodel import ModelSet
from ..sensitivity import row_norms, through_displacement
from ..study import MU0, Study

#: Names of the deviations, in the order of the columns of ε.
INPUTS = ("G", "remanence", "magnet_diameter", "magnet_height", "chip_x", "chip_y", "chip_z",
          "tilt_x", "tilt_y")
#: Percentiles a specification sheet quotes.
PERCENTILES = (5.0, 50.0, 95.0)
#: Step [m] of the central differences of the field in the magnet's displacement.
STEP = 2e-6


def sigmas(study: Study) -> np.ndarray:
    """Standard deviations of the deviations :data:`INPUTS` (relative, m, m, m, m, m, rad)."""
    t = study.tolerances
    return np.array([t.G, t.remanence, t.magnet_diameter, t.magnet_height, t.chip_lateral,
                     t.chip_lateral, t.chip_vertical, t.magnet_tilt, t.magnet_tilt])


@dataclass(frozen=True)
class Unit:
    """What the response of a unit needs: the nominal design and its force derivatives."""

    study: Study
    H: float
    G: float
    M_z: float
    #: ∂F/∂(p, q) at rest of the nominal design (2 × 2) [N].
    dF_dx: np.ndarray
    #: Full-range loads (F_r,min, F_z,max) [N].
    F_range: tuple[float, float]
    #: Field noise (σ_x, σ_z) [T] or None.
    noise: tuple[float, float] | None
    #: The chip's standoff [m] (None: the study's).
    standoff: float | None = None


def unit_context(models: ModelSet, study: Study, H: float, G: float, M_z: float,
                 F_range, noise, standoff: float | None = None) -> Unit:
    """The nominal design's data for :func:`responses` (``standoff`` [m]: the design's chip
    position, default the study's)."""
    dF = np.stack([np.asarray(models[k].jet(0.0, 0.0, H, 1)[1], dtype=float)
                   for k in ("f_r", "f_z")])
    return Unit(study, float(H), float(G), float(M_z), G * dF, tuple(F_range), noise,
                standoff)


def field_derivatives(u: Unit, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Field (B_x, B_z) at the chip [T], (n, 2), and ∂(B_x, B_z)/∂(p, q), (n, 2, 2), of units
    with deviations ``x`` (n, 9) in the units of :func:`sigmas`."""
    import magpylib as magpy
    from scipy.spatial.transform import Rotation

    s, m = u.study, u.study.magnet
    n = len(x)
    _, z0 = hall_from_magnet_centre(s, 0.0, 0.0, u.H, u.standoff)
    centre = np.array([0.0, 0.0, -float(z0)])
    # the magnet's displacement: rest, ±STEP along x (u_r) and along z (u_z)
    shifts = np.array([[0, 0, 0], [STEP, 0, 0], [-STEP, 0, 0], [0, 0, STEP], [0, 0, -STEP]])
    k = len(shifts)
    dims = np.column_stack([2 * m.R_m + x[:, 2], m.H_m + x[:, 3]])
    pol = np.zeros((n, 3))
    pol[:, 2] = MU0 * u.M_z * (1.0 + x[:, 1])
    chip = np.column_stack([x[:, 4], x[:, 5], x[:, 6]])
    rot = Rotation.from_rotvec(np.repeat(np.column_stack([x[:, 7], x[:, 8], np.zeros(n)]), k,
                                         axis=0))
    B = magpy.func.cylinder_field(
        "B", np.repeat(chip, k, axis=0), np.repeat(dims, k, axis=0),
        np.repeat(pol, k, axis=0), positions=np.tile(centre + shifts, (n, 1)),
        orientations=rot).reshape(n, k, 3)[..., [0, 2]]
    dB_dur = (B[:, 1] - B[:, 2]) / (2 * STEP)
    dB_duz = (B[:, 3] - B[:, 4]) / (2 * STEP)
    a = float(loading_path(s, 1.0, 0.0, u.H)[1])  # u_z = a p, u_r = −a q
    return B[:, 0], np.stack([a * dB_duz, -a * dB_dur], axis=-1)


def responses(u: Unit, eps: np.ndarray) -> dict[str, np.ndarray]:
    """The responses of units with standardised deviations ``eps`` (n, 9) (each N(0, 1) in the
    Monte Carlo), each an array (n,).

    Γ_r, Γ_z, σ_Fr, σ_Fz at rest relative to the nominal unit's (the metamodels' values times
    these ratios are the units' values); F_r,min, F_z,max [N]; ``cal_r``, ``cal_z`` [N]: the
    force error of a tared unit read with the nominal unit's calibration, largest over the
    full-range loads (F_r,min, 0), (0, F_z,max) and both; ``offset_r``, ``offset_z`` [N]: the
    false force of its field at rest if not tared.
    """
    eps = np.atleast_2d(np.asarray(eps, dtype=float))
    x = eps * sigmas(u.study)
    both = np.vstack([np.zeros((1, x.shape[1])), x])  # row 0: the nominal unit
    B0, dB = field_derivatives(u, both)
    gain = (1.0 + both[:, 0])[:, None, None]
    J = through_displacement(gain * u.dF_dx, dB)  # (n + 1, 2, 2): ∂F/∂B of each unit
    g_r, g_z = row_norms(J)
    out = {"Gamma_r_0": g_r[1:] / g_r[0], "Gamma_z_0": g_z[1:] / g_z[0],
           "F_r_min": u.F_range[0] * gain[1:, 0, 0], "F_z_max": u.F_range[1] * gain[1:, 0, 0]}
    if u.noise is not None:
        var = np.einsum("nij,j,nij->ni", J, np.square(u.noise), J)
        sig = np.sqrt(var)
        out |= {"sigma_Fr_0": sig[1:, 0] / sig[0, 0], "sigma_Fz_0": sig[1:, 1] / sig[0, 1]}
    E = np.einsum("ij,njk->nik", J[0], np.linalg.inv(J[1:])) - np.eye(2)  # J_nom J_i⁻¹ − I
    loads = np.array([[u.F_range[0], 0.0], [0.0, u.F_range[1]], list(u.F_range)])
    err = np.abs(np.einsum("nij,lj->nli", E, loads)).max(axis=1)
    off = np.abs(np.einsum("ij,nj->ni", J[0], B0[1:] - B0[0]))
    return out | {"cal_r": err[:, 0], "cal_z": err[:, 1], "offset_r": off[:, 0],
                  "offset_z": off[:, 1]}


def monte_carlo(fn, n_inputs: int, samples: int, seed: int) -> dict[str, np.ndarray]:
    """Responses ``fn(eps)`` of ``samples`` draws of ``eps`` ~ N(0, I) (n_inputs columns) from
    NumPy's generator seeded with ``seed`` (the same seed gives the same draws)."""
    eps = np.random.default_rng(seed).standard_normal((samples, n_inputs))
    return fn(eps)


def linearised(fn, n_inputs: int, step: float = 1e-3) -> dict[str, tuple[float, float]]:
    """(value, standard deviation) of each response by linear propagation:
    σ_y² = Σ_i (∂y/∂ε_i)², the derivatives by central differences of ``step`` in ε."""
    E = np.vstack([np.zeros(n_inputs), step * np.eye(n_inputs), -step * np.eye(n_inputs)])
    y = fn(E)
    out = {}
    for k, v in y.items():
        d = (v[1:1 + n_inputs] - v[1 + n_inputs:]) / (2 * step)
        out[k] = (float(v[0]), float(np.sqrt(np.sum(d**2))))
    return out


def contributions(fn, n_inputs: int, step: float = 1e-3) -> dict[str, list[float]]:
    """|y(step e_i) − y(0)| / step of each response: the standard deviation each input alone
    gives it to first order (which tolerance dominates). One-sided, because some responses
    are magnitudes |a · ε|, whose central difference at 0 vanishes."""
    y = fn(np.vstack([np.zeros(n_inputs), step * np.eye(n_inputs)]))
    return {k: [float(abs(d)) for d in (v[1:] - v[0]) / step] for k, v in y.items()}


def percentiles(samples: dict[str, np.ndarray]) -> dict[str, list[float]]:
    """The :data:`PERCENTILES` of each response."""
    return {k: [float(p) for p in np.percentile(v, PERCENTILES)] for k, v in samples.items()}
