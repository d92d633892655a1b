"""One sensor as a value: the body, the magnet and the chip a design is built from.

A :class:`Sensor` is what a designer builds and what ``force.h`` is calibrated for: the body's
height, radius, silicone and shear modulus, the magnet's size, grade and magnetisation, and the
Hall chip's part, setting and distance below the body. ``Result.sensor`` is the chosen one;
:func:`magtact.calibrate`, :func:`magtact.error_budget` and ``Result.evaluate_sensor`` take one.

The study describes the problem (requirements, ranges, catalogue, loading, tolerances) and the
parts it starts from; a design's parts travel as a sensor beside it, never inside a modified
study (:meth:`Sensor.of_study` gives the study's own parts at a design).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ._errors import MagtactError
from ._records import entry, from_json_or_none, keys, to_json
from .parts import SILICONES, ChipSetting
from .study import MU0, Study, from_si


@dataclass(frozen=True)
class SettingRecord:
    """A chip's setting (:class:`magtact.parts.ChipSetting`) as the files hold it: the fields
    in the order of the MLX90393's datasheet."""

    gain_sel: int | None = entry(kind=int, optional=True)
    res: int | None = entry(kind=int, optional=True)
    osr: int | None = entry(kind=int, optional=True)
    dig_filt: int | None = entry(kind=int, optional=True)


#: The chip setting fields in the order of the MLX90393's datasheet.
SETTING_FIELDS = keys(SettingRecord)


