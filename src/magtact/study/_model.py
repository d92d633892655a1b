"""Typed, immutable description of a sensor study (SI units inside).

Each TOML section is one frozen dataclass below. A field's metadata says how it is written in a
study file: the key is the field name followed by the unit suffix (``R`` in metres is ``R_mm`` in
millimetres), ``positive`` asks for a value > 0, ``choices`` lists the allowed strings,
``minimum`` and ``maximum`` bound the value as written. Every number is also checked *after* its
conversion to SI against ``bounds``, the range a physical sensor (or a run that finishes) can
have: by default :data:`magtact.study._units.PHYSICAL` of its unit, so no value overflows or
vanishes in the conversion. Adding a setting is adding one field here; loading, validation and
TOML export follow from the metadata.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np
import tomli_w

from ..parts import GRADES, SILICONES, SIZES
from ._units import PHYSICAL, from_si, to_si


def setting(default, unit: str = "", *, positive: bool = False, choices=None,
            integer: bool = False, minimum=None, maximum=None, bounds=None, doc: str = "",
            missing=None):
    """A study setting with its user unit (``default`` is given in SI).

    ``bounds = (low, high)`` is the physical range of the value in SI (inclusive; a zero is
    also accepted when ``minimum`` is 0); default: the range of its unit in
    :data:`magtact.study._units.PHYSICAL`. ``maximum`` bounds the value as written (integers:
    the work a study may ask for). ``missing``: the value a complete study file (``base =
    "none"``) that leaves the key out means, for a setting that files written before it
    existed lack (None: the key is required there).
    """
    if bounds is None and not choices and not integer:
        bounds = PHYSICAL.get(unit)
    return field(default=default, metadata={
        "unit": unit, "positive": positive, "choices": choices, "integer": integer,
        "minimum": minimum, "maximum": maximum, "bounds": bounds, "doc": doc,
        "missing": missing,
    })


def key_of(f) -> str:
    """The TOML key of a dataclass field: its name plus the unit suffix."""
    unit = f.metadata.get("unit", "")
    return f"{f.name}_{unit}" if unit else f.name


#: Named mesh densities of the structural half body, coarse to fine (cells per direction in
#: ``DENSITIES`` of ``magtact/geometry/_body_mesh.py``). "accurate" has twice the default's
#: cells in z and radially, "fine" twice the default's cells in every direction (the reference
#: of bench/results/mechanics_convergence_H*.json).
MESH_DENSITIES = ("coarse", "default", "accurate", "fine")

@dataclass(frozen=True)
class Body:
    """Elastomer body: one cylinder of radius R and height H + H_g (docs/method.md §1)."""

    R: float = setting(6e-3, "mm", positive=True, doc="body radius")
    H_g: float = setting(4.97e-3, "mm", positive=True, doc="upper part height")
    R_g: float = setting(6e-3, "mm", positive=True, doc="radius of the upper part")
    R_h: float = setting(1e-3, "mm", minimum=0.0, doc="radius of the rounded top edge")


@dataclass(frozen=True)
class Magnet:
    """Axially magnetised cylindrical magnet."""

    R_m: float = setting(2.5e-3, "mm", positive=True, doc="magnet radius")
    H_m: float = setting(2e-3, "mm", positive=True, doc="magnet height")
    M_z: float = setting(1.2e6, "A_per_m", positive=True, doc="axial magnetisation")
    placement: str = setting("covered", choices=("covered", "flush"),
                             doc="'covered': H_m/2 of elastomer above, distances to the "
                                 "centre; 'flush': top at the top face, distances to the "
                                 "lower face")
    grade: str = setting("custom", choices=("custom", *GRADES),
                         doc="NdFeB grade (docs/method.md §10): sets M_z = B_r / μ0 with the "
                             "grade's nominal B_r; 'custom': M_z as given")
    size: str = setting("custom", choices=("custom", *SIZES),
                        doc="cylinder size '<diameter>x<height>' in mm: sets R_m and H_m; "
                            "'custom': R_m and H_m as given")


@dataclass(frozen=True)
class Loading:
    """Loading path, friction and Hall saturation (docs/method.md §1)."""

    dz_sat: float = setting(2.97e-3, "mm", positive=True,
                            doc="magnet–sensor distance at which the Hall reading saturates")
    mu_f: float = setting(0.45, positive=True, bounds=(1e-3, 10.0),
                          doc="Coulomb friction coefficient elastomer/plates")
    theta_max: float = setting(math.atan(0.45), "rad", positive=True, bounds=(1e-6, 1.5),
                               doc="largest shear angle; at most atan(mu_f)")


@dataclass(frozen=True)
class Material:
    """Incompressible neo-Hookean elastomer."""

    G_ref: float = setting(29.4e3, "kPa", positive=True,
                           doc="shear modulus of the structural solves (F scales with G)")
    bulk_ratio: float = setting(5000.0, minimum=1000.0, bounds=(1000.0, 1e9),
                                doc="bulk / shear modulus (nearly incompressible)")
    silicone: str = setting("Ecoflex 00-30", choices=("none", *SILICONES),
                            doc="the silicone the sensor is cast from (docs/method.md §10); "
                                "the design card says whether its G range holds each design's "
                                "G; 'none': not named")
    relaxation_g1: float = setting(0.0, minimum=0.0, bounds=(0.0, 100.0),
                                   doc="the silicone's relaxation (docs/method.md §15): G_1 / "
                                       "G_inf of G(t) = G_inf (1 + g1 exp(-t/tau1) + g2 "
                                       "exp(-t/tau2)); 0 with g2: none given (the catalogue's "
                                       "series of the silicone, if it has one)")
    relaxation_tau1: float = setting(1.0, "s", positive=True, bounds=(1e-6, 1e7),
                                     doc="relaxation time of the first term")
    relaxation_g2: float = setting(0.0, minimum=0.0, bounds=(0.0, 100.0),
                                   doc="G_2 / G_inf of the second term")
    relaxation_tau2: float = setting(10.0, "s", positive=True, bounds=(1e-6, 1e7),
                                     doc="relaxation time of the second term")


@dataclass(frozen=True)
class Design:
    """Design space (H, G and, optionally, M_z) and the original design of the published
    sensor (docs/method.md §7)."""

    H: tuple[float, float] = setting((3e-3, 7e-3), "mm", positive=True, doc="range of H")
    G: tuple[float, float] = setting((10e3, 50e3), "kPa", positive=True, doc="range of G")
    M_z: tuple[float, float] = setting((0.0, 0.0), "A_per_m", minimum=0.0, bounds=(1e3, 1e7),
                                       doc="range of the magnetisation M_z (the magnet's "
                                           "grade) as a design variable; [0, 0]: fixed at "
                                           "magnet.M_z")
    R_m: tuple[float, float] = setting((0.0, 0.0), "mm", minimum=0.0,
                                       doc="range of the magnet radius as a design variable; "
                                           "[0, 0]: fixed at magnet.R_m")
    H_m: tuple[float, float] = setting((0.0, 0.0), "mm", minimum=0.0,
                                       doc="range of the magnet height as a design variable; "
                                           "[0, 0]: fixed at magnet.H_m")
    R: tuple[float, float] = setting((0.0, 0.0), "mm", minimum=0.0,
                                     doc="range of the body radius as a design variable; "
                                         "[0, 0]: fixed at body.R")
    standoff: tuple[float, float] = setting(
        (0.0, 3e-3), "mm", minimum=0.0, bounds=(1e-6, 20e-3),
        doc="range of the chip's standoff below the body (a thicker board, a spacer) as a "
            "design variable of the sensor problem; [0, 0]: fixed at hall.standoff_mm")
    grades: tuple[str, ...] = setting(
        tuple(GRADES), choices=tuple(GRADES),
        doc="magnet grades the sensor problem chooses from (catalogue names, each sets M_z); "
            "[]: the study's magnet only")
    silicones: tuple[str, ...] = setting(
        tuple(SILICONES), choices=tuple(SILICONES),
        doc="silicones the sensor problem chooses from (catalogue names, each bounds G to the "
            "range of its cited figures); []: G free over the design range, the body cast from "
            "[material] silicone; a study that sets [material] silicone and not this chooses "
            "that silicone alone", missing=())
    magnet_sizes: tuple[str, ...] = setting(
        tuple(SIZES), choices=tuple(SIZES),
        doc="magnet sizes the sensor problem chooses from (catalogue names '<diameter>x"
            "<height>' in mm; each answered from the bundled data that hold it); []: the "
            "study's magnet only; a study that sets the magnet's size and not this keeps "
            "that magnet", missing=())
    H_original: float = setting(3e-3, "mm", positive=True, doc="H of the original sensor")
    G_original: float = setting(29.4e3, "kPa", positive=True, doc="G of the original sensor")


@dataclass(frozen=True)
class DOE:
    """Full-factorial levels (docs/method.md §4)."""

    n_t: int = setting(21, integer=True, minimum=2, maximum=1001,
                       doc="levels of the non-dimensional load t")
    n_theta: int = setting(5, integer=True, minimum=1, maximum=101, doc="levels of the shear angle")
    n_H: int = setting(5, integer=True, minimum=1, maximum=101, doc="levels of the base height H")
    n_G: int = setting(5, integer=True, minimum=1, maximum=1001,
                       doc="levels of the shear modulus G")
    n_R_m: int = setting(3, integer=True, minimum=2, maximum=21,
                         doc="levels of the magnet radius (when it is a design variable)")
    n_H_m: int = setting(3, integer=True, minimum=2, maximum=21,
                         doc="levels of the magnet height (when it is a design variable)")
    n_R: int = setting(3, integer=True, minimum=2, maximum=21,
                       doc="levels of the body radius (when it is a design variable)")


@dataclass(frozen=True)
class Magnetics:
    """Field solver settings (docs/method.md §2)."""

    solver: str = setting("fe", choices=("fe", "exact"), doc="field solver")
    h_magnet: float = setting(0.1e-3, "mm", positive=True,
                              doc="FE element size at the magnet surface")
    growth_near: float = setting(0.0125, minimum=0.0, bounds=(1e-4, 10.0),
                                 doc="FE size growth per unit distance within `near` of the magnet")
    near: float = setting(13e-3, "mm", positive=True,
                          doc="thickness of the finely graded zone around the magnet (holds the "
                              "Hall point path)")
    growth: float = setting(0.3, positive=True, bounds=(1e-2, 100.0),
                            doc="FE element size growth per unit distance beyond `near` (grading)")
    far_r: float = setting(100.0, positive=True, bounds=(2.0, 1000.0),
                           doc="far boundary radius in units of R_m")
    far_z: float = setting(50.0, positive=True, bounds=(1.0, 1000.0),
                           doc="far boundary half-height in units of H_m")


@dataclass(frozen=True)
class Mechanics:
    """Structural solver settings (docs/method.md §3)."""

    mesh: str = setting("default", choices=MESH_DENSITIES,
                        doc="named mesh density of the hexahedral half body")
    element: str = setting("hex8", choices=("hex8", "hex20", "hex27"),
                           doc="hexahedra of the body: trilinear (hex8, Q1/P0), 20-node "
                               "serendipity (hex20, Q2s/P0) or triquadratic (hex27, Q2/P0) on "
                               "the cells of the mesh density")
    contact: str = setting("nodes", choices=("nodes", "faces"),
                           doc="contact of the body with the plates: at the nodes of its outer "
                               "surface, or integrated at the Gauss points of its faces")
    scale_in_G: bool = setting(True, doc="solve at G_ref and scale forces by G/G_ref")
    solver: str = setting("pardiso", choices=("pardiso", "superlu"),
                          doc="sparse direct solver of the Newton systems")
    threads: int = setting(1, integer=True, minimum=0, maximum=1024,
                           doc="threads of the PARDISO solver (0: library default)")
    contact_penalty: float = setting(5.0, positive=True, bounds=(1e-3, 1e6),
                                     doc="contact penalty relative to the solid's nodal stiffness")
    elastic_slip: float = setting(5e-5, "mm", positive=True, bounds=(1e-12, 1e-3),
                                  doc="allowable elastic slip of sticking contact points")
    magnet_edge_radius: float = setting(6e-4, "mm", minimum=0.0,
                                        doc="radius of the rounded lower edge of the rigid magnet "
                                            "in the structural model (0: sharp)")
    dt_initial: float = setting(0.025, positive=True, bounds=(1e-9, 1.0),
                                doc="first load step (in units of t)")
    dt_min: float = setting(1e-4, positive=True, bounds=(1e-9, 1.0),
                            doc="smallest load step before a path fails")
    dt_max: float = setting(0.1, positive=True, bounds=(1e-9, 1.0), doc="largest load step")
    max_newton: int = setting(12, integer=True, minimum=2, maximum=1000,
                              doc="Newton iterations per step")
    newton_tol: float = setting(1e-6, positive=True, bounds=(1e-15, 0.5),
                                doc="relative residual tolerance of the Newton iterations")


@dataclass(frozen=True)
class Constraints:
    """Force constraints of the design optimisation (docs/method.md §7)."""

    F_r_c: float = setting(-0.25, "N", doc="F_r,min must be at most this (shear capacity)")
    F_z_c: float = setting(5.0, "N", positive=True, doc="F_z,max must be at least this")
    source: str = setting("requirements", choices=("requirements", "values", "reference"),
                          doc="'requirements': the forces of [requirements] (F_r,c = -F_r, "
                              "F_z,c = F_z); 'values': the numbers above; 'reference': the "
                              "original design's")
    G_tolerance: float = setting(0.0, minimum=0.0, maximum=0.5, bounds=(0.0, 0.5),
                                 doc="fabrication tolerance δ of G: the force constraints must "
                                     "hold at G (1 − δ); Γ and σ_F are reported at G (1 + δ)")
    chip_range: bool = setting(False, doc="true: the [hall] chip must stay within its range "
                                          "over each design's stable region (a constraint of "
                                          "the optimisation)")


@dataclass(frozen=True)
class Requirements:
    """The specification the sensor must meet (docs/method.md §10): the forces it must carry
    and read on every loading path without leaving its chip's range, the sample rate, and
    optionally a resolution and a footprint. The defaults are the MagOne sensor's forces."""

    F_z: float = setting(5.0, "N", positive=True, bounds=(1e-3, 1e4),
                         doc="normal force the sensor must read, from 0 to this")
    F_r: float = setting(0.25, "N", positive=True, bounds=(1e-4, 1e3),
                         doc="shear force the sensor must carry and read, from 0 to this")
    rate: float = setting(100.0, "Hz", minimum=0.0, bounds=(1e-3, 1e6),
                          doc="sample rate (full XYZ read) the chip setting must reach; 0: any")
    resolution: float = setting(0.0, "mN", minimum=0.0, bounds=(1e-9, 1e3),
                                doc="largest force noise σ_F (1 σ, worst over the required "
                                    "loads); 0: no target")
    R_max: float = setting(0.0, "mm", minimum=0.0, bounds=(1e-4, 1.0),
                           doc="largest body radius (footprint); 0: no limit")


