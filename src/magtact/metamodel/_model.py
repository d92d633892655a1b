"""Closed-form metamodels: a SymPy expression, its derivatives, and compiled NumPy functions."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Protocol, runtime_checkable

import numpy as np
import symengine as se
import sympy as sp

from ..study import mm
from ._symbols import GEOMETRY, PQ_TO_TTH, PQH, SYMBOLS, TTH, TTH_TO_PQ, features, p, q

#: Names of the four responses of a :class:`ModelSet` and their SI units.
RESPONSES: dict[str, str] = {"B_r": "T", "B_z": "T", "f_r": "N/Pa", "f_z": "N/Pa"}


def geometry_values(name: str, needed: tuple[str, ...], given: dict) -> list:
    """The values of the geometric variables ``needed`` by model ``name``, in order, from
    ``given`` (others are ignored; each may be an array broadcasting with t, θ, H).

    Raises
    ------
    ValueError
        If one of them is not given.
    """
    missing = [g for g in needed if g not in given]
    if missing:
        raise ValueError(f"model {name} depends on {missing}: give their values "
                         "(or bind them with ModelSet.at)")
    return [given[g] for g in needed]


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
                         f"allowed: t, theta, H (or the features p, q, H) and the geometric "
                         f"design variables R_m, H_m, R")
    if names & {"t", "theta"} and names & {"p", "q"}:
        raise ValueError("metamodel expression mixes (t, theta) and the features (p, q)")
    return expr.xreplace({s: SYMBOLS[s.name] for s in expr.free_symbols})


def _derivative_tensors(expr, symbols, order: int) -> list:
    """Flattened derivative tensors of ``expr`` w.r.t. ``symbols`` of orders 0..``order``.

    Differentiation runs in SymEngine (fast, no expression printing); entry k of order n is
    the derivative along the multi-index ``numpy.unravel_index(k, (len(symbols),) * n)``.
    """
    levels = [[se.sympify(expr)]]
    syms = [se.sympify(s) for s in symbols]
    for _ in range(order):
        levels.append([d.diff(s) for d in levels[-1] for s in syms])
    return [e for level in levels for e in level]


def _lambdify(exprs: list, symbols):
    """Compile expressions to one vectorised function (LLVM if available) with CSE.

    LLVM's optimisation passes are left out (``opt_level=0``): they take three quarters of a
    compilation and speed up the evaluation of these expressions not at all (the array
    handling around it dominates), and a design compiles some seventy functions."""
    args = [se.sympify(s) for s in symbols]
    try:
        return se.Lambdify(args, exprs, cse=True, backend="llvm", opt_level=0)
    except (RuntimeError, ValueError, TypeError):  # SymEngine built without LLVM
        return se.Lambdify(args, exprs, cse=True, backend="lambda")


def _evaluate(fn, n_sym: int, order: int, *args) -> list[np.ndarray]:
    """Evaluate a compiled derivative stack: [value, d1, ..., d_order], each (..., n, ..., n)."""
    args = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    shape = args[0].shape
    out = np.asarray(fn(np.stack(args, axis=-1).reshape(-1, len(args))), dtype=float)
    out = out.reshape(int(np.prod(shape, dtype=int)), -1)
    res, k = [], 0
    for n in range(order + 1):
        size = n_sym**n
        res.append(out[:, k:k + size].reshape(shape + (n_sym,) * n))
        k += size
    return res


@runtime_checkable
class Response(Protocol):
    """What every model of a response offers (:class:`Metamodel`, the exact field
    :class:`magtact.metamodel.ExactField`, a force composed from a field model): values and
    derivatives over (t, θ, H), broadcast, SI; ``geometry`` the values [m] of the geometric
    design variables the model depends on (``R_m``, ``H_m``, ``R``).
    """

    name: str
    units: str

    def value(self, t, theta, H, **geometry) -> np.ndarray:
        """The response at (t, θ, H)."""

    def jet(self, t, theta, H, order: int = 1, **geometry) -> list[np.ndarray]:
        """Value and derivatives w.r.t. the features (p, q) = (t, t tan θ) at fixed H, up to
        ``order``: ``[f, ∇f, ∇²f, ...]``."""


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

        The expressions are stored in the form a model file reads back (constants as doubles,
        SymPy's evaluated form), so a saved model loads exactly.

        Raises
        ------
        ValueError
            For symbols other than t, theta, H, p, q, a mix of both forms, or functions outside
            the whitelist of :func:`magtact.metamodel.parse_expression`.
        """
        from ._parse import format_expression, parse_expression

        expr = _canonical(expr)
        if {s.name for s in expr.free_symbols} & {"p", "q"}:
            expr_pq, expr = expr, expr.subs(PQ_TO_TTH)
        else:
            expr_pq = expr.subs(TTH_TO_PQ)
        # The form a model file reads back (whitelisted functions, constants as doubles), so
        # that saving and loading is exact.
        expr, expr_pq = (parse_expression(format_expression(e)) for e in (expr, expr_pq))
        return cls(name=name, expr=expr, units=units, expr_pq=expr_pq, info=dict(info or {}))

    @classmethod
    def from_text(cls, name: str, text: str, text_pq: str, units: str,
                  info: dict | None = None) -> Metamodel:
        """A model from the text of its two forms as a model file of the package holds them
        (files its tests read whole): the SymPy forms are built when first asked for, the
        compiled functions straight from the text. A design compiles the force models of a
        dozen magnet sizes, and building their SymPy forms costs a hundred times more than
        reading them into SymEngine."""
        model = object.__new__(cls)
        for key, value in (("name", name), ("units", units), ("info", dict(info or {})),
                           ("_text", {"tth": text, "pq": text_pq})):
            object.__setattr__(model, key, value)
        return model

    def __getattr__(self, attr: str):
        # called only for attributes not set: the SymPy forms of a model made from text
        text = self.__dict__.get("_text")
        if attr not in ("expr", "expr_pq") or text is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {attr!r}")
        from ._parse import parse_expression

        geo = tuple(g.name for g in GEOMETRY)
        object.__setattr__(self, "expr", parse_expression(text["tth"], ("t", "theta", "H", *geo)))
        object.__setattr__(self, "expr_pq", parse_expression(text["pq"], ("p", "q", "H", *geo)))
        return self.__dict__[attr]

    @property
    def text(self) -> tuple[str, str]:
        """The two forms, (t, θ, H) and (p, q, H), as a model file writes them
        (:func:`magtact.metamodel.format_expression`)."""
        text = self.__dict__.get("_text")
        if text is not None:
            return text["tth"], text["pq"]
        from ._parse import format_expression

        return format_expression(self.expr), format_expression(self.expr_pq)

    def _symengine(self, form: str):
        """The form "tth" or "pq" as a SymEngine expression (from the text where the model
        was made from text)."""
        text = self.__dict__.get("_text")
        if text is not None:
            return se.sympify(text[form])
        return se.sympify(self.expr if form == "tth" else self.expr_pq)

    @cached_property
    def _compiled(self) -> dict:
        return {}

    @cached_property
    def geometry(self) -> tuple[str, ...]:
        """Names of the geometric design variables besides H the model depends on."""
        text = self.__dict__.get("_text")
        symbols = se.sympify(text["tth"]).free_symbols if text else self.expr.free_symbols
        names = {str(s) for s in symbols}
        return tuple(g.name for g in GEOMETRY if g.name in names)

    def _fn(self, form: str, order: int):
        """Compiled stack of derivatives up to ``order``: form "tth" (t, θ, H) or "pq"; the
        geometric variables follow as arguments (derivatives are not taken along them)."""
        key = (form, order)
        if key not in self._compiled:
            geo = tuple(SYMBOLS[g] for g in self.geometry)
            exprs = _derivative_tensors(self._symengine(form), TTH if form == "tth" else (p, q),
                                        order)
            self._compiled[key] = _lambdify(exprs, (TTH if form == "tth" else PQH) + geo)
        return self._compiled[key]

    def _geo(self, geometry: dict) -> list:
        return geometry_values(self.name, self.geometry, geometry)

    # ---- evaluation ----------------------------------------------------------------------
    def value(self, t, theta, H, **geometry) -> np.ndarray:
        """Model value at (t, θ, H) (broadcast), in ``units``; ``geometry``: values [m] of the
        geometric design variables it depends on (:attr:`geometry`)."""
        return _evaluate(self._fn("tth", 0), 3, 0, t, theta, H, *self._geo(geometry))[0]

    def grad(self, t, theta, H, **geometry) -> np.ndarray:
        """Gradient w.r.t. (t, θ, H), shape (..., 3)."""
        return _evaluate(self._fn("tth", 1), 3, 1, t, theta, H, *self._geo(geometry))[1]

    def hess(self, t, theta, H, **geometry) -> np.ndarray:
        """Hessian w.r.t. (t, θ, H), shape (..., 3, 3)."""
        return _evaluate(self._fn("tth", 2), 3, 2, t, theta, H, *self._geo(geometry))[2]

    def bind(self, **geometry: float) -> Metamodel:
        """The model at fixed values [m] of its geometric design variables: a model of
        (t, θ, H) alone that evaluates through this one's compiled functions."""
        return _Bound(self, dict(zip(self.geometry, map(float, self._geo(geometry)),
                                     strict=True)))

    def jet(self, t, theta, H, order: int = 1, **geometry) -> list[np.ndarray]:
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
        pv, qv = features(t, theta)
        # two derivative directions (p, q); H and the geometry enter as parameters
        return _evaluate(self._fn("pq", order), 2, order, pv, qv, H, *self._geo(geometry))

    def __repr__(self) -> str:
        return f"Metamodel({self.name!r}, {self.expr}, units={self.units!r})"