@dataclass(frozen=True)
class Sensor:
    """One sensor, every quantity in SI.

    Attributes
    ----------
    H, G : float
        The body's base height [m] and shear modulus [Pa].
    R : float
        The body's radius [m].
    silicone : str
        The silicone the body is cast from (``"none"``: not named).
    R_m, H_m : float
        The magnet's radius and height [m].
    grade : str
        The magnet's grade (``"custom"``: the magnetisation as given).
    M_z : float
        The magnet's axial magnetisation [A/m].
    chip : str
        The Hall chip's part (the study's ``[hall] chip``).
    setting : ChipSetting or None
        The chip's setting (None: a chip without a setting table).
    standoff : float
        The chip's distance below the body [m].

    Examples
    --------
    >>> import magtact
    >>> result = magtact.design()                                   # doctest: +SKIP
    >>> result.sensor.changed(grade="N42", standoff=1e-3)           # doctest: +SKIP
    """

    H: float = entry(unit="mm")
    G: float = entry(unit="kPa")
    R: float = entry(unit="mm")
    silicone: str = entry(kind=str)
    R_m: float = entry("magnet_R_m_mm", "mm")
    H_m: float = entry("magnet_H_m_mm", "mm")
    grade: str = entry("magnet_grade", kind=str)
    M_z: float = entry(unit="A_per_m")
    chip: str = entry(kind=str)
    setting: ChipSetting | None = entry("chip_setting", kind=SettingRecord, shape=ChipSetting,
                                        optional=True)
    standoff: float = entry(unit="mm")

    @classmethod
    def of_study(cls, study: Study, H: float, G: float, M_z: float | None = None,
                 **geometry: float) -> Sensor:
        """The sensor of design (H [m], G [Pa]) with ``study``'s own parts: its magnet (of
        magnetisation ``M_z`` [A/m] where given), silicone, chip at the study's standoff and
        setting (None: the study's ``[hall]`` setting, or one picked per design), and the
        values [m] of its geometric design variables given in ``geometry`` (``R``, ``R_m``,
        ``H_m``)."""
        m, b = study.magnet, study.body
        return cls(float(H), float(G), float(geometry.get("R", b.R)), study.material.silicone,
                   float(geometry.get("R_m", m.R_m)), float(geometry.get("H_m", m.H_m)),
                   m.grade, float(m.M_z if M_z is None else M_z), study.hall.chip, None,
                   float(study.hall.standoff))

    def changed(self, *, H: float | None = None, G: float | None = None,
                grade: str | None = None, standoff: float | None = None,
                setting: ChipSetting | None = None, silicone: str | None = None) -> Sensor:
        """This sensor with the parts named changed and every other kept (SI; a grade sets
        M_z from the catalogue's nominal remanence)."""
        out = self
        if grade is not None:
            out = replace(out, grade=grade, M_z=grade_M_z(grade))
        for name, value in (("H", H), ("G", G), ("standoff", standoff), ("setting", setting),
                            ("silicone", silicone)):
            if value is not None:
                out = replace(out, **{name: value})
        return out

    def check(self, study: Study, free: tuple[str, ...] = ()) -> None:
        """Refuse a sensor that ``study``'s models cannot answer for: a body radius, magnet
        size or chip other than the study's (``free``: its geometric design variables, which
        the sensor may set), or a silicone the catalogue does not hold.

        Raises
        ------
        MagtactError
            Naming the part and the study's own.
        """
        for name, what, mine, own in (("R", "body radius", self.R, study.body.R),
                                      ("R_m", "magnet radius", self.R_m, study.magnet.R_m),
                                      ("H_m", "magnet height", self.H_m, study.magnet.H_m)):
            if name not in free and abs(mine - own) > 1e-12:
                raise MagtactError(f"the sensor's {what} ({from_si(mine, 'mm'):.4g} mm) is "
                                   f"not study {study.name!r}'s ({from_si(own, 'mm'):.4g} "
                                   "mm): its models are for the study's")
        if self.chip != study.hall.chip:
            raise MagtactError(f"the sensor's chip {self.chip} is not study {study.name!r}'s "
                               f"({study.hall.chip})")
        if self.silicone != "none" and self.silicone not in SILICONES:
            raise MagtactError(f"silicone: {self.silicone!r} is not in the catalogue; the "
                               f"silicones: {', '.join(SILICONES)}")

    def to_json(self) -> dict:
        """The sensor in user units, each key naming its unit."""
        return to_json(self)

    @classmethod
    def from_json(cls, data) -> Sensor | None:
        """The sensor :meth:`to_json` wrote, back in SI; None for anything else."""
        return from_json_or_none(cls, data)

    def words(self) -> str:
        """The sensor in one line (mm, kPa, MA/m; 3 significant figures)."""
        setting = "" if self.setting is None else f" at {self.setting.words()}"
        return (f"H {from_si(self.H, 'mm'):.3g} mm, G {from_si(self.G, 'kPa'):.3g} kPa "
                f"({self.silicone}), R {from_si(self.R, 'mm'):.3g} mm; magnet ⌀"
                f"{from_si(2 * self.R_m, 'mm'):.3g} × {from_si(self.H_m, 'mm'):.3g} mm "
                f"{self.grade}, M_z {self.M_z / 1e6:.4g} MA/m; {self.chip}{setting}, "
                f"{from_si(self.standoff, 'mm'):.3g} mm below the body")

    def __str__(self) -> str:
        """Body, magnet and chip, one per line (≤ 25 lines of ≤ 100 characters)."""
        from ._display import sensor_parts_rows, text_block

        return text_block(*sensor_parts_rows(self))

    def _repr_html_(self) -> str:
        from ._display import html_block, sensor_parts_rows

        return html_block(*sensor_parts_rows(self))


def grade_M_z(grade: str) -> float:
    """M_z [A/m] of a catalogue grade (its nominal remanence over μ0).

    Raises
    ------
    MagtactError
        For a grade that is not a catalogue name (the message lists them).
    """
    from .parts import grade as catalogue_grade

    if not isinstance(grade, str):
        raise MagtactError(f"grade: expected a catalogue name such as 'N42', got "
                           f"{type(grade).__name__}")
    try:
        return float(catalogue_grade(grade).M_z(MU0)[0])
    except KeyError as exc:
        raise MagtactError(f"grade: {exc.args[0]}") from None
