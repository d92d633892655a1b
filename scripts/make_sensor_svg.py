"""Draw docs/sensor.svg: the sensor's cross-section in the plane of shear, with its symbols.

The dimensions are those of the built-in MagOne study at H = 3 mm and θ = θ_max, read from
``magtact.study.magone()``, so the figure follows the defaults. Plain SVG text, no plotting
library::

    python scripts/make_sensor_svg.py [--out docs/sensor.svg]
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

from magtact.study import from_si, magone

SCALE = 40.0  # px per mm
X0, Y0 = 400.0, 500.0  # pixel position of the Hall point (the origin)
FONT = 'font-family="DejaVu Sans, Helvetica, Arial, sans-serif"'


def px(x_mm: float, z_mm: float) -> tuple[float, float]:
    """Pixel coordinates of a point (x, z) [mm] of the plane of shear."""
    return X0 + SCALE * x_mm, Y0 - SCALE * z_mm


def label(text: str, size: int = 15) -> str:
    """SVG text content with ``a_bc`` written as a subscript (``_`` then letters/digits)."""
    out = []
    for part in re.split(r"(_[A-Za-z0-9,]+)", text):
        if part.startswith("_"):
            sub = round(0.7 * size)
            out.append(f'<tspan baseline-shift="sub" font-size="{sub}">{part[1:]}</tspan>')
        else:
            out.append(part.replace("&", "&amp;").replace("<", "&lt;"))
    return "".join(out)


def text(x: float, y: float, s: str, anchor: str = "start", size: int = 15,
         color: str = "#222") -> str:
    return (f'<text x="{x:.1f}" y="{y:.1f}" text-anchor="{anchor}" font-size="{size}" '
            f'fill="{color}" {FONT}>{label(s, size)}</text>')


def line(a, b, style: str = 'stroke="#222" stroke-width="1.2"') -> str:
    return f'<line x1="{a[0]:.1f}" y1="{a[1]:.1f}" x2="{b[0]:.1f}" y2="{b[1]:.1f}" {style}/>'


def dim_v(x_mm: float, z0: float, z1: float, name: str, at: tuple[float, float]) -> list[str]:
    """A vertical dimension line at x from z0 to z1 [mm], labelled ``name`` starting at ``at``
    (x, z) [mm]."""
    a, b = px(x_mm, z0), px(x_mm, z1)
    style = 'stroke="#1f4e9a" stroke-width="1.2" marker-start="url(#arr)" marker-end="url(#arr)"'
    return [line(a, b, style), text(*px(*at), name, color="#1f4e9a")]


def dim_h(z_mm: float, x0: float, x1: float, name: str, above: bool = True) -> list[str]:
    """A horizontal dimension line at z from x0 to x1 [mm], labelled ``name``."""
    a, b = px(x0, z_mm), px(x1, z_mm)
    style = 'stroke="#1f4e9a" stroke-width="1.2" marker-start="url(#arr)" marker-end="url(#arr)"'
    return [line(a, b, style),
            text(min(a[0], b[0]) + 30, a[1] + (-7 if above else 18), name, color="#1f4e9a")]


def rounded_body(R: float, top: float, R_h: float) -> str:
    """Path of the body's section: rectangle [−R, R] × [0, top] with both top corners rounded."""
    r = SCALE * R_h
    (xl, yb), (xr, yt) = px(-R, 0.0), px(R, top)
    return (f'M {xl:.1f} {yb:.1f} L {xr:.1f} {yb:.1f} L {xr:.1f} {yt + r:.1f} '
            f'A {r:.1f} {r:.1f} 0 0 0 {xr - r:.1f} {yt:.1f} L {xl + r:.1f} {yt:.1f} '
            f'A {r:.1f} {r:.1f} 0 0 0 {xl:.1f} {yt + r:.1f} Z')


def magnet(x_c: float, z_c: float, R_m: float, H_m: float, r_edge: float) -> str:
    """Path of the magnet's section centred at (x_c, z_c) [mm], lower corners rounded."""
    r = SCALE * r_edge
    (xl, yb), (xr, yt) = px(x_c - R_m, z_c - H_m / 2), px(x_c + R_m, z_c + H_m / 2)
    return (f'M {xl:.1f} {yt:.1f} L {xr:.1f} {yt:.1f} L {xr:.1f} {yb - r:.1f} '
            f'A {r:.1f} {r:.1f} 0 0 1 {xr - r:.1f} {yb:.1f} L {xl + r:.1f} {yb:.1f} '
            f'A {r:.1f} {r:.1f} 0 0 1 {xl:.1f} {yb - r:.1f} Z')


