"""Closed-form metamodels: a SymPy expression, its derivatives, and compiled NumPy functions."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import sympy as sp

from ._symbols import PQ_TO_TTH, PQH, SYMBOLS, TTH, TTH_TO_PQ, p, q

#: Names of the four responses of a :class:`ModelSet` and their SI units.
RESPONSES: dict[str, str] = {"B_r": "T", "B_z": "T", "f_r": "N/Pa", "f_z": "N/Pa"}


def _canonical(expr) -> sp.Expr:
    """``expr`` with its symbols replaced by the canonical ones of the same name.

    Raises
    ------
    ValueError
        If ``expr`` contains a symbol other than t, theta, H, p, q, or mixes the (t, θ) and
        (p, q) forms.
    """
    expr = sp.sympify(expr) if not isinstance(expr, sp.Basic) else expr
    names = {s.name for s in expr.free_symbols}
    unknown = names - set(SYMBOLS)
    if unknown:
        raise ValueError(f"metamodel expression has unknown symbols {sorted(unknown)}; "
                         f"allowed: t, theta, H (or the features p, q, H)")
    if names & {"t", "theta"} and names & {"p", "q"}:
        raise ValueError("metamodel expression mixes (t, theta) and the features (p, q)")
    return expr.xreplace({s: SYMBOLS[s.name] for s in expr.free_symbols})


def _compile(exprs, symbols):
    """Compile a nested list of expressions to one vectorised NumPy function (with CSE)."""
    return sp.lambdify(symbols, exprs, modules="numpy", cse=True)


def _broadcast_eval(fn, shape_tail, *args):
    """Evaluate a compiled nested-list function and stack to (broadcast shape, *shape_tail)."""
    args = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    shape = args[0].shape
    out = fn(*args)
    flat = [out]
    for _ in shape_tail:
        flat = [v for row in flat for v in row]
    arr = np.empty(shape + shape_tail)
    for k, v in enumerate(flat):
        arr[(...,) + np.unravel_index(k, shape_tail)] = np.broadcast_to(v, shape)
    return arr


@dataclass(frozen=True, eq=False)
class Metamodel:
    """One response as a closed-form expression of (t, θ, H).

    Parameters
    ----------
    name : str
        Response name (``"B_r"``, ``"B_z"``, ``"f_r"``, ``"f_z"`` in a :class:`ModelSet`).
    expr : sympy.Expr
        The model in (t, θ, H), H in metres.
    units : str
        SI unit of the value (``"T"``, ``"N/Pa"``).
    expr_pq : sympy.Expr
        The same model in the features (p, q, H) = (t, t tan θ, H) (see
        :mod:`magtact.metamodel._symbols`). Smooth in (p, q) means smooth in the displacement u.
    info : dict
        Provenance: accuracy report, fit settings, training data hash, transform.

    Notes
    -----
    ``expr`` is ``expr_pq`` with p = t, q = t tan θ. ``value``,
    ``grad`` and ``hess`` differentiate ``expr`` with respect to (t, θ, H) [units per -, rad, m].
    ``jet`` differentiates ``expr_pq`` with respect to (p, q) at fixed H, as the sensitivity needs.
    Build one with :meth:`from_expr`.
    """

    name: str
    expr: sp.Expr
    units: str
    expr_pq: sp.Expr
    info: dict[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def from_expr(cls, name: str, expr, units: str, info: dict | None = None) -> Metamodel:
        """A model from a SymPy expression in (t, theta, H) or in the features (p, q, H).

        An expression in (t, θ, H) is converted to the feature form by t = p, θ = atan(q / p);
        unless it is a function of (t, t tan θ, H) (a smooth function of u), the feature form
        keeps 1/p terms and its sensitivity is undefined at t = 0, as it physically is.

        Raises
        ------
        ValueError
            For symbols other than t, theta, H, p, q, or a mix of both forms.
        """
        expr = _canonical(expr)
        if {s.name for s in expr.free_symbols} & {"p", "q"}:
            expr_pq, expr = expr, expr.subs(PQ_TO_TTH)
        else:
            expr_pq = expr.subs(TTH_TO_PQ)
        return cls(name=name, expr=expr, units=units, expr_pq=expr_pq, info=dict(info or {}))

    @cached_property
    def _grad_exprs(self):
        return [sp.diff(self.expr, s) for s in TTH]

    @cached_property
    def _f_value(self):
        return _compile(self.expr, TTH)

    @cached_property
    def _f_grad(self):
        return _compile(self._grad_exprs, TTH)

    @cached_property
    def _f_hess(self):
        return _compile([[sp.diff(g, s) for s in TTH] for g in self._grad_exprs], TTH)

    @cached_property
    def _f_jet(self):
        e = self.expr_pq
        d1 = [sp.diff(e, s) for s in (p, q)]
        d2 = [[sp.diff(a, s) for s in (p, q)] for a in d1]
        d3 = [[[sp.diff(b, s) for s in (p, q)] for b in row] for row in d2]
        return [_compile(e, PQH), _compile(d1, PQH), _compile(d2, PQH), _compile(d3, PQH)]

    # ---- evaluation ----------------------------------------------------------------------
    def value(self, t, theta, H) -> np.ndarray:
        """Model value at (t, θ, H) (broadcast), in ``units``."""
        return _broadcast_eval(self._f_value, (), t, theta, H)

    def grad(self, t, theta, H) -> np.ndarray:
        """Gradient w.r.t. (t, θ, H), shape (..., 3)."""
        return _broadcast_eval(self._f_grad, (3,), t, theta, H)

    def hess(self, t, theta, H) -> np.ndarray:
        """Hessian w.r.t. (t, θ, H), shape (..., 3, 3)."""
        return _broadcast_eval(self._f_hess, (3, 3), t, theta, H)

    def jet(self, t, theta, H, order: int = 1) -> list[np.ndarray]:
        """Value and derivatives w.r.t. the features (p, q) at fixed H, up to ``order`` (≤ 3).

        Returns
        -------
        list of numpy.ndarray
            ``[value (...), d/d(p,q) (..., 2), d²/d(p,q)² (..., 2, 2), d³ (..., 2, 2, 2)]``
            truncated after ``order``; evaluated at p = t, q = t tan θ.
        """
        if not 0 <= order <= 3:
            raise ValueError(f"jet order must be 0..3, got {order}")
        t = np.asarray(t, dtype=float)
        pv, qv = t, t * np.tan(np.asarray(theta, dtype=float))
        tails = [(), (2,), (2, 2), (2, 2, 2)]
        return [_broadcast_eval(self._f_jet[k], tails[k], pv, qv, H) for k in range(order + 1)]

    def __repr__(self) -> str:
        return f"Metamodel({self.name!r}, {self.expr}, units={self.units!r})"


@dataclass(frozen=True, eq=False)
class ModelSet:
    """The four responses of a study: B_r, B_z [T] and f_r, f_z = F / G [N/Pa] over (t, θ, H).

    ``B_r`` and ``B_z`` may be any object with the :class:`Metamodel` evaluation interface
    (``value``, ``grad``, ``hess``, ``jet``), such as the exact field model.
    """

    B_r: Metamodel
    B_z: Metamodel
    f_r: Metamodel
    f_z: Metamodel

    @classmethod
    def from_exprs(cls, exprs: dict, info: dict | None = None) -> ModelSet:
        """A model set from SymPy expressions keyed ``B_r, B_z, f_r, f_z`` (see ``from_expr``).

        Raises
        ------
        ValueError
            If a key is missing or unknown.
        """
        missing, extra = set(RESPONSES) - set(exprs), set(exprs) - set(RESPONSES)
        if missing or extra:
            raise ValueError(f"ModelSet needs exactly the keys {list(RESPONSES)}; "
                             f"missing {sorted(missing)}, unknown {sorted(extra)}")
        return cls(**{k: Metamodel.from_expr(k, exprs[k], RESPONSES[k], info) for k in RESPONSES})

    def __getitem__(self, name: str) -> Metamodel:
        if name not in RESPONSES:
            raise KeyError(f"no response {name!r}; responses: {list(RESPONSES)}")
        return getattr(self, name)

    def items(self):
        """(name, model) pairs in the order B_r, B_z, f_r, f_z."""
        return [(k, getattr(self, k)) for k in RESPONSES]

    def fields(self, t, theta, H) -> tuple[np.ndarray, np.ndarray]:
        """(B_r, B_z) [T] at (t, θ, H) (broadcast)."""
        return self.B_r.value(t, theta, H), self.B_z.value(t, theta, H)

    def forces(self, t, theta, H, G) -> tuple[np.ndarray, np.ndarray]:
        """(F_r, F_z) = G (f_r, f_z) [N] at (t, θ, H [m], G [Pa]) (broadcast)."""
        G = np.asarray(G, dtype=float)
        return G * self.f_r.value(t, theta, H), G * self.f_z.value(t, theta, H)