@dataclass(frozen=True)
class MetamodelSettings:
    """Genetic-programming metamodels (docs/method.md §5); fixed generations and seed:
    reproducible."""

    generations: int = setting(100, integer=True, minimum=1, maximum=100_000,
                               doc="GP generations per fit")
    population: int = setting(600, integer=True, minimum=10, maximum=100_000,
                              doc="GP population size")
    max_length: int = setting(60, integer=True, minimum=3, maximum=200,
                              doc="largest expression (tree nodes)")
    local_iterations: int = setting(5, integer=True, minimum=0, maximum=1000,
                                    doc="Levenberg-Marquardt steps on the constants per evaluation")
    operators: str = setting("smooth", choices=("smooth", "rational"),
                             doc="'smooth': add, sub, mul, div, exp, log, sqrt, tanh; "
                                 "'rational': add, sub, mul, div")
    seed: int = setting(0, integer=True, minimum=0, maximum=2**32 - 1,
                      doc="random seed of the first fit")
    retries: int = setting(2, integer=True, minimum=0, maximum=100,
                           doc="refits with the next seeds when a model fails the guard rails")
    holdout_paths: int = setting(4, integer=True, minimum=0, maximum=10_000,
                                 doc="interior (theta, H) paths held out to measure accuracy")
    b_model: str = setting("fit", choices=("fit", "exact"),
                           doc="'fit': GP models of B_r, B_z; 'exact': the closed-form field")
    threads: int = setting(2, integer=True, minimum=1, maximum=1024, doc="threads of the GP")


