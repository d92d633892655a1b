"""The force-noise objective of the publication's problem and the best chip setting of a
design (docs/method.md §10); the setting choice itself is :func:`magtact.chip.setting_for`."""

from __future__ import annotations

from dataclasses import dataclass

from ..chip import SettingChoice, require_noise, setting_for
from ..metamodel import ModelSet
from ..parts import SettingFigures
from ..sensitivity import Responses
from ..study import Study, hall_chip
from ._design import per_design


def best_setting(models: ModelSet, study: Study, H: float, G: float, M_z: float | None = None
                 ) -> SettingChoice | None:
    """The best chip setting for design (H [m], G [Pa][, M_z [A/m]]) (see the module notes),
    or None for a chip without a setting table."""
    return setting_for(models, study, per_design(models, H, G, study, M_z))


@dataclass(frozen=True)
class SigmaObjective:
    """The force-noise objective of the optimisation (docs/method.md §10).

    ``responses`` serve γ_r, γ_z as the force noise per unit G, √(J_kx² σ_x² + J_kz² σ_z²) / G
    [N/Pa], with (σ_x, σ_z) the chip's noise at ``figures`` (the upper end of its interval),
    so that every optimisation over designs (per-design extrema, exact reduction, NSGA-II)
    minimises σ_F,r,max and σ_F,z,max [N] instead of Γ. The setting is the study's where it
    fixes one, else the one picked for design (H, G) (by default the original design);
    ``figures`` is None for a chip without a setting table (the study's noise).
    """

    responses: Responses
    noise: tuple[float, float]
    figures: SettingFigures | None
    H: float
    G: float


def sigma_objective(models: ModelSet, study: Study, H: float | None = None,
                    G: float | None = None, M_z: float | None = None) -> SigmaObjective:
    """The σ_F objective of ``study`` with the chip setting of design (H [m], G [Pa][, M_z])
    (default: the original design) where the study leaves the setting to magtact.

    Raises
    ------
    StudyError
        Naming ``hall.noise_x_uT`` when the chip's noise is not known.
    """
    H = study.design.H_original if H is None else float(H)
    G = study.design.G_original if G is None else float(G)
    chip = hall_chip(study)
    figures = chip.figures
    if chip.picked and chip.noise is None:
        figures = setting_for(models, study, per_design(models, H, G, study, M_z)).figures
    if figures is not None:
        noise = (figures.sigma_x[1], figures.sigma_z[1])
    else:
        noise = require_noise(chip, "the σ_F objective")
    return SigmaObjective(Responses(models, noise), noise, figures, H, G)
