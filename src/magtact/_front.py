"""The front door and the one chain from a study to its answer.

``magtact.load`` reads a study; :func:`design` picks the models for it (bundled data and the
shipped fit, a data set, or a folder of model files) and runs :func:`solve`, the only path from
models and a study to a :class:`Result`: the optimisation (over (H, G[, M_z]) or with geometric
design variables), the decision, and the designer's answer for the chosen and the original
design. ``magtact run``, ``magtact optimise`` and the Python API all go through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

from . import _answers
from ._errors import MagtactError
from ._sensor import Sensor
from .study import Study, checked_si, from_si, load_study

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .budget import Budget
    from .calibration import Calibration, SensorMap
    from .designer import DesignAnswer
    from .metamodel import ModelSet
    from .optimise import (
        ForceConstraints,
        GeometryOptimisation,
        Optimisation,
        SensorOptimisation,
    )


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


#: User unit of each design variable (the study-file key is the name plus ``_<unit>``).
UNITS = {"H": "mm", "G": "kPa", "M_z": "A_per_m", "R_m": "mm", "H_m": "mm", "R": "mm",
         "standoff": "mm"}


@dataclass(frozen=True)
class Result:
    """The answer for one study (:func:`design`, :func:`solve`): a record of what was
    computed. The work over it is done by functions that take it first (:func:`error_budget`,
    :func:`calibrate`, :func:`write_results`, :func:`write_results_into`); its methods
    ``budget``, ``calibrate``, ``write`` and ``write_into`` are the same functions.

    Attributes
    ----------
    study : Study
    models : ModelSet
        B_r, B_z, f_r, f_z: the closed-form models every number comes from.
    models_source : str
        Where the models came from, in words (the shipped fit, fitted now, a folder).
    optimisation : Optimisation or GeometryOptimisation
        Everything the optimisation computed: maps, both Pareto sets, the decision on each,
        timings (:class:`magtact.optimise.Optimisation`; with geometric design variables
        :class:`magtact.optimise.GeometryOptimisation`).
    chosen, original : DesignAnswer
        The designer's answer (extrema, resolution with the study's Hall chip, saturation) for
        the design the decision rule picks and for the study's original design.
    variables : dict of float
        The chosen design's variables [SI] by name (``H``, ``G``, and ``M_z``, ``R_m``,
        ``H_m``, ``R`` where they are design variables); :attr:`chosen_design` in user units.
    dataset : xarray.Dataset or None
        The DOE data set the models were fitted to, where known (its per-path mesh error
        enters the error budget).

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design("magone")                          # doctest: +SKIP
    >>> result.chosen_design                                        # doctest: +SKIP
    {'H_mm': 3.0, 'G_kPa': 22.57...}
    >>> result.evaluate(H_mm=4.0, G_kPa=30.0).design.Gamma_z_max   # doctest: +SKIP
    >>> magtact.error_budget(result)                                # doctest: +SKIP
    """

    study: Study
    models: ModelSet
    models_source: str
    optimisation: Optimisation | GeometryOptimisation
    chosen: DesignAnswer
    original: DesignAnswer
    variables: dict[str, float]
    dataset: object = None
    #: The sensor problem's answer (the whole sensor; None for the publication's problem).
    sensor_design: SensorOptimisation | None = None
    #: The chosen sensor: its body, magnet and chip (:class:`magtact.Sensor`), the one
    #: :func:`calibrate` and :func:`error_budget` act on by default.
    sensor: Sensor | None = None

    @property
    def constraints(self) -> ForceConstraints:
        """The force constraints the design meets (F_r,c, F_z,c [N])."""
        return self.optimisation.constraints

    @property
    def active_constraints(self) -> tuple[str, ...]:
        """``"F_r"`` and/or ``"F_z"``: constraints the chosen design meets with (almost) no
        margin (within ``optimise.active_rtol`` of the limit)."""
        d = self.chosen.design
        return self.constraints.active(d.F_r_min, d.F_z_max, self.study.optimise.active_rtol)

    @property
    def pareto(self):
        """NSGA-II's Pareto set (:class:`magtact.optimise.ParetoSet`, or ``DesignSet`` over
        the geometric design variables)."""
        return self.optimisation.pareto

    @property
    def chosen_design(self) -> dict[str, float]:
        """The chosen design's variables in user units (``H_mm``, ``G_kPa`` ...)."""
        return {f"{k}_{UNITS[k]}": float(from_si(v, UNITS[k])) for k, v in self.variables.items()}

    @property
    def card(self) -> dict:
        """The design card: ``header`` and ``rows`` (words and units) for the chosen and the
        original design (:func:`magtact.report.card_rows`)."""
        from .report import card_rows

        header, rows = card_rows([self.chosen, self.original], self.constraints,
                                 rtol=self.study.optimise.active_rtol)
        from ._display import Card
        from .report import parts_list

        doc = {"header": header, "rows": rows + self._budget_rows()}
        if self.chosen.verdict is not None:  # the verdict and the parts lead, as in card.json
            doc = {"verdict": self.chosen.verdict.to_json(),
                   "parts": parts_list(self.chosen)} | doc
        return Card(doc)

    @cached_property
    def budgets(self) -> tuple[Budget, Budget] | None:
        """The error budgets of the chosen and the original design (:func:`error_budget`, with
        the data set's mesh error); None over geometric design variables (a budget belongs to one
        geometry)."""
        if self.study.geometric_variables:
            return None
        return tuple(error_budget(self, a, dataset=self.dataset)
                     for a in (self.chosen, self.original))

    def _budget_rows(self) -> list[list[str]]:
        from .budget import budget_card_rows
        from .metamodel import fit_quality_rows  # a poor fit is said on the card

        return fit_quality_rows(self.models, 2) + (
            [] if self.budgets is None else budget_card_rows(self.budgets))

    def of(self, answer: DesignAnswer) -> tuple[ModelSet, Study]:
        """The models and the study of a design's answer: its magnet, the chip's standoff and
        setting (in the sensor problem, with the exact field at that standoff)."""
        study = self.study if answer.study is None else answer.study
        if study.optimise.problem == "sensor" and not study.geometric_variables:
            from .chip import exact_field_models

            return exact_field_models(self.models, study), study
        return self.models, study

    def evaluate(self, *, H_mm: float, G_kPa: float, M_z_A_per_m: float | None = None,
                 label: str = "design", grade: str | None = None,
                 standoff_mm: float | None = None, robust: bool = False,
                 **geometry_mm: float) -> DesignAnswer:
        """The designer's answer for any design, given in user units.

        Parameters
        ----------
        H_mm, G_kPa : float
            Base height [mm] and shear modulus [kPa].
        M_z_A_per_m : float, optional
            Magnetisation [A/m]; default the magnet's own.
        label : str
            Name of the design in the answer.
        grade : str, optional
            The magnet's grade (a catalogue name, sets M_z); default the study's magnet.
        standoff_mm : float, optional
            The chip's distance below the body [mm]; default ``[hall] standoff_mm``.
        robust : bool
            Also the verdict over the built units (``answer.robust``: each requirement at
            the worst corner of ``[tolerances]`` and as a yield,
            :func:`magtact.tolerance.robust_verdict`; about 2 s).
        **geometry_mm : float
            ``R_m_mm``, ``H_m_mm``, ``R_mm`` where the study has them as design variables
            (default: the study's own value).

        Returns
        -------
        DesignAnswer
            Its ``verdict`` says which requirements the design meets, with margins; its
            ``design`` has the force extrema and whether the force constraints hold.

        Raises
        ------
        MagtactError
            For a value out of its physical range or an unknown or fixed geometric variable.
        """
        values = {"H": checked_si(H_mm, "mm", "H_mm"), "G": checked_si(G_kPa, "kPa", "G_kPa")}
        if M_z_A_per_m is not None:
            values["M_z"] = checked_si(M_z_A_per_m, "A_per_m", "M_z_A_per_m")
            # the study file's rule: a grade sets M_z, and an M_z also given must agree
            from .study import check_parts

            part = grade if grade is not None or self.study.M_z_variable else \
                self.study.magnet.grade
            if part is not None:
                check_parts(part, "custom", {"M_z": values["M_z"]},
                            {"M_z": "M_z_A_per_m", "grade": "grade"})
        own = self.study.geometry()
        for key, v in geometry_mm.items():
            name = key.removesuffix("_mm")
            if name not in own:
                known = ", ".join(f"{k}_mm" for k in own) or "none (R_m, H_m and R are fixed)"
                raise MagtactError(f"{key}: not a geometric design variable of study "
                                   f"{self.study.name!r}; its geometric design variables: "
                                   f"{known}")
            own[name] = checked_si(v, "mm", key)
        from .doe import check_design  # no answer outside the data's domain

        check_design(self.study, values["H"], self.dataset, **own)
        study = self.study
        if grade is not None or standoff_mm is not None:
            study = _with_parts(study, grade, standoff_mm)
        a = _answer(self.models, study, values | own, label)
        return with_robust(self, a) if robust else a

    def budget(self, answer: DesignAnswer | None = None, *, dataset=None,
               seeds: dict | None = None, noise: tuple[float, float] | None = None) -> Budget:
        """Same as ``magtact.error_budget(self, answer, ...)`` (:func:`error_budget`)."""
        return error_budget(self, answer, dataset=dataset, seeds=seeds, noise=noise)

    def evaluate_sensor(self, sensor: Sensor, label: str = "sensor") -> DesignAnswer:
        """The designer's answer for a whole sensor (:class:`magtact.Sensor`, e.g.
        ``result.sensor.changed(grade="N42")``): its H and G with its magnet, chip setting,
        standoff and silicone, with this result's models.

        Raises
        ------
        MagtactError
            For a sensor whose body radius, magnet size or chip are not the study's (those
            need models of their own), or a design outside the data's domain.
        """
        from .doe import check_design

        names = self.study.geometric_variables
        geometry = {k: getattr(sensor, k) for k in names}
        study = sensor.into(self.study, free=names)
        check_design(self.study, sensor.H, self.dataset, **geometry)
        return _answer(self.models, study, {"H": sensor.H, "G": sensor.G} | geometry, label)

    def calibrate(self, answer: DesignAnswer | None = None, *, presses=None,
                  noise: tuple[float, float] | None = None, **options) -> Calibration:
        """Same as ``magtact.calibrate(self, answer, ...)`` (:func:`calibrate`)."""
        return calibrate(self, answer, presses=presses, noise=noise, **options)

    def figures(self) -> dict[str, Figure]:
        """The optimisation's figures, the error budget of the chosen design and its
        calibration's error (where the study has one geometry) as matplotlib figures, by name
        (computing the budgets and the calibration if not done yet)."""
        from .report import calibration_figure, draw_budget, optimise_figure_objects

        figs = dict(optimise_figure_objects(self.optimisation))
        if self.budgets is not None:
            from .budget import budget_json

            figs["budget_chosen"] = draw_budget(budget_json(self.budgets[0]))
            figs["calibration"] = calibration_figure(calibrate(self))
        return figs

    def write(self, out: str | Path, figures: bool = True, budget: bool = True) -> list[Path]:
        """Same as ``magtact.write_results(self, out, ...)`` (:func:`write_results`)."""
        return write_results(self, out, figures=figures, budget=budget)

    def write_into(self, out: str | Path, figures: bool = True, budget: bool = True,
                   explorer: bool = False) -> list[Path]:
        """Same as ``magtact.write_results_into(self, out, ...)``
        (:func:`write_results_into`)."""
        return write_results_into(self, out, figures=figures, budget=budget,
                                  explorer=explorer)

    def __str__(self) -> str:
        """A few lines in mN, N, mm and kPa (3 significant figures)."""
        from ._display import result_rows, text_block

        return text_block(*result_rows(self))

    def _repr_html_(self) -> str:
        from ._display import html_block, result_rows

        return html_block(*result_rows(self))


