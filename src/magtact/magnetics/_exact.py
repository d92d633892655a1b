"""Exact field of a uniformly, axially magnetised cylinder (closed form, elliptic integrals).

Coordinates: cylindrical (r, z) with the magnet's centre at the origin and its axis along z.
All quantities SI: lengths in m, magnetisation in A/m, flux density in T.
"""

from __future__ import annotations

import numpy as np

from ..study import MU0

#: Relative tolerance of the arithmetic-geometric iteration in :func:`cel`.
_CEL_TOL = 1e-15
_CEL_MAX_ITER = 60


def cel(kc, p, c, s) -> np.ndarray:
    """Bulirsch's generalised complete elliptic integral, vectorised.

    Parameters
    ----------
    kc, p, c, s : array_like
        Broadcastable arrays; ``kc`` must be non-zero and ``p`` non-negative (the cases the
        cylinder field needs).

    Returns
    -------
    numpy.ndarray
        ``cel(kc, p, c, s)`` with the broadcast shape of the inputs.

    Notes
    -----
    .. math::

        \\mathrm{cel}(k_c, p, c, s) = \\int_0^{\\pi/2}
            \\frac{c\\cos^2\\varphi + s\\sin^2\\varphi}
                 {(\\cos^2\\varphi + p\\sin^2\\varphi)
                  \\sqrt{\\cos^2\\varphi + k_c^2\\sin^2\\varphi}}
            \\,d\\varphi

    evaluated by Bulirsch's (1969) quadratically convergent Landen/AGM iteration. The special
    cases are K(k) = cel(k_c, 1, 1, 1), E(k) = cel(k_c, 1, 1, k_c²), with k_c² = 1 − k².
    """
    kc, p, c, s = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (kc, p, c, s)))
    return _cel_sets(kc, [(p, c, s)])[0]


def _cel_sets(kc: np.ndarray, sets: list[tuple]) -> list[np.ndarray]:
    """:func:`cel` for one ``kc`` array and several (p, c, s) sets of its shape: the
    Landen/AGM sequence of k_c is shared by every set, so several integrals over the same
    modulus cost little more than one.

    Every point takes the same number of Landen steps: the first after which the sequence of
    k_c has converged at every point. The points go through them in blocks of ``_CEL_BLOCK``
    (:class:`_Landen`), so that a block's arrays stay in the processor's cache: each block
    steps on until it has converged at the most steps any block has needed so far, and where a
    later block needs more, the earlier ones take those steps too (and must have converged
    there as well). Each point's arithmetic is that of one pass over all of them."""
    if np.any(kc == 0):
        raise ValueError("cel: kc must be non-zero (the integral diverges)")
    if any(np.any(p < 0) for p, _, _ in sets):
        raise ValueError("cel: p must be >= 0")
    shape = kc.shape
    kc = kc.reshape(-1)
    sets = [tuple(np.reshape(v, -1) for v in st) for st in sets]
    blocks = [_Landen(kc[b], [tuple(v[b] for v in st) for st in sets])
              for b in (slice(a, a + _CEL_BLOCK) for a in range(0, max(kc.size, 1), _CEL_BLOCK))]
    out = [np.empty(kc.size) for _ in sets]
    steps, done = 0, [-1] * len(blocks)  # done: the steps at which a block's values were taken
    while any(d != steps for d in done):
        for i, block in enumerate(blocks):
            block.step_to(steps)
            steps = block.n
            if done[i] != steps:
                b = slice(i * _CEL_BLOCK, (i + 1) * _CEL_BLOCK)
                for whole, part in zip(out, block.values(), strict=True):
                    whole[b] = part
                done[i] = steps
    return [v.reshape(shape) for v in out]


#: Points per block of :func:`_cel_sets` (its dozen work arrays within a core's cache).
_CEL_BLOCK = 8192