class _Bound:
    """A :class:`Metamodel` at fixed geometric design variables (see :meth:`Metamodel.bind`)."""

    def __init__(self, model: Metamodel, geometry: dict[str, float]):
        self.model, self.geometry_values = model, geometry
        self.name, self.units, self.info = model.name, model.units, model.info

    @cached_property
    def expr(self) -> sp.Expr:
        return self.model.expr.xreplace(self._sub)

    @cached_property
    def expr_pq(self) -> sp.Expr:
        return self.model.expr_pq.xreplace(self._sub)

    @property
    def _sub(self) -> dict:
        return {SYMBOLS[g]: sp.Float(v) for g, v in self.geometry_values.items()}

    geometry = ()

    # other geometric values given to a bound model are ignored, as by any model that does
    # not depend on them
    def value(self, t, theta, H, **_):
        return self.model.value(t, theta, H, **self.geometry_values)

    def grad(self, t, theta, H, **_):
        return self.model.grad(t, theta, H, **self.geometry_values)

    def hess(self, t, theta, H, **_):
        return self.model.hess(t, theta, H, **self.geometry_values)

    def jet(self, t, theta, H, order: int = 1, **_):
        return self.model.jet(t, theta, H, order, **self.geometry_values)

    def __repr__(self) -> str:
        return f"Metamodel({self.name!r}, {self.expr}, units={self.units!r})"


