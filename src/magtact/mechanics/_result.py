"""Typed results and errors of the structural solves."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..study import mm


class PathFailed(RuntimeError):
    """A loading path could not be completed.

    Attributes
    ----------
    t : float
        Load level of the step that failed (the smallest step size was reached).
    theta, H : float
        Shear angle [rad] and base height [m] of the path.
    t_converged : float
        Last converged load level.
    partial : PathResult or None
        The path over the load levels reached before the failure (at least two), or None.
    """

    def __init__(self, t: float, theta: float, H: float, t_converged: float, reason: str = "",
                 partial: PathResult | None = None):
        self.t, self.theta, self.H, self.t_converged = t, theta, H, t_converged
        self.partial = partial
        msg = (f"structural path failed at t = {t:.5g} (theta = {theta:.4f} rad, "
               f"H = {mm(H):.4g} mm); last converged t = {t_converged:.5g}")
        super().__init__(msg + (f": {reason}" if reason else ""))


@dataclass(frozen=True)
class PathResult:
    """Reaction forces of the sensor body along one loading path (docs/method.md §3).

    Attributes
    ----------
    t : (n_t,) ndarray
        Load levels, non-dimensional.
    u_r, u_z : (n_t,) ndarray
        Magnet (and upper plate) displacement [m]: u_r ≥ 0 along +x, u_z ≤ 0 down.
    F_r, F_z : (n_t,) ndarray
        Full-body force [N] exerted on the body by its lower support, i.e. the reaction on the
        lower surface: base z = 0 plus the lower plate's contact, twice the half model.
        F_z > 0 when the body is compressed; F_r < 0 when the magnet is pushed along +x
        (the support holds the body back).
    G : float
        Shear modulus [Pa] these forces belong to.
    H, theta : float
        Base height [m] and shear angle [rad].
    newton_iterations, cutbacks, steps : int
        Newton iterations of the solve (linear solves, failed steps included), step cut-backs
        and converged steps.
    wall_time : float
        Wall-clock time of the solve [s].
    n_dofs, n_cells : int
        Size of the half model (displacement DOFs incl. the two plate points; hexahedra).
    mesh : str
        Name of the mesh density.
    timings : dict
        Seconds spent assembling the solid (``solid``) and the contacts (``contact``), in the
        sparse factorisations (``factorization``) and the triangular solves (``solve``).
    jacobians : int
        Tangent matrices assembled and factorised.
    """

    t: np.ndarray
    u_r: np.ndarray
    u_z: np.ndarray
    F_r: np.ndarray
    F_z: np.ndarray
    G: float
    H: float
    theta: float
    newton_iterations: int
    cutbacks: int
    steps: int
    wall_time: float
    n_dofs: int
    n_cells: int
    mesh: str
    timings: dict = field(default_factory=dict)
    jacobians: int = 0

    def scaled(self, G: float) -> PathResult:
        """The same path for shear modulus ``G`` [Pa]: every force × G / self.G (exact)."""
        if not G > 0:
            raise ValueError(f"G must be positive, got {G}")
        k = G / self.G
        return replace(self, F_r=self.F_r * k, F_z=self.F_z * k, G=float(G))
