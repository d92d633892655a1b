"""Hall chips: presets from the vendors' datasheets and the study's own figures.

Every preset figure is a datasheet statement, cited with the setting it holds for. A figure the
datasheets magtact cites do not state (the RMS noise depends on gain, resolution, oversampling
and filter settings) is left out: the study must give it, and the message says so.
"""

from __future__ import annotations

from dataclasses import dataclass

from ._load import StudyError
from ._model import Study


@dataclass(frozen=True)
class HallPreset:
    """What a datasheet states about a chip (SI; None: not stated in the cited source)."""

    name: str
    range_x: float | None
    range_z: float | None
    noise_x: float | None
    noise_z: float | None
    setting: str
    source: str


#: Chip presets (docs/method.md §10).
HALL_PRESETS: dict[str, HallPreset] = {
    "MLX90393": HallPreset(
        "Melexis MLX90393", 50e-3, 50e-3, None, None,
        setting="lowest gain (GAIN_SEL), the widest range",
        source="Melexis MLX90393 Triaxis Magnetic Node datasheet, rev. 006 (2020), "
               "Features: 'Wide dynamic range (5-50mT) with on-the-fly programmable gain'"),
    "TLE493D": HallPreset(
        "Infineon TLE493D (W2B6 / P2B6)", 160e-3, 160e-3, None, None,
        setting="full range",
        source="Infineon TLE493D-W2B6 datasheet v1.2 (2019), Features: '3D magnetic flux "
               "density sensing of ±160 mT'"),
}


@dataclass(frozen=True)
class HallChip:
    """The study's Hall chip: noise σ [T RMS] and range [T, ±] per axis (x: shear, z: normal).

    ``noise`` is None when neither the study nor the preset gives it; ``missing`` then names
    the study keys to set.
    """

    name: str
    noise_x: float | None
    noise_z: float | None
    range_x: float
    range_z: float
    setting: str
    source: str

    @property
    def noise(self) -> tuple[float, float] | None:
        """(σ_x, σ_z) [T], or None if not known."""
        if self.noise_x is None or self.noise_z is None:
            return None
        return (self.noise_x, self.noise_z)

    @property
    def missing(self) -> tuple[str, ...]:
        """Study keys whose figure is unknown."""
        return tuple(k for k, v in (("hall.noise_x_uT", self.noise_x),
                                    ("hall.noise_z_uT", self.noise_z)) if v is None)


def hall_chip(study: Study) -> HallChip:
    """The Hall chip of ``study``: its ``[hall]`` figures, zeros filled from the chip preset.

    Raises
    ------
    StudyError
        For a ``custom`` chip without a range (the range has no default).
    """
    h = study.hall
    preset = HALL_PRESETS.get(h.chip)

    def pick(value: float, attr: str):
        if value > 0:
            return value
        return None if preset is None else getattr(preset, attr)

    out = {}
    for attr in ("noise_x", "noise_z", "range_x", "range_z"):
        out[attr] = pick(getattr(h, attr), attr)
    for attr in ("range_x", "range_z"):
        if out[attr] is None:
            raise StudyError(f"hall.{attr}_mT", "give the chip's measuring range (> 0): a "
                                                "'custom' chip has no preset")
    own = any(getattr(h, a) > 0 for a in ("noise_x", "noise_z", "range_x", "range_z"))
    if preset is None:
        return HallChip("custom chip", out["noise_x"], out["noise_z"], out["range_x"],
                        out["range_z"], "as given in the study", "the study")
    return HallChip(preset.name, out["noise_x"], out["noise_z"], out["range_x"],
                    out["range_z"], preset.setting,
                    preset.source + ("; figures given in the study replace the preset's"
                                     if own else ""))
