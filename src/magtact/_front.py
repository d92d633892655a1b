"""The front door and the one chain from a study to its answer.

``magtact.load`` reads a study; :func:`design` picks the models for it (bundled data and the
shipped fit, a data set, or a folder of model files) and runs :func:`solve`, the only path from
models and a study to a :class:`Result`: the optimisation (over (H, G[, M_z]) or with geometric
design variables), the decision, and the designer's answer for the chosen and the original
design. ``magtact run``, ``magtact optimise`` and the Python API all go through it. The work
over a result that needs none of the report is here too (:func:`error_budget`,
:func:`calibrate`, :func:`force_map`); the record itself is ``magtact._result``, what the report
makes of it ``magtact._outputs``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING

from . import _answers
from ._errors import MagtactError
from ._result import Result, _answer, _exact_models
from ._sensor import Sensor
from .study import Study, load_study

if TYPE_CHECKING:
    from .budget import Budget
    from .calibration import Calibration, SensorMap
    from .designer import DesignAnswer
    from .metamodel import ModelSet
    from .optimise import ForceConstraints


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
    magtact.error_budgets : the budgets of the chosen and the original design, with the data
        set.

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
    models, study, sensor = result.of(a)
    chip, said = (a.chip, None) if noise is None else noise_given(a.chip, noise)
    b = budget_of(models, study, a.H, a.G, a.design.M_z, label=a.label, design=a.design,
                  dataset=dataset, seeds=seeds, chip=chip, sensor=sensor)
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
    models, study, sensor = result.of(a)
    return calibration_of(models, study, a.H, a.G, a.design.M_z, noise=noise,
                          presses=presses, chip=a.chip, dataset=result.dataset,
                          sensor=sensor, **options)


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
        models, study, _ = result.of(a)
    return sensor_map(models, study, a.H, a.G, a.design.M_z, design=a.design,
                      sensor=a.sensor)


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
    chosen = kept["study"]
    if sensor and (chosen.magnet.R_m, chosen.magnet.H_m) != (study.magnet.R_m,
                                                            study.magnet.H_m):
        # another magnet size was chosen: its models and data set are the bundled ones
        models, models_source, dataset = models_for(chosen)
    return Result(models=models, models_source=models_source, dataset=dataset, **kept)


def _solve(models: ModelSet, study: Study, constraints: ForceConstraints, sensor: bool
           ) -> Result:
    """:func:`solve`'s work (its models source and data set left for the caller)."""
    from .optimise import InfeasibleError, optimise, optimise_geometry

    models_source, dataset, own = "given", None, study.geometry()
    if sensor and study.design.magnet_sizes:
        sized = _sized_result(models, study, constraints)
        if sized is not None:
            return sized
        study = _own_size(study)  # no size meets the problem: its own magnet says why
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
    chosen = _values_answer(models, study, values, "chosen")
    return Result(study, models, models_source, opt, chosen,
                  _values_answer(models, study, original, "original"), values, dataset,
                  sensor=chosen.sensor)


def _values_answer(models: ModelSet, study: Study, values: dict[str, float], label: str):
    """The answer for a design given by its variables [SI] (H, G, and M_z and the geometric
    ones where the study has them) with the study's own parts."""
    geometry = {k: values[k] for k in study.geometric_variables if k in values}
    sensor = Sensor.of_study(study, values["H"], values["G"], values.get("M_z"), **geometry)
    return _answer(models, study, sensor, label, values.get("M_z"))


def _infeasible(models: ModelSet, study: Study, constraints, message: str) -> Exception:
    """The error of a specification no design meets, carrying the answer (what binds, what to
    relax: :func:`magtact.designer.infeasibility`) where the force requirements are those that
    cannot be met together; a plain :class:`InfeasibleError` otherwise (the chip's range)."""
    from .designer import InfeasibleSpecification, infeasibility
    from .optimise import InfeasibleError

    if constraints.F_r_c > 0 or constraints.F_z_c <= 0:
        return InfeasibleError(message)
    return InfeasibleSpecification(message, infeasibility(models, study, constraints, message))


def _required(study: Study, constraints) -> Study:
    """``study`` with forces given as constraints (``magtact optimise --Fzc``) as its required
    forces."""
    from dataclasses import replace

    req = study.requirements
    F_r, F_z = (-constraints.F_r_c, constraints.F_z_c)
    k = 1.0 - constraints.tolerance
    if (F_r * k, F_z * k) != (req.F_r, req.F_z):
        study = replace(study, requirements=replace(req, F_r=F_r * k, F_z=F_z * k))
    return study


def _own_size(study: Study) -> Study:
    """``study`` with its own magnet alone to choose from."""
    from dataclasses import replace

    return replace(study, design=replace(study.design, magnet_sizes=()))


