"""Rules a study keeps beyond each setting's own range: unit mistakes, pairs of settings no
physical sensor has, which key a message blames, and the rules every command applies before
its work (:func:`check_study`, also run by ``magtact study``)."""

from __future__ import annotations

import math

from ._errors import StudyError
from ._model import Study, holdout_limit
from ._units import LABEL, MU0, PLAUSIBLE_KEYS, from_si, unit_mistake

#: Room temperature [°C] a study's temperature change ``[environment] delta_T_K`` starts from
#: (an assumption: the catalogue of ``parts/data/magnets.toml`` states no reference
#: temperature for its remanence).
ROOM_C = 20.0
#: Largest remanence change α ΔT a linear reversible coefficient may describe: a magnet at
#: half its remanence or below is far outside the range where one coefficient holds (an
#: assumption, not a catalogue figure).
MAX_REMANENCE_CHANGE = 0.5

#: For each key a consistency rule names, the other keys that rule reads: when the user's file
#: does not give the named key (its value comes from the base study) but gives one of these,
#: the message blames the key the user wrote.
INVOLVED: dict[str, tuple[str, ...]] = {
    "magnet.R_m_mm": ("body.R_mm", "magnet.size"),
    "body.R_g_mm": ("body.R_mm",),
    "magnet.H_m_mm": ("body.H_g_mm", "magnet.placement", "magnet.size"),
    "body.R_h_mm": ("body.R_mm", "magnet.R_m_mm", "body.H_g_mm", "magnet.size"),
    "loading.dz_sat_mm": ("design.H_mm", "body.H_g_mm", "magnet.H_m_mm", "magnet.placement",
                          "magnet.size"),
    "loading.theta_max_rad": ("loading.mu_f",),
    "mechanics.magnet_edge_radius_mm": ("magnet.R_m_mm", "magnet.H_m_mm", "magnet.size"),
    "magnetics.h_magnet_mm": ("magnet.R_m_mm", "magnet.H_m_mm", "magnet.size"),
    "array.pitch_mm": ("body.R_mm",),
    "design.H_original_mm": ("design.H_mm",),
    "design.G_original_kPa": ("design.G_kPa",),
    "environment.delta_T_K": ("environment.remanence_tc_pct_per_K", "magnet.grade"),
}


def written_keys(data: dict) -> set[str]:
    """The ``section.key`` names a study document gives (those of its tables)."""
    return {f"{name}.{key}" for name, table in data.items() if isinstance(table, dict)
            for key in table}


def blamed(exc: StudyError, written: set[str], source) -> StudyError:
    """``exc`` as it should reach the user: unchanged when the file gives the key it names or
    gives none of the keys its rule reads; else naming the first key of the rule the file
    gives, and saying where the other value came from."""
    if exc.key in written or exc.key not in INVOLVED:
        return exc
    own = next((k for k in INVOLVED[exc.key] if k in written), None)
    if own is None:
        return exc
    return StudyError(own, f"with {exc.key} from the base study (the file does not set it): "
                           f"[{exc.key}] {exc.reason}", source)


