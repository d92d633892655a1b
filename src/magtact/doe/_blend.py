"""A magnet between the bundled sizes: the weighted sum of the data sets (and shipped fits) of
the sizes around it.

The weights are Lagrange's: the value at the magnet is the weighted sum of the values at the
sizes, derivatives alike, exact for a quadratic. Along the radius (sizes of one height), the
quadratic through the three radii nearest the magnet's and around it (docs/method.md §10: the
forces interpolate within 2 % of their range on the magnet-size DOE). Between the bundled
heights, the quadratic through the three heights, each height's value at the magnet's radius
being its size of that radius where there is one, else the blend along the radius of that
height (the quadratic through three sizes, or the line through the two around it where only two
describe the study); the weight of a size is the product of its height's and its radius'.
"""

from __future__ import annotations

import json

import numpy as np

from .._errors import MagtactError
from ..study import from_si


def lagrange_weights(nodes, x: float) -> np.ndarray:
    """The weights of the polynomial through ``nodes`` at ``x`` (Lagrange): a value at ``x``
    is the weighted sum of the values at the nodes, derivatives alike.

    .. math:: w_k = \\prod_{m \\ne k} \\frac{x - x_m}{x_k - x_m}
    """
    r = np.asarray(nodes, dtype=float)
    return np.array([np.prod([(x - r[m]) / (r[k] - r[m]) for m in range(r.size) if m != k])
                     for k in range(r.size)])


def _mm(x: float) -> str:
    return f"{from_si(x, 'mm'):.3g}"


def _described(study, sizes) -> list[tuple[str, float, float, object]]:
    """(size, R_m, H_m, study at that size) of each broad bundled size whose data describe
    ``study`` with its magnet."""
    from ..parts import SIZES
    from ._dataset import _outline, bundled_path, differences

    out = []
    for size in sizes:
        name = f"broad_{size}_doe.nc"
        sub = study.sized(size)
        if bundled_path(name).is_file() and not differences(_outline(name), sub):
            out.append((size, SIZES[size].R_m, SIZES[size].H_m, sub))
    return out


def _along_radius(held, R_m: float, lowest: int) -> list[tuple[float, tuple]] | None:
    """The weights of the sizes ``held`` (of one height) at radius ``R_m``: the size itself,
    else the quadratic through the three radii nearest it and around it, else (``lowest`` 2)
    the line through the two around it; None where none is."""
    for h in held:
        if np.isclose(h[1], R_m, rtol=1e-9):
            return [(1.0, h)]
    near = sorted(held, key=lambda h: abs(h[1] - R_m))[:3]
    for n in (3, 2) if lowest <= 2 else (3,):
        if len(near) < n:
            continue
        pick = near[:n] if n == 3 else [max((h for h in held if h[1] < R_m), default=None,
                                            key=lambda h: h[1]),
                                        min((h for h in held if h[1] > R_m), default=None,
                                            key=lambda h: h[1])]
        if any(h is None for h in pick):
            continue
        radii = [h[1] for h in pick]
        if min(radii) < R_m < max(radii):
            return list(zip(lagrange_weights(radii, R_m), pick, strict=True))
    return None


def blend_weights(study, sizes) -> list[tuple[float, str, object]]:
    """(weight, size, study at that size) of the blend of ``study``'s magnet from the broad
    bundled ``sizes`` (see the module notes).

    Raises
    ------
    MagtactError
        Saying why no blend answers the study.
    """
    R_m, H_m = study.magnet.R_m, study.magnet.H_m
    mine = f"{_mm(2 * R_m)} × {_mm(H_m)} mm"
    held = _described(study, sizes)
    heights = sorted({h[2] for h in held})
    if any(np.isclose(h, H_m, rtol=1e-9) for h in heights):
        same = [h for h in held if np.isclose(h[2], H_m, rtol=1e-9)]
        found = _along_radius(same, R_m, lowest=3)
        if found is None:
            names = ", ".join(h[0] for h in sorted(same, key=lambda h: h[1])) or "none"
            raise MagtactError(
                f"nor is the {mine} magnet a blend of bundled sizes: a blend along the radius "
                "takes three sizes of its height around it that describe the study (those "
                f"that do: {names})")
        return [(float(w), h[0], h[3]) for w, h in found]
    near = sorted(heights, key=lambda h: abs(h - H_m))[:3]
    if len(near) < 3 or not min(near) < H_m < max(near):
        raise MagtactError(
            f"nor is the {mine} magnet a blend of bundled sizes: a blend along the height takes "
            "three heights of bundled sizes around its own (those that describe the study: "
            + (", ".join(_mm(h) for h in heights) or "none") + " mm)")
    out: dict[str, list] = {}
    for wh, h in zip(lagrange_weights(near, H_m), near, strict=True):
        same = [x for x in held if np.isclose(x[2], h, rtol=1e-9)]
        found = _along_radius(same, R_m, lowest=2)
        if found is None:
            raise MagtactError(
                f"nor is the {mine} magnet a blend of bundled sizes: at the height {_mm(h)} mm "
                f"no bundled size has its diameter of {_mm(2 * R_m)} mm or lies on both sides "
                "of it")
        for wr, x in found:
            out.setdefault(x[0], [0.0, x[3]])[0] += float(wh * wr)
    return [(w, size, sub) for size, (w, sub) in out.items()]


def bundled_blend(study, sizes: tuple[str, ...] | None = None) -> tuple:
    """The magnet of ``study`` as a blend of the broad bundled data sets around it (see the
    module notes). Returns the blended data set (forces, displacements and fields, each the
    weighted sum; rescaled to the study's G levels and magnetisation) and the parts ``(size
    name, weight, data set, study at that size)``. ``sizes``: the broad sizes it may blend
    (default: all of :data:`magtact.doe.BROAD_SIZES`).

    Raises
    ------
    MagtactError
        Saying why no blend answers the study.
    """
    from ._dataset import BROAD_SIZES, load_bundled, rescaled_for

    weights = blend_weights(study, BROAD_SIZES if sizes is None else sizes)
    parts = tuple((size, w, rescaled_for(load_bundled(f"broad_{size}_doe.nc"), sub), sub)
                  for w, size, sub in weights)
    blend = sum(w * ds[list(ds.data_vars)] for _, w, ds, _ in parts)
    along = "radius" if len({p[3].magnet.H_m for p in parts}) == 1 else "height and radius"
    blend.attrs = dict(parts[0][2].attrs) | {
        "study_toml": study.to_toml(),
        "blended_from": json.dumps({size: w for size, w, _, _ in parts}),
        "blending": f"the weighted sum along the magnet's {along} of the bundled data sets "
                    "of the sizes around it (Lagrange's quadratic weights)"}
    for name in blend.data_vars:
        blend[name].attrs = dict(parts[0][2][name].attrs)
    return blend, parts
