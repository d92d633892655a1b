"""FFT band-pass filter of a signal sampled along the displacement (docs/method.md §8)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import MagtactError


@dataclass(frozen=True)
class FilterSettings:
    """Cut-offs of the band-pass filter, in cycles per metre of vertical displacement u_z.

    The filter keeps spatial frequencies f with ``f_lo <= f <= f_hi``. ``f_lo = 0`` keeps the mean
    and slow trends (a plain low-pass); ``f_hi = None`` keeps all high frequencies. The CLI takes
    both in cycles per millimetre.

    Attributes
    ----------
    f_lo : float
        Lower cut-off [1/m], ≥ 0. Default 0.
    f_hi : float or None
        Upper cut-off [1/m]. Default 2000 /m = 2 cycles/mm (wavelengths below 0.5 mm of
        displacement are noise: the field and the forces vary over millimetres).
    """

    f_lo: float = 0.0
    f_hi: float | None = 2000.0

    def __post_init__(self):
        if not (math.isfinite(self.f_lo) and self.f_lo >= 0.0):
            raise MagtactError(f"filter: f_lo must be >= 0 and finite, got {self.f_lo}")
        if self.f_hi is not None and not (math.isfinite(self.f_hi) and self.f_hi > self.f_lo):
            raise MagtactError(f"filter: f_hi ({self.f_hi} 1/m) must exceed f_lo ({self.f_lo} 1/m)")

    @property
    def active(self) -> bool:
        """False when the filter passes everything."""
        return self.f_lo > 0.0 or self.f_hi is not None


def bandpass(y, dx: float, settings: FilterSettings) -> np.ndarray:
    """Band-pass filter ``y`` sampled at uniform spacing ``dx`` by an ideal FFT mask.

    Parameters
    ----------
    y : array_like, shape (n,)
        Samples at uniform spacing.
    dx : float
        Sample spacing [m] (its sign does not matter).
    settings : FilterSettings
        Cut-offs [1/m].

    Returns
    -------
    numpy.ndarray, shape (n,)
        The filtered samples.

    Notes
    -----
    A measured curve is not periodic, so a plain FFT would see a jump between its two ends and
    ring. A straight line ℓ through estimates of the two end values is split off, y = ℓ + r. Each
    end value is the least-squares parabola through the samples within two cut-off wavelengths
    2/f_hi of that end, evaluated at the end (so noise on the last sample does not pin the
    curve; with ``f_hi = None`` the end samples themselves). The residual r nearly vanishes at
    both ends, and its odd extension [r, −r reversed] of period 2(n − 1)|dx| is nearly continuous
    with a continuous slope, so its Fourier coefficients decay fast. The ideal mask is applied to
    that extension at frequencies f_k = k / (2 (n − 1) |dx|). The line ℓ is kept when
    ``f_lo = 0`` and removed otherwise (it is the slowest content of the curve).
    """
    y = np.asarray(y, dtype=float)
    n = y.size
    if n < 3 or not settings.active:
        return y.copy()
    s = np.linspace(0.0, 1.0, n)
    w = 1 if settings.f_hi is None else int(round(2.0 / (settings.f_hi * abs(dx)))) + 1
    w = min(max(w, 1), n)
    ends = (_end_value(y[:w]), _end_value(y[::-1][:w]))
    line = ends[0] + (ends[1] - ends[0]) * s
    r = y - line
    ext = np.concatenate([r, -r[-2:0:-1]])  # period 2(n − 1)
    spectrum = np.fft.rfft(ext)
    f = np.fft.rfftfreq(ext.size, d=abs(dx))
    keep = f >= settings.f_lo
    if settings.f_hi is not None:
        keep &= f <= settings.f_hi
    filtered = np.fft.irfft(spectrum * keep, n=ext.size)[:n]
    return filtered + (line if settings.f_lo == 0.0 else 0.0)


def _end_value(y: np.ndarray) -> float:
    """Value at index 0 of the least-squares parabola through ``y`` (y[0] if len < 4)."""
    if y.size < 4:
        return float(y[0])
    return float(np.polyfit(np.arange(y.size, dtype=float), y, 2)[-1])
