"""The whole study in one call: field → DOE → metamodels → optimisation → validation → report.

Each stage writes its files into its own folder of the results folder and is recorded in
``run.json`` (status, wall time, message) as soon as it ends, so the report — built from the
folder alone by :func:`magtact.report.build_report` — always says what ran, what failed and
why. A failed stage does not stop the run; the stages that need its output are marked
``skipped`` with the reason. Nothing is ever shown in place of a missing result.

The stages write into a staging folder inside the results folder; the complete results replace
the previous run's only at the end, one run at a time, and never over a file magtact did not
write (:mod:`magtact._runfolder`, docs/method.md §14).
"""

from __future__ import annotations

import os
import platform
import shutil
import sys
import time
import traceback
import uuid
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from ._display import mN, sig
from ._errors import MagtactError, MissingFileError
from ._files import write_text
from ._front import calibrate, solve
from ._outputs import error_budgets, write_results_into
from ._runfolder import (
    RunLock,
    RunManifest,
    StageRecord,
    check_replaceable,
    recover,
    remove_dead,
    staging,
    swap,
    write_stamp,
)
from ._versions import RUN, package_versions
from .study import Study, check_study

#: File in each stage folder naming the run (``run.json``'s ``run_id``) that wrote the folder.
RUN_STAMP = ".magtact-run"


class StageSkipped(Exception):
    """A stage could not run because an input it needs is missing (not an error of its own)."""


@dataclass(frozen=True)
class RunResult:
    """Outcome of :func:`run_study`: the folder, the report file, the stage records and the
    answer (the design card's verdict and parts, or what binds where no design meets the
    requirements: ``answer["infeasible"]``)."""

    folder: Path
    report: Path
    stages: tuple[StageRecord, ...]
    wall_time_s: float
    answer: dict | None = None

    @property
    def ok(self) -> bool:
        """True if every stage succeeded (stages skipped because no design meets the
        requirements count as done: that is the answer)."""
        return all(s.status in ("ok", "warning") or (self.infeasible and s.status == "skipped")
                   for s in self.stages)

    @property
    def infeasible(self) -> bool:
        """True if no design meets the study's requirements (the answer says what binds)."""
        return isinstance(self.answer, dict) and isinstance(self.answer.get("infeasible"), dict)

    def __str__(self) -> str:
        from ._display import run_rows, text_block

        return text_block(*run_rows(self))

    def _repr_html_(self) -> str:
        from ._display import html_block, run_rows

        return html_block(*run_rows(self))


@dataclass
class _Context:
    """Objects the stages hand to each other (in memory) and the run's options."""

    study: Study
    folder: Path
    recompute: bool
    refit: bool
    data: list[Path] | None
    cache: Path | None
    workers: int | None
    log: Callable[[str], None]
    dataset: object = None
    models: object = None
    models_source: str = "none"
    result: object = None
    doe_source: str = "none"
    #: The answer where no design meets the requirements (:class:`magtact.designer.Infeasible`).
    infeasible: object = None
    #: The design card of the run (its verdict and parts), for the caller.
    card: dict | None = None
    #: The error budgets of the chosen and the original design (:func:`magtact.error_budgets`),
    #: computed once for the design card and written by the budget stage.
    budgets: object = None


