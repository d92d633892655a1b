"""Sensitivity-optimal design (docs/method.md §7).

Per design (H, G): stable shear bounds and the largest F_z, Γ_r, Γ_z (:func:`per_design`); maps
over (H, G) (:func:`design_maps`); over designs: NSGA-II (:func:`pareto_nsga2`), the exact
reduction to a curve over H (:func:`exact_reduction`), the decision rule (:func:`choose`);
:func:`compare` two designs; :func:`optimise` runs it all.
"""

from ..chip import chip_margin
from ._box import BoxOptimum, box_optimum
from ._conditioning import ShearBoundConditioning, shear_bound_conditioning
from ._design import (
    DesignMaps,
    DesignResult,
    HeightResult,
    HeightTable,
    as_responses,
    design_maps,
    force_extrema,
    force_table,
    heights_batch,
    per_design,
    per_height,
    per_heights,
)
from ._geometry import (
    DesignSet,
    GeometricChoice,
    GeometryOptimisation,
    describe,
    geometry_choice_json,
    optimise_geometry,
    write_geometry_outputs,
)
from ._pareto import (
    Choice,
    Comparison,
    DesignProblem,
    ForceConstraints,
    InfeasibleError,
    ParetoSet,
    Reduction,
    best_magnetisation,
    choose,
    compare,
    decision_index,
    exact_reduction,
    feasible_G,
    force_constraints,
    front_gap,
    nondominated,
    pareto_nsga2,
    sweep,
)
from ._run import (
    ChosenFile,
    FrontGapWarning,
    Optimisation,
    Timings,
    design_file_definition,
    optimise,
    write_optimise_outputs,
)
from ._sensor import (
    WARN_GAP as WARN_GAP_SENSOR,
)
from ._sensor import (
    SensorDesign,
    SensorGapWarning,
    SensorOptimisation,
    SensorPareto,
    SensorSpace,
    exact_sensor_reduction,
    most_shear_within,
    optimise_sensor,
    sensor_nsga2,
    sensor_space,
    silicone_ranges,
)
from ._setting import best_setting, sigma_objective

__all__ = [
    "Comparison", "DesignProblem", "DesignResult", "ForceConstraints", "FrontGapWarning",
    "GeometryOptimisation", "InfeasibleError", "Optimisation", "SensorDesign", "SensorGapWarning",
    "SensorOptimisation", "box_optimum", "compare", "force_constraints", "optimise",
    "optimise_geometry", "optimise_sensor", "per_design", "per_heights", "shear_bound_conditioning",
    "sigma_objective", "write_optimise_outputs",
]
