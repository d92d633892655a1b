"""The Hall chip's range: as a constraint of the optimisation, along a design's paths, and
against the field at rest (docs/method.md §10).

The field along a path depends on the geometry only (H, t, θ), not on G, and so does the stable
region t ≤ t_m(H), θ ≤ θ_m(H): a chip that must stay within its range over the region the sensor
is used in restricts the heights, whatever the silicone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..metamodel import ExactField, ModelSet
from ..study import HallChip, Study, StudyError, hall_chip, mm, mt

#: Load levels and angles of the saturation scan along the paths.
N_SCAN_T, N_SCAN_THETA = 201, 21

#: Grid over each height's stable region (fractions of t_m and θ_m) on which the field is read.
N_T, N_THETA = 41, 11


def chip_margin(study: Study, H, t_m, theta_m, geometry: dict | None = None) -> np.ndarray:
    """How far the exact field exceeds the chip's range over each height's stable region.

    .. math:: m(H) = \\max_{t \\le t_m,\\ θ \\le θ_m}
              \\max\\left(\\frac{|B_x|}{B_{x,\\mathrm{range}}},
              \\frac{|B_z|}{B_{z,\\mathrm{range}}}\\right) - 1

    Parameters
    ----------
    study : Study
        Geometry, loading path and the ``[hall]`` chip.
    H, t_m, theta_m : array_like, shape (n,)
        Heights [m] and their stable shear bounds (t_m, θ_m [rad]).
    geometry : dict of array_like, optional
        Each row's values [m] of the study's geometric design variables (shape (n,)); the
        field depends on the magnet's (R_m, H_m).

    Returns
    -------
    numpy.ndarray, shape (n,)
        ≤ 0 where the chip reads the whole stable region.
    """
    chip = hall_chip(study)
    H, t_m, theta_m = (np.atleast_1d(np.asarray(v, float)) for v in (H, t_m, theta_m))
    s = np.linspace(0.0, 1.0, N_T)[:, None, None]
    u = np.linspace(0.0, 1.0, N_THETA)[None, :, None]
    T, TH = s * t_m[None, None, :], u * theta_m[None, None, :]
    HH = np.broadcast_to(H[None, None, :], T.shape)
    B_r, B_z = ExactField(study, "B_r"), ExactField(study, "B_z")
    geo = {k: np.broadcast_to(np.asarray(v, float), H.shape)[None, None, :]
           for k, v in (geometry or {}).items() if k in B_r.geometry}
    ratio = np.maximum(np.abs(B_r.value(T, TH, HH, **geo)) / chip.range_x,
                       np.abs(B_z.value(T, TH, HH, **geo)) / chip.range_z)
    return ratio.max(axis=(0, 1)) - 1.0


@dataclass(frozen=True)
class Saturation:
    """The largest field along the paths against the chip's range."""

    B_max_x: float
    B_max_z: float
    #: First load t (and its θ, axis, forces [N]) at which the chip saturates; None: never.
    t: float | None = None
    theta: float | None = None
    axis: str | None = None
    F_r: float | None = None
    F_z: float | None = None
    #: :func:`magtact.optimise.chip_margin` over the design's stable region (≤ 0: the chip reads
    #: all of it); NaN when not computed.
    region_margin: float = float("nan")

    @property
    def saturates(self) -> bool:
        return self.t is not None

    @property
    def in_region(self) -> bool:
        """Whether the chip saturates inside the stable region (where the sensor is used)."""
        return bool(self.region_margin > 0)


def _weakest(study: Study) -> Study:
    """``study`` with its sensor problem's weakest field: the lowest grade, the largest
    standoff."""
    from dataclasses import replace

    from ..parts import grade
    from ..study import MU0

    d = study.design
    M_z = min((grade(g).M_z(MU0)[0] for g in d.grades), default=study.magnet.M_z)
    standoff = d.standoff[1] if d.standoff[1] > 0 else study.hall.standoff
    return replace(study, magnet=replace(study.magnet, M_z=M_z),
                   hall=replace(study.hall, standoff=standoff))


def check_rest_field(study: Study) -> None:
    """Refuse a chip range below the field at rest of every design in the study's range.

    The field at rest is weakest at the tallest body (the magnet farthest from the chip); in
    the sensor problem also with the weakest grade and the chip at its largest standoff.

    Raises
    ------
    StudyError
        Naming ``hall.range_x_mT`` or ``hall.range_z_mT``.
    """
    if study.optimise.problem == "sensor" and not study.geometric_variables:
        study = _weakest(study)
    chip = hall_chip(study)
    H = study.design.H[1]
    s = study.hall.standoff
    below = f", the chip {mm(s):.3g} mm below the body" if s > 0 else ""
    for axis, name in (("x", "B_r"), ("z", "B_z")):
        b = abs(float(ExactField(study, name).value(0.0, 0.0, H)))
        limit = chip.range_x if axis == "x" else chip.range_z
        if b > limit:
            raise StudyError(f"hall.range_{axis}_mT",
                             f"{mt(limit):.4g} mT is below the field at rest of every design "
                             f"(|B_{axis}| = {mt(b):.4g} mT even at the tallest, H = "
                             f"{mm(H):.3g} mm{below}): the {chip.name} would read nothing but "
                             "its limit")


def saturation(study: Study, models: ModelSet, H: float, G: float, chip: HallChip
               ) -> Saturation:
    """The exact field along every path (t ∈ [0, 1], θ ∈ [0, θ_max]) against the chip's range.

    A range below the field at rest shows as saturation at t = 0 (see
    :func:`check_rest_field` for the study-wide check).
    """
    t = np.linspace(0.0, 1.0, N_SCAN_T)
    th = np.linspace(0.0, study.loading.theta_max, N_SCAN_THETA)
    T, TH = np.meshgrid(t, th, indexing="ij")
    B = {"x": np.abs(ExactField(study, "B_r").value(T, TH, H)),
         "z": np.abs(ExactField(study, "B_z").value(T, TH, H))}
    limit = {"x": chip.range_x, "z": chip.range_z}
    over = (B["x"] > limit["x"]) | (B["z"] > limit["z"])
    out = dict(B_max_x=float(B["x"].max()), B_max_z=float(B["z"].max()))
    if not over.any():
        return Saturation(**out)
    i = int(np.argmax(over.any(axis=1)))  # first load level with a saturated angle
    j = int(np.argmax(over[i]))
    axis = "x" if B["x"][i, j] > limit["x"] else "z"
    F_r, F_z = models.forces(t[i], th[j], H, G)
    return Saturation(**out, t=float(t[i]), theta=float(th[j]), axis=axis,
                      F_r=float(F_r), F_z=float(F_z))