#: Definitions of the sensitivity Γ (docs/method.md §6): "jacobian", the total
#: derivative ∂F/∂B through the magnet's displacement, a property of the sensor; "published",
#: the partial derivative in B of a force model F(B_r, B_z, t, θ, H) at fixed (t, θ, H), as in
#: de Boer et al. (Sensors 2017), a property of the fitted expression as much as of the sensor.
SENSITIVITY_DEFINITIONS = ("jacobian", "published")


#: Hall chips with presets (docs/method.md §10), and "custom" for a chip of the user's.
HALL_CHIPS = ("MLX90393", "TLV493D", "TLE493D", "custom")


@dataclass(frozen=True)
class Hall:
    """The 3-axis Hall chip under the magnet: field noise and measuring range per axis
    (docs/method.md §10). A zero takes the chip preset's figure; a preset without a figure
    asks for it."""

    chip: str = setting("MLX90393", choices=HALL_CHIPS,
                        doc="Hall chip preset, or 'custom' (give all four figures)")
    noise_x: float = setting(0.0, "uT", minimum=0.0, bounds=(0.0, 1.0),
                             doc="RMS field noise along x (the shear direction) at your chip "
                                 "setting; 0: the preset's")
    noise_z: float = setting(0.0, "uT", minimum=0.0, bounds=(0.0, 1.0),
                             doc="RMS field noise along z at your chip setting; 0: the preset's")
    range_x: float = setting(0.0, "mT", minimum=0.0, bounds=(0.0, 100.0),
                             doc="measuring range ± along x; 0: the preset's")
    range_z: float = setting(0.0, "mT", minimum=0.0, bounds=(0.0, 100.0),
                             doc="measuring range ± along z; 0: the preset's")
    gain_sel: int = setting(-1, integer=True, minimum=-1, maximum=255,
                            doc="MLX90393 GAIN_SEL (0-7); -1: magtact picks the setting with "
                                "the lowest force noise per design")
    res: int = setting(-1, integer=True, minimum=-1, maximum=255,
                       doc="MLX90393 RES_XYZ (0-3); -1: picked")
    osr: int = setting(-1, integer=True, minimum=-1, maximum=255,
                       doc="MLX90393 OSR (0-3); -1: picked")
    dig_filt: int = setting(-1, integer=True, minimum=-1, maximum=255,
                            doc="MLX90393 DIG_FILT (0-7); -1: picked")
    read_fraction: float = setting(1.0, positive=True, bounds=(1e-3, 1.0),
                                   doc="the picked chip setting must hold the field over the "
                                       "loads t <= read_fraction * t_m of the stable region "
                                       "(1: all of it)")
    standoff: float = setting(0.0, "mm", minimum=0.0, bounds=(1e-6, 20e-3),
                              doc="distance of the chip's sensing point below the body's base "
                                  "(the original design's, and any design's where the standoff "
                                  "is not a design variable)")


