"""The model a validation compares with: responses along one loading path.

A :class:`PathModel` maps the vertical magnet displacement u_z [m] of the loading path at one
shear angle θ and one design (H, G) to the four responses B_r, B_z [T] and F_r, F_z [N]. It can be
fed by the metamodels (:meth:`PathModel.from_metamodels`), by a direct simulation of the same
design and θ (:meth:`PathModel.from_simulation`), by tabulated samples
(:meth:`PathModel.from_samples`), or by any function (tests use analytic ones).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from .._errors import MagtactError
from ..geometry import loading_path
from ..study import Study, kpa, mm
from ._io import RESPONSES


@dataclass(frozen=True)
class PathModel:
    """Model responses along the loading path of one design at shear angle ``theta``.

    Attributes
    ----------
    fn : callable
        ``fn(u_z) -> {"B_r": ..., "B_z": ..., "F_r": ..., "F_z": ...}``: u_z [m] of shape (n,)
        to arrays of shape (n,) in T and N.
    theta : float
        Shear angle of the path [rad].
    label : str
        How the model is named in tables and figures.
    u_z_range : tuple of float or None
        (lowest, highest) u_z [m] where the model is defined; None: everywhere.
    """

    fn: Callable[[np.ndarray], Mapping[str, np.ndarray]]
    theta: float
    label: str = "model"
    u_z_range: tuple[float, float] | None = None

    def __call__(self, u_z) -> dict[str, np.ndarray]:
        """The four responses at ``u_z`` [m], shape (n,) each."""
        u_z = np.asarray(u_z, dtype=float)
        out = self.fn(u_z)
        missing = [r for r in RESPONSES if r not in out]
        if missing:
            raise ValueError(f"model {self.label!r} does not give {', '.join(missing)}")
        values = {r: np.broadcast_to(np.asarray(out[r], dtype=float), u_z.shape).copy()
                  for r in RESPONSES}
        for r, v in values.items():
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise MagtactError(f"model {self.label!r} gives a non-finite {r} ({v[bad[0]]}) at "
                                 f"u_z = {mm(u_z.flat[bad[0]]):.6g} mm ({bad.size} of "
                                 f"{v.size} points)")
        return values

    @classmethod
    def from_samples(cls, u_z, values: Mapping[str, np.ndarray], theta: float,
                     label: str = "model") -> PathModel:
        """Interpolate tabulated responses (cubic spline in u_z).

        Parameters
        ----------
        u_z : array_like, shape (n,)
            Strictly monotonic vertical displacements [m], n ≥ 4.
        values : mapping
            ``B_r, B_z`` [T] and ``F_r, F_z`` [N], each of shape (n,).
        theta : float
            Shear angle [rad].
        label : str
            Name of the model.
        """
        from scipy.interpolate import CubicSpline

        u_z = np.asarray(u_z, dtype=float)
        order = np.argsort(u_z)
        if np.any(np.diff(u_z[order]) <= 0):
            raise ValueError("model samples: u_z must be strictly monotonic")
        splines = {r: CubicSpline(u_z[order], np.asarray(values[r], dtype=float)[order])
                   for r in RESPONSES}
        return cls(fn=lambda u: {r: s(u) for r, s in splines.items()}, theta=float(theta),
                   label=label, u_z_range=(float(u_z[order[0]]), float(u_z[order[-1]])))

    @classmethod
    def from_metamodels(cls, models, study: Study, H: float, G: float, theta: float,
                        label: str | None = None) -> PathModel:
        """The metamodels of a study at design (H, G) and shear angle θ.

        Parameters
        ----------
        models : magtact.metamodel.ModelSet
            Metamodels ``B_r, B_z`` [T] and ``f_r, f_z`` [N/Pa] of (t, θ, H).
        study : Study
            The study the metamodels were fitted on (its loading path maps u_z to t).
        H, G : float
            Design [m, Pa].
        theta : float
            Shear angle [rad].

        Notes
        -----
        u_z = t (Δz_sat + H_m − H − H_g) (docs/method.md §1), so t = u_z / u_z(t = 1); F = G f.
        """
        u_z1 = float(loading_path(study, 1.0, theta, H)[1])

        def fn(u_z):
            t = u_z / u_z1
            return {"B_r": models.B_r.value(t, theta, H), "B_z": models.B_z.value(t, theta, H),
                    "F_r": G * models.f_r.value(t, theta, H),
                    "F_z": G * models.f_z.value(t, theta, H)}

        name = label or f"metamodels, H = {mm(H):.3g} mm, G = {kpa(G):.3g} kPa"
        return cls(fn=fn, theta=float(theta), label=name, u_z_range=(u_z1, 0.0))

    @classmethod
    def from_simulation(cls, study: Study, H: float, G: float, theta: float, *,
                        solver: str = "exact", mesh=None, label: str | None = None) -> PathModel:
        """Simulate the design (H, G) at θ directly: field and structural solves.

        B comes from :func:`magtact.magnetics.hall_field` at any requested u_z (``solver``:
        "exact" or "fe"); F from one :func:`magtact.mechanics.simulate_path` at the study's
        load levels, interpolated in u_z by a cubic spline.

        Parameters
        ----------
        study : Study
            Study settings (geometry, material, mesh).
        H, G : float
            Design [m, Pa].
        theta : float
            Shear angle [rad].
        solver : {"exact", "fe"}
            Field solver.
        mesh : optional
            Passed to ``simulate_path``.
        """
        from scipy.interpolate import CubicSpline

        from ..magnetics import hall_field
        from ..mechanics import simulate_path

        path = simulate_path(study, H, theta, G=G, mesh=mesh)
        u_z1 = float(loading_path(study, 1.0, theta, H)[1])
        order = np.argsort(path.u_z)
        forces = {name: CubicSpline(np.asarray(path.u_z)[order], np.asarray(f)[order])
                  for name, f in (("F_r", path.F_r), ("F_z", path.F_z))}

        def fn(u_z):
            B_r, B_z = hall_field(study, u_z / u_z1, theta, H, solver=solver)
            return {"B_r": B_r, "B_z": B_z, **{k: s(u_z) for k, s in forces.items()}}

        name = label or (f"simulation ({solver} field, FE forces), H = {mm(H):.3g} mm, "
                         f"G = {kpa(G):.3g} kPa")
        return cls(fn=fn, theta=float(theta), label=name, u_z_range=(u_z1, 0.0))