def with_robust(result: Result, answer: DesignAnswer) -> DesignAnswer:
    """``answer`` with its verdict over the built units (``answer.robust``,
    :func:`magtact.tolerance.robust_verdict`: each requirement at the worst corner of the
    study's ``[tolerances]`` and as a yield with its confidence interval)."""
    from dataclasses import replace

    from .tolerance import robust_verdict

    if answer.robust is not None or answer.verdict is None or answer.study is None:
        return answer
    models, _ = result.of(answer)
    return replace(answer, robust=robust_verdict(models, answer))


def error_budget(result: Result, answer: DesignAnswer | None = None, *, dataset=None,
                 seeds: dict | None = None, noise: tuple[float, float] | None = None
                 ) -> Budget:
    """The error budget of a design of a result (docs/method.md §12): every disturbance of
    the field as a false force in mN beside the resolution.

    Parameters
    ----------
    result : Result
        The answer of a study (:func:`design`, :func:`solve`).
    answer : DesignAnswer or Sensor, optional
        ``result.chosen`` (default), ``result.original``, one of ``result.evaluate``, or a
        sensor (``result.sensor.changed(grade="N42")``, :meth:`Result.evaluate_sensor`).
    dataset : xarray.Dataset, optional
        The models' DOE data set, for the mesh's error (its ``err_F_*``).
    seeds : dict, optional
        A seed study (``magtact reproduce``'s ``publication.json``) for the seed spread.
    noise : (σ_x, σ_z) [T], optional
        Field noise in place of the chip's own figure (the chip at the design's setting
        otherwise); the budget's ``noise_source`` says so.

    Returns
    -------
    Budget
        Its rows in N, the resolution and the array's smallest pitch
        (:class:`magtact.budget.Budget`).

    Raises
    ------
    MagtactError
        For a study with geometric design variables (the budget is for one geometry).

    See Also
    --------
    Result.budget : the same, as a method.
    Result.budgets : the budgets of the chosen and the original design, with the data set.

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design()                                   # doctest: +SKIP
    >>> print(magtact.error_budget(result, result.original))        # doctest: +SKIP
    """
    from dataclasses import replace

    from .budget import error_budget as budget_of
    from .budget import noise_given

    a = _answer_of(result, answer)
    models, study = result.of(a)
    chip, said = (a.chip, None) if noise is None else noise_given(a.chip, noise)
    b = budget_of(models, study, a.H, a.G, a.design.M_z, label=a.label, design=a.design,
                  dataset=dataset, seeds=seeds, chip=chip)
    return b if said is None else replace(b, noise_source=said)