@dataclass(frozen=True)
class Sensitivity:
    """How the sensitivity Γ = |∂F/∂B| is defined (docs/method.md §6)."""

    definition: str = setting("jacobian", choices=SENSITIVITY_DEFINITIONS,
                              doc="'jacobian': dF/dB through the magnet displacement (default); "
                                  "'published': partial derivative in B of F(B, t, theta, H) "
                                  "at fixed (t, theta, H), as in the publication")


@dataclass(frozen=True)
class Optimise:
    """Design optimisation (docs/method.md §7): per-design extrema, maps, NSGA-II, reduction."""

    population: int = setting(200, integer=True, minimum=4, maximum=100_000,
                              doc="population of NSGA-II and of box_optimum's evolution")
    seed: int = setting(0, integer=True, minimum=0, maximum=2**32 - 1,
                      doc="random seed of every evolutionary run (NSGA-II, box_optimum)")
    ga_generations: int = setting(15, integer=True, minimum=1, maximum=10_000,
                                  doc="generations of box_optimum's evolution before its "
                                      "trust-region refinement")
    nsga2_generations: int = setting(100, integer=True, minimum=1, maximum=10_000,
                                     doc="NSGA-II generations")
    tol: float = setting(1e-12, positive=True, bounds=(1e-16, 0.1),
                         doc="refinement tolerance (relative)")
    grid_n: int = setting(10, integer=True, minimum=2, maximum=1000,
                          doc="map levels along H and along G")
    sweep_n: int = setting(1001, integer=True, minimum=3, maximum=100_001,
                           doc="heights of the exact reduction's 1D sweep")
    sweep_coarse: int = setting(41, integer=True, minimum=2, maximum=10_001,
                                doc="heights of the sweep solved from full start grids")
    start_t: int = setting(41, integer=True, minimum=2, maximum=1001,
                           doc="start grid along t of the batched per-height solver")
    start_theta: int = setting(21, integer=True, minimum=2, maximum=1001,
                               doc="start grid along theta of the batched per-height solver")
    active_rtol: float = setting(1e-2, positive=True, bounds=(1e-12, 1.0),
                                 doc="a constraint is active when |margin| <= this x |limit|")
    problem: str = setting("sensor", choices=("sensor", "publication"),
                           doc="'sensor': the whole sensor (H, G, magnet grade, standoff, chip "
                               "setting) that meets [requirements] with the least force noise; "
                               "'publication': the publication's (H, G) problem")
    sensor_population: int = setting(60, integer=True, minimum=4, maximum=100_000,
                                     doc="population of NSGA-II in the sensor problem")
    sensor_generations: int = setting(30, integer=True, minimum=1, maximum=10_000,
                                      doc="NSGA-II generations in the sensor problem")
    objective: str = setting("gamma", choices=("gamma", "sigma_F"),
                             doc="'gamma': minimise the sensitivities Γ_r,max, Γ_z,max [N/T] "
                                 "(the publication's); 'sigma_F': the force noise σ_F,r, "
                                 "σ_F,z [N] with the [hall] chip at its setting (docs/method.md "
                                 "§10)")
    geometry_n: int = setting(11, integer=True, minimum=2, maximum=1001,
                              doc="levels of each geometric design variable besides H in the "
                                  "exact reduction's grid")