def draw(H_mm: float = 3.0) -> str:
    """The SVG document for base height ``H_mm`` at θ = θ_max and t = 1."""
    s = magone()
    R, H_g, R_h = (from_si(v, "mm") for v in (s.body.R, s.body.H_g, s.body.R_h))
    R_m, H_m = from_si(s.magnet.R_m, "mm"), from_si(s.magnet.H_m, "mm")
    dz_sat = from_si(s.loading.dz_sat, "mm")
    r_edge = from_si(s.mechanics.magnet_edge_radius, "mm")
    theta = s.loading.theta_max
    top = H_mm + H_g
    dz0 = H_mm + H_g - H_m  # covered magnet: height of its centre above the Hall point
    u_z = dz_sat + H_m - H_mm - H_g  # t = 1
    u_r = -u_z * math.tan(theta)
    xs, zs = u_r, dz0 + u_z  # magnet centre at t = 1

    el = ['<?xml version="1.0" encoding="UTF-8"?>',
          '<svg xmlns="http://www.w3.org/2000/svg" width="900" height="640" '
          'viewBox="0 0 900 640">',
          '<title>magtact: the sensor and its coordinates</title>',
          '<defs>',
          '<marker id="arr" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
          'markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" '
          'fill="#1f4e9a"/></marker>',
          '<marker id="arrk" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
          'markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" '
          'fill="#222"/></marker>',
          '<marker id="arrr" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
          'markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" '
          'fill="#b22222"/></marker>',
          '<pattern id="hatch" width="8" height="8" patternUnits="userSpaceOnUse" '
          'patternTransform="rotate(45)"><line x1="0" y1="0" x2="0" y2="8" stroke="#777" '
          'stroke-width="1.5"/></pattern>',
          '</defs>',
          '<rect width="900" height="640" fill="white"/>',
          text(450, 28, "The sensor in the plane of shear (y = 0), MagOne defaults, "
                        f"H = {H_mm:g} mm", "middle", 17)]

    # plates
    xa, ya = px(-R - 1.6, 0.0)
    xb, _ = px(R + 1.6, 0.0)
    el.append(f'<rect x="{xa:.1f}" y="{ya:.1f}" width="{xb - xa:.1f}" height="18" '
              'fill="url(#hatch)" stroke="#555"/>')
    el.append(text(xa, ya + 38, "lower rigid plate z = 0 (fixed; contact with friction μ_f)",
                   size=14))
    _, yt = px(0.0, top)
    el.append(f'<rect x="{xa:.1f}" y="{yt - 18:.1f}" width="{xb - xa:.1f}" height="18" '
              'fill="url(#hatch)" stroke="#555"/>')
    el.append(text(xa, yt - 26, "upper rigid plate: moves with the magnet by u = (u_r, u_z); "
                                "contact with friction μ_f", size=14))

    # body, base/upper split, axis
    el.append(f'<path d="{rounded_body(R, top, R_h)}" fill="#f3e7c9" stroke="#8a6d2f" '
              'stroke-width="1.6"/>')
    el.append(line(px(-R, H_mm), px(R, H_mm),
                   'stroke="#8a6d2f" stroke-width="1" stroke-dasharray="5 4"'))
    el.append(line(px(0, -0.6), px(0, top + 0.9),
                   'stroke="#888" stroke-width="1" stroke-dasharray="10 4 2 4"'))

    # magnet, unloaded and at t = 1
    el.append(f'<path d="{magnet(0.0, dz0, R_m, H_m, r_edge)}" fill="#c0392b" '
              'fill-opacity="0.85" stroke="#7b241c" stroke-width="1.4"/>')
    el.append(text(*px(0.6, dz0 + 0.4), "M_z ↑", size=14, color="white"))
    el.append(f'<path d="{magnet(xs, zs, R_m, H_m, r_edge)}" fill="none" stroke="#b22222" '
              'stroke-width="1.4" stroke-dasharray="6 4"/>')
    el.append(text(*px(xs - R_m + 0.1, zs - H_m / 2 - 0.45), "magnet at t = 1 (Δz = Δz_sat)",
                   size=13, color="#b22222"))

    # centre A, the path of A and θ
    a, b = px(0.0, dz0), px(xs, zs)
    el.append(f'<circle cx="{a[0]:.1f}" cy="{a[1]:.1f}" r="3.5" fill="#222"/>')
    el.append(text(a[0] - 18, a[1] - 6, "A", size=15))
    el.append(line(a, b, 'stroke="#b22222" stroke-width="2" marker-end="url(#arrr)"'))
    el.append(f'<circle cx="{b[0]:.1f}" cy="{b[1]:.1f}" r="3" fill="#b22222"/>')
    arc_r = 70.0
    e = (a[0] + arc_r * math.sin(theta), a[1] + arc_r * math.cos(theta))
    el.append(f'<path d="M {a[0]:.1f} {a[1] + arc_r:.1f} A {arc_r} {arc_r} 0 0 0 '
              f'{e[0]:.1f} {e[1]:.1f}" fill="none" stroke="#b22222" stroke-width="1.2"/>')
    mid = theta / 2
    el.append(text(a[0] + (arc_r + 6) * math.sin(mid) + 2, a[1] + (arc_r + 6) * math.cos(mid) + 12,
                   "θ", "start", 16, "#b22222"))
    el.append(text(b[0] + 10, b[1] + 4, "u(t), t ∈ [0, 1]", size=14, color="#b22222"))

    # Hall point, coordinate axes
    h = px(0.0, 0.0)
    el.append(f'<rect x="{h[0] - 16:.1f}" y="{h[1] + 2:.1f}" width="32" height="12" '
              'fill="#2c3e50"/>')
    el.append(f'<circle cx="{h[0]:.1f}" cy="{h[1]:.1f}" r="4.5" fill="#1f77b4" '
              'stroke="white" stroke-width="1.2"/>')
    el.append(line(h, (h[0] + 70, h[1]), 'stroke="#222" stroke-width="1.5" '
                                           'marker-end="url(#arrk)"'))
    el.append(text(h[0] + 74, h[1] + 5, "x (shear, B_r, F_r)", size=14))
    el.append(line(h, (h[0], h[1] - 48), 'stroke="#222" stroke-width="1.5" '
                                           'marker-end="url(#arrk)"'))
    el.append(text(h[0] + 7, h[1] - 26, "z (B_z, F_z)", size=14))
    el.append(text(xa, h[1] + 60, "Hall point = origin (the 3-axis Hall chip sits below the base)",
                   size=14, color="#1f77b4"))
    el.append(line((h[0] - 60, h[1] + 47), (h[0] - 5, h[1] + 6),
                   'stroke="#1f77b4" stroke-width="1"'))

    # dimensions
    el += dim_v(R + 0.9, 0.0, H_mm, "H (design variable)", (R + 1.1, H_mm / 2 - 0.1))
    el += dim_v(R + 0.9, H_mm, top, f"H_g = {H_g:g} mm", (R + 1.1, H_mm + H_g / 2 - 0.1))
    el += dim_v(-R - 0.9, 0.0, dz0, "Δz_0 = H + H_g − H_m", (-R + 0.3, 0.75 * dz0))
    el += dim_v(-R_m - 0.5, dz0 - H_m / 2, dz0 + H_m / 2, f"H_m = {H_m:g}",
                (-R_m - 2.3, dz0 - 0.1))
    el += dim_v(-1.6, 0.0, zs, f"Δz_sat = {dz_sat:g}", (-4.4, 1.3))
    el += dim_h(dz0 + H_m / 2 + 0.35, 0.0, R_m, f"R_m = {R_m:g}")
    el += dim_h(top + 1.25, 0.0, R, f"R = {R:g} mm")
    el.append(text(*px(R - 2.1, top - 1.2), f"R_h = {R_h:g}", size=13, color="#8a6d2f"))
    el.append(text(*px(R_m + 0.35, dz0 - H_m / 2 - 0.35),
                   f"edge fillet {r_edge:g} mm", "start", 13, "#7b241c"))
    el.append(text(*px(-R + 0.3, top - 0.7), f"cover H_m/2 = {H_m / 2:g} mm", "start", 13,
                   "#8a6d2f"))
    el.append(text(*px(-R + 0.3, 0.35), "base part", "start", 13, "#8a6d2f"))
    el.append(text(*px(-R + 0.3, H_mm + 0.3), "upper part", "start", 13, "#8a6d2f"))

    # legend of the load
    y = 596
    el.append(text(30, y, "Loading path: u_z = t (Δz_sat + H_m − H − H_g), u_r = −u_z tan θ; "
                          "t = 1 brings the magnet's centre A to Δz_sat above the Hall point.",
                   size=14))
    el.append(text(30, y + 22, "z up, y = 0 is a plane of symmetry; lengths in mm; the dashed "
                               "line at z = H separates the base part from the upper part.",
                   size=14))
    el.append("</svg>")
    return "\n".join(el) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/sensor.svg"))
    args = parser.parse_args()
    args.out.write_text(draw(), encoding="utf-8")
    print(args.out)


if __name__ == "__main__":
    main()