def run_study(study: Study, out: str | Path, *, recompute: bool = False, refit: bool = False,
              data: list[str | Path] | None = None, cache: str | Path | None = ".magtact-cache",
              workers: int | None = None, command: str = "",
              evidence: str | Path | None = None,
              log: Callable[[str], None] = print) -> RunResult:
    """Run every stage of a study into ``out`` and build the HTML report.

    Parameters
    ----------
    study : Study
        The study.
    out : path
        Results folder (created). Each stage writes into ``out/<stage>/``; ``run.json``,
        ``study.toml``, ``evidence/`` and ``report.html`` sit at the top.
    recompute : bool
        False (default): use the DOE data set bundled with magtact (only valid for the
        built-in MagOne study); True: run the full FE design of experiments (cached in
        ``cache``).
    refit : bool
        False (default): when the DOE data and the fit settings are exactly those of the fit
        shipped with magtact, use that fit; True: always fit the metamodels.
    data : list of path, optional
        Validation CSV files; default: the shipped SYNTHETIC example (labelled so).
    cache : path, optional
        DOE job cache folder (with ``recompute``); None: no cache.
    workers : int, optional
        DOE worker processes (default: the number of cores).
    command : str
        The command line, recorded in the report.
    evidence : path, optional
        Folder of benchmark results (``*.json``, e.g. ``bench/results`` of a source checkout),
        copied into ``out/evidence`` and shown in the report. None: no evidence section content.
    log : callable
        Progress messages.

    Returns
    -------
    RunResult

    Raises
    ------
    MissingFileError
        If ``evidence`` is given but is not a folder (checked before any stage runs).
    magtact._runfolder.FolderInUse
        If another run is writing ``out`` (the message names its process).
    magtact.study.StudyError
        If ``[metamodel] holdout_paths`` exceeds what the study's DOE allows.
    magtact._runfolder.NotMagtactsFile
        If a file or folder where the run writes (``study.toml``, a stage folder, ...) was not
        written by an earlier run or was changed since (checked before any stage runs).
    """
    if evidence is not None and not Path(evidence).is_dir():
        raise MissingFileError(f"{evidence}: no such folder of benchmark results")
    check_study(study)  # the rules of magtact study, before the DOE, which may take hours
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    run_id = uuid.uuid4().hex
    command = command or "run_study(...)"
    with RunLock(folder, command, writes=outputs()):
        _forget_previous_run(folder)
        stage = staging(folder, run_id)
        ctx = _Context(study=study, folder=stage, recompute=recompute, refit=refit,
                       data=[Path(p) for p in data] if data else None,
                       cache=Path(cache) if cache is not None else None, workers=workers,
                       log=log)
        manifest = RunManifest(run_id, study.name, command,
                               datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC"),
                               recompute=recompute, refit=refit, versions=versions())
        try:
            records = _run_stages(ctx, run_id, manifest, start)
        except BaseException as exc:  # stopped: the staging folder says how and where
            manifest.interrupted = f"{type(exc).__name__} {exc}".strip()
            manifest.write(stage)
            raise
        if evidence is not None:
            _copy_evidence(Path(evidence), stage)
        manifest.finished = datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
        manifest.wall_time_s = time.perf_counter() - start
        manifest.write(stage)
        from .report import report_document

        write_text(stage / "report.html", report_document(stage, shown=folder))
        write_stamp(stage, run_id)
        swap(folder, stage, run_id)
        remove_dead(folder)
    return RunResult(folder=folder, report=folder / "report.html", stages=tuple(records),
                     wall_time_s=time.perf_counter() - start, answer=ctx.card)


def _run_stages(ctx: _Context, run_id: str, manifest: RunManifest, start: float
                ) -> list[StageRecord]:
    """Run the stages into ``ctx.folder``, recording each in its ``run.json`` as it ends."""
    from .report import saved_in_background

    folder = ctx.folder
    (folder / "study.toml").write_text(ctx.study.to_toml(), encoding="utf-8")
    manifest.write(folder)
    # each stage's figures are written by a worker process while the next stages compute
    with saved_in_background() as saver:
        records = _each_stage(ctx, run_id, manifest, start, saver)
        failed = saver.finish()
    for rec in records:
        if rec.key in failed:
            rec.status = "failed"
            rec.message = "; ".join([rec.message, "figures not written: "
                                     + "; ".join(failed[rec.key])]).lstrip("; ")
    if failed:
        manifest.stages = list(records)
        manifest.write(folder)
    return records


def _each_stage(ctx: _Context, run_id: str, manifest: RunManifest, start: float, saver
                ) -> list[StageRecord]:
    folder, log = ctx.folder, ctx.log
    records = []
    for n, (key, title, fn) in enumerate(STAGES, start=1):
        saver.tag = key
        rec = StageRecord(key=key, title=title)
        log(f"[{n}/{len(STAGES)}] {title} ...")
        t0 = time.perf_counter()
        try:
            rec.message = fn(ctx, rec) or ""
            # a stage that completed with a caveat (a poor fit, a front gap) says so
            rec.status = "warning" if any(n.startswith("WARNING") for n in rec.notes) else "ok"
        except StageSkipped as exc:
            rec.status, rec.message = "skipped", str(exc)
        except Exception as exc:  # a failed stage is reported, the run goes on
            rec.status, rec.message = "failed", f"{type(exc).__name__}: {exc}"
            logs = folder / "logs"
            logs.mkdir(exist_ok=True)
            (logs / f"{key}.traceback.txt").write_text(traceback.format_exc(), encoding="utf-8")
        rec.wall_time_s = time.perf_counter() - t0
        if (folder / key).is_dir():  # what the stage wrote belongs to this run
            (folder / key / RUN_STAMP).write_text(run_id, encoding="utf-8")
        log(f"      {rec.status} ({rec.wall_time_s:.1f} s) {rec.message}")
        records.append(rec)
        manifest.stages = list(records)
        manifest.doe_source = ctx.doe_source
        manifest.wall_time_s = time.perf_counter() - start
        manifest.write(folder)
    return records


