"""The exact closed-form field as the "B model": no fit error, same interface as a Metamodel.

The Hall point sits at (X, Z) relative to the magnet's centre, affine in the features:
X = a(H) q, Z = Z0(H) − a(H) p with a(H) = Δz_sat − Δz0(H) (the load's u_z per unit t) and
Z0(H) the unloaded height (negative) — both from :mod:`magtact.geometry`. The field is
``magtact.magnetics.cylinder_field`` at (|X|, Z), with B_r along +x: B_r = sign(X) B_ρ(|X|, Z),
an odd, smooth function of X (the cylindrical B_ρ vanishes linearly on the axis).

Derivatives with respect to (X, Z) up to third order come from central finite differences on a
7 × 7 stencil of step h = 20 µm (weights of order 6 for first, 6 for second and 4 for third
derivatives). The field varies on the scale of the magnet–sensor distance L ≥ 2 mm, so the
truncation error is about (h / L)^4 ≈ 1e-8 relative for third derivatives and the rounding error
about ε (L / h)^3 ≈ 1e-10; first derivatives are accurate to ~1e-12.
"""

from __future__ import annotations

from functools import cached_property
from math import factorial

import numpy as np

from ..study import Study
from ._fit import _affine_in_H
from ._symbols import feature_jacobian, features, q_hessian

#: Finite-difference step in the Hall position [m].
STEP = 2e-5
_OFFSETS = np.arange(-3, 4)


def _weights() -> np.ndarray:
    """Central-difference weights (4, 7) for derivative orders 0..3 on offsets −3..3 (unit step)."""
    V = np.array([[k**m / factorial(m) for k in _OFFSETS] for m in range(7)], dtype=float)
    return np.linalg.solve(V, np.eye(7)[:, :4]).T


class ExactField:
    """B_r or B_z [T] of the exact cylinder-magnet field, as a function of (t, θ, H).

    Parameters
    ----------
    study : Study
        Geometry of the magnet and the loading path.
    name : {"B_r", "B_z"}

    Notes
    -----
    Offers ``value``, ``grad``, ``hess`` (w.r.t. (t, θ, H)) and ``jet`` (w.r.t. the features
    (p, q)) like :class:`magtact.metamodel.Metamodel`; it has no SymPy expression.
    """

    units = "T"

    def __init__(self, study: Study, name: str):
        if name not in ("B_r", "B_z"):
            raise ValueError(f"ExactField name must be 'B_r' or 'B_z', got {name!r}")
        from ..geometry import hall_from_magnet_centre, loading_path

        self.study, self.name = study, name
        self.a0, self.a1 = _affine_in_H(lambda h: float(loading_path(study, 1.0, 0.0, h)[1]),
                                        study)
        self.z0, self.z1 = _affine_in_H(
            lambda h: float(hall_from_magnet_centre(study, 0.0, 0.0, h)[1]), study)
        self.info = {"kind": "exact closed-form field (magtact.magnetics.cylinder_field)"}

    @cached_property
    def _W(self):
        return _weights()

    def _field(self, X, Z):
        from ..magnetics import cylinder_field

        m = self.study.magnet
        br, bz = cylinder_field(np.abs(X), Z, m.R_m, m.H_m, m.M_z)
        return br * np.sign(X) if self.name == "B_r" else bz

    def _position(self, t, theta, H):
        t, theta, H = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (t, theta, H)))
        a = self.a0 + self.a1 * H
        pv, qv = features(t, theta)
        return t, theta, H, a, a * qv, self.z0 + self.z1 * H - a * pv

    def _derivs(self, X, Z, order):
        """D[i][j] = ∂^(i+j) B / ∂X^i ∂Z^j for i + j ≤ order, each of the shape of X."""
        if order == 0:
            return {(0, 0): self._field(X, Z)}
        o = _OFFSETS * STEP
        F = self._field(X[..., None, None] + o[:, None], Z[..., None, None] + o[None, :])
        W = self._W
        return {(i, j): np.einsum("...ab,a,b->...", F, W[i], W[j]) / STEP ** (i + j)
                for i in range(order + 1) for j in range(order + 1 - i)}

    def value(self, t, theta, H) -> np.ndarray:
        """Field component [T] at (t, θ, H) (broadcast)."""
        *_, X, Z = self._position(t, theta, H)
        return self._field(X, Z)

    def _chain(self, t, theta, H, order):
        t, theta, H, a, X, Z = self._position(t, theta, H)
        D = self._derivs(X, Z, order)
        Jq = feature_jacobian(t, theta)[..., 1, :]  # ∂q/∂(t, θ); X = a(H) q
        zero = np.zeros_like(t)
        dX = np.stack([a * Jq[..., 0], a * Jq[..., 1], self.a1 * features(t, theta)[1]],
                      axis=-1)
        dZ = np.stack([-a, zero, self.z1 - self.a1 * t], axis=-1)
        return t, theta, a, Jq, D, dX, dZ

    def grad(self, t, theta, H) -> np.ndarray:
        """Gradient w.r.t. (t, θ, H), shape (..., 3)."""
        *_, D, dX, dZ = self._chain(t, theta, H, 1)
        return D[1, 0][..., None] * dX + D[0, 1][..., None] * dZ

    def hess(self, t, theta, H) -> np.ndarray:
        """Hessian w.r.t. (t, θ, H), shape (..., 3, 3)."""
        t, theta, a, Jq, D, dX, dZ = self._chain(t, theta, H, 2)
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

    def jet(self, t, theta, H, order: int = 1) -> list[np.ndarray]:
        """Value and derivatives w.r.t. (p, q) up to ``order`` (≤ 3); see ``Metamodel.jet``.

        ∂/∂p = −a ∂/∂Z and ∂/∂q = a ∂/∂X at fixed H.
        """
        if not 0 <= order <= 3:
            raise ValueError(f"jet order must be 0..3, got {order}")
        t, theta, H, a, X, Z = self._position(t, theta, H)
        D = self._derivs(X, Z, order)
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