def check_parts(grade_name: str, size_name: str, given: dict[str, float],
                keys: dict[str, str], source=None) -> dict[str, float]:
    """The magnet's values its grade and size set, a value also given checked against them:
    the one rule of the study file (``[magnet] grade``, ``size`` with ``M_z_A_per_m``,
    ``R_m_mm``, ``H_m_mm``) and of :meth:`magtact.Result.evaluate` (``grade`` with
    ``M_z_A_per_m``).

    Parameters
    ----------
    grade_name, size_name : str
        Catalogue names, or ``"custom"`` (sets nothing).
    given : dict
        Values the caller also gives (``M_z``, ``R_m``, ``H_m`` → SI).
    keys : dict
        How the caller names ``M_z``, ``R_m``, ``H_m``, ``grade`` and ``size`` in a message.

    Returns
    -------
    dict
        ``M_z`` = B_r / μ0 (the grade's nominal B_r) and ``R_m``, ``H_m`` (the size), SI.

    Raises
    ------
    StudyError
        Naming the given value that conflicts (beyond a relative 1e-9) and the part that sets
        it: "give one of the two".
    """
    from ..parts import grade, size

    values = {}
    if grade_name != "custom":
        values["M_z"] = grade(grade_name).M_z(MU0)[0]
    if size_name != "custom":
        sz = size(size_name)
        values |= {"R_m": sz.R_m, "H_m": sz.H_m}
    units = {"M_z": "A_per_m", "R_m": "mm", "H_m": "mm"}
    for name, value in values.items():
        if name in given and not math.isclose(given[name], value, rel_tol=1e-9):
            what = "grade" if name == "M_z" else "size"
            unit = units[name]
            part = grade_name if what == "grade" else size_name
            raise StudyError(keys[name], f"{from_si(given[name], unit):g} conflicts with "
                                         f"{keys[what]} = {part!r} ({from_si(value, unit):.6g} "
                                         f"{LABEL.get(unit, unit)}); give one of the two", source)
    return values


def check_unit(full: str, name: str, unit: str, value, si, source) -> None:
    """Refuse a value of a key of :data:`magtact.study._units.PLAUSIBLE_KEYS` that looks like
    a unit mistake (:func:`magtact.study._units.unit_mistake`), naming the key as written.

    ``full``: the key as written (``design.G_kPa``); ``name``: ``section.setting``
    (``design.G``); ``value``: as written; ``si``: the same in SI.
    """
    if name not in PLAUSIBLE_KEYS:
        return
    hint = unit_mistake(unit, value, si)
    if hint is not None:
        shown = value if not isinstance(value, list | tuple) else list(value)
        raise StudyError(full, f"= {shown!r}: {hint}", source)


def unit_hint(name: str, unit: str, value, si) -> str:
    """``": <why>; did you give <unit>?"`` for a value outside its physical bounds that a
    neighbouring unit would make plausible (keys of :data:`PLAUSIBLE_KEYS` only), else ``""``."""
    hint = unit_mistake(unit, value, si) if name in PLAUSIBLE_KEYS else None
    return "" if hint is None else f": {hint}"


def check_physical(s: Study, source) -> None:
    """Pairs of settings that no physical sensor has, each message naming a key to change.

    * The temperature change and the remanence's coefficient: the change α ΔT must stay
      within :data:`MAX_REMANENCE_CHANGE` (a linear coefficient holds for small changes), and
      ΔT from :data:`ROOM_C` must stay within the magnet's largest working temperature
      (:func:`working_limit`; ``parts/data/magnets.toml``: 80 °C for the N series).
    """
    env = s.environment
    change = env.remanence_tc * env.delta_T
    if abs(change) > MAX_REMANENCE_CHANGE:
        raise StudyError("environment.delta_T_K",
                         f"a temperature change of {env.delta_T:g} K with "
                         f"environment.remanence_tc_pct_per_K = "
                         f"{from_si(env.remanence_tc, 'pct_per_K'):g} changes the remanence by "
                         f"{100 * change:+.3g} %: no magnet keeps a linear reversible "
                         f"coefficient that far (at most ±{100 * MAX_REMANENCE_CHANGE:g} % is "
                         "accepted); give a smaller temperature change or coefficient", source)
    limit = working_limit(s)
    if limit is not None and env.delta_T > limit[0] - ROOM_C:
        raise StudyError("environment.delta_T_K",
                         f"{env.delta_T:g} K above {ROOM_C:g} °C takes the magnet ({limit[1]}) "
                         f"beyond its working temperature of {limit[0]:g} °C (the catalogue's "
                         f"limit); at most {limit[0] - ROOM_C:g} K", source)