def _same_size(study: Study, name: str) -> bool:
    from .parts import SIZES

    z = SIZES[name]
    return (math.isclose(z.R_m, study.magnet.R_m, rel_tol=1e-9)
            and math.isclose(z.H_m, study.magnet.H_m, rel_tol=1e-9))


def _sized_result(models: ModelSet, study: Study, constraints) -> Result | None:
    """The sensor problem over the magnet sizes of ``[design] magnet_sizes``: each size's
    problem (:meth:`magtact.study.Study.sized`, answered from the bundled data that hold it,
    its shipped fit) solved by the exact reduction on the nominal parts, the size of the least
    √(σ_F,r² + σ_F,z²) then solved whole (its worst corner, NSGA-II's cross-check:
    :func:`_sensor_result`). The result's study is the problem at the chosen size; its sensor
    problem's answer lists the best sensor of every size. None where no size has a sensor
    (the study's own magnet then says why)."""
    from dataclasses import replace
    from functools import partial

    from ._parallel import fork_map
    from .optimise import optimise

    names = study.design.magnet_sizes
    # the exact field's library, loaded once here rather than by each worker
    import magpylib.core  # noqa: F401

    # the largest magnets first: they are the ones that carry a sensor, the longer solves
    from .parts import SIZES

    screened = fork_map(partial(_screen_size, models, study, constraints), names,
                        first=lambda n: -SIZES[n].R_m ** 2 * SIZES[n].H_m if n in SIZES else 0)
    best = [choice for choice, _ in screened]
    notes = [note for _, note in screened]
    solved = [n for n, c in zip(names, best, strict=True) if c is not None]
    if not solved:
        return None
    name = min(solved, key=lambda n: best[names.index(n)].sigma)
    st = study.sized(name)
    m = models if _same_size(study, name) else models_for(st)[0]
    original = _values_answer(models, _required(study, constraints),
                              {"H": study.design.H_original, "G": study.design.G_original},
                              "original")
    result = _sensor_result(m, st, optimise(m, st, constraints), constraints, "given", None,
                            original=original)
    per = replace(result.sensor_design, sizes=tuple(names), per_size=tuple(best),
                  size_notes=tuple(notes), size=name)
    return replace(result, sensor_design=per)


#: Heights of the force table (:func:`magtact.optimise.force_table`) on which every magnet size
#: is compared.
SIZE_HEIGHTS = 21


def _screen_size(models: ModelSet, study: Study, constraints, name: str):
    """One magnet size of :func:`_sized_result`'s screen: the best sensor of its problem on its
    nominal parts (None where it has none) and a note (why it has none, or a caution where its
    fit is poor; empty otherwise)."""
    from .metamodel import fit_quality
    from .optimise import InfeasibleError, force_table, optimise_sensor

    st = study.sized(name)
    try:
        m = models if _same_size(study, name) else models_for(st)[0]
    except MagtactError:
        return None, "no bundled data hold this size"
    try:  # the stable box and force extrema on fewer heights than the chosen size's
        sensor = optimise_sensor(m, _required(st, constraints),
                                 force_table(m, st, SIZE_HEIGHTS), constraints, nsga2=False)
    except InfeasibleError:
        return None, "no sensor of this size meets the requirements"
    quality = fit_quality(m)
    return sensor.choice, "" if not quality.is_poor else "its fit is poor (" + "; ".join(
        f"{k}: held-out R² {quality.held_out[k][0]:.3g}, error "
        f"{quality.held_out[k][1]:.1%} of the range" for k in quality.poor) + ")"