def calibrate(result: Result, answer: DesignAnswer | None = None, *, presses=None,
              noise: tuple[float, float] | None = None, **options) -> Calibration:
    """The calibration of a design of a result for firmware and, with ``presses``, of one
    built unit (docs/method.md §13), with the chip at the design's setting.

    Parameters
    ----------
    result : Result
        The answer of a study with one geometry.
    answer : DesignAnswer or Sensor, optional
        ``result.chosen`` (default), ``result.original``, one of ``result.evaluate``, or a
        sensor (``result.sensor.changed(grade="N42")``, :meth:`Result.evaluate_sensor`).
    presses : Presses, optional
        A built unit's measured (B, F) (:func:`magtact.calibration.read_presses`).
    noise : (σ_x, σ_z) [T], optional
        Field noise in place of the chip's own figure.
    **options
        As :func:`magtact.calibration.calibrate`: ``fit``, ``degrees``, ``table_sizes``,
        ``model_error``, ``force_source`` (``"auto"`` fits a unit to the FE forces of the
        result's DOE data set when it holds the design's H, docs/method.md §13.4).

    Returns
    -------
    Calibration
        The field-to-force map, the firmware's approximation and, with ``presses``, the
        unit's parameters (:class:`magtact.calibration.Calibration`).

    Raises
    ------
    MagtactError
        For a study with geometric design variables, an unknown noise, presses that do not
        identify the parameters.

    See Also
    --------
    Result.calibrate : the same, as a method.

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design()                                   # doctest: +SKIP
    >>> print(magtact.calibrate(result))                            # doctest: +SKIP
    """
    from .calibration import calibrate as calibration_of

    if result.study.geometric_variables:
        raise MagtactError("a calibration belongs to one geometry: fix the geometric "
                           "design variables (study.at(...)) with models fitted to it")
    a = _answer_of(result, answer)
    models, study = result.of(a)
    return calibration_of(models, study, a.H, a.G, a.design.M_z, noise=noise,
                          presses=presses, chip=a.chip, dataset=result.dataset, **options)