def versions() -> dict[str, str]:
    """Versions of Python, the platform and the packages in :data:`magtact._versions.RUN`."""
    out = {"python": sys.version.split()[0], "platform": platform.platform(),
           "machine": platform.machine(), "cpus": str(os.cpu_count())}
    return out | package_versions(RUN)


# ---- stages ----------------------------------------------------------------------------------
def _stage_field(ctx: _Context, rec: StageRecord) -> str:
    from .magnetics import write_field_outputs
    from .report import field_figures

    files = write_field_outputs(ctx.study, ctx.folder / "field",
                                progress=lambda m: ctx.log(f"      {m}"), figures=field_figures)
    return f"{len(files)} files (solver: {ctx.study.magnetics.solver})"


def _stage_doe(ctx: _Context, rec: StageRecord) -> str:
    from .doe import bundled_for, run_doe, save_dataset, write_csv

    folder = ctx.folder / "doe"
    if ctx.recompute:
        ds = run_doe(ctx.study, cache=ctx.cache, workers=ctx.workers)
        a = ds.attrs
        ctx.doe_source = (f"recomputed: {a.get('run_paths_computed')} structural paths "
                          f"computed, {a.get('run_paths_cached')} from the cache")
    else:
        try:  # the bundled data, rescaled exactly to the study's G levels and M_z
            ds = bundled_for(ctx.study, advice="run with --recompute")
        except MagtactError as exc:
            raise StageSkipped(str(exc)) from None
        ctx.doe_source = (f"bundled with magtact (precomputed FE DOE "
                          f"{ds.attrs.get('bundled_name', '')}"
                          + (", rescaled exactly to this study's G levels and M_z)"
                             if "rescaled_from" in ds.attrs else ")"))
    folder.mkdir(parents=True, exist_ok=True)
    save_dataset(ds, folder / "doe.nc")
    write_csv(ds, folder / "doe.csv")
    ctx.dataset = ds
    try:
        from .report import fig_doe

        fig_doe(ds, folder / "doe_forces")
    except ImportError as exc:
        rec.notes.append(f"no DOE figure: {exc}")
    return f"{ds['F_r'].size:,} force points, {ds['B_r'].size:,} field points; {ctx.doe_source}"


def _stage_metamodel(ctx: _Context, rec: StageRecord) -> str:
    if ctx.dataset is None:
        raise StageSkipped("needs the DOE data set, which is missing")
    from .metamodel import copy_prefitted, find_shipped, select_metamodels, write_fit_outputs

    if ctx.study.geometric_variables and (ctx.refit or
                                          find_shipped(ctx.study, ctx.dataset) is None):
        return _fit_geometry(ctx, rec)
    chosen = select_metamodels(ctx.study, ctx.dataset, refit=ctx.refit,
                               log=lambda m: ctx.log(f"      {m}"))
    ctx.models_source = chosen.source
    if chosen.poor_fit:
        rec.notes.append(f"WARNING: {chosen.quality.message()}")
    if chosen.shipped is not None:
        ctx.models, _ = copy_prefitted(chosen.shipped, ctx.folder / "metamodel",
                                       models=chosen.models)
        return ("B_r, B_z, f_r, f_z: the fit shipped with magtact for this very data set and "
                "these settings (same data SHA-256; --refit fits again)")
    from .report import fit_figures
    from .sensitivity import compare_with_data

    result, files = write_fit_outputs(ctx.study, ctx.dataset, ctx.folder / "metamodel",
                                      gamma_check=compare_with_data, figures=fit_figures,
                                      result=chosen.fit)
    ctx.models = result.model_set(ctx.study)
    worst = max((r.test.max_rel_err for r in result.reports.values() if r.test is not None),
                default=float("nan"))
    return (f"B_r, B_z, f_r, f_z ({ctx.study.metamodel.generations} GP generations, B model: "
            f"{ctx.study.metamodel.b_model}); largest held-out relative error {worst:.3g}")