def _sensor_result(models: ModelSet, study: Study, opt, constraints, models_source: str,
                   dataset, nominal=None, original=None) -> Result:
    """The sensor problem's :class:`Result`: the whole sensor (:func:`magtact.optimise.
    optimise_sensor`) as the chosen design, the publication's optimisation kept beside it.
    Forces given as constraints (``magtact optimise --Fzc``) become the required forces.
    ``nominal``: the reduction's answer on the nominal parts where already solved;
    ``original``: the original design's answer where it is not of ``study``'s magnet."""
    from .optimise import optimise_sensor

    study = _required(study, constraints)
    table = opt.reduction.table
    sensor = nominal or optimise_sensor(models, study, table, constraints, nsga2=False)
    c = sensor.choice
    # where no sensor's loads within the normal force include the shear, the later solves ask
    # without it at once (the verdict says no)
    within = not c.F_r_within < study.requirements.F_r * (1.0 - 1e-9)
    chosen = _answer(models, study, c.sensor(study), "chosen")
    sensor, chosen, problem = _for_every_unit(models, study, table, constraints, sensor, chosen,
                                              within)
    # NSGA-II's cross-check on the problem solved last, its reduction reused
    checked = optimise_sensor(models, study, table, *problem, reduction=sensor,
                              shear_within=within)
    if checked.choice != sensor.choice:
        chosen = _robust(models, _answer(models, study, checked.choice.sensor(study),
                                         "chosen"))
    sensor = checked
    c = sensor.choice
    sensor = _root_found_saturation(models, study, sensor, chosen.verdict.F_saturation)
    if original is None:
        original = _values_answer(models, study, {"H": study.design.H_original,
                                                  "G": study.design.G_original}, "original")
    values = {"H": c.H, "G": c.G, "M_z": c.M_z, "standoff": c.standoff}
    return Result(study, models, models_source, opt, chosen, original, values, dataset,
                  sensor, chosen.sensor)


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

    from .optimise import InfeasibleError, optimise_sensor
    from .tolerance import worst_factors, yield_factors

    problem = (constraints, 1.0, 1.0)
    if study.tolerances.design_for != "worst":
        return sensor, _robust(models, chosen), problem
    k = 1.0 - constraints.tolerance  # the required forces
    target = study.tolerances.yield_target
    # the solves decide on the worst corners alone (without a yield target); the answer kept
    # gets the whole verdict, its samples and yields, at the end
    quick = target <= 0
    chosen = _robust(models, chosen, samples=not quick)
    for _ in range(WORST_CORNER_SOLVES):
        normal, shear = chosen.robust["normal"], chosen.robust["shear"]
        if normal.met and shear.met:
            break
        m = _exact_models(models, study, chosen.sensor, None)
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
        chosen = _robust(models, _answer(models, study, c.sensor(study), "chosen"),
                         samples=not quick)
    if quick:
        chosen = _robust(models, chosen)
    return sensor, chosen, problem


def _robust(models: ModelSet, answer, samples: bool = True):
    """``answer`` with its robust verdict (:func:`magtact.tolerance.robust_verdict`; without
    ``samples``, its worst corners alone)."""
    from dataclasses import replace

    from .tolerance import robust_verdict

    return replace(answer, robust=robust_verdict(
        _exact_models(models, answer.study, answer.sensor, answer.design.M_z), answer,
        samples=samples))


def _root_found_saturation(models: ModelSet, study: Study, sensor, F_chosen: float):
    """``sensor`` with the saturation figure of its designs root-found along the paths
    (:func:`magtact.chip.saturation_force`, the verdict's figure) instead of the first
    saturated level of the optimiser's grid: one figure in every file."""
    from dataclasses import replace

    from .chip import saturation_force
    from .optimise import per_design
    from .study import hall_chip

    def figure(d):
        if d == sensor.choice:
            return F_chosen
        built = d.sensor(study)
        m = _exact_models(models, study, built, None)
        box = per_design(m, d.H, d.G, study)
        return saturation_force(study, m, d.H, d.G, hall_chip(study, built.setting),
                                box.t_m, box.theta_m, M_z=built.M_z, standoff=built.standoff)

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

    if data is None and not refit and study in _SHIPPED:
        return _SHIPPED[study]
    if data is not None:
        ds = load_dataset(data)
    else:
        try:
            ds = bundled_for(study)
        except MagtactError as exc:
            if refit:
                raise
            try:
                found = _blend(study)
            except MagtactError as why:
                raise MagtactError(f"{exc}. {str(why)[0].upper()}{str(why)[1:]}") from None
            _keep(study, found)
            return found
    selection = select_metamodels(study, ds, refit=refit, log=log)
    found = selection.models, selection.source, ds
    if data is None and selection.fit is None:
        _keep(study, found)
    return found


def _keep(study: Study, found: tuple) -> None:
    if len(_SHIPPED) >= 64:  # a process that asks for many studies keeps the latest
        _SHIPPED.clear()
    _SHIPPED[study] = found


#: The bundled data and shipped models of the studies asked for in this process, by study (a
#: frozen value; the package's data never change while it runs): the magnet sizes' problems are
#: asked for again by the answer and its commands.
_SHIPPED: dict[Study, tuple] = {}


def _blend(study: Study):
    """:func:`models_for` of a magnet between the bundled sizes: the data sets and shipped
    fits of the sizes around it blended along its radius, or its height and radius
    (:func:`magtact.doe.bundled_blend`; its error where none is)."""
    from .doe import bundled_blend
    from .metamodel import blended_metamodels

    ds, parts = bundled_blend(study)
    selection = blended_metamodels(study, parts)
    if selection is None:
        raise MagtactError("nor is it a blend of bundled sizes: a size around it has no "
                           "shipped fit")
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
        A DOE data set (``magtact doe``) for a study the bundled data set does not describe
        (it answers the study's own magnet: no other size is chosen).
    models : path, optional
        A folder of model files (``magtact fit``) to use instead of fitting (likewise).
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
    if data is not None or models is not None:
        study = _own_size(study)  # the data or models given answer the study's own magnet
    m, source, ds = models_for(study, data=data, models=models, refit=refit, log=log)
    return solve(m, study, constraints, models_source=source, dataset=ds)