def write_results(result: Result, out: str | Path, *, figures: bool = True,
                  budget: bool = True) -> list[Path]:
    """Write a result into the results folder ``out``: the optimisation's tables, the design
    card (``card.json``), the error budgets (``budget.json``) and the figures.

    ``out`` has the rules of ``magtact`` commands (docs/method.md §14): its lock is held while
    writing, the files appear only once all are complete, and a file there that magtact did
    not write is never replaced.

    Parameters
    ----------
    result : Result
    out : path
        The results folder (made if missing).
    figures : bool
        Draw the figures (PNG and SVG).
    budget : bool
        Write ``budget.json`` (where the study has one geometry).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    MagtactError
        If another process is writing ``out``, or an output would replace a file that is
        not magtact's (the message names the files).

    See Also
    --------
    write_results_into : the same into a folder the caller already holds.
    Result.write : the same, as a method.

    Examples
    --------
    >>> import magtact
    >>> magtact.write_results(magtact.design(), "design")         # doctest: +SKIP
    """
    from ._runfolder import command_outputs

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with command_outputs(out, "magtact.Result.write") as o:
        files = write_results_into(result, o.folder, figures=figures, budget=budget)
    return [o.final(p) for p in files]


def write_results_into(result: Result, out: str | Path, *, figures: bool = True,
                       budget: bool = True, explorer: bool = False) -> list[Path]:
    """:func:`write_results` straight into ``out``, for a caller that already holds the
    folder (a command's or a run's staging folder): no lock, no check of what is there.

    Parameters
    ----------
    result : Result
    out : path
        The folder (it must exist).
    figures, budget : bool
        As :func:`write_results`.
    explorer : bool
        Also the report's design explorer (``explorer.json``, a grid of
        ``result.evaluate``).

    Returns
    -------
    list of Path
        The files written.

    See Also
    --------
    Result.write_into : the same, as a method.
    """
    from .budget import write_budgets
    from .optimise import write_geometry_outputs, write_optimise_outputs
    from .report import (
        budget_figures,
        fig_geometry_pareto,
        optimise_figures,
        write_card,
        write_explorer,
    )

    out = Path(out)
    if result.study.geometric_variables:
        files = write_geometry_outputs(result.optimisation, out,
                                       figures=fig_geometry_pareto if figures else None)
    else:
        files = write_optimise_outputs(result.optimisation, result.models, out,
                                       figures=optimise_figures if figures else None)
    if result.sensor_design is not None:  # the whole sensor is the chosen design
        written = result.sensor_design.write(out, result.chosen.design)
        files = [f for f in files if f.name != "chosen.json"] + written
    files.append(write_card([result.chosen, result.original], out, result.constraints,
                            rtol=result.study.optimise.active_rtol, study=result.study,
                            extra_rows=result._budget_rows()))
    grid = write_explorer(result, out) if explorer else None  # for the report's explorer
    if grid is not None:
        files.append(grid)
    if budget and result.budgets is not None:
        files.append(write_budgets(result.budgets, result.study, out,
                                   figures=budget_figures if figures else None))
    return files