def _fit_geometry(ctx: _Context, rec: StageRecord) -> str:
    """Force models over (t, θ, H) and the geometric design variables; the field is exact."""
    from .metamodel import fit_models, fit_quality, save_models

    result = fit_models(ctx.dataset, ctx.study, log=lambda m: ctx.log(f"      {m}"))
    ctx.models = result.model_set(ctx.study)
    if fit_quality(ctx.models).is_poor:
        rec.notes.append(f"WARNING: {fit_quality(ctx.models).message()}")
    ctx.models_source = "fitted now to the data set"
    save_models(ctx.models, ctx.folder / "metamodel")
    worst = max((r.test.max_rel_err for r in result.reports.values() if r.test is not None),
                default=float("nan"))
    return (f"f_r, f_z over (t, theta, H, {', '.join(ctx.study.geometric_variables)}) "
            f"({ctx.study.metamodel.generations} GP generations; B: exact field); largest "
            f"held-out relative error {worst:.3g}")


def _stage_optimise(ctx: _Context, rec: StageRecord) -> str:
    if ctx.models is None:
        raise StageSkipped("needs the metamodels, which are missing")
    from .designer import InfeasibleSpecification
    from .optimise import FrontGapWarning, describe

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", FrontGapWarning)
        try:
            result = solve(ctx.models, ctx.study, models_source=ctx.models_source,
                           dataset=ctx.dataset)
        except InfeasibleSpecification as exc:  # an answer, not a failure
            from .report import write_infeasible_card

            ctx.infeasible = exc.answer
            (ctx.folder / "optimise").mkdir(parents=True, exist_ok=True)
            write_infeasible_card(exc.answer, ctx.folder / "optimise", ctx.study)
            ctx.card = _card_of(ctx.folder / "optimise")
            relax = exc.answer.relaxation
            return ("no design meets the requirements; "
                    + (f"relax {relax.text}" if relax is not None else str(exc)))
    for w in caught:  # a disagreement of NSGA-II and the exact reduction is said in the report
        if issubclass(w.category, FrontGapWarning):
            rec.notes.append(f"WARNING: {w.message}")
            ctx.log(f"      WARNING: {w.message}")
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    # the budget is a stage of its own; the explorer's grid is for the report
    ctx.budgets = error_budgets(result)
    write_results_into(result, ctx.folder / "optimise", budget=False, explorer=True,
                       budgets=ctx.budgets)
    ctx.result = result
    ctx.card = _card_of(ctx.folder / "optimise")
    if ctx.study.geometric_variables:
        r = result.optimisation
        return (f"design chosen: {describe(r.choice.values)} (exact reduction: "
                f"{describe(r.exact_choice.values)}; NSGA-II within {100 * r.gap:.2g} % of the "
                "exact front)")
    return "design chosen"


def _one_geometry(ctx: _Context, what: str):
    """The run's result for a stage that belongs to one geometry (else the stage is skipped,
    saying why)."""
    if ctx.infeasible is not None:
        raise StageSkipped(NO_DESIGN)
    if ctx.result is None:
        raise StageSkipped("needs the chosen design, which is missing")
    if ctx.study.geometric_variables:
        raise StageSkipped(f"{what} belongs to one geometry: give the chosen geometry a study "
                           "of its own (fixed R_m, H_m, R)")
    return ctx.result


def _stage_budget(ctx: _Context, rec: StageRecord) -> str:
    result = _one_geometry(ctx, "the error budget")
    from .budget import write_budgets
    from .report import budget_figures

    budgets = ctx.budgets if ctx.budgets is not None else error_budgets(result)
    write_budgets(budgets, ctx.study, ctx.folder / "budget", figures=budget_figures)
    top = budgets[0].largest(1)[0]
    return f"largest row of the chosen design: {top.name} ({top.component}), {mN(top.worst)} worst"


#: The firmware candidates a run measures (``magtact calibrate`` measures the full sweep of
#: :func:`magtact.calibration.firmware_approximation`): the sweep's higher orders and largest
#: table cost most of its time and are chosen only where these do not reach σ_F.
RUN_CALIBRATION = {"degrees": (4, 6, 8, 10, 12), "table_sizes": (16, 32, 64, 128)}


def _stage_calibration(ctx: _Context, rec: StageRecord) -> str:
    result = _one_geometry(ctx, "a calibration")
    from .calibration import write_calibration_outputs
    from .report import calibration_figures

    cal = calibrate(result, **RUN_CALIBRATION)
    write_calibration_outputs(cal, ctx.folder / "calibration", figures=calibration_figures)
    a = cal.firmware.chosen
    if not cal.firmware.reached:
        rec.notes.append("no firmware candidate of the run's sweep reaches σ_F: magtact "
                         "calibrate measures the full sweep")
    return (f"chosen design's map for firmware: {a.kind}, {a.bytes} bytes, largest error "
            f"{mN(a.err_r)} shear, {mN(a.err_z)} normal, against σ_F {mN(cal.sigma_F[0])} / "
            f"{mN(cal.sigma_F[1])}")


