"""The published MagOne study's numbers, as facts to compare against (never targets).

de Boer et al., "Design Optimisation of a Magnetic Field Based Soft Tactile Sensor", Sensors 17
(2017) 2539. G as printed in the publication (kPa); the
`magone` preset reads it ten times larger (docs/method.md §9).
"""

from __future__ import annotations

from .._records import si_value
from ..study import to_si
from ._file import DesignRow

#: Designs of the publication: (H [mm], G as printed [kPa]).
ORIGINAL = (3.0, 2.94)
FABRICATED = (4.1, 2.94)
#: Height of the fabricated sensor [m] (the material is the original design's); the SYNTHETIC
#: validation example simulates this sensor (``magtact.validation.SYNTHETIC_H``).
H_FABRICATED = to_si(FABRICATED[0], "mm")

def _design(H_mm: float, G_kPa: float, Gamma_r_max: float, Gamma_z_max: float,
            F_r_min: float, F_z_max: float) -> DesignRow:
    """A design as the publication prints it (H [mm], G as printed [kPa], Γ [N/T], F [N]), in
    SI: the values that write the printed numbers again."""
    return DesignRow(si_value(H_mm, "mm"), si_value(G_kPa, "kPa"), Gamma_r_max, Gamma_z_max,
                     F_r_min, F_z_max)


#: Per design: H, G as printed, Γ_r,max, Γ_z,max [N/T], F_r,min, F_z,max [N] (no t_m, θ_m).
DESIGNS: dict[str, DesignRow] = {
    "original": _design(3.0, 2.94, 0.81, 50.5, -0.34, 7.03),
    "fabricated": _design(4.1, 2.94, 0.47, 43.8, -0.23, 5.23),
    "optimum_default": _design(4.11, 3.14, 0.48, 45.7, -0.25, 5.47),
    "optimum_reference": _design(4.17, 4.51, 0.68, 56.7, -0.34, 7.15),
}
#: Constraints of the publication's optimisation: F_r,c [N], F_z,c [N].
CONSTRAINTS = (-0.25, 5.0)
#: Branches of the published Pareto set (disconnected: G constant; F_r active, G rising in H).
PARETO_BRANCHES = 2
#: Qualitative statements of the publication.
QUALITATIVE = {
    "Gamma_z_along_t": "increasing",
    "Gamma_z_over_Gamma_r": "about 10 (60 to 95 at the designs above)",
}