#: Layouts of a taxel array (docs/method.md §12).
ARRAY_LAYOUTS = ("square", "hexagonal")


@dataclass(frozen=True)
class Array:
    """The taxel array around the sensor, for the neighbours' crosstalk of the error budget
    (docs/method.md §12): every taxel is this sensor, its magnet on its own chip's axis."""

    pitch: float = setting(0.0, "mm", minimum=0.0,
                           doc="centre distance of neighbouring taxels; 0: no array given "
                               "(the budget then assumes touching bodies, pitch = 2 body.R)")
    layout: str = setting("square", choices=ARRAY_LAYOUTS,
                          doc="'square' (8 neighbours in the first ring) or 'hexagonal' (6)")
    rings: int = setting(1, integer=True, minimum=1, maximum=10,
                         doc="rings of neighbours around the taxel")


@dataclass(frozen=True)
class Environment:
    """What moves the field besides the force: temperature and stray fields (docs/method.md
    §12). The cited figures and their sources are in docs/method.md §12."""

    delta_T: float = setting(10.0, "K", positive=True, bounds=(1e-3, 200.0),
                             doc="temperature change the budget quotes its temperature rows "
                                 "at (the rows per kelvin are in budget.json)")
    remanence_tc: float = setting(-0.12e-2, "pct_per_K", bounds=(-1e-2, 1e-2),
                                  doc="reversible temperature coefficient of the magnet's "
                                      "remanence; default: sintered NdFeB, the strong end of "
                                      "the typical -0.09 to -0.12 %/K")
    remanence_tc_tolerance: float = setting(0.03e-2, "pct_per_K", minimum=0.0,
                                            bounds=(0.0, 1e-2),
                                            doc="how well the remanence coefficient is known "
                                                "(the residual after temperature "
                                                "compensation); default: the width of the "
                                                "typical NdFeB range")
    chip_drift: float = setting(0.0, "pct_per_K", bounds=(-1e-2, 1e-2),
                                doc="the Hall chip's sensitivity drift; 0: not modelled (no "
                                    "cited figure)")
    earth_field: float = setting(65e-6, "uT", minimum=0.0, bounds=(0.0, 1e-3),
                                 doc="magnitude of the Earth's field; default: the largest at "
                                     "the Earth's surface (25-65 µT)")
    stray_field: float = setting(0.0, "uT", minimum=0.0, bounds=(0.0, 0.1),
                                 doc="magnitude of a further stray field (steel, motors); 0: "
                                     "none")
    press_time: float = setting(1.0, "s", positive=True, bounds=(1e-4, 1e5),
                                doc="the load history of the time rows (docs/method.md §15): "
                                    "seconds from rest to the full press, and back (the "
                                    "hysteresis row)")
    hold: float = setting(60.0, "s", positive=True, bounds=(1e-4, 1e7),
                          doc="seconds a full press is held at constant force (the creep row)")
    calibrated_on: str = setting("long", choices=("long", "short"),
                                 doc="the modulus the sensor's force map is calibrated on: "
                                     "'long' the long-time G_inf (a slow calibration), 'short' "
                                     "the instantaneous G(0)")