@dataclass(frozen=True, eq=False)
class ModelSet:
    """The four responses of a study: B_r, B_z [T] and f_r, f_z = F / G [N/Pa] over (t, θ, H).

    Each is a :class:`Response` (a :class:`Metamodel`, or for ``B_r`` and ``B_z`` the exact
    field model).
    """

    B_r: Response
    B_z: Response
    f_r: Response
    f_z: Response

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

    @property
    def definition(self) -> str:
        """The sensitivity definition the force models serve: ``"jacobian"`` for models of
        (t, θ, H), ``"published"`` for force models of (B_r, B_z, t, θ, H) along the path."""
        kinds = {getattr(m, "definition", "jacobian") for m in (self.f_r, self.f_z)}
        if len(kinds) != 1:
            raise ValueError("f_r and f_z belong to different sensitivity definitions")
        return kinds.pop()

    @property
    def geometry(self) -> tuple[str, ...]:
        """Geometric design variables besides H that some model depends on."""
        names = {g for _, m in self.items() for g in getattr(m, "geometry", ())}
        return tuple(g.name for g in GEOMETRY if g.name in names)

    def at(self, **geometry: float) -> ModelSet:
        """The models at fixed geometric design variables [m] (the models of
        ``study.at(**geometry)``): each model that depends on them is bound
        (:meth:`Metamodel.bind`, ``ExactField.bind``)."""
        return ModelSet(**{k: m.bind(**geometry) if getattr(m, "geometry", ()) else m
                           for k, m in self.items()})

    def __getitem__(self, name: str) -> Metamodel:
        if name not in RESPONSES:
            raise KeyError(f"no response {name!r}; responses: {list(RESPONSES)}")
        return getattr(self, name)

    def items(self):
        """(name, model) pairs in the order B_r, B_z, f_r, f_z."""
        return [(k, getattr(self, k)) for k in RESPONSES]

    def check_finite(self, study, n: tuple[int, int, int] = (41, 11, 11)) -> None:
        """Refuse models that are not finite somewhere on the study's domain.

        Each response is evaluated on an ``n`` grid over t in [0, 1], θ in [0, θ_max] and H over
        the design range; no NaN or inf may come from a model into a result.

        Raises
        ------
        MagtactError
            Naming the response, the first point where it is not finite, and how many are.
        """
        from .._errors import MagtactError

        t = np.linspace(0.0, 1.0, n[0])
        theta = np.linspace(0.0, study.loading.theta_max, n[1])
        H = np.linspace(*study.design.H, n[2])
        T, TH, HH = np.meshgrid(t, theta, H, indexing="ij")
        for name, model in self.items():
            with np.errstate(all="ignore"):
                v = np.broadcast_to(np.asarray(model.value(T, TH, HH), dtype=float), T.shape)
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                i = np.unravel_index(bad[0], T.shape)
                raise MagtactError(f"model {name} is not finite ({v[i]}) at t = {T[i]:.4g}, "
                                   f"theta = {TH[i]:.4g} rad, H = {mm(HH[i]):.4g} mm ({bad.size}"
                                   f" of {v.size} points of the study's domain)")

    def fields(self, t, theta, H) -> tuple[np.ndarray, np.ndarray]:
        """(B_r, B_z) [T] at (t, θ, H) (broadcast)."""
        return self.B_r.value(t, theta, H), self.B_z.value(t, theta, H)

    def forces(self, t, theta, H, G) -> tuple[np.ndarray, np.ndarray]:
        """(F_r, F_z) = G (f_r, f_z) [N] at (t, θ, H [m], G [Pa]) (broadcast)."""
        G = np.asarray(G, dtype=float)
        return G * self.f_r.value(t, theta, H), G * self.f_z.value(t, theta, H)