def _stage_validation(ctx: _Context, rec: StageRecord) -> str:
    if ctx.models is None:
        raise StageSkipped("needs the metamodels, which are missing")
    if ctx.study.geometric_variables:
        raise StageSkipped("repeat tests belong to one built sensor: validate the chosen "
                           "geometry with its own study (fixed R_m, H_m, R)")
    from .validation import PathModel, read_experiment, synthetic_files, validate, write_outputs

    if not ctx.data:
        other = _other_sensor(ctx.study)
        if other:  # the example was made on the MagOne sensor
            raise StageSkipped("the shipped example data belong to the MagOne sensor, not "
                               f"this study's ({other}): give measurements of this sensor "
                               "(--measured)")
    files = ctx.data or synthetic_files()
    if not ctx.data:
        rec.notes.append("no data given: the shipped SYNTHETIC example data set was used")
    experiment = read_experiment(files)
    H, G = experiment.design()
    model = PathModel.from_metamodels(ctx.models, ctx.study, H, G, experiment.theta)
    result = validate(experiment, model)
    from .report import validation_figures

    write_outputs(result, ctx.folder / "validation", sources=files, figures=validation_figures)
    rec.notes.extend(result.notes)
    worst = max(result.rows(), key=lambda r: r["eps_percent"]
                if r["eps_percent"] == r["eps_percent"] else -1.0)
    kind = "SYNTHETIC data" if result.synthetic else "experiment"
    return (f"{kind}, {result.n_tests} tests; largest ε = {sig(worst['eps_percent'])} % "
            f"({worst['response']})")


STAGES: tuple[tuple[str, str, Callable], ...] = (
    ("field", "Magnetic field", _stage_field),
    ("doe", "Design of experiments", _stage_doe),
    ("metamodel", "Metamodels", _stage_metamodel),
    ("optimise", "Optimisation", _stage_optimise),
    ("budget", "Error budget", _stage_budget),
    ("calibration", "Calibration", _stage_calibration),
    ("validation", "Validation against experiments", _stage_validation),
)


# ---- helpers ---------------------------------------------------------------------------------
#: Why the stages after the optimisation have nothing to work on.
NO_DESIGN = "no design meets the requirements (the verdict says what binds and what to relax)"


def _card_of(folder: Path) -> dict | None:
    """The design card the optimisation wrote (its verdict and parts), or None."""
    from .report import read_card

    return read_card(folder)


def _other_sensor(study: Study) -> str:
    """How ``study``'s sensor differs from the MagOne sensor the shipped example data were
    made on ("" where it is that sensor): magnet, body and loading."""
    from .study import load_study

    ref = load_study("magone")
    names = {"magnet": ("R_m", "H_m", "M_z", "placement"), "body": ("R", "H_g", "R_g", "R_h"),
             "loading": ("dz_sat",)}
    words = {"R_m": "magnet radius", "H_m": "magnet height", "M_z": "magnetisation",
             "placement": "magnet placement", "R": "body radius", "H_g": "gap height",
             "R_g": "gap radius", "R_h": "hole radius", "dz_sat": "saturation depth"}
    differ = [words[k] for section, keys in names.items() for k in keys
              if getattr(getattr(study, section), k) != getattr(getattr(ref, section), k)]
    return ", ".join(f"{w} differs" for w in differ[:3])


def _forget_previous_run(folder: Path) -> None:
    """Before a run (its lock held): finish the swap of a run killed while putting its results
    in place, and refuse if a file or folder where this run will write is not magtact's."""
    recover(folder)
    check_replaceable(folder, outputs())


def outputs() -> tuple[str, ...]:
    """The names a run writes at the top of its results folder."""
    return ("study.toml", "run.json", "report.html", "logs", "evidence",
            *(key for key, _, _ in STAGES))


def _copy_evidence(source: Path, folder: Path) -> None:
    """Copy ``source/*.json`` into ``folder/evidence``."""
    target = folder / "evidence"
    target.mkdir(exist_ok=True)
    for path in sorted(source.glob("*.json")):
        shutil.copy2(path, target / path.name)

