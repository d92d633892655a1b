"""The front door: a study in, the chosen design out (``magtact.load``, ``magtact.design``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ._errors import MagtactError
from .study import Study, from_si, load_study


def load(source: str | Path | None = None, **sections: dict) -> Study:
    """A study from a preset name, a TOML file, or either with some settings changed.

    Parameters
    ----------
    source : str or path, optional
        ``"magone"`` (default), ``"magone-printed"``, or a study file.
    **sections : dict
        Settings to change, by section, in the units of a study file
        (``constraints={"F_z_c_N": 4.0}``, ``design={"H_mm": [3, 9]}``).

    Raises
    ------
    MagtactError
        For an unknown preset, a missing file or a setting that does not validate (the message
        names the key).

    Examples
    --------
    >>> import magtact
    >>> magtact.load("magone", constraints={"F_z_c_N": 4.0}).constraints.F_z_c
    4.0
    """
    study = load_study(source)
    if not sections:
        return study
    import tomllib

    from .study import study_from_dict

    data = tomllib.loads(study.to_toml())
    for name, values in sections.items():
        if not isinstance(values, dict):
            raise MagtactError(f"[{name}] must be given as a dict of settings, got "
                               f"{type(values).__name__}")
        data.setdefault(name, {})
        if isinstance(data[name], dict):
            data[name] = data[name] | values
        else:
            data[name] = values
    return study_from_dict(data, "keyword settings")


@dataclass(frozen=True)
class DesignSummary:
    """One design in user units (the numbers a sensor designer reads).

    Attributes
    ----------
    H_mm : base height [mm]
    G_kPa : shear modulus of the elastomer [kPa]
    Gamma_r_max_N_per_T, Gamma_z_max_N_per_T : worst sensitivities of the shear and normal force
        estimate to field error [N/T] over the stable region
    F_r_min_N : largest shear force before shear turns unstable (negative) [N]
    F_z_max_N : largest normal force in the stable region [N]
    sensitivity_definition : "jacobian" or "published"
    """

    H_mm: float
    G_kPa: float
    Gamma_r_max_N_per_T: float
    Gamma_z_max_N_per_T: float
    F_r_min_N: float
    F_z_max_N: float
    sensitivity_definition: str

    @classmethod
    def of(cls, d, definition: str) -> DesignSummary:
        """From a :class:`magtact.optimise.DesignResult` (SI inside)."""
        return cls(float(from_si(d.H, "mm")), float(from_si(d.G, "kPa")), float(d.Gamma_r_max),
                   float(d.Gamma_z_max), float(d.F_r_min), float(d.F_z_max), definition)

    def __str__(self) -> str:
        return (f"H = {self.H_mm:.3f} mm, G = {self.G_kPa:.2f} kPa: "
                f"Γ_r,max = {self.Gamma_r_max_N_per_T:.4g} N/T, "
                f"Γ_z,max = {self.Gamma_z_max_N_per_T:.4g} N/T, "
                f"F_r,min = {self.F_r_min_N:.4g} N, F_z,max = {self.F_z_max_N:.4g} N "
                f"({self.sensitivity_definition} Γ)")


@dataclass(frozen=True)
class Design:
    """The answer of :func:`design`.

    Attributes
    ----------
    study : Study
    chosen : DesignSummary
        The design the decision rule picks from NSGA-II's Pareto set.
    original : DesignSummary
        The study's original design, for comparison.
    active_constraints : tuple of str
        ``"F_r"`` and/or ``"F_z"``: constraints the chosen design meets with (almost) no margin.
    models_source : str
        Where the metamodels came from (the shipped fit, or fitted now).
    optimisation : magtact.optimise.Optimisation
        Everything the optimisation computed (maps, Pareto sets, timings).
    """

    study: Study
    chosen: DesignSummary
    original: DesignSummary
    active_constraints: tuple[str, ...]
    models_source: str
    optimisation: object

    def write(self, out: str | Path, figures: bool = True) -> list[Path]:
        """Write the optimisation's tables (and figures) into ``out``; return the files."""
        from .report import optimise_figures

        return self.optimisation.write(out, figures=optimise_figures if figures else None)

    def __str__(self) -> str:
        return (f"{self.study.name}: chosen {self.chosen}; active constraints "
                f"{', '.join(self.active_constraints) or 'none'}\n"
                f"original {self.original}")


def design(study: Study | str | Path | None = None, *, data: str | Path | None = None,
           refit: bool = False, log: Callable[[str], None] | None = None) -> Design:
    """From a study to its chosen design in one call.

    Uses the DOE data set bundled with magtact (when it describes the study) or ``data``, and
    the metamodels shipped for it when they match the data and settings, else fits them
    (minutes); then the optimisation (docs/method.md §7).

    Parameters
    ----------
    study : Study, preset name or study file, optional
        Default: the built-in MagOne study.
    data : path, optional
        A DOE data set (``magtact doe``) for a study the bundled data set does not describe.
    refit : bool
        Fit the metamodels even when the shipped fit matches.
    log : callable, optional
        Progress messages.

    Raises
    ------
    MagtactError
        A study the bundled data set does not describe and no ``data``; infeasible constraints.

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design("magone")                      # doctest: +SKIP
    >>> result.chosen.H_mm, result.chosen.G_kPa                 # doctest: +SKIP
    """
    from .doe import bundled_for, load_dataset
    from .metamodel import select_metamodels
    from .optimise import optimise, per_design

    if not isinstance(study, Study):
        study = load_study(study)
    ds = load_dataset(data) if data is not None else bundled_for(study)
    selection = select_metamodels(study, ds, refit=refit, log=log)
    opt = optimise(selection.models, study)
    definition = study.sensitivity.definition
    d = study.design
    original = per_design(selection.models, d.H_original, d.G_original, study)
    return Design(study, DesignSummary.of(opt.choice.design, definition),
                  DesignSummary.of(original, definition), tuple(opt.choice.active),
                  selection.source, opt)
