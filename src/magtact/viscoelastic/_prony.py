"""The relaxation modulus G(t) = G_∞ + Σ G_i exp(−t/τ_i) of a silicone (a Prony series) and the
hereditary force it gives along a history (docs/method.md §15)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import MagtactError


def _finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise MagtactError(f"Prony series: {name} = {value!r} is not a number") from None
    if not math.isfinite(v):
        raise MagtactError(f"Prony series: {name} = {v!r} is not finite")
    return v


@dataclass(frozen=True)
class Prony:
    """A shear relaxation modulus G(t) = G_∞ + Σ_i G_i exp(−t/τ_i) [Pa], t in seconds.

    Attributes
    ----------
    G_inf : float
        The long-time (equilibrium) modulus G_∞ [Pa], > 0.
    G : tuple of float
        The moduli G_i [Pa] of the relaxing terms, each ≥ 0.
    tau : tuple of float
        Their relaxation times τ_i [s], each > 0.
    source : str
        Where the series comes from (a citation with its test, or the study that gives it).

    Raises
    ------
    MagtactError
        One line naming the bad value: a negative or non-positive modulus, a non-positive
        time, NaN or infinity, or terms of unequal count.
    """

    G_inf: float
    G: tuple[float, ...] = ()
    tau: tuple[float, ...] = ()
    source: str = ""

    def __post_init__(self):
        G_inf = _finite("G_inf", self.G_inf)
        if G_inf <= 0:
            raise MagtactError(f"Prony series: G_inf = {G_inf:g} Pa must be positive (the "
                               "long-time modulus of a solid)")
        G = tuple(_finite(f"G_{i + 1}", g) for i, g in enumerate(np.atleast_1d(self.G)))
        tau = tuple(_finite(f"tau_{i + 1}", t) for i, t in enumerate(np.atleast_1d(self.tau)))
        if len(G) != len(tau):
            raise MagtactError(f"Prony series: {len(G)} moduli G_i but {len(tau)} times tau_i "
                               "(one time per modulus)")
        for i, g in enumerate(G):
            if g < 0:
                raise MagtactError(f"Prony series: G_{i + 1} = {g:g} Pa is negative (a "
                                   "relaxing modulus is at least 0)")
        for i, t in enumerate(tau):
            if t <= 0:
                raise MagtactError(f"Prony series: tau_{i + 1} = {t:g} s must be positive")
        object.__setattr__(self, "G_inf", G_inf)
        object.__setattr__(self, "G", G)
        object.__setattr__(self, "tau", tau)

    @classmethod
    def from_ratios(cls, G_inf: float, g, tau, source: str = "") -> Prony:
        """The series with G_i = g_i G_∞ (``g``: the ratios G_i / G_∞, dimensionless)."""
        G_inf = _finite("G_inf", G_inf)
        g = [_finite(f"g_{i + 1}", v) for i, v in enumerate(np.atleast_1d(g))]
        return cls(G_inf, tuple(v * G_inf for v in g), tuple(np.atleast_1d(tau)), source)

    @property
    def G0(self) -> float:
        """The instantaneous modulus G(0) = G_∞ + Σ G_i [Pa]."""
        return self.G_inf + math.fsum(self.G)

    @property
    def ratios(self) -> tuple[float, ...]:
        """g_i = G_i / G_∞."""
        return tuple(g / self.G_inf for g in self.G)

    def scaled(self, G_inf: float) -> Prony:
        """The same relaxation shape (ratios and times) with the long-time modulus ``G_inf``."""
        return Prony.from_ratios(G_inf, self.ratios, self.tau, self.source)

    def relaxation(self, t) -> np.ndarray:
        """G(t) [Pa] at times ``t`` ≥ 0 [s] (broadcast)."""
        t = np.asarray(t, dtype=float)
        out = np.full(t.shape, self.G_inf)
        for g, tau in zip(self.G, self.tau, strict=True):
            out = out + g * np.exp(-t / tau)
        return out


def _history(time, name: str, values, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Checked (time, values) of a history: finite, times strictly increasing."""
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    if time.ndim != 1 or len(time) < 1:
        raise MagtactError("history: time must be a 1-D array of at least one sample")
    if values.shape[0] != len(time):
        raise MagtactError(f"history: {len(time)} times but {values.shape[0]} values of "
                           f"{what}")
    for arr, label in ((time, "time"), (values, name)):
        bad = np.flatnonzero(~np.isfinite(arr.reshape(len(time), -1)).all(axis=1))
        if len(bad):
            k = int(bad[0])
            v = arr.reshape(len(time), -1)[k]
            raise MagtactError(f"history: {label}[{k}] = "
                               f"{v[0] if v.size == 1 else v.tolist()} is not finite "
                               f"({what} must be a number at every time)")
    if np.any(np.diff(time) <= 0):
        k = int(np.flatnonzero(np.diff(time) <= 0)[0]) + 1
        raise MagtactError(f"history: time[{k}] = {time[k]:g} s does not follow time[{k - 1}] "
                           f"= {time[k - 1]:g} s (times must increase)")
    return time, values


