"""NdFeB magnet grades and cylinder sizes, and the shear modulus of castable silicones, from
``magtact/parts/data`` (docs/method.md §10)."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources

#: One psi in Pa.
PSI = 6894.757293168


def _load(name: str) -> dict:
    return tomllib.loads(resources.files("magtact.parts").joinpath("data", name)
                         .read_text("utf-8"))


@dataclass(frozen=True)
class Grade:
    """A sintered NdFeB grade: remanence B_r [T] min and max, its temperature coefficient
    [1/K] and the largest working temperature [°C]."""

    name: str
    B_r_min: float
    B_r_max: float
    alpha: float
    max_temperature_C: float
    source: str

    @property
    def B_r(self) -> float:
        """Nominal remanence [T]: the midpoint of min and max (the catalogue states none)."""
        return 0.5 * (self.B_r_min + self.B_r_max)

    def M_z(self, mu0: float) -> tuple[float, float, float]:
        """(nominal, min, max) magnetisation M = B_r / μ0 [A/m]."""
        return (self.B_r / mu0, self.B_r_min / mu0, self.B_r_max / mu0)


@dataclass(frozen=True)
class Size:
    """An axially magnetised cylinder: radius R_m and height H_m [m]."""

    name: str
    R_m: float
    H_m: float
    source: str


@dataclass(frozen=True)
class Relaxation:
    """A silicone's relaxation: G(t) = G_∞ (1 + Σ g_i exp(−t/τ_i)), with ``g`` the ratios
    G_i / G_∞ and ``tau`` the times [s], from ``source`` (the publication and its test)."""

    g: tuple[float, ...]
    tau: tuple[float, ...]
    source: str


@dataclass(frozen=True)
class Silicone:
    """A silicone's shear modulus figures G [Pa], each with (source, method), and its
    relaxation (None where no cited series is known: ``relaxation_note`` says what was
    searched)."""

    name: str
    figures: tuple[tuple[float, str, str], ...]
    relaxation: Relaxation | None = None
    relaxation_note: str = ""

    @property
    def G_range(self) -> tuple[float, float]:
        values = [g for g, _, _ in self.figures]
        return (min(values), max(values))

    def contains(self, G: float) -> bool:
        lo, hi = self.G_range
        return lo <= G <= hi


def _grades() -> dict[str, Grade]:
    d = _load("magnets.toml")["grades"]
    out = {}
    for k, v in d.items():
        if isinstance(v, list):
            out[k] = Grade(k, float(v[0]), float(v[1]), d["alpha_Br_percent_per_C"] / 100.0,
                           float(d["max_temperature_C"]), d["source"])
    return out


def _sizes() -> dict[str, Size]:
    d = _load("magnets.toml")["sizes"]
    return {k: Size(k, 0.5e-3 * v["D_mm"], 1e-3 * v["H_mm"], v["source"]) for k, v in d.items()}


def _silicones() -> dict[str, Silicone]:
    d = _load("silicones.toml")
    out = {}
    for name, v in d["silicone"].items():
        figs = []
        if "psi_100" in v:
            s = d["smooth_on_100_percent_modulus"]
            figs.append((v["psi_100"] * PSI / 3.0, s["source"] + f" ({v['psi_100']:g} psi)",
                         s["method"]))
        if "yeoh_C1_MPa" in v:
            s = d["yeoh_fit"]
            figs.append((2.0 * v["yeoh_C1_MPa"] * 1e6, s["source"] + f" (C1 = "
                         f"{v['yeoh_C1_MPa']:g} MPa)", s["method"]))
        if "pdms_ratio" in v:
            s = d["pdms_compression"]
            figs.append((20e6 / v["pdms_ratio"] / 3.0, s["source"] + f" (ratio "
                         f"{v['pdms_ratio']:g}:1)", s["method"]))
        rel = v.get("relaxation")
        relaxation = None if rel is None else Relaxation(
            tuple(float(x) for x in rel["g"]), tuple(float(x) for x in rel["tau_s"]),
            str(rel["source"]))
        note = "" if relaxation is not None else d["relaxation_search"]["result"]
        out[name] = Silicone(name, tuple(figs), relaxation, note)
    return out


#: NdFeB grades by name (N35 ... N52).
GRADES: dict[str, Grade] = _grades()
#: Cylinder sizes by name ("<diameter>x<height>" in mm).
SIZES: dict[str, Size] = _sizes()
#: Silicones by name.
SILICONES: dict[str, Silicone] = _silicones()


def _lookup(table: dict, name: str, what: str):
    if name not in table:
        raise KeyError(f"unknown {what} {name!r}; known: {', '.join(table)}")
    return table[name]


def grade(name: str) -> Grade:
    """The grade ``name`` (KeyError listing the known ones)."""
    return _lookup(GRADES, name, "magnet grade")


def size(name: str) -> Size:
    """The cylinder size ``name`` (KeyError listing the known ones)."""
    return _lookup(SIZES, name, "magnet size")


def silicones_around(G: float) -> tuple[list[Silicone], Silicone | None, Silicone | None]:
    """The silicones whose G range contains ``G`` [Pa], and the nearest softer and stiffer
    ones whose ranges do not (None where there is none)."""
    inside = [s for s in SILICONES.values() if s.contains(G)]
    below = [s for s in SILICONES.values() if s.G_range[1] < G]
    above = [s for s in SILICONES.values() if s.G_range[0] > G]
    return (inside, max(below, key=lambda s: s.G_range[1], default=None),
            min(above, key=lambda s: s.G_range[0], default=None))
