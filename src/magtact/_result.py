"""The record of a study's answer, :class:`Result`, and the designer's answer for any design
over it (:meth:`Result.evaluate`).

A record only: what the report makes of a result (the design card, the error budgets, the
figures, the results folder) is in ``magtact._outputs``, so that this module and whoever holds a
result need none of the report's code.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from ._errors import MagtactError
from ._sensor import Sensor
from .study import Study, checked_si, from_si

if TYPE_CHECKING:
    from .designer import DesignAnswer
    from .metamodel import ModelSet
    from .optimise import (
        ForceConstraints,
        GeometryOptimisation,
        Optimisation,
        SensorOptimisation,
    )


#: User unit of each design variable (the study-file key is the name plus ``_<unit>``).
UNITS = {"H": "mm", "G": "kPa", "M_z": "A_per_m", "R_m": "mm", "H_m": "mm", "R": "mm",
         "standoff": "mm"}


@dataclass(frozen=True)
class Result:
    """The answer for one study (:func:`magtact.design`, :func:`magtact.solve`): a plain,
    frozen record of what was computed. It holds no cache and imports none of the report; its
    properties only read its fields.

    What is made of a result is done by functions that take it first:
    :func:`magtact.card` (the design card), :func:`magtact.error_budgets` (the error budgets of
    the chosen and the original design), :func:`magtact.figures` (matplotlib figures),
    :func:`magtact.error_budget` and :func:`magtact.calibrate` (of any design of it),
    :func:`magtact.force_map`, :func:`magtact.write_results` and
    :func:`magtact.write_results_into` (a results folder). Its methods answer for other
    designs on its models: :meth:`evaluate`, :meth:`evaluate_sensor`, :meth:`of`.

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
    sensor_design : SensorOptimisation or None
        The sensor problem's answer (None for the publication's problem).
    sensor : Sensor or None
        The chosen sensor (body, magnet, chip: :class:`magtact.Sensor`).

    See Also
    --------
    magtact.card, magtact.error_budgets, magtact.figures : what the report shows of it.
    magtact.write_results : its results folder.

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design("magone")                          # doctest: +SKIP
    >>> result.chosen_design                                        # doctest: +SKIP
    {'H_mm': 3.0, 'G_kPa': 22.57...}
    >>> result.evaluate(H_mm=4.0, G_kPa=30.0).design.Gamma_z_max   # doctest: +SKIP
    >>> budgets = magtact.error_budgets(result)                     # doctest: +SKIP
    >>> print(magtact.card(result, budgets))                        # doctest: +SKIP
    >>> magtact.write_results(result, "design", budgets=budgets)   # doctest: +SKIP
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
    #: :func:`magtact.calibrate` and :func:`magtact.error_budget` act on by default.
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

    def of(self, answer: DesignAnswer) -> tuple[ModelSet, Study, Sensor]:
        """The models, the study and the sensor of a design's answer (in the sensor problem
        the models hold the exact field of the sensor's magnet at its standoff)."""
        study = self.study if answer.study is None else answer.study
        sensor = answer.sensor
        if study.optimise.problem == "sensor" and not study.geometric_variables:
            return _exact_models(self.models, study, sensor, answer.design.M_z), study, sensor
        return self.models, study, sensor

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
        sensor = Sensor.of_study(self.study, values["H"], values["G"], values.get("M_z"),
                                 **own)
        if grade is not None or standoff_mm is not None:
            sensor = sensor.changed(grade=grade, standoff=None if standoff_mm is None else
                                    checked_si(standoff_mm, "mm", "standoff_mm",
                                               bounds=(0.0, 20e-3)))
            if grade is not None and "M_z" in values:  # the M_z given, checked against it
                sensor = replace(sensor, M_z=values["M_z"])
        a = _answer(self.models, self.study, sensor, label, values.get("M_z"))
        return with_robust(self, a) if robust else a

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
        sensor.check(self.study, free=names)
        check_design(self.study, sensor.H, self.dataset, **geometry)
        return _answer(self.models, self.study, sensor, label)

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

    if answer.robust is not None or answer.verdict is None or answer.sensor is None:
        return answer
    models, _, _ = result.of(answer)
    return replace(answer, robust=robust_verdict(models, answer))


def _answer(models: ModelSet, study: Study, sensor: Sensor, label: str,
            M_z: float | None = None) -> DesignAnswer:
    """The designer's answer for ``sensor``, a design of ``study`` (at its geometry; in the
    sensor problem with the exact field of its magnet at its standoff); ``M_z``: as
    :func:`magtact.designer.answer`."""
    from .designer import answer

    geometry = {k: getattr(sensor, k) for k in study.geometric_variables}
    if geometry:
        models, study = models.at(**geometry), study.at(**geometry)
    elif study.optimise.problem == "sensor":
        models = _exact_models(models, study, sensor, M_z)
    return answer(models, study, sensor, label, M_z)


def _exact_models(models: ModelSet, study: Study, sensor: Sensor, M_z: float | None
                  ) -> ModelSet:
    """``models`` with the exact field of ``sensor``'s magnet at its standoff; where ``M_z``
    scales the field (a design variable), the field of the study's magnet, which the
    evaluation scales by M_z over the study's."""
    from .chip import exact_field_models

    return exact_field_models(models, study, sensor.standoff,
                              sensor.M_z if M_z is None else None)