def working_limit(s: Study) -> tuple[float, str] | None:
    """The magnet's largest working temperature [°C] and what it is taken as: its catalogue
    grade's, or, for a custom magnet whose remanence μ0 M_z is at least the weakest catalogue
    grade's (sintered NdFeB; ``parts/data/magnets.toml`` lists the N series only), the N
    series' limit; None for a weaker custom magnet (its material is not known)."""
    from ..parts import GRADES, grade

    mg = s.magnet
    if mg.grade != "custom":
        return grade(mg.grade).max_temperature_C, f"magnet.grade = {mg.grade!r}"
    weakest = min(GRADES.values(), key=lambda g: g.B_r_min)
    B_r = MU0 * mg.M_z
    if B_r < weakest.B_r_min:
        return None
    top = max(g.max_temperature_C for g in GRADES.values())
    return top, (f"custom, B_r = μ0 M_z = {B_r:.3g} T: sintered NdFeB, taken as the "
                 f"catalogue's N series")


def check_field_mesh(s: Study, source=None) -> None:
    """The field's FE mesh settings among themselves: the far boundary must enclose the magnet
    and its finely meshed near zone (radially far_r · R_m > R_m + near; axially
    far_z · H_m > H_m / 2 + near).

    Raises
    ------
    StudyError
        Naming ``magnetics.far_r`` or ``magnetics.far_z`` and the size it must exceed.
    """
    m, f = s.magnet, s.magnetics
    if f.far_r * m.R_m <= m.R_m + f.near:
        raise StudyError("magnetics.far_r", f"the far boundary r = far_r·R_m must lie beyond "
                                            f"the near zone (R_m + near = "
                                            f"{from_si(m.R_m + f.near, 'mm'):g} mm), got far_r = "
                                            f"{f.far_r:g}", source)
    if f.far_z * m.H_m <= 0.5 * m.H_m + f.near:
        raise StudyError("magnetics.far_z", f"the far boundary z = ±far_z·H_m must lie beyond "
                                            f"the near zone (H_m/2 + near = "
                                            f"{from_si(0.5 * m.H_m + f.near, 'mm'):g} mm), got "
                                            f"far_z = {f.far_z:g}", source)


def near_zone_reach(s: Study) -> float:
    """The farthest the Hall point gets from the magnet [m] over the DOE's paths (every t, θ and
    H level): the distance from the magnet's surface, with the chip's standoff, as the field
    solver measures it (docs/method.md §1: u_z = t (Δz_sat − Δz0), u_r = −u_z tan θ, the Hall
    point at x = −u_r below the magnet's centre)."""
    import numpy as np

    b, mg, ld = s.body, s.magnet, s.loading
    t, th, H = np.meshgrid(s.t_levels, s.theta_levels, s.H_levels, indexing="ij")
    d0 = H + b.H_g - mg.H_m  # unloaded magnet–sensor distance Δz0
    u_z = t * (ld.dz_sat - d0)
    u_r = -u_z * np.tan(th)
    centre = d0 + (0.0 if mg.placement == "covered" else mg.H_m / 2) + u_z + s.hall.standoff
    gap = np.hypot(np.maximum(np.abs(u_r) - mg.R_m, 0.0), np.maximum(centre - mg.H_m / 2, 0.0))
    return float(gap.max())


def check_near_zone(s: Study, source=None) -> None:
    """The finely meshed zone around the magnet (``[magnetics] near_mm``) must reach the Hall
    point on every path of the DOE (:func:`near_zone_reach`).

    Raises
    ------
    StudyError
        Naming ``magnetics.near_mm``, the reach needed and the setting.
    """
    reach = near_zone_reach(s)
    if reach > s.magnetics.near:
        raise StudyError("magnetics.near_mm",
                         f"the Hall point reaches {from_si(reach, 'mm'):.4g} mm from the magnet "
                         f"on the DOE's paths, beyond the finely meshed zone near_mm = "
                         f"{from_si(s.magnetics.near, 'mm'):g}; increase near_mm", source)


