"""magtact: design magnetic soft tactile sensors by simulation, metamodels and optimisation.

The front door::

    import magtact
    study = magtact.load("magone")          # a preset, a study file, or either with changes
    result = magtact.design(study)          # a Result: bundled data and shipped fit
    print(result.chosen)                    # H [mm], G [kPa], Γ [N/T], forces [N]
    result.evaluate(H_mm=4.0, G_kPa=30.0)   # any other design, same models

``magtact.solve(models, study)`` is the chain behind it, from models to the :class:`Result`.
A :class:`Result` is a record; the work over it is done by functions that take it first::

    magtact.error_budget(result)            # the chosen design's error budget (mN)
    magtact.calibrate(result)               # its field-to-force map and firmware
    magtact.write_results(result, "design") # tables, card.json, budget.json, figures
    magtact.card(result)                    # the design card; error_budgets, figures alike

(``error_budget``, not ``budget``: ``magtact.budget`` is the error budget's sub-package.)

``magtact.run`` runs every stage into a results folder with an HTML report; the stages are
sub-packages (``magtact.study``, ``magnetics``, ``mechanics``, ``doe``, ``metamodel``,
``sensitivity``, ``optimise``, ``validation``, ``publication``, ``report``). The method:
docs/method.md.
"""

from importlib.metadata import PackageNotFoundError, version

from ._errors import MagtactError
from ._front import (
    Result,
    calibrate,
    design,
    error_budget,
    force_map,
    load,
    models_for,
    solve,
)
from ._outputs import card, error_budgets, figures, write_results, write_results_into
from ._sensor import Sensor
from .study import Study

try:
    __version__ = version("magtact")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"


def run(study: Study | str | None = None, out: str = "results", **options):
    """Every stage of ``study`` into the folder ``out`` with its HTML report
    (:func:`magtact.pipeline.run_study`; options as there). Returns its ``RunResult``."""
    from .pipeline import run_study

    if not isinstance(study, Study):
        study = load(study)
    return run_study(study, out, **options)


__all__ = ["MagtactError", "Result", "Sensor", "Study", "__version__", "calibrate", "card",
           "design", "error_budget", "error_budgets", "figures", "force_map", "load",
           "models_for", "run", "solve", "write_results", "write_results_into"]
