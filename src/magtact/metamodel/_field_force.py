"""Force models of the published sensitivity definition: F / G as a function of field and load.

de Boer et al. (Sensors 2017, Eq. 15) fit the force as f(B_r, B_z, t, θ, H) and take the
sensitivity as its partial derivative in B at fixed (t, θ, H) (docs/method.md §6).
Here the same model is written in the features (p, q) = (t, t tan θ) instead of (t, θ): at
t > 0 the two sets determine each other, so "fixed (t, θ)" and "fixed (p, q)" are the same
partial derivative, and the features keep the expression smooth at t = 0.

:class:`FieldForceModel` is the fitted expression f̂(B_r, B_z, p, q, H) [N/Pa]. Along the
sensor's own path the field is B(p, q, H), so the force the sensor feels is the composition

    f(p, q, H) = f̂(B_r(p, q, H), B_z(p, q, H), p, q, H),

served by :class:`ComposedForce` with the chain rule: with z = (B_r, B_z, p, q) and
Z1 = ∂z/∂(p, q), Z2 = ∂²z/∂(p, q)²,

    ∇f = f̂_a Z1_a,    ∇²f = Z1_aᵀ f̂_ab Z1_b + f̂_a Z2_a,

and the same for the partial derivatives s_k = ∂f̂/∂B_k (k = r, z) composed with the path, whose
values are the published sensitivity per unit G.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

import numpy as np
import sympy as sp

from ._model import _derivative_tensors, _evaluate, _lambdify
from ._symbols import H, features, p, q

#: Field symbols of a field-force model [T].
B_r, B_z = sp.symbols("B_r B_z")
#: Variables of the partial derivatives, in this order: (B_r, B_z, p, q).
FIELD_VARS = (B_r, B_z, p, q)
#: Every symbol a field-force expression may contain, by name.
FIELD_SYMBOLS: dict[str, sp.Symbol] = {s.name: s for s in (B_r, B_z, p, q, H)}


@dataclass(frozen=True, eq=False)
class FieldForceModel:
    """A force per unit G as an expression of (B_r [T], B_z [T], p, q, H [m]) [N/Pa].

    Parameters
    ----------
    name : {"f_r", "f_z"}
    expr : sympy.Expr
        In the symbols of :data:`FIELD_SYMBOLS`.
    units : str
        ``"N/Pa"``.
    info : dict
        Provenance (accuracy, settings, seed, data hash).
    """

    name: str
    expr: sp.Expr
    units: str = "N/Pa"
    info: dict[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def from_expr(cls, name: str, expr, info: dict | None = None) -> FieldForceModel:
        """A model from an expression, stored in the form a model file reads back exactly.

        Raises
        ------
        ValueError
            For symbols other than B_r, B_z, p, q, H or functions outside the whitelist.
        """
        from ._parse import format_expression, parse_expression

        expr = sp.sympify(expr)
        unknown = {s.name for s in expr.free_symbols} - set(FIELD_SYMBOLS)
        if unknown:
            raise ValueError(f"field-force expression has unknown symbols {sorted(unknown)}; "
                             f"allowed: {sorted(FIELD_SYMBOLS)}")
        expr = expr.xreplace({s: FIELD_SYMBOLS[s.name] for s in expr.free_symbols})
        expr = parse_expression(format_expression(expr), FIELD_SYMBOLS)
        return cls(name=name, expr=expr, info=dict(info or {}))

    @cached_property
    def _compiled(self) -> dict:
        return {}

    def derivatives(self, Br, Bz, pv, qv, Hv, order: int) -> list[np.ndarray]:
        """Value and derivatives in (B_r, B_z, p, q) up to ``order`` (≤ 3), broadcast.

        Returns ``[value (...), (..., 4), (..., 4, 4), (..., 4, 4, 4)]`` truncated after
        ``order``; index 0 is B_r, 1 is B_z, 2 is p, 3 is q.
        """
        if not 0 <= order <= 3:
            raise ValueError(f"derivative order must be 0..3, got {order}")
        if order not in self._compiled:
            exprs = _derivative_tensors(self.expr, FIELD_VARS, order)
            self._compiled[order] = _lambdify(exprs, FIELD_VARS + (H,))
        return _evaluate(self._compiled[order], 4, order, Br, Bz, pv, qv, Hv)

    def __repr__(self) -> str:
        return f"FieldForceModel({self.name!r}, {self.expr})"


def _compose(g: list[np.ndarray], Z1: np.ndarray, Z2: np.ndarray | None, order: int):
    """Jet in x = (p, q) of g(z(x)) from g's z-derivatives ``g`` and z's x-derivatives."""
    out = [g[0]]
    if order >= 1:
        out.append(np.einsum("...a,...ai->...i", g[1], Z1))
    if order >= 2:
        out.append(np.einsum("...ab,...ai,...bj->...ij", g[2], Z1, Z1)
                   + np.einsum("...a,...aij->...ij", g[1], Z2))
    return out


@dataclass(frozen=True, eq=False)
class ComposedForce:
    """A :class:`FieldForceModel` evaluated along the sensor's path, B = B(p, q, H).

    Serves the force f(t, θ, H) [N/Pa] (``value``, ``jet`` in (p, q) up to order 2) and the
    partial derivatives ∂f̂/∂B along the path (``partials``), the published sensitivity per unit
    G. B models are any objects with the ``value``/``jet`` interface of
    :class:`magtact.metamodel.Metamodel`.
    """

    #: The sensitivity definition this force model serves (``ModelSet.definition``; a force
    #: model without this attribute serves the Jacobian definition).
    definition: ClassVar[str] = "published"

    model: FieldForceModel
    B_r: Any
    B_z: Any

    @property
    def name(self) -> str:
        return self.model.name

    @property
    def units(self) -> str:
        return self.model.units

    @property
    def info(self) -> dict:
        return self.model.info

    @property
    def expr(self) -> sp.Expr:
        """The fitted expression in (B_r, B_z, p, q, H)."""
        return self.model.expr

    def _path(self, t, theta, Hv, order: int):
        """z = (B_r, B_z, p, q) along the path and its x-derivatives Z1, Z2."""
        t = np.asarray(t, dtype=float)
        theta = np.asarray(theta, dtype=float)
        pv, qv = features(t, theta)
        jr = self.B_r.jet(t, theta, Hv, order)
        jz = self.B_z.jet(t, theta, Hv, order)
        shape = np.broadcast_shapes(np.shape(jr[0]), np.shape(jz[0]), pv.shape, qv.shape,
                                    np.shape(Hv))
        z = [np.broadcast_to(a, shape) for a in (jr[0], jz[0], pv, qv)]
        Z1 = Z2 = None
        if order >= 1:
            Z1 = np.zeros(shape + (4, 2))
            Z1[..., 0, :], Z1[..., 1, :] = jr[1], jz[1]
            Z1[..., 2, 0] = Z1[..., 3, 1] = 1.0
        if order >= 2:
            Z2 = np.zeros(shape + (4, 2, 2))
            Z2[..., 0, :, :], Z2[..., 1, :, :] = jr[2], jz[2]
        return z, Z1, Z2, np.broadcast_to(np.asarray(Hv, dtype=float), shape)

    def value(self, t, theta, Hv) -> np.ndarray:
        """f(t, θ, H) = f̂(B(t, θ, H), t, t tan θ, H) [N/Pa]."""
        z, _, _, Hb = self._path(t, theta, Hv, 0)
        return self.model.derivatives(*z, Hb, 0)[0]

    def jet(self, t, theta, Hv, order: int = 1) -> list[np.ndarray]:
        """f and its derivatives in (p, q) at fixed H, up to ``order`` (≤ 2)."""
        if not 0 <= order <= 2:
            raise ValueError(f"a composed force serves derivatives up to order 2, got {order}")
        z, Z1, Z2, Hb = self._path(t, theta, Hv, order)
        return _compose(self.model.derivatives(*z, Hb, order), Z1, Z2, order)

    def partials(self, t, theta, Hv, order: int = 0) -> list[list[np.ndarray]]:
        """∂f̂/∂B_r and ∂f̂/∂B_z along the path, each as a jet in (p, q) up to ``order`` (≤ 2).

        Returns ``[jet of ∂f̂/∂B_r, jet of ∂f̂/∂B_z]`` [N/(Pa·T)].
        """
        if not 0 <= order <= 2:
            raise ValueError(f"partials serve derivatives up to order 2, got {order}")
        z, Z1, Z2, Hb = self._path(t, theta, Hv, order)
        D = self.model.derivatives(*z, Hb, order + 1)
        out = []
        for k in (0, 1):  # B_r, B_z
            g = [np.take(D[n + 1], k, axis=-(n + 1)) for n in range(order + 1)]
            out.append(_compose(g, Z1, Z2, order))
        return out

    def __repr__(self) -> str:
        return f"ComposedForce({self.model!r})"