def _answer_of(result: Result, answer: DesignAnswer | Sensor | None) -> DesignAnswer:
    """The answer a function over a result acts on: the chosen design's (None), the answer
    given, or that of a sensor given (:meth:`Result.evaluate_sensor`)."""
    if answer is None:
        return result.chosen
    if isinstance(answer, Sensor):
        return result.evaluate_sensor(answer)
    return answer


def force_map(result: Result, answer: DesignAnswer | Sensor | None = None) -> SensorMap:
    """The field-to-force map of a design of a result (docs/method.md §13): ``.force(B)``
    for readings B (..., 3) [T], ``.field(F)`` the forward map.

    Parameters
    ----------
    result : Result
    answer : DesignAnswer or Sensor, optional
        ``result.chosen`` (default), another answer, or a sensor.
    """
    from .calibration import sensor_map

    a = _answer_of(result, answer)
    geometry = {k: v for k, v in result.variables.items()
                if k in result.study.geometric_variables}
    if geometry and answer is None:
        models, study = result.models.at(**geometry), result.study.at(**geometry)
    else:
        models, study = result.of(a)
    return sensor_map(models, study, a.H, a.G, a.design.M_z, design=a.design)


def _answer(models: ModelSet, study: Study, values: dict[str, float], label: str
            ) -> DesignAnswer:
    """The designer's answer for a design given by its variables [SI] (at its geometry; in
    the sensor problem with the exact field of its magnet at its standoff)."""
    from .designer import answer

    geometry = {k: values[k] for k in study.geometric_variables if k in values}
    if geometry:
        models, study = models.at(**geometry), study.at(**geometry)
    elif study.optimise.problem == "sensor":
        from .chip import exact_field_models

        models = exact_field_models(models, study)
    return answer(models, study, values["H"], values["G"], label, values.get("M_z"))


def _with_parts(study: Study, grade: str | None, standoff_mm: float | None) -> Study:
    """``study`` with the magnet of ``grade`` and the chip at ``standoff_mm``."""
    from ._sensor import with_parts

    standoff = (None if standoff_mm is None
                else checked_si(standoff_mm, "mm", "standoff_mm", bounds=(0.0, 20e-3)))
    return with_parts(study, grade=grade, standoff=standoff)