def check_holdout(s: Study, n_theta: int | None = None, n_H: int | None = None,
                  data: str | None = None, source: str | None = None) -> None:
    """Refuse, before any work, more held-out paths (``[metamodel] holdout_paths``) than a fit
    can hold out of the DOE's (θ, H) paths: those of the data set ``data`` (``n_theta × n_H``
    levels) when given, else those the study's ``[doe]`` asks for. ``source``: the study file
    (default: the study's name).

    Raises
    ------
    StudyError
        Naming the setting, the number of paths and where they come from.
    """
    n_theta = s.doe.n_theta if n_theta is None else n_theta
    n_H = s.doe.n_H if n_H is None else n_H
    n, most = s.metamodel.holdout_paths, holdout_limit(n_theta, n_H)
    if n > most:
        of = (f"the data set {data} has {n_theta} × {n_H}" if data is not None else
              f"the DOE's {n_theta} × {n_H} (doe.n_theta × doe.n_H)")
        raise StudyError("metamodel.holdout_paths", f"{n} held-out paths, but {of} (θ, H) "
                                                    f"paths allow at most {most} (interior "
                                                    "paths, leaving some to fit)",
                         source or f"study {s.name!r}")


#: Largest required force a body can be asked to carry, in G_max π R² (the stiffest modulus
#: of the design range times the body's base area): a neo-Hookean body compressed to half its
#: height carries 3.5 G π R² (σ = G (λ − λ⁻²) at λ = 0.5), beyond the stable region of any
#: design; ten is far above every design the study can reach (the MagOne study's largest
#: reachable F_z is 3.6 G_max π R²).
MAX_LOAD_FACTOR = 10.0


def check_requirements(s: Study, source: str | None = None) -> None:
    """The required forces (``[requirements] F_z_N``, ``F_r_N``) against what a body of the
    study can carry at all: at most :data:`MAX_LOAD_FACTOR` × G_max π R² (G_max the upper
    bound of ``[design] G_kPa``, R the body's radius or its largest design value); a value
    that is plausible in mN says so.

    Raises
    ------
    StudyError
        Naming the requirement, the limit and the likely unit.
    """
    R = s.geometric_variables.get("R", (s.body.R, s.body.R))[1]
    G_max = s.design.G[1]
    limit = MAX_LOAD_FACTOR * G_max * math.pi * R ** 2
    r = s.requirements
    for key, value in (("requirements.F_z_N", r.F_z), ("requirements.F_r_N", r.F_r)):
        if value > limit:
            hint = "; did you give mN?" if value * 1e-3 <= limit else ""
            raise StudyError(key, f"= {value:g} N is more than a body of radius "
                                  f"{from_si(R, 'mm'):g} mm can carry at the stiffest G of the "
                                  f"design range ({from_si(G_max, 'kPa'):g} kPa): at most about "
                                  f"{MAX_LOAD_FACTOR:g} G π R² = {limit:.3g} N (half its height "
                                  f"in compression carries 3.5 G π R²){hint}", source)


def check_study(s: Study, source: str | None = None) -> None:
    """Every rule a command applies to a study before its work, in one place: ``magtact
    study`` and ``magtact run`` call it, so a study the check accepts is one the commands
    accept.

    * held-out paths within what the study's DOE allows (:func:`check_holdout`);
    * the required forces within what a body of the study can carry
      (:func:`check_requirements`);
    * the field's FE mesh settings among themselves (:func:`check_field_mesh`) and the near
      zone around the magnet against the Hall point's reach (:func:`check_near_zone`), when the
      field is solved by FE (``[magnetics] solver = "fe"``).

    Raises
    ------
    StudyError
        Naming the key to change.
    """
    check_holdout(s, source=source)
    check_requirements(s, source or f"study {s.name!r}")
    if s.magnetics.solver == "fe":
        check_field_mesh(s, source or f"study {s.name!r}")
        check_near_zone(s, source or f"study {s.name!r}")