@dataclass(frozen=True)
class Tolerances:
    """Fabrication tolerances (docs/method.md §12, §16): the error budget's Monte Carlo and
    the robust verdict. The spreads of G, the magnet's size, the chip's height and the body's
    height are standard deviations of normal distributions around the nominal value; the
    robust verdict truncates each at ±``coverage`` of them. The magnet's remanence is its
    grade's catalogue range (``remanence`` is the spread of a custom magnet); the temperature,
    the chip's sensitivity and offset and the FE forces' bias are ranges."""

    G: float = setting(0.05, "pct", minimum=0.0, bounds=(0.0, 0.3),
                       doc="spread of the elastomer's shear modulus (relative)")
    remanence: float = setting(0.01, "pct", minimum=0.0, bounds=(0.0, 0.3),
                               doc="spread of the magnet's remanence within its grade "
                                   "(relative)")
    magnet_diameter: float = setting(0.05e-3, "mm", minimum=0.0, bounds=(1e-9, 1e-3),
                                     doc="spread of the magnet's diameter")
    magnet_height: float = setting(0.05e-3, "mm", minimum=0.0, bounds=(1e-9, 1e-3),
                                   doc="spread of the magnet's height")
    chip_lateral: float = setting(0.1e-3, "mm", minimum=0.0, bounds=(1e-9, 2e-3),
                                  doc="spread of the chip's position under the magnet, per "
                                      "horizontal axis")
    chip_vertical: float = setting(0.05e-3, "mm", minimum=0.0, bounds=(1e-9, 1e-3),
                                   doc="spread of the chip's height (and of the magnet's in "
                                       "the cast body)")
    magnet_tilt: float = setting(math.radians(1.0), "deg", minimum=0.0, bounds=(0.0, 0.2),
                                 doc="spread of the magnet's tilt, per horizontal axis")
    samples: int = setting(4000, integer=True, minimum=100, maximum=1_000_000,
                           doc="Monte-Carlo samples")
    seed: int = setting(0, integer=True, minimum=0, maximum=2**32 - 1,
                        doc="seed of the Monte Carlo")
    body_height: float = setting(0.05e-3, "mm", minimum=0.0, bounds=(1e-9, 1e-3),
                                 doc="spread of the body's base height H (the mould and the "
                                     "cast; assumed, no cited figure)")
    coverage: float = setting(3.0, positive=True, bounds=(0.5, 6.0),
                              doc="the robust verdict's tolerance box: each normal spread "
                                  "truncated at ± this many standard deviations")
    temperature_C: tuple[float, float] = setting(
        (10.0, 40.0), bounds=(-60.0, 200.0),
        doc="working temperature range [°C] of the robust verdict: the remanence follows the "
            "grade's coefficient from 20 °C (assumed indoor use, no cited figure)")
    chip_sensitivity: float = setting(0.0, "pct", minimum=0.0, bounds=(0.0, 0.5),
                                      doc="band of the chip's sensitivity (±, relative) over "
                                          "the temperature range; 0: the chip's datasheet "
                                          "figure (MLX90393: 3 %, Table 9 SENSTHD)")
    chip_offset_x: float = setting(0.0, "uT", minimum=0.0, bounds=(0.0, 0.1),
                                   doc="band of the chip's x and y offset (±) over the "
                                       "temperature range; 0: the chip's datasheet figure "
                                       "(MLX90393: 1000 LSB at GAIN_SEL 7, RES 0 = 150 µT, "
                                       "Table 9 OFFSTHD)")
    chip_offset_z: float = setting(0.0, "uT", minimum=0.0, bounds=(0.0, 0.1),
                                   doc="band of the chip's z offset (±); 0: the chip's "
                                       "datasheet figure (MLX90393: 242 µT)")
    fe_force_bias: float = setting(0.05, "pct", minimum=0.0, bounds=(0.0, 0.5),
                                   doc="how far the FE forces may lie above the converged ones "
                                       "(one-sided): the default mesh's F_z(t = 1) at H = 3 mm, "
                                       "+5.0 % (docs/verification.md; +8.4 % at H = 7 mm)")
    robust_samples: int = setting(1024, integer=True, minimum=64, maximum=1_048_576,
                                  doc="units of the robust verdict's quasi-Monte Carlo (a "
                                      "power of 2; split in robust_replicates scrambled Sobol "
                                      "sets)")
    robust_replicates: int = setting(8, integer=True, minimum=2, maximum=1024,
                                     doc="independently scrambled Sobol sets of the yield; "
                                         "their spread gives its confidence interval")
    design_for: str = setting("worst", choices=("worst", "nominal"),
                              doc="the sensor problem's chip constraint and forces at the worst "
                                  "corner of this box ('worst') or at the nominal parts")
    yield_target: float = setting(0.0, minimum=0.0, bounds=(0.0, 1.0),
                                  doc="with design_for = 'worst': design for this fraction of "
                                      "units reading the normal requirement instead of the "
                                      "worst corner (e.g. 0.99); 0: the worst corner")