def solve(models: ModelSet, study: Study, constraints: ForceConstraints | None = None, *,
          models_source: str = "given", dataset=None) -> Result:
    """From models and a study to the :class:`Result`: the one chain every caller uses.

    The optimisation (docs/method.md §7: NSGA-II and the exact reduction over (H, G[, M_z]),
    or over the geometric design variables as well), the decision rule on NSGA-II's set, and
    the designer's answer for the chosen and the original design (docs/method.md §10).

    Parameters
    ----------
    models : ModelSet
        B_r, B_z, f_r, f_z (over the geometric design variables where the study has them).
    study : Study
    constraints : ForceConstraints, optional
        Default: the study's ``[constraints]`` (:func:`magtact.optimise.force_constraints`).
    models_source : str
        Where the models came from, in words (kept in the result).
    dataset : xarray.Dataset, optional
        The DOE data set of the models (kept in the result for the error budget).

    Raises
    ------
    MagtactError
        Models not finite on the design domain, infeasible constraints (with the best reachable
        values), a chip that reads nothing but its limit.
    """
    from .designer import check_rest_field
    from .optimise import force_constraints

    own = study.geometry()
    sensor = study.optimise.problem == "sensor" and not study.geometric_variables
    check_rest_field(study.at(**own) if own else study)  # before any work
    if sensor:  # a chip whose noise is not known, before any work
        from .chip import chip_options

        chip_options(study)
    if constraints is None:
        constraints = force_constraints(models, study)

    def answer() -> dict:
        r = _solve(models, study, constraints, sensor)
        return {f.name: getattr(r, f.name) for f in fields(Result)
                if f.name not in ("models", "models_source", "dataset")}

    kept = _answers.kept(_answers.key(models, study, constraints), answer)
    return Result(models=models, models_source=models_source, dataset=dataset, **kept)


def _solve(models: ModelSet, study: Study, constraints: ForceConstraints, sensor: bool
           ) -> Result:
    """:func:`solve`'s work (its models source and data set left for the caller)."""
    from .optimise import InfeasibleError, optimise, optimise_geometry

    models_source, dataset, own = "given", None, study.geometry()
    if sensor:
        try:
            opt = optimise(models, study, constraints)
        except InfeasibleError as exc:
            r = study.requirements
            raise _infeasible(models, study, constraints,
                              f"the requirements cannot be met (requirements.F_z_N = {r.F_z:g} "
                              f"N, F_r_N = {r.F_r:g} N): {exc}") from None
        return _sensor_result(models, study, opt, constraints, models_source, dataset)
    if study.geometric_variables:
        opt = optimise_geometry(models, study, constraints)
        values = dict(opt.choice.values)
        if not study.M_z_variable:
            values.pop("M_z", None)
    else:
        try:
            opt = optimise(models, study, constraints)
        except InfeasibleError as exc:
            raise _infeasible(models, study, constraints, str(exc)) from None
        d = opt.choice.design
        values = {"H": d.H, "G": d.G} | ({} if d.M_z is None else {"M_z": d.M_z})
    original = {"H": study.design.H_original, "G": study.design.G_original} | own
    chosen = _answer(models, study, values, "chosen")
    return Result(study, models, models_source, opt, chosen,
                  _answer(models, study, original, "original"), values, dataset,
                  sensor=Sensor.of(chosen))


def _infeasible(models: ModelSet, study: Study, constraints, message: str) -> Exception:
    """The error of a specification no design meets, carrying the answer (what binds, what to
    relax: :func:`magtact.designer.infeasibility`) where the force requirements are those that
    cannot be met together; a plain :class:`InfeasibleError` otherwise (the chip's range)."""
    from .designer import InfeasibleSpecification, infeasibility
    from .optimise import InfeasibleError

    if constraints.F_r_c > 0 or constraints.F_z_c <= 0:
        return InfeasibleError(message)
    return InfeasibleSpecification(message, infeasibility(models, study, constraints, message))


