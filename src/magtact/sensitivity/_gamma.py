"""Sensitivity of force to field, Γ (docs/method.md §6), and its derivatives for the optimiser.

Derivation
----------
At fixed design H the responses are functions of the magnet displacement u = (u_r, u_z). The
features p = t, q = t tan θ are linear in u (u_z = a p, u_r = −a q, a = Δz_sat − Δz0(H)), so
with x = (p, q) and the constant matrix K = ∂x/∂u,

    ∂F/∂B = (∂F/∂u)(∂B/∂u)⁻¹ = (∂F/∂x K)(∂B/∂x K)⁻¹ = (∂F/∂x)(∂B/∂x)⁻¹.

With J = ∂(B_r, B_z)/∂(p, q) and D = det J,

    ∂f/∂B = [f_p B_z,q − f_q B_z,p,  f_q B_r,p − f_p B_r,q] / D,     γ = |∂f/∂B|,

and Γ = G γ [N/T] because F = G f. Everything is evaluated at (p, q) = (t, t tan θ): nothing
divides by t, so Γ is finite at t = 0 and equals its limit t → 0 whenever the models are smooth
in u (the fitted models are, by construction). The map (t, θ) → (p, q) enters only the chain rule
of the derivatives with respect to (t, θ) the optimiser asks for:

    ∇_(t,θ) g = Jxᵀ ∇_x g,   ∇²_(t,θ) g = Jxᵀ ∇²_x g Jx + g_q ∇²_(t,θ) q,
    Jx = [[1, 0], [tan θ, t sec²θ]],  ∇²_(t,θ) q = [[0, sec²θ], [sec²θ, 2 t sec²θ tan θ]].
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..metamodel import ModelSet, feature_jacobian, q_hessian

#: Names served by :class:`Responses`: f = F / G [N/Pa] and γ = Γ / G [N/(T·Pa)].
NAMES = ("f_r", "f_z", "gamma_r", "gamma_z")


def through_displacement(dF_dx, dB_dx):
    """∂F/∂B = (∂F/∂x)(∂B/∂x)⁻¹ for any coordinates x of the displacement (..., 2, 2).

    Works on NumPy arrays (stacked, rows F or B, columns x) and on SymPy matrices alike.
    """
    if isinstance(dB_dx, sp.MatrixBase):
        return dF_dx * dB_dx.inv()
    # the inverse of each 2 × 2 block in closed form, adj(J) / det J: a stacked
    # ``numpy.linalg.inv`` costs a LAPACK call per block
    a, b = dB_dx[..., 0, 0], dB_dx[..., 0, 1]
    c, d = dB_dx[..., 1, 0], dB_dx[..., 1, 1]
    det = a * d - b * c
    f, g = dF_dx[..., 0], dF_dx[..., 1]  # (..., rows of F)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.stack([(f * d[..., None] - g * c[..., None]),
                        (g * a[..., None] - f * b[..., None])], axis=-1) / det[..., None, None]
    return out


def row_norms(S):
    """Γ_r, Γ_z: the Euclidean norms of the rows (F_r, F_z) of ∂F/∂B (..., 2, 2)."""
    return np.hypot(S[..., 0, 0], S[..., 0, 1]), np.hypot(S[..., 1, 0], S[..., 1, 1])


def _phi_functions():
    """γ of v = (f_p, f_q, Br_p, Br_q, Bz_p, Bz_q), with its 1st and 2nd derivatives."""
    v = sp.symbols("fp fq brp brq bzp bzq", real=True)
    fp, fq, brp, brq, bzp, bzq = v
    s = through_displacement(sp.Matrix([[fp, fq]]), sp.Matrix([[brp, brq], [bzp, bzq]]))
    phi = sp.sqrt(sp.cancel(s[0]) ** 2 + sp.cancel(s[1]) ** 2)
    d1 = [sp.diff(phi, a) for a in v]
    d2 = [[sp.diff(g, a) for a in v] for g in d1]
    return (sp.lambdify(v, phi, "numpy", cse=True), sp.lambdify(v, d1, "numpy", cse=True),
            sp.lambdify(v, d2, "numpy", cse=True))


def _phi():
    """:func:`_phi_functions` as written out by ``scripts/make_phi.py`` (the derivation takes
    seconds; its code is checked against a fresh one by the tests)."""
    from ._phi_code import phi, phi_d1, phi_d2

    return phi, phi_d1, phi_d2


def _stack(nested, shape, tail):
    """Nested list of broadcastable arrays → array of shape (*shape, *tail)."""
    flat = [nested]
    for _ in tail:
        flat = [v for row in flat for v in row]
    out = np.empty(shape + tail)
    for k, v in enumerate(flat):
        out[(...,) + np.unravel_index(k, tail)] = np.broadcast_to(v, shape)
    return out


def _jets(models: ModelSet, t, theta, H, order: int):
    """Jets w.r.t. (p, q) of f_r, f_z, B_r, B_z up to ``order`` (see ``Metamodel.jet``)."""
    return {k: m.jet(t, theta, H, order) for k, m in models.items()}


def dF_dB(models: ModelSet, t, theta, H, G=1.0) -> np.ndarray:
    """∂F/∂B at fixed design under the model set's definition, shape (..., 2, 2) [N/T].

    Rows (F_r, F_z), columns (B_r, B_z); arguments broadcast (t [-], θ [rad], H [m], G [Pa]).
    For ``models.definition == "jacobian"`` the total derivative through the displacement,
    (∂F/∂u)(∂B/∂u)⁻¹; for ``"published"`` the partial derivatives of the force models
    F(B_r, B_z, t, θ, H) in B at fixed (t, θ, H), evaluated on the sensor's path.
    """
    G = np.asarray(G, dtype=float)[..., None, None]
    if models.definition == "published":
        rows = [[jet[0] for jet in models[f].partials(t, theta, H, 0)] for f in ("f_r", "f_z")]
        return G * _stack(rows, np.broadcast_shapes(*(np.shape(v) for r in rows for v in r)),
                          (2, 2))
    jets = _jets(models, t, theta, H, 1)
    J = np.stack([jets["B_r"][1], jets["B_z"][1]], axis=-2)  # (..., 2 [B], 2 [p, q])
    dfx = np.stack([jets["f_r"][1], jets["f_z"][1]], axis=-2)  # (..., 2 [f], 2 [p, q])
    return G * through_displacement(dfx, J)


def gamma(models: ModelSet, t, theta, H, G) -> tuple[np.ndarray, np.ndarray]:
    """Sensitivities Γ_r, Γ_z [N/T] at (t, θ, H, G) (broadcast).

    Γ_r = |∂F_r/∂B|, Γ_z = |∂F_z/∂B| (docs/method.md §6) under the model set's definition
    (see :func:`dF_dB`); finite at t = 0 (see the module notes).
    """
    return row_norms(dF_dB(models, t, theta, H, G))


class Responses:
    """Compiled responses f_r, f_z, γ_r, γ_z (per unit G) and their derivatives in (t, θ).

    ``Responses(models).at(H)`` fixes the design height H [m] and serves, vectorised over arrays
    ``t`` and ``theta`` of any broadcastable shape S:

    - ``value(name, t, theta)`` → shape S,
    - ``grad(name, t, theta)`` → shape S + (2,), derivatives w.r.t. (t, θ),
    - ``hess(name, t, theta)`` → shape S + (2, 2),

    for ``name`` in ``"f_r", "f_z"`` [N/Pa] and ``"gamma_r", "gamma_z"`` [N/(T·Pa)]. Multiply by
    G [Pa] for F [N] and Γ [N/T]; G does not change where the extrema are. ``H`` may also be an
    array broadcasting against ``t`` and ``theta`` (many designs in one call).

    Derivatives are exact: those of f come from the symbolic models; those of γ from the
    symbolic first to third derivatives of f and B w.r.t. the features (p, q) by the chain rule
    (see the module notes), so they are finite at t = 0. γ = |∂f/∂B| is not differentiable
    where both components of ∂f/∂B vanish (γ = 0), as any norm.

    Examples
    --------
    >>> r = Responses(models).at(4e-3)                       # doctest: +SKIP
    >>> Gamma_r = 20e3 * r.value("gamma_r", t, theta)         # doctest: +SKIP
    >>> g, h = r.grad("f_r", t, theta), r.hess("f_r", t, theta)  # doctest: +SKIP
    """

    def __init__(self, models: ModelSet, noise: tuple[float, float] | None = None):
        self.models = models
        #: (σ_x, σ_z) [T]: with it, γ_r, γ_z are the force noise per unit G [N/Pa],
        #: √(J_kx² σ_x² + J_kz² σ_z²) / G (docs/method.md §10) instead of |∂f/∂B|.
        self.noise = None if noise is None else (float(noise[0]), float(noise[1]))
        if self.noise is not None and not all(v > 0 for v in self.noise):
            raise ValueError(f"noise must be two RMS field noises > 0 [T], got {noise!r}")

    def at(self, H, **geometry) -> ResponsesAtH:
        """The responses at design height ``H`` [m] (a float, or an array that broadcasts
        against the ``t, theta`` arrays of the calls, for many designs at once) and, for
        models over geometric design variables, at their values ``geometry`` [m] (floats or
        arrays like ``H``)."""
        if self.models.definition == "published":
            if geometry:
                raise ValueError("the published sensitivity definition has no geometric "
                                 "design variables")
            if self.noise is not None:
                raise ValueError("the force noise needs the Jacobian sensitivity definition")
            return PublishedResponsesAtH(self.models, H)
        out = ResponsesAtH(self.models, H, **geometry)
        out.noise = self.noise
        return out

    @property
    def definition(self) -> str:
        """The sensitivity definition of the models (``"jacobian"`` or ``"published"``)."""
        return self.models.definition


class ResponsesAtH:
    """Responses at design height(s) H [m] (and geometry); see :class:`Responses`."""

    #: (σ_x, σ_z) [T] weighting the field axes (see :class:`Responses`); None: Γ.
    noise: tuple[float, float] | None = None

    def __init__(self, models: ModelSet, H, **geometry):
        self.models = models
        self.H = float(H) if np.ndim(H) == 0 else np.asarray(H, dtype=float)
        self.geometry = geometry

    def _check(self, name):
        if name not in NAMES:
            raise ValueError(f"unknown response {name!r}; choose from {list(NAMES)}")

    def value(self, name: str, t, theta) -> np.ndarray:
        """Value of ``name`` at (t, θ), shape of the broadcast inputs."""
        self._check(name)
        if name in ("f_r", "f_z"):
            return self.models[name].value(t, theta, self.H, **self.geometry)
        return self._gamma_jet(name, t, theta, 0)[0]

    def grad(self, name: str, t, theta) -> np.ndarray:
        """Gradient of ``name`` w.r.t. (t, θ), shape (..., 2)."""
        self._check(name)
        if name in ("f_r", "f_z"):
            return self.models[name].grad(t, theta, self.H, **self.geometry)[..., :2]
        _, gx = self._gamma_jet(name, t, theta, 1)
        return _to_ttheta(t, theta, gx)

    def hess(self, name: str, t, theta) -> np.ndarray:
        """Hessian of ``name`` w.r.t. (t, θ), shape (..., 2, 2)."""
        self._check(name)
        if name in ("f_r", "f_z"):
            return self.models[name].hess(t, theta, self.H, **self.geometry)[..., :2, :2]
        _, gx, hx = self._gamma_jet(name, t, theta, 2)
        return _to_ttheta_hess(t, theta, gx, hx)

    def _gamma_jet(self, name, t, theta, order):
        """γ and its derivatives w.r.t. x = (p, q) up to ``order`` (≤ 2)."""
        f = "f_r" if name == "gamma_r" else "f_z"
        jf, jr, jz = (self.models[k].jet(t, theta, self.H, order + 1, **self.geometry)
                      for k in (f, "B_r", "B_z"))
        if self.noise is not None:  # B/σ: the row norm of J diag(σ), the force noise per G
            jr = [d / self.noise[0] for d in jr]
            jz = [d / self.noise[1] for d in jz]
        # v_i = first derivatives, shape (..., 6); dv = their x-gradients (..., 6, 2); ...
        v = np.concatenate([jf[1], jr[1], jz[1]], axis=-1)
        shape = v.shape[:-1]
        phi, dphi, d2phi = _phi()
        args = [v[..., i] for i in range(6)]
        out = [np.broadcast_to(phi(*args), shape)]
        if order >= 1:
            dv = np.concatenate([jf[2], jr[2], jz[2]], axis=-2)  # (..., 6, 2)
            Phi1 = _stack(dphi(*args), shape, (6,))
            out.append(np.einsum("...i,...ik->...k", Phi1, dv))
        if order >= 2:
            d2v = np.concatenate([jf[3], jr[3], jz[3]], axis=-3)  # (..., 6, 2, 2)
            Phi2 = _stack(d2phi(*args), shape, (6, 6))
            out.append(np.einsum("...ij,...ik,...jl->...kl", Phi2, dv, dv)
                       + np.einsum("...i,...ikl->...kl", Phi1, d2v))
        return out


class PublishedResponsesAtH(ResponsesAtH):
    """Responses at height(s) H under the published definition; see :class:`Responses`.

    The forces are the field-force models composed with the path, f = f̂(B(p, q, H), p, q, H),
    and γ = |∂f̂/∂B| at fixed (p, q, H) (equivalently fixed (t, θ, H)), composed with the path.
    With s = (s_r, s_z) = ∂f̂/∂(B_r, B_z) along the path, γ = |s| and

        ∇γ = Σ_k s_k ∇s_k / γ,   ∇²γ = (Σ_k ∇s_k ∇s_kᵀ + s_k ∇²s_k) / γ − ∇γ ∇γᵀ / γ,

    with ∇ in (p, q), converted to (t, θ) like the Jacobian's.
    """

    def _jet(self, name, t, theta, order):
        if name in ("f_r", "f_z"):
            return self.models[name].jet(t, theta, self.H, order)
        f = "f_r" if name == "gamma_r" else "f_z"
        (sr, sz) = self.models[f].partials(t, theta, self.H, order)
        g = np.hypot(sr[0], sz[0])  # the row norm of ∂f/∂B, as in row_norms
        out = [g]
        if order >= 1:
            with np.errstate(invalid="ignore", divide="ignore"):
                dg = (sr[0][..., None] * sr[1] + sz[0][..., None] * sz[1]) / g[..., None]
            out.append(dg)
        if order >= 2:
            outer = (np.einsum("...i,...j->...ij", sr[1], sr[1])
                     + np.einsum("...i,...j->...ij", sz[1], sz[1])
                     + sr[0][..., None, None] * sr[2] + sz[0][..., None, None] * sz[2])
            with np.errstate(invalid="ignore", divide="ignore"):
                out.append((outer - np.einsum("...i,...j->...ij", dg, dg))
                           / g[..., None, None])
        return out

    def value(self, name: str, t, theta) -> np.ndarray:
        self._check(name)
        return self._jet(name, t, theta, 0)[0]

    def grad(self, name: str, t, theta) -> np.ndarray:
        self._check(name)
        return _to_ttheta(t, theta, self._jet(name, t, theta, 1)[1])

    def hess(self, name: str, t, theta) -> np.ndarray:
        self._check(name)
        _, gx, hx = self._jet(name, t, theta, 2)
        return _to_ttheta_hess(t, theta, gx, hx)


def _to_ttheta(t, theta, gx):
    """∇_(t,θ) g = Jxᵀ ∇_x g."""
    return np.einsum("...ki,...k->...i", feature_jacobian(t, theta), gx)


def _to_ttheta_hess(t, theta, gx, hx):
    """∇²_(t,θ) g = Jxᵀ ∇²_x g Jx + g_q ∇²_(t,θ) q."""
    J = feature_jacobian(t, theta)
    return (np.einsum("...ki,...kl,...lj->...ij", J, hx, J)
            + gx[..., 1, None, None] * q_hessian(t, theta))


def force_noise(models: ModelSet, t, theta, H, G, sigma_B) -> tuple[np.ndarray, np.ndarray]:
    """Force noise σ_Fr, σ_Fz [N] from field noise, at (t, θ, H, G) (broadcast).

    .. math:: σ_F = \\sqrt{\\operatorname{diag}(J Σ_B J^T)},\\quad J = ∂F/∂B,

    with Σ_B the covariance of the field noise [T²]: a (2, 2) matrix over (B_x, B_z), or
    (σ_x, σ_z) [T] for independent axes, Σ_B = diag(σ_x², σ_z²) (docs/method.md §10). For
    isotropic noise σ this is Γ σ. J follows the model set's definition (see :func:`dF_dB`).
    """
    S = np.asarray(sigma_B, dtype=float)
    cov = np.diag(S**2) if S.shape == (2,) else S
    if cov.shape != (2, 2):
        raise ValueError(f"sigma_B must be (σ_x, σ_z) or a 2 x 2 covariance, got shape {S.shape}")
    J = dF_dB(models, t, theta, H, G)
    var = np.einsum("...ij,jk,...ik->...i", J, cov, J)
    return np.sqrt(var[..., 0]), np.sqrt(var[..., 1])
