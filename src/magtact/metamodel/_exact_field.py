"""The exact closed-form field as the "B model": no fit error, same interface as a Metamodel.

The Hall point sits at (X, Z) relative to the magnet's centre, affine in the features:
X = a q, Z = Z0 − a p with a = Δz_sat − Δz0 (the load's u_z per unit t) and Z0 the unloaded
height (negative), both affine in H and in the magnet height H_m — from :mod:`magtact.geometry`.
The field is ``magtact.magnetics.cylinder_field`` at (|X|, Z), with B_r along +x:
B_r = sign(X) B_ρ(|X|, Z), an odd, smooth function of X (the cylindrical B_ρ vanishes linearly
on the axis). Where the magnet's radius or height is a design variable of the study, the model
takes its values like a fitted model takes them (arrays broadcasting with t, θ, H).

Derivatives with respect to (X, Z) up to third order come from central finite differences on a
7 × 7 stencil of step h = 20 µm (weights of order 6 for first, 6 for second and 4 for third
derivatives); first derivatives need only the stencil's two axes. The field varies on the scale
of the magnet–sensor distance L ≥ 2 mm, so the truncation error is about (h / L)^4 ≈ 1e-8
relative for third derivatives and the rounding error about ε (L / h)^3 ≈ 1e-10; first
derivatives are accurate to ~1e-12.
"""

from __future__ import annotations

from functools import cached_property
from math import factorial

import numpy as np

from ..study import Study
from ._model import geometry_values
from ._symbols import affine_in_H, feature_jacobian, features, q_hessian

#: Finite-difference step in the Hall position [m].
STEP = 2e-5
#: Distance from the axis, relative to the magnet-point scale, below which B_ρ/ρ is taken as
#: its limit −½ ∂B_z/∂z: the quotient's rounding error (~ε L/ρ) and the limit's truncation
#: error (~(ρ/L)²) are equal near 2e-6, both ~1e-11 relative.
AXIS_BAND = 2e-6
_OFFSETS = np.arange(-3, 4)


def _weights() -> np.ndarray:
    """Central-difference weights (4, 7) for derivative orders 0..3 on offsets −3..3 (unit step)."""
    V = np.array([[k**m / factorial(m) for k in _OFFSETS] for m in range(7)], dtype=float)
    return np.linalg.solve(V, np.eye(7)[:, :4]).T


def _coefficients(fun, study: Study) -> tuple[float, float, float]:
    """(c0, c_H, c_Hm) of a function of the study's geometry that is affine in H and in the
    magnet height: fun(s, H) = c0 + c_H H + c_Hm s.magnet.H_m. Without H_m as a design
    variable c_Hm = 0 and c0 holds the magnet's own height."""
    if "H_m" not in study.geometric_variables:
        return (*affine_in_H(lambda h: fun(study, h), study), 0.0)
    lo, hi = study.geometric_variables["H_m"]
    def at(v):
        sub = study.at(H_m=v)
        return affine_in_H(lambda h: fun(sub, h), study)

    (c0_lo, c1_lo), (c0_mid, c1_mid), (c0_hi, c1_hi) = (at(v) for v in (lo, 0.5 * (lo + hi), hi))
    scale = max(abs(c0_lo), abs(c0_hi), abs(c1_lo) * study.design.H[1])
    slope = (c0_hi - c0_lo) / (hi - lo)
    if not (abs(c1_hi - c1_lo) <= 1e-12 * scale and abs(c1_mid - c1_lo) <= 1e-12 * scale
            and abs(c0_lo + slope * 0.5 * (hi - lo) - c0_mid) <= 1e-12 * scale):
        raise ValueError("the loading path is not affine in the magnet height")
    return c0_lo - slope * lo, c1_lo, slope


#: The last evaluation of the field (arguments, both components): B_r and B_z are asked for at
#: the same points one after the other (the sensitivity needs both), and cost one evaluation.
_LAST: list = [((), None)]