class _Landen:
    """Bulirsch's iteration over one block of moduli ``kc`` and the (p, c, s) sets."""

    def __init__(self, kc: np.ndarray, sets: list[tuple]):
        k = np.abs(kc)
        self.state = []
        for p, c, s in sets:
            # p > 0 in every call the cylinder field makes except on the mantle line r = R
            # (p = 0), where the general branch of Bulirsch's algorithm applies.
            pos = p > 0
            pp = np.where(pos, np.sqrt(np.where(pos, p, 1.0)), 0.0)
            cc = c.copy()
            ss = np.where(pos, s / np.where(pos, pp, 1.0), s)
            if not np.all(pos):
                pg = np.where(pos, 0.0, p)  # the general branch, evaluated where p <= 0 only
                f = kc * kc
                q = 1.0 - f
                g = 1.0 - pg
                f = f - pg
                q = q * (s - c * pg)
                pn = np.sqrt(f / g)
                cn = (c - s) / g
                sn = -q / (g * g * pn) + cn * pn
                pp = np.where(pos, pp, pn)
                cc = np.where(pos, cc, cn)
                ss = np.where(pos, ss, sn)
            f = cc
            cc = cc + ss / pp
            g = k / pp
            ss = 2.0 * (ss + f * g)
            pp = g + pp
            self.state.append([cc, ss, pp])
        em = np.ones_like(k)
        self.g, self.em, self.k, self.kk = em, k + em, k, k
        self.n = 0  # Landen steps taken

    def converged(self) -> bool:
        """Whether |g − k| ≤ g ``_CEL_TOL`` at every point (g: the previous arithmetic
        mean)."""
        return bool(np.all(np.abs(self.g - self.k) <= self.g * _CEL_TOL))

    def step(self) -> None:
        """One Landen step of the moduli and every set."""
        self.k = k = 2.0 * np.sqrt(self.kk)
        self.kk = kk = k * self.em
        for st in self.state:
            cc, ss, pp = st
            f = cc
            cc = cc + ss / pp
            gp = kk / pp
            st[:] = cc, 2.0 * (ss + f * gp), gp + pp
        self.g = self.em
        self.em = k + self.em
        self.n += 1

    def step_to(self, n: int) -> None:
        """Take steps up to ``n``, then on until converged (``self.n``: where it is)."""
        while self.n < n:
            self.step()
        while not self.converged():
            if self.n >= _CEL_MAX_ITER - 1:
                # the iteration converges quadratically for every valid input
                raise RuntimeError("cel: no convergence")  # pragma: no cover
            self.step()

    def values(self) -> list[np.ndarray]:
        """cel of each set at the steps taken."""
        em = self.em
        return [0.5 * np.pi * (ss + cc * em) / (em * (em + pp)) for cc, ss, pp in self.state]