def holdout_limit(n_theta: int, n_H: int) -> int:
    """Most (θ, H) paths a fit may hold out of ``n_theta × n_H``: the interior ones (all of a
    direction with at most two levels), and never every path (docs/method.md §4)."""
    inner = (n_theta - 2 if n_theta > 2 else n_theta) * (n_H - 2 if n_H > 2 else n_H)
    return min(inner, n_theta * n_H - 1)


@dataclass(frozen=True)
class Study:
    """A complete sensor study. All quantities in SI (m, Pa, N, T, rad, A/m)."""

    name: str = "MagOne"
    description: str = ""
    body: Body = field(default_factory=Body)
    magnet: Magnet = field(default_factory=Magnet)
    loading: Loading = field(default_factory=Loading)
    material: Material = field(default_factory=Material)
    design: Design = field(default_factory=Design)
    doe: DOE = field(default_factory=DOE)
    magnetics: Magnetics = field(default_factory=Magnetics)
    mechanics: Mechanics = field(default_factory=Mechanics)
    requirements: Requirements = field(default_factory=Requirements)
    constraints: Constraints = field(default_factory=Constraints)
    metamodel: MetamodelSettings = field(default_factory=MetamodelSettings)
    sensitivity: Sensitivity = field(default_factory=Sensitivity)
    hall: Hall = field(default_factory=Hall)
    optimise: Optimise = field(default_factory=Optimise)
    array: Array = field(default_factory=Array)
    environment: Environment = field(default_factory=Environment)
    tolerances: Tolerances = field(default_factory=Tolerances)

    def __str__(self) -> str:
        """The sensor, the design ranges and the requirements in a few lines (``to_toml()``:
        every setting)."""
        from .._display import study_rows, text_block

        return text_block(*study_rows(self))

    def _repr_html_(self) -> str:
        from .._display import html_block, study_rows

        return html_block(*study_rows(self))

    # ---- design variables --------------------------------------------------------------------
    @property
    def M_z_variable(self) -> bool:
        """Whether the magnetisation is a design variable (``[design] M_z_A_per_m``)."""
        return self.design.M_z[1] > 0

    @property
    def M_z_bounds(self) -> tuple[float, float]:
        """Range of M_z [A/m]: the design range, or the magnet's own M_z at both ends."""
        return self.design.M_z if self.M_z_variable else (self.magnet.M_z, self.magnet.M_z)

    @property
    def geometric_variables(self) -> dict[str, tuple[float, float]]:
        """The geometric design variables besides H, by name (``R_m``, ``H_m``, ``R``), with
        their ranges [m]; empty when only H (and G, M_z) are design variables."""
        return {k: getattr(self.design, k) for k in GEOMETRY
                if getattr(self.design, k)[1] > 0}

    @property
    def geometry_levels(self) -> dict[str, np.ndarray]:
        """DOE levels [m] of each geometric design variable besides H."""
        return {k: _levels(*rng, getattr(self.doe, f"n_{k}"))
                for k, rng in self.geometric_variables.items()}

    def geometry(self) -> dict[str, float]:
        """The study's own (fixed) values [m] of the geometric design variables besides H."""
        return {k: getattr(getattr(self, GEOMETRY[k]), k) for k in self.geometric_variables}

    def at(self, **values: float) -> Study:
        """This study with geometric design variables fixed: ``values`` [m] by name (``R_m``,
        ``H_m``, ``R``) replace the magnet's or body's value, and the variable's design range is
        cleared. An upper part as wide as the body stays as wide as it."""
        unknown = set(values) - set(GEOMETRY)
        if unknown:
            raise ValueError(f"not geometric design variables: {sorted(unknown)}; "
                             f"choose from {list(GEOMETRY)}")
        magnet = replace(self.magnet, **{k: float(v) for k, v in values.items()
                                         if GEOMETRY[k] == "magnet"})
        body = self.body
        if "R" in values:
            R = float(values["R"])
            body = replace(body, R=R, R_g=R if body.R_g == body.R else min(body.R_g, R))
        design = replace(self.design, **{k: (0.0, 0.0) for k in values})
        return replace(self, magnet=magnet, body=body, design=design)

    def sized(self, name: str) -> Study:
        """This problem with the magnet of catalogue size ``name`` (its R_m and H_m) and no
        other size to choose from (``[design] magnet_sizes`` cleared)."""
        z = SIZES[name]
        return replace(self, magnet=replace(self.magnet, size=name, R_m=z.R_m, H_m=z.H_m),
                       design=replace(self.design, magnet_sizes=()))

    # ---- DOE levels (SI) -------------------------------------------------------------------
    @property
    def t_levels(self) -> np.ndarray:
        """Non-dimensional load levels in [0, 1], shape (n_t,)."""
        return np.linspace(0.0, 1.0, self.doe.n_t)

    @property
    def theta_levels(self) -> np.ndarray:
        """Shear angle levels in [0, θ_max] [rad], shape (n_theta,)."""
        return _levels(0.0, self.loading.theta_max, self.doe.n_theta)

    @property
    def H_levels(self) -> np.ndarray:
        """Base height levels [m], shape (n_H,)."""
        return _levels(*self.design.H, self.doe.n_H)

    @property
    def G_levels(self) -> np.ndarray:
        """Shear modulus levels [Pa], shape (n_G,)."""
        return _levels(*self.design.G, self.doe.n_G)

    def to_toml(self) -> str:
        """The study as TOML text in user units (round-trips through :func:`load_study`)."""
        return study_to_toml(self)


