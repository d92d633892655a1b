"""The published MagOne study's numbers, as facts to compare against (never targets).

de Boer et al., "Design Optimisation of a Magnetic Field Based Soft Tactile Sensor", Sensors 17
(2017) 2539. G as printed in the publication (kPa); the
`magone` preset reads it ten times larger (docs/method.md §9).
"""

from __future__ import annotations

from ..study import to_si

#: Designs of the publication: (H [mm], G as printed [kPa]).
ORIGINAL = (3.0, 2.94)
FABRICATED = (4.1, 2.94)
#: Height of the fabricated sensor [m] (the material is the original design's); the SYNTHETIC
#: validation example simulates this sensor (``magtact.validation.SYNTHETIC_H``).
H_FABRICATED = to_si(FABRICATED[0], "mm")

#: Per design: Γ_r,max, Γ_z,max [N/T], F_r,min, F_z,max [N]; G as printed.
DESIGNS: dict[str, dict[str, float]] = {
    "original": {"H_mm": 3.0, "G_kPa": 2.94, "Gamma_r_max": 0.81, "Gamma_z_max": 50.5,
                 "F_r_min": -0.34, "F_z_max": 7.03},
    "fabricated": {"H_mm": 4.1, "G_kPa": 2.94, "Gamma_r_max": 0.47, "Gamma_z_max": 43.8,
                   "F_r_min": -0.23, "F_z_max": 5.23},
    "optimum_default": {"H_mm": 4.11, "G_kPa": 3.14, "Gamma_r_max": 0.48, "Gamma_z_max": 45.7,
                        "F_r_min": -0.25, "F_z_max": 5.47},
    "optimum_reference": {"H_mm": 4.17, "G_kPa": 4.51, "Gamma_r_max": 0.68,
                          "Gamma_z_max": 56.7, "F_r_min": -0.34, "F_z_max": 7.15},
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