def _both_components(r, Z, R_m, H_m, M_z) -> tuple[np.ndarray, np.ndarray]:
    from ..magnetics import cylinder_field

    args = (r, Z, R_m, H_m, M_z)
    key, value = _LAST[0]
    if len(key) == 5 and all(np.shape(a) == np.shape(b) and np.array_equal(a, b)
                             for a, b in zip(args, key, strict=True)):
        return value
    value = cylinder_field(*args)
    _LAST[0] = (args, value)  # one tuple: a reader sees an old or a new entry, never a mix
    return value


#: The last evaluation of the field with its z-derivatives (see ``_LAST``).
_LAST_JET: list = [((), None)]


def _jet_components(r, Z, R_m, H_m, M_z) -> tuple[np.ndarray, ...]:
    """(B_ρ, B_z, ∂B_ρ/∂z, ∂B_z/∂z) at (r, Z); the last evaluation is kept, as in
    ``_both_components``."""
    from ..magnetics import cylinder_field_dz

    args = (r, Z, R_m, H_m, M_z)
    key, value = _LAST_JET[0]
    if len(key) == 5 and all(np.shape(a) == np.shape(b) and np.array_equal(a, b)
                             for a, b in zip(args, key, strict=True)):
        return value
    value = (*_both_components(*args), *cylinder_field_dz(*args))
    _LAST_JET[0] = (args, value)
    return value