def _levels(lo: float, hi: float, n: int) -> np.ndarray:
    return np.array([lo]) if n == 1 else np.linspace(lo, hi, n)


#: Geometric design variables besides H: name -> the section holding its fixed value.
GEOMETRY: dict[str, str] = {"R_m": "magnet", "H_m": "magnet", "R": "body"}

SECTIONS: tuple[str, ...] = tuple(
    f.name for f in fields(Study) if f.name not in ("name", "description")
)


def study_to_toml(s: Study) -> str:
    """The complete study as TOML in user units (``base = "none"``: nothing implicit)."""
    out: dict = {"base": "none", "name": s.name, "description": s.description}
    for name in SECTIONS:
        sec = getattr(s, name)
        table = {}
        for f in fields(sec):
            value, unit = getattr(sec, f.name), f.metadata["unit"]
            if isinstance(value, tuple):
                value = [v if isinstance(v, str) else _tidy(v, unit) for v in value]
            elif isinstance(value, float):
                value = _tidy(value, unit)
            table[key_of(f)] = value
        out[name] = table
    return tomli_w.dumps(out)


def _tidy(si: float, unit: str) -> float:
    """The shortest user-unit number that converts back to exactly ``si``."""
    for digits in range(12, 18):
        user = float(f"{from_si(si, unit):.{digits}g}")
        if to_si(user, unit) == si:
            return user
    return float(from_si(si, unit))
