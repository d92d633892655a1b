"""The domain of the data a study's answers rest on, and the one check of a design against it.

The metamodels are fitted to a DOE over a box of heights (and magnet or body sizes); outside
it they extrapolate, and closed-form GP expressions extrapolate wildly (Γ_r,max of 3.5·10¹⁶ N/T
at H = 12 mm on the MagOne models). Every entry point that takes a design asks
:func:`check_design` first. G and M_z have no such limit: the forces are exactly proportional to
G and the field to M_z (docs/method.md §3, §7).
"""

from __future__ import annotations

from dataclasses import dataclass

from .._errors import MagtactError
from ..study import Study, from_si
from ._dataset import geometry_dims

#: Relative slack on the domain's edges (round-off of a design at a level).
EDGE_RTOL = 1e-9


@dataclass(frozen=True)
class Domain:
    """The box of designs the data covers [m].

    Attributes
    ----------
    H : (float, float)
        The heights.
    geometry : dict of str to (float, float)
        The geometric design variables besides H (``R_m``, ``H_m``, ``R``) the data spans.
    source : str
        Where the box comes from, in words.
    """

    H: tuple[float, float]
    geometry: dict[str, tuple[float, float]]
    source: str

    def describe(self) -> str:
        """The box in mm, e.g. ``H ∈ [3, 7] mm``."""
        parts = [f"{k} ∈ [{from_si(lo, 'mm'):.4g}, {from_si(hi, 'mm'):.4g}] mm"
                 for k, (lo, hi) in {"H": self.H, **self.geometry}.items()]
        return ", ".join(parts)


def domain_of(study: Study, dataset=None) -> Domain:
    """The domain of a study's answers: its design ranges of H and the geometric design
    variables (inside the data its models were fitted to, whose identity check requires it),
    narrowed to the DOE data set's levels when the data set is given."""
    H = tuple(study.design.H)
    geo = dict(study.geometric_variables)
    source = f"the design ranges of study {study.name!r}"
    if dataset is not None and "H" in getattr(dataset, "coords", {}):
        def clip(rng, values):
            return (max(rng[0], float(values.min())), min(rng[1], float(values.max())))

        H = clip(H, dataset["H"].values)
        geo = {k: clip(v, dataset[k].values) if k in geometry_dims(dataset) else v
               for k, v in geo.items()}
        source += " within the DOE data set's levels"
    return Domain(H, geo, source)


def check_design(study: Study, H: float, dataset=None, **geometry: float) -> None:
    """Refuse a design outside the domain of the data its answer rests on (:func:`domain_of`).

    Parameters
    ----------
    study : Study
    H : float
        Base height [m].
    dataset : xarray.Dataset, optional
        The DOE data set the models were fitted to (its levels bound the domain).
    **geometry : float
        ``R_m``, ``H_m``, ``R`` [m] of the design, where the domain spans them.

    Raises
    ------
    MagtactError
        Naming the value, the domain and where it comes from.
    """
    d = domain_of(study, dataset)
    for name, value, (lo, hi) in [("H", H, d.H)] + [
            (k, geometry[k], d.geometry[k]) for k in d.geometry if k in geometry]:
        tol = EDGE_RTOL * max(abs(lo), abs(hi))
        v = float(value)
        if not (lo - tol <= v <= hi + tol):  # NaN is outside too
            raise MagtactError(
                f"the design's {name} = {from_si(v, 'mm'):.6g} mm lies outside the domain of "
                f"the data its answer rests on ({d.describe()}: {d.source}): the metamodels "
                "would extrapolate there; choose a design inside it, or compute a DOE that "
                f"covers it ([design] {name}_mm, magtact doe)")
