"""The symbols of every metamodel and the features they are built on.

Responses are functions of the load t, shear angle θ and base height H (docs/method.md §1). The map
(t, θ) → u = (u_r, u_z) is singular at t = 0, so fitted models are built in the *features*

    p = t,   q = t tan θ,   H

which are linear in u at fixed H (u_z = a p, u_r = −a q with a = Δz_sat − Δz0(H) < 0). A model
that is smooth in (p, q, H) is smooth in u, and the sensitivity (docs/method.md §6) computed with
derivatives in (p, q) is finite at t = 0 by construction. The same model in (t, θ, H) follows by
substituting p = t, q = t tan θ.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

#: Non-dimensional load t [-], shear angle θ [rad], base height H [m]. No assumptions on
#: purpose: with real symbols SymPy rewrites sqrt(x**2) as the kink |x|.
t, theta, H = sp.symbols("t theta H")
#: Features p = t [-] and q = t tan θ [-].
p, q = sp.symbols("p q")

#: Symbols of the (t, θ, H) form, in the order of gradients and Hessians.
TTH = (t, theta, H)
#: Symbols of the feature form (p, q, H).
PQH = (p, q, H)

#: Substitution feature form → (t, θ, H) form.
PQ_TO_TTH = {p: t, q: t * sp.tan(theta)}
#: Substitution (t, θ, H) form → feature form (exact where t > 0).
TTH_TO_PQ = {t: p, theta: sp.atan(q / p)}

#: Geometric design variables besides H [m] (magnet radius, magnet height, body radius): a
#: model fitted over them has them as inputs like H; the Jacobian stays one in (p, q).
R_m, H_m, R = sp.symbols("R_m H_m R")
GEOMETRY = (R_m, H_m, R)

#: Every symbol a model may contain, by name.
SYMBOLS: dict[str, sp.Symbol] = {s.name: s for s in (t, theta, H, p, q, *GEOMETRY)}


def features(t, theta) -> tuple[np.ndarray, np.ndarray]:
    """The features (p, q) = (t, t tan θ) of a load point (broadcast arrays)."""
    t, theta = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(theta, dtype=float))
    return t, t * np.tan(theta)


def feature_jacobian(t, theta) -> np.ndarray:
    """∂(p, q)/∂(t, θ), shape (..., 2, 2): rows p, q; columns t, θ.

    .. math:: \\begin{pmatrix} 1 & 0 \\\\ \\tan θ & t \\sec^2 θ \\end{pmatrix}
    """
    t, theta = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(theta, dtype=float))
    J = np.zeros(t.shape + (2, 2))
    J[..., 0, 0] = 1.0
    J[..., 1, 0] = np.tan(theta)
    J[..., 1, 1] = t / np.cos(theta) ** 2
    return J


def q_hessian(t, theta) -> np.ndarray:
    """∂²q/∂(t, θ)², shape (..., 2, 2) (p = t is linear: its Hessian is zero)."""
    t, theta = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(theta, dtype=float))
    sec2 = 1.0 / np.cos(theta) ** 2
    out = np.zeros(t.shape + (2, 2))
    out[..., 0, 1] = out[..., 1, 0] = sec2
    out[..., 1, 1] = 2.0 * t * sec2 * np.tan(theta)
    return out


def affine_in_H(fun, study) -> tuple[float, float]:
    """Coefficients (c0, c1) of a function of H that is affine: fun(H) = c0 + c1 H.

    Checked at the midpoint of the study's H range; the Hall-point features (X, Z) are built
    from these coefficients (docs/method.md §5).
    """
    lo, hi = study.design.H
    c1 = (fun(hi) - fun(lo)) / (hi - lo)
    c0 = fun(lo) - c1 * lo
    mid = 0.5 * (lo + hi)
    scale = max(abs(fun(lo)), abs(fun(hi)))
    if not abs(fun(mid) - (c0 + c1 * mid)) <= 1e-12 * scale:
        raise ValueError("the loading path is not affine in H; the field features do not apply")
    # Rounding leaves ~1e-16 where a coefficient is exactly zero (e.g. H_g = dz_sat + H_m).
    c0 = 0.0 if abs(c0) <= 1e-12 * scale else c0
    c1 = 0.0 if abs(c1) * hi <= 1e-12 * scale else c1
    return float(c0), float(c1)