def _sensor_result(models: ModelSet, study: Study, opt, constraints, models_source: str,
                   dataset) -> Result:
    """The sensor problem's :class:`Result`: the whole sensor (:func:`magtact.optimise.
    optimise_sensor`) as the chosen design, the publication's optimisation kept beside it.
    Forces given as constraints (``magtact optimise --Fzc``) become the required forces."""
    from dataclasses import replace

    from .optimise import optimise_sensor

    req = study.requirements
    F_r, F_z = (-constraints.F_r_c, constraints.F_z_c)
    k = 1.0 - constraints.tolerance
    if (F_r * k, F_z * k) != (req.F_r, req.F_z):
        study = replace(study, requirements=replace(req, F_r=F_r * k, F_z=F_z * k))
    table = opt.reduction.table
    sensor = optimise_sensor(models, study, table, constraints, nsga2=False)
    c = sensor.choice
    # where no sensor's loads within the normal force include the shear, the later solves ask
    # without it at once (the verdict says no)
    within = not c.F_r_within < study.requirements.F_r * (1.0 - 1e-9)
    chosen = _answer(models, c.apply(study), {"H": c.H, "G": c.G}, "chosen")
    sensor, chosen, problem = _for_every_unit(models, study, table, constraints, sensor, chosen,
                                              within)
    # NSGA-II's cross-check on the problem solved last, its reduction reused
    checked = optimise_sensor(models, study, table, *problem, reduction=sensor,
                              shear_within=within)
    if checked.choice != sensor.choice:
        chosen = _robust(models, _answer(models, checked.choice.apply(study),
                                         {"H": checked.choice.H, "G": checked.choice.G},
                                         "chosen"))
    sensor = checked
    c = sensor.choice
    sensor = _root_found_saturation(models, study, sensor, chosen.verdict.F_saturation)
    original = _answer(models, study, {"H": study.design.H_original,
                                       "G": study.design.G_original}, "original")
    values = {"H": c.H, "G": c.G, "M_z": c.M_z, "standoff": c.standoff}
    return Result(study, models, models_source, opt, chosen, original, values, dataset,
                  sensor, Sensor.of(chosen))


#: Solves of the sensor problem at the worst corner at most (each calibrates the worst
#: corner's factors on the sensor the one before chose).
WORST_CORNER_SOLVES = 2


def _for_every_unit(models: ModelSet, study: Study, table, constraints, sensor, chosen,
                    shear_within: bool = True):
    """The sensor problem solved for the worst corner of the chosen sensor's tolerance box
    (``[tolerances] design_for = "worst"``, docs/method.md §16), and the chosen answer with
    its robust verdict.

    Where the nominal choice's worst corner does not read the required normal force or carry the
    required shear, the problem is solved again with the chip's constraint at that corner
    (:func:`magtact.tolerance.worst_factors`: the forces' factor of the softest body and the FE
    bias, the reading's factor that folds the field's tolerances into one scale, both calibrated on
    the sensor chosen before) and the force constraints for the softest body (the shear's, where it
    falls short, for the worst corner's shear over the nominal one's); the factors are calibrated
    again on the new choice while its worst corner falls short, at most :data:`WORST_CORNER_SOLVES`
    times. NSGA-II cross-checks the problem solved last. With ``[tolerances] yield_target`` the same
    for that fraction of units (:func:`magtact.tolerance.yield_factors`). ``shear_within``: as
    :func:`magtact.optimise.optimise_sensor`.
    """
    from dataclasses import replace

    from .chip import exact_field_models
    from .optimise import InfeasibleError, optimise_sensor
    from .tolerance import worst_factors, yield_factors

    chosen = _robust(models, chosen)
    problem = (constraints, 1.0, 1.0)
    if study.tolerances.design_for != "worst":
        return sensor, chosen, problem
    k = 1.0 - constraints.tolerance  # the required forces
    target = study.tolerances.yield_target
    for _ in range(WORST_CORNER_SOLVES):
        normal, shear = chosen.robust["normal"], chosen.robust["shear"]
        if normal.met and shear.met:
            break
        m = exact_field_models(models, chosen.study)
        w = worst_factors(m, chosen) if target <= 0 else yield_factors(m, chosen, target)
        force = min(w.force, k)
        # where the worst corner falls short of the shear: the body asked for the shear over
        # the worst corner's share of the nominal unit's (besides the softest body and the FE
        # bias, the forces' factor, the body's height and the load envelope move it); where
        # no sensor then meets the problem, or the nominal unit itself falls short of the
        # shear, the normal force's factors alone
        short = (not shear.met and 0 < shear.worst < shear.nominal
                 and math.isfinite(shear.nominal) and chosen.verdict["shear"].met is True)
        shear_factors = [min(force, shear.worst / shear.nominal * k)] if short else []
        worst = None
        for force_r in [*shear_factors, force]:
            at_worst = replace(constraints, F_r_c=constraints.F_r_c * k / force_r,
                               F_z_c=constraints.F_z_c * k / force, tolerance=1.0 - force)
            try:
                worst = optimise_sensor(models, study, table, at_worst, field_factor=w.field,
                                        read_factor=w.read, nsga2=False,
                                        shear_within=shear_within)
                break
            except InfeasibleError:
                continue
        if worst is None:
            # no sensor reads the requirements at the worst corner: the nominal choice stands,
            # its robust verdict saying for which fraction of units each requirement holds
            break
        sensor, problem = worst, (at_worst, w.field, w.read)
        c = sensor.choice
        chosen = _robust(models, _answer(models, c.apply(study), {"H": c.H, "G": c.G},
                                         "chosen"))
    return sensor, chosen, problem