def cylinder_field(r, z, R_m, H_m, M_z) -> tuple[np.ndarray, np.ndarray]:
    """Flux density of an axially magnetised cylinder centred at the origin (exact).

    Parameters
    ----------
    r : array_like
        Radial coordinate of the field points [m], r ≥ 0 (r = 0 is the axis).
    z : array_like
        Axial coordinate of the field points [m], relative to the magnet's centre; broadcast
        with ``r``.
    R_m, H_m : float or array_like
        Magnet radius and height [m]; the magnet occupies r ≤ R_m, |z| ≤ H_m / 2. Arrays
        broadcast with ``r`` and ``z`` (one magnet per field point).
    M_z : float or array_like
        Uniform axial magnetisation [A/m] (polarisation μ0 M_z with μ0 = ``magtact.study.MU0``).

    Returns
    -------
    B_r, B_z : numpy.ndarray
        Radial and axial flux density [T], each of the broadcast shape of ``r`` and ``z``.
        Inside the magnet this is B = μ0 (H + M). On the magnet's two rim circles
        (r = R_m, z = ±H_m/2) the field is singular and the result is NaN.

    Notes
    -----
    The magnet is equivalent to a solenoid sheet of current density M_z on its mantle. With
    a = R_m, b = H_m/2, z± = z ± b and B0 = μ0 M_z / π (Derby & Olbert, Am. J. Phys. 78, 2010):

    .. math::

        \\alpha_\\pm = \\frac{a}{\\sqrt{z_\\pm^2 + (r + a)^2}}, \\quad
        \\beta_\\pm = \\frac{z_\\pm}{\\sqrt{z_\\pm^2 + (r + a)^2}}, \\quad
        \\gamma = \\frac{a - r}{a + r}, \\quad
        k_\\pm = \\sqrt{\\frac{z_\\pm^2 + (a - r)^2}{z_\\pm^2 + (a + r)^2}}

        B_r = B_0 \\left[\\alpha_+ \\mathrm{cel}(k_+, 1, 1, -1)
                        - \\alpha_- \\mathrm{cel}(k_-, 1, 1, -1)\\right]

        B_z = \\frac{B_0 a}{a + r} \\left[
            \\beta_+ \\mathrm{cel}(k_+, \\gamma^2, 1, \\gamma)
            - \\beta_- \\mathrm{cel}(k_-, \\gamma^2, 1, \\gamma)\\right]

    On the axis k± = 1 and γ = 1, which gives B_r = 0 and the textbook
    B_z = μ0 M_z / 2 (β+ − β−); on the mantle line r = a, γ = 0 (``cel`` with p = 0).
    """
    r, z, a, h, M_z = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                            for v in (r, z, R_m, H_m, M_z)))
    if np.any(r < 0):
        raise ValueError("cylinder_field: r must be >= 0 (cylindrical radius)")
    if not (np.all(a > 0) and np.all(h > 0)):
        raise ValueError(f"cylinder_field: R_m and H_m must be positive, got {R_m}, {H_m}")
    b = 0.5 * h
    rim = np.isclose(r, a, rtol=0.0, atol=1e-12 * a) & np.isclose(np.abs(z), b, rtol=0.0,
                                                                  atol=1e-12 * a)
    r = np.where(rim, 0.0, r)  # evaluate a harmless point there, replaced by NaN below
    gamma = (a - r) / (a + r)
    # both faces (z ± b) in one array, both integrals over one AGM sequence
    zs = np.stack([z + b, z - b])
    den = np.sqrt(zs * zs + (a + r) ** 2)
    kc = np.sqrt(zs * zs + (a - r) ** 2) / den
    one = np.ones(kc.shape)
    gam = np.broadcast_to(gamma, kc.shape)
    c_r, c_z = _cel_sets(kc, [(one, one, -one), (gam * gam, one, gam)])
    t_r, t_z = (a / den) * c_r, (zs / den) * c_z
    B_r, B_z = t_r[0] - t_r[1], t_z[0] - t_z[1]
    B0 = MU0 * M_z / np.pi
    B_r = np.where(rim, np.nan, B0 * B_r)
    B_z = np.where(rim, np.nan, B0 * a / (a + r) * B_z)
    return B_r, B_z


def cylinder_field_dz(r, z, R_m, H_m, M_z) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives ∂B_r/∂z, ∂B_z/∂z [T/m] of :func:`cylinder_field` (exact).

    Arguments as :func:`cylinder_field` (arrays broadcast).

    Notes
    -----
    The magnet's field is that of its two faces' magnetic charge ±M_z. The z-derivative of a
    uniformly charged disk's potential is its charge times the solid angle the disk subtends,
    and the gradient of that solid angle is the field of a current loop along the disk's rim
    (magpylib's numerically stable ``current_circle_Hfield``, Ortner et al., Magnetism 3, 2023).
    Hence ∂B/∂z = μ0 M_z [H_loop(r, z + H_m/2) − H_loop(r, z − H_m/2)] with loops of radius R_m
    carrying 1 A. The other derivatives follow from the field being curl- and divergence-free
    outside the magnet: ∂B_z/∂r = ∂B_r/∂z, ∂B_r/∂r = −B_r/r − ∂B_z/∂z.
    """
    from magpylib.core import current_circle_Hfield

    r, z, a, h, M_z = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                            for v in (r, z, R_m, H_m, M_z)))
    shape = r.shape
    r, z, a, h, M_z = (v.ravel() for v in (r, z, a, h, M_z))
    one = np.ones(r.size)
    b = 0.5 * h
    both = current_circle_Hfield(np.concatenate([a, a]), np.concatenate([r, r]),
                                 np.concatenate([z + b, z - b]), np.concatenate([one, one]))
    n = r.size
    k = MU0 * M_z
    d_r = k * (both[0, :n] - both[0, n:])
    d_z = k * (both[2, :n] - both[2, n:])
    return d_r.reshape(shape), d_z.reshape(shape)