class ExactField:
    """B_r or B_z [T] of the exact cylinder-magnet field, as a function of (t, θ, H).

    Parameters
    ----------
    study : Study
        Geometry of the magnet and the loading path. Where its magnet radius ``R_m`` or height
        ``H_m`` is a design variable, the model depends on it (:attr:`geometry`): the calls take
        its values [m] by name, as :class:`magtact.metamodel.Metamodel` calls do.
    name : {"B_r", "B_z"}
    standoff : float or array_like, optional
        The chip's standoff [m] instead of the study's: an array that broadcasts against the
        ``t, theta`` arrays of the calls puts each point's chip at its own standoff (many chip
        positions in one evaluation).
    M_z : float, optional
        The magnet's axial magnetisation [A/m] instead of the study's (a design's magnet; 1.0
        gives the field per unit magnetisation).

    Notes
    -----
    Offers ``value``, ``grad``, ``hess`` (w.r.t. (t, θ, H)), ``jet`` (w.r.t. the features
    (p, q)) and ``bind`` like :class:`magtact.metamodel.Metamodel`; it has no SymPy expression.
    """

    units = "T"

    def __init__(self, study: Study, name: str, standoff=None, M_z: float | None = None):
        if name not in ("B_r", "B_z"):
            raise ValueError(f"ExactField name must be 'B_r' or 'B_z', got {name!r}")
        from ..geometry import hall_from_magnet_centre, loading_path

        self.study, self.name, self.standoff = study, name, standoff
        self.M_z = study.magnet.M_z if M_z is None else float(M_z)
        self.geometry = tuple(k for k in ("R_m", "H_m") if k in study.geometric_variables)
        self.a0, self.a1, self.a2 = _coefficients(
            lambda s, h: float(loading_path(s, 1.0, 0.0, h)[1]), study)

        def hall(standoff=None):
            return _coefficients(lambda s, h: float(
                hall_from_magnet_centre(s, 0.0, 0.0, h, standoff)[1]), study)

        self.z0, self.z1, self.z2 = hall()
        if standoff is not None:  # the Hall point's height at each standoff
            levels, where = np.unique(np.asarray(standoff, float), return_inverse=True)
            z0 = np.empty(levels.size)
            for i, v in enumerate(levels):
                c0, c1, c2 = hall(float(v))
                if not np.allclose((c1, c2), (self.z1, self.z2), rtol=1e-9, atol=1e-12):
                    raise ValueError("the Hall point's height is not the study's shifted by "
                                     "the standoff")
                z0[i] = c0
            self.z0 = z0[where].reshape(np.shape(standoff))
            if np.ndim(standoff) == 0:  # one chip position: its own coefficients
                self.z0, self.z1, self.z2 = c0, c1, c2
        self.info = {"kind": "exact closed-form field (magtact.magnetics.cylinder_field)"}

    def bind(self, **geometry: float) -> ExactField:
        """The field of the study at fixed values [m] of its geometric design variables
        (``study.at(**geometry)``); a model of (t, θ, H) alone."""
        geometry_values(self.name, self.geometry, geometry)
        return ExactField(self.study.at(**{k: v for k, v in geometry.items()
                                           if k in self.study.geometric_variables}), self.name,
                          self.standoff, self.M_z)

    @cached_property
    def _W(self):
        return _weights()

    def _magnet(self, geometry: dict) -> tuple:
        """(R_m, H_m, M_z) of the magnet: the given values of the design variables, the
        study's own for the rest."""
        m = self.study.magnet
        given = dict(zip(self.geometry, geometry_values(self.name, self.geometry, geometry),
                         strict=True))
        return (np.asarray(given.get("R_m", m.R_m), dtype=float),
                np.asarray(given.get("H_m", m.H_m), dtype=float), self.M_z)

    def _field(self, X, Z, magnet):
        R_m, H_m, M_z = magnet
        br, bz = _both_components(np.abs(X), Z, R_m, H_m, M_z)
        return br * np.sign(X) if self.name == "B_r" else bz

    def _position(self, t, theta, H, magnet):
        t, theta, H, H_m = np.broadcast_arrays(
            *(np.asarray(v, dtype=float) for v in (t, theta, H, magnet[1])))
        a = self.a0 + self.a1 * H + self.a2 * H_m
        pv, qv = features(t, theta)
        return t, theta, H, a, a * qv, self.z0 + self.z1 * H + self.z2 * H_m - a * pv

    def _derivs(self, X, Z, order, magnet):
        """D[i][j] = ∂^(i+j) B / ∂X^i ∂Z^j for i + j ≤ order, each of the shape of X."""
        R_m, H_m, M_z = magnet
        if order == 0:
            return {(0, 0): self._field(X, Z, magnet)}
        o = _OFFSETS * STEP
        W = self._W
        if order == 1:
            return self._first_derivatives(X, Z, magnet)
        F = self._field(X[..., None, None] + o[:, None], Z[..., None, None] + o[None, :],
                        (np.asarray(R_m)[..., None, None], np.asarray(H_m)[..., None, None],
                         M_z))
        return {(i, j): np.einsum("...ab,a,b->...", F, W[i], W[j]) / STEP ** (i + j)
                for i in range(order + 1) for j in range(order + 1 - i)}

    def _first_derivatives(self, X, Z, magnet):
        """Value and first derivatives in (X, Z), exact: the field and its z-derivatives
        (:func:`magtact.magnetics.cylinder_field_dz`) at each point; with ρ = |X| the
        derivatives along ρ follow from the field being curl- and divergence-free,
        ∂B_z/∂ρ = ∂B_ρ/∂z and ∂B_ρ/∂ρ = −B_ρ/ρ − ∂B_z/∂z (on the axis, where B_ρ/ρ → ∂B_ρ/∂ρ,
        ∂B_ρ/∂ρ = −½ ∂B_z/∂z; within ``AXIS_BAND`` of it too)."""
        rho = np.abs(X)
        b_rho, b_z, d_rho, d_z = _jet_components(rho, Z, *magnet)
        sign = np.sign(X)
        # B_ρ/ρ = −½ ∂B_z/∂z + O(ρ²/L²); the quotient itself loses ~ε L/ρ of its precision
        # (B_ρ is computed to ~ε of the field), so close to the axis the limit is the more
        # accurate: below ρ = AXIS_BAND · L both errors are under ~1e-11 (L = √(R_m² + Z²))
        near = rho <= AXIS_BAND * np.hypot(magnet[0], Z)
        with np.errstate(invalid="ignore", divide="ignore"):
            over = np.where(near, -0.5 * d_z, b_rho / np.where(near, 1.0, rho))
        if self.name == "B_r":  # B_r = sign(X) B_ρ(|X|): ∂B_r/∂X = ∂B_ρ/∂ρ
            return {(0, 0): sign * b_rho, (1, 0): -over - d_z, (0, 1): sign * d_rho}
        return {(0, 0): b_z, (1, 0): sign * d_rho, (0, 1): d_z}

    def value(self, t, theta, H, **geometry) -> np.ndarray:
        """Field component [T] at (t, θ, H) (broadcast); ``geometry``: values [m] of the
        design variables it depends on (:attr:`geometry`)."""
        magnet = self._magnet(geometry)
        *_, X, Z = self._position(t, theta, H, magnet)
        return self._field(X, Z, magnet)

    def _chain(self, t, theta, H, order, geometry):
        magnet = self._magnet(geometry)
        t, theta, H, a, X, Z = self._position(t, theta, H, magnet)
        D = self._derivs(X, Z, order, magnet)
        Jq = feature_jacobian(t, theta)[..., 1, :]  # ∂q/∂(t, θ); X = a(H) q
        zero = np.zeros_like(t)
        dX = np.stack([a * Jq[..., 0], a * Jq[..., 1], self.a1 * features(t, theta)[1]],
                      axis=-1)
        dZ = np.stack([-a, zero, self.z1 - self.a1 * t], axis=-1)
        return t, theta, a, Jq, D, dX, dZ

    def grad(self, t, theta, H, **geometry) -> np.ndarray:
        """Gradient w.r.t. (t, θ, H), shape (..., 3)."""
        *_, D, dX, dZ = self._chain(t, theta, H, 1, geometry)
        return D[1, 0][..., None] * dX + D[0, 1][..., None] * dZ

    def hess(self, t, theta, H, **geometry) -> np.ndarray:
        """Hessian w.r.t. (t, θ, H), shape (..., 3, 3)."""
        t, theta, a, Jq, D, dX, dZ = self._chain(t, theta, H, 2, geometry)
        out = (D[2, 0][..., None, None] * dX[..., :, None] * dX[..., None, :]
               + D[1, 1][..., None, None] * (dX[..., :, None] * dZ[..., None, :]
                                             + dZ[..., :, None] * dX[..., None, :])
               + D[0, 2][..., None, None] * dZ[..., :, None] * dZ[..., None, :])
        d2X = np.zeros(t.shape + (3, 3))
        d2X[..., :2, :2] = a[..., None, None] * q_hessian(t, theta)
        d2X[..., :2, 2] = d2X[..., 2, :2] = self.a1 * Jq
        out += D[1, 0][..., None, None] * d2X
        out[..., 0, 2] -= D[0, 1] * self.a1
        out[..., 2, 0] -= D[0, 1] * self.a1
        return out

    def jet(self, t, theta, H, order: int = 1, **geometry) -> list[np.ndarray]:
        """Value and derivatives w.r.t. (p, q) up to ``order`` (≤ 3); see ``Metamodel.jet``.

        ∂/∂p = −a ∂/∂Z and ∂/∂q = a ∂/∂X at fixed H.
        """
        if not 0 <= order <= 3:
            raise ValueError(f"jet order must be 0..3, got {order}")
        magnet = self._magnet(geometry)
        t, theta, H, a, X, Z = self._position(t, theta, H, magnet)
        D = self._derivs(X, Z, order, magnet)
        out = [D[0, 0]]
        for k in range(1, order + 1):
            arr = np.empty(t.shape + (2,) * k)
            for idx in np.ndindex(*(2,) * k):
                n_q = sum(idx)
                n_p = k - n_q
                arr[(...,) + idx] = (-a) ** n_p * a**n_q * D[n_q, n_p]
            out.append(arr)
        return out

    def __repr__(self) -> str:
        return f"ExactField({self.name!r})"