def _robust(models: ModelSet, answer):
    """``answer`` with its robust verdict (:func:`magtact.tolerance.robust_verdict`)."""
    from dataclasses import replace

    from .chip import exact_field_models
    from .tolerance import robust_verdict

    return replace(answer, robust=robust_verdict(exact_field_models(models, answer.study),
                                                 answer))


def _root_found_saturation(models: ModelSet, study: Study, sensor, F_chosen: float):
    """``sensor`` with the saturation figure of its designs root-found along the paths
    (:func:`magtact.chip.saturation_force`, the verdict's figure) instead of the first
    saturated level of the optimiser's grid: one figure in every file."""
    from dataclasses import replace

    from .chip import exact_field_models, saturation_force
    from .optimise import per_design
    from .study import hall_chip

    def figure(d):
        if d == sensor.choice:
            return F_chosen
        s = d.apply(study)
        m = exact_field_models(models, s)
        box = per_design(m, d.H, d.G, s)
        return saturation_force(s, m, d.H, d.G, hall_chip(s), box.t_m, box.theta_m)

    red = sensor.reduction_choice
    return replace(sensor, choice=replace(sensor.choice, F_saturation=F_chosen),
                   reduction_choice=replace(red, F_saturation=figure(red)))


def models_for(study: Study, *, data: str | Path | None = None,
               models: str | Path | None = None, refit: bool = False,
               log: Callable[[str], None] | None = None) -> tuple[ModelSet, str, object]:
    """The models of a study, where they come from (in words) and their DOE data set (None
    when the models come from files).

    ``models`` (a folder of model files, ``magtact fit``) when given; else the shipped fit when
    it matches the data set and the fit settings (and not ``refit``), else a new fit (minutes)
    to ``data`` (a DOE data set) or, without it, to the data set bundled with magtact (when it
    describes the study).

    Raises
    ------
    MagtactError
        A study the bundled data set does not describe and no ``data``; unreadable files.
    """
    from .metamodel import load_models, select_metamodels

    if models is not None:
        return (load_models(models, definition=study.sensitivity.definition),
                f"model files in {models}", None)
    from .doe import bundled_for, load_dataset

    ds = load_dataset(data) if data is not None else bundled_for(study)
    selection = select_metamodels(study, ds, refit=refit, log=log)
    return selection.models, selection.source, ds


def design(study: Study | str | Path | None = None, *, data: str | Path | None = None,
           models: str | Path | None = None, constraints: ForceConstraints | None = None,
           refit: bool = False, log: Callable[[str], None] | None = None) -> Result:
    """From a study to its answer in one call.

    Picks the models (:func:`models_for`: the shipped fit of the bundled DOE when they match,
    else a fit to ``data``, or the model files in ``models``) and runs :func:`solve`
    (docs/method.md §7, §10).

    Parameters
    ----------
    study : Study, preset name or study file, optional
        Default: the built-in MagOne study.
    data : path, optional
        A DOE data set (``magtact doe``) for a study the bundled data set does not describe.
    models : path, optional
        A folder of model files (``magtact fit``) to use instead of fitting.
    constraints : ForceConstraints, optional
        Default: the study's ``[constraints]``.
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
    >>> result.chosen_design["H_mm"], result.chosen_design["G_kPa"]   # doctest: +SKIP
    """
    if not isinstance(study, Study):
        study = load_study(study)
    m, source, ds = models_for(study, data=data, models=models, refit=refit, log=log)
    return solve(m, study, constraints, models_source=source, dataset=ds)