class _State:
    """The hereditary integrals h_i(t) = ∫ exp(−(t − s)/τ_i) df(s) of one history, advanced a
    step at a time with f linear in time over the step (exact for such an f)."""

    def __init__(self, prony: Prony, f0, t0: float):
        self.p = prony
        self.G = np.asarray(prony.G, dtype=float)
        self.tau = np.asarray(prony.tau, dtype=float)
        f0 = np.asarray(f0, dtype=float)
        # the body rests undeformed before t0: a jump to f0 at t0 loads every term fully
        self.h = np.repeat(f0[None, ...], len(self.G), axis=0)
        self.f, self.t = f0, float(t0)

    def force(self) -> np.ndarray:
        return self.p.G_inf * self.f + np.tensordot(self.G, self.h, axes=1)

    def _coefficients(self, t: float):
        dt = t - self.t
        a = np.exp(-dt / self.tau)
        b = -self.tau * np.expm1(-dt / self.tau) / dt  # τ (1 − e^{−Δ/τ}) / Δ without round-off
        return a, b

    def to_f(self, t: float, f) -> np.ndarray:
        """Advance to time t with f(t) given (displacement control); the force at t."""
        a, b = self._coefficients(t)
        f = np.asarray(f, dtype=float)
        shape = (-1,) + (1,) * f.ndim
        self.h = a.reshape(shape) * self.h + b.reshape(shape) * (f - self.f)[None, ...]
        self.f, self.t = f, float(t)
        return self.force()

    def to_force(self, t: float, F) -> np.ndarray:
        """Advance to time t with the force F(t) given (force control); f at t."""
        a, b = self._coefficients(t)
        F = np.asarray(F, dtype=float)
        shape = (-1,) + (1,) * F.ndim
        rest = np.tensordot(self.G, a.reshape(shape) * self.h
                            - b.reshape(shape) * self.f[None, ...], axes=1)
        f = (F - rest) / (self.p.G_inf + float(np.dot(self.G, b)))
        self.h = a.reshape(shape) * self.h + b.reshape(shape) * (f - self.f)[None, ...]
        self.f, self.t = f, float(t)
        return f


def hereditary_force(prony: Prony, time, f) -> np.ndarray:
    """The force F(t) = ∫ G(t − s) df(s) [N] along a displacement history.

    Parameters
    ----------
    prony : Prony
        The relaxation modulus.
    time : (n,) array_like
        Increasing times [s].
    f : (n,) or (n, k) array_like
        The elastic force per unit modulus f = F_elastic / G [N/Pa] at each time (one column
        per force component), linear in time between samples; the body rests undeformed
        before ``time[0]`` (a nonzero ``f[0]`` is a step at ``time[0]``).

    Returns
    -------
    ndarray
        F at each time, shape of ``f`` [N]. Exact (to round-off) for f linear between
        samples; with no relaxing term it is G_∞ f exactly.

    Raises
    ------
    MagtactError
        For a time or an f that is not finite, or times that do not increase.
    """
    time, f = _history(time, "f", f, "the elastic force")
    dt = np.diff(time)
    if dt.size and np.all(np.abs(dt - dt[0]) <= 1e-12 * dt[0]):
        return _uniform_hereditary_force(prony, dt[0], f)
    st = _State(prony, f[0], time[0])
    out = np.empty_like(f)
    out[0] = st.force()
    for k in range(1, len(time)):
        out[k] = st.to_f(time[k], f[k])
    return out


def _uniform_hereditary_force(prony: Prony, dt: float, f: np.ndarray) -> np.ndarray:
    """:func:`hereditary_force` on equal steps ``dt``: each term's recursion
    h_k = a h_(k−1) + b (f_k − f_(k−1)), h_0 = f_0 (:class:`_State`, a = e^(−Δ/τ),
    b = τ (1 − a)/Δ), as one linear filter over the whole history."""
    from scipy.signal import lfilter

    out = prony.G_inf * f
    for G, tau in zip(np.atleast_1d(prony.G), np.atleast_1d(prony.tau), strict=True):
        a = np.exp(-dt / tau)
        b = -tau * np.expm1(-dt / tau) / dt
        x = np.concatenate([f[:1], b * np.diff(f, axis=0)], axis=0)
        out = out + G * lfilter([1.0], [1.0, -a], x, axis=0)
    return out


def held_force(prony: Prony, time, f, hold_from: int) -> tuple[np.ndarray, np.ndarray]:
    """A displacement history up to sample ``hold_from``, then the force held constant at its
    value there (a press held by a constant load: the body creeps).

    Parameters
    ----------
    time, f
        As in :func:`hereditary_force`; ``f`` after ``hold_from`` is ignored (it is solved).
    hold_from : int
        The sample from which the force is held.

    Returns
    -------
    (F, f) : ndarray, ndarray
        The force [N] and the elastic force per unit modulus [N/Pa] at every time.
    """
    time, f = _history(time, "f", f, "the elastic force")
    if not 0 <= hold_from < len(time):
        raise MagtactError(f"history: hold_from = {hold_from} is outside the {len(time)} "
                           "samples")
    st = _State(prony, f[0], time[0])
    F_out, f_out = np.empty_like(f), f.copy()
    F_out[0] = st.force()
    for k in range(1, hold_from + 1):
        F_out[k] = st.to_f(time[k], f[k])
    held = F_out[hold_from].copy()
    for k in range(hold_from + 1, len(time)):
        f_out[k] = st.to_force(time[k], held)
        F_out[k] = held
    return F_out, f_out
