"""One sensor as a value: the body, the magnet and the chip a design is built from.

A :class:`Sensor` is what a designer builds and what ``force.h`` is calibrated for: the body's
height, radius, silicone and shear modulus, the magnet's size, grade and magnetisation, and the
Hall chip's part, setting and distance below the body. ``Result.sensor`` is the chosen one;
:func:`magtact.calibrate`, :func:`magtact.error_budget` and ``Result.evaluate_sensor`` take one.

The lower functions of magtact still read a design's parts from a study; :meth:`Sensor.into`
and :func:`with_parts` are the one place where a sensor's parts are put into one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ._errors import MagtactError
from .parts import ChipSetting
from .study import MU0, Study, from_si

#: The chip setting fields in the order of the MLX90393's datasheet.
SETTING_FIELDS = ("gain_sel", "res", "osr", "dig_filt")


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

    H: float
    G: float
    R: float
    silicone: str
    R_m: float
    H_m: float
    grade: str
    M_z: float
    chip: str
    setting: ChipSetting | None
    standoff: float

    @classmethod
    def of(cls, answer) -> Sensor:
        """The sensor of a designer's answer (:class:`magtact.designer.DesignAnswer`): its
        design (H, G) and the parts of the study it was answered with."""
        s = answer.study
        if s is None:
            raise MagtactError(f"the answer {answer.label!r} holds no study: its parts are "
                               "not known")
        figures = answer.chip.figures
        M_z = s.magnet.M_z if answer.design.M_z is None else float(answer.design.M_z)
        return cls(float(answer.H), float(answer.G), s.body.R, s.material.silicone,
                   s.magnet.R_m, s.magnet.H_m, s.magnet.grade, float(M_z), s.hall.chip,
                   None if figures is None else figures.setting, s.hall.standoff)

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

    def into(self, study: Study, free: tuple[str, ...] = ()) -> Study:
        """``study`` with this sensor's parts: the magnet's grade and M_z, the chip's standoff
        and setting, the silicone (:func:`with_parts`). ``free``: the study's geometric design
        variables (``R``, ``R_m``, ``H_m``), which the sensor may set.

        Raises
        ------
        MagtactError
            If the sensor's body radius, magnet size or chip are not the study's (those need
            models of their own).
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
        return with_parts(study, grade=self.grade, M_z=self.M_z, standoff=self.standoff,
                          setting=self.setting, silicone=self.silicone)

    def to_json(self) -> dict:
        """The sensor in user units, each key naming its unit."""
        return {"H_mm": from_si(self.H, "mm"), "G_kPa": from_si(self.G, "kPa"),
                "R_mm": from_si(self.R, "mm"), "silicone": self.silicone,
                "magnet_R_m_mm": from_si(self.R_m, "mm"),
                "magnet_H_m_mm": from_si(self.H_m, "mm"), "magnet_grade": self.grade,
                "M_z_A_per_m": self.M_z, "chip": self.chip,
                "chip_setting": None if self.setting is None else {
                    k: getattr(self.setting, k) for k in SETTING_FIELDS},
                "standoff_mm": from_si(self.standoff, "mm")}

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


def with_parts(study: Study, *, grade: str | None = None, M_z: float | None = None,
               standoff: float | None = None, setting: ChipSetting | None = None,
               silicone: str | None = None) -> Study:
    """``study`` with a design's parts (SI; None keeps the study's): the magnet's grade and
    M_z (a grade alone sets M_z from the catalogue), the chip's standoff and setting (fixed
    in ``[hall]``), the silicone.

    Raises
    ------
    MagtactError
        For a grade or a silicone that is not in the catalogue.
    """
    magnet, hall, material = study.magnet, study.hall, study.material
    if grade is not None:
        magnet = replace(magnet, grade=grade, M_z=grade_M_z(grade) if M_z is None else M_z)
    elif M_z is not None:
        magnet = replace(magnet, M_z=float(M_z))
    if standoff is not None:
        hall = replace(hall, standoff=float(standoff))
    if setting is not None and setting.gain_sel is not None:
        hall = replace(hall, **{k: int(getattr(setting, k)) for k in SETTING_FIELDS})
    if silicone is not None:
        from .parts import SILICONES

        if silicone != "none" and silicone not in SILICONES:
            raise MagtactError(f"silicone: {silicone!r} is not in the catalogue; the "
                               f"silicones: {', '.join(SILICONES)}")
        material = replace(material, silicone=silicone)
    return replace(study, magnet=magnet, hall=hall, material=material)
