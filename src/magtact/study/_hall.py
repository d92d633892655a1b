"""Hall chips: the chip tables of :mod:`magtact.parts`, presets from the vendors' datasheets and
the study's own figures (docs/method.md §10).

The MLX90393 and the TLV493D have tables (``magtact/parts/data``): a chip setting determines
their LSB, range, noise and sample rate. For the MLX90393 the study may fix the setting
(``[hall] gain_sel``, ``res``, ``osr``, ``dig_filt``) or leave any part of it at -1, and then
magtact picks, per design, the setting with the lowest force noise (see
:func:`magtact.designer.best_setting`). The TLE493D has a preset with its range only (no noise
figure was found in magtact's sources): the study must give its noise.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..parts import (
    MLX_FIELDS,
    PERMITTED_PAIR,
    ChipSetting,
    SettingError,
    SettingFigures,
    chip_part,
    chip_table,
)
from ._errors import StudyError
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


#: Chip presets without a setting table (docs/method.md §10).
HALL_PRESETS: dict[str, HallPreset] = {
    "TLE493D": HallPreset(
        "Infineon TLE493D (W2B6 / P2B6)", 160e-3, 160e-3, None, None,
        setting="full range",
        source="Infineon TLE493D-W2B6 datasheet v1.2 (2019), Features: '3D magnetic flux "
               "density sensing of ±160 mT'"),
}


@dataclass(frozen=True)
class HallChip:
    """The study's Hall chip: noise σ [T RMS] and range [T, ±] per axis (x: shear, z: normal).

    ``noise`` is None when neither the study nor the chip's data give it: ``missing`` then
    names the study keys to set, or, when ``picked`` (a chip setting magtact picks per design),
    the noise comes with the setting (:func:`magtact.designer.best_setting`). The range of a
    picked setting is the widest the study's fixed setting fields allow.
    """

    name: str
    noise_x: float | None
    noise_z: float | None
    range_x: float
    range_z: float
    setting: str
    source: str
    picked: bool = False
    figures: SettingFigures | None = None

    @property
    def noise(self) -> tuple[float, float] | None:
        """(σ_x, σ_z) [T], or None if not known."""
        if self.noise_x is None or self.noise_z is None:
            return None
        return (self.noise_x, self.noise_z)

    @property
    def missing(self) -> tuple[str, ...]:
        """Study keys whose figure is unknown without a design (a setting picked per design
        brings its noise: :func:`magtact.designer.answer`)."""
        return tuple(k for k, v in (("hall.noise_x_uT", self.noise_x),
                                    ("hall.noise_z_uT", self.noise_z)) if v is None)


def fixed_setting(study: Study) -> dict[str, int]:
    """The MLX90393 setting fields the study fixes (``-1``: picked), by field name."""
    return {k: getattr(study.hall, k) for k in MLX_FIELDS if getattr(study.hall, k) >= 0}


def own_noise(study: Study) -> tuple[float | None, float | None]:
    """The noise (σ_x, σ_z) [T] the study gives (None where 0: the chip data's)."""
    return tuple(v if v > 0 else None for v in (study.hall.noise_x, study.hall.noise_z))


def candidate_settings(study: Study):
    """The permitted settings of the study's chip that agree with its fixed fields."""
    table = chip_table(study.hall.chip)
    fixed = fixed_setting(study)
    for s in table.settings():
        if all(getattr(s, k) == v for k, v in fixed.items()):
            yield s


def setting_figures(study: Study, setting: ChipSetting) -> SettingFigures:
    """LSB, range, noise and rate of the study's chip at ``setting``, the study's own noise
    figures replacing the chip data's, and its own ranges (where given) the setting's."""
    fig = chip_table(study.hall.chip).figures(setting, own_noise(study))
    h = study.hall
    if h.range_x > 0 or h.range_z > 0:
        fig = replace(fig, range_x=h.range_x or fig.range_x, range_z=h.range_z or fig.range_z)
    return fig


def check_hall(study: Study) -> None:
    """Refuse a ``[hall]`` setting the chip does not have or permit, a sample rate it cannot
    reach, and a custom chip without its noise (StudyError naming the key)."""
    h = study.hall
    if study.optimise.objective == "sigma_F" and study.sensitivity.definition != "jacobian":
        raise StudyError("optimise.objective", "the force noise σ_F needs the Jacobian "
                                               "sensitivity (sensitivity.definition = "
                                               "'jacobian')")
    fixed = fixed_setting(study)
    part = chip_part(h.chip)
    for k in fixed:
        if k not in part.setting_fields:
            raise StudyError(f"hall.{k}", f"the {h.chip} has no {MLX_FIELDS[k][0]} setting; "
                                          "leave it at -1 (the MLX90393's only)")
    if part.custom:
        for k, v in (("noise_x", h.noise_x), ("noise_z", h.noise_z)):
            if not v > 0:
                raise StudyError(f"hall.{k}_uT", "give the chip's RMS field noise (> 0): a "
                                                 "'custom' chip has no data")
    if not part.has_rate:  # the verdict says the rate is unknown
        return
    table = part.table
    for k, v in fixed.items():
        word, n = MLX_FIELDS[k]
        if v >= n:
            raise StudyError(f"hall.{k}", f"{word} of the {table.name} is 0 to {n - 1} (-1: "
                                          f"magtact picks it), got {v}")
    if all(k in fixed for k in PERMITTED_PAIR):  # the pair fixed: is it permitted?
        pair = {k: fixed[k] for k in PERMITTED_PAIR}
        try:
            table.check(ChipSetting(**dict.fromkeys(MLX_FIELDS, 0) | pair))
        except SettingError as exc:
            raise StudyError(f"hall.{exc.key}", exc.reason) from None
    rate = study.requirements.rate
    if rate > table.fastest:
        raise StudyError("requirements.rate_Hz", f"{rate:g} Hz is above the {table.name}'s "
                                             f"fastest permitted sample rate, {table.fastest:g} "
                                             "Hz (full XYZ read)")
    rates = [setting_figures(study, s).rate for s in _rate_classes(study)]
    if rates and max(rates) < rate:
        raise StudyError("requirements.rate_Hz", f"{rate:g} Hz is above the fastest sample "
                                             f"rate of the fixed setting fields, "
                                             f"{max(rates):g} Hz")


def _rate_classes(study: Study):
    """One candidate setting per (OSR, DIG_FILT) (the rate depends on these only)."""
    seen = set()
    for s in candidate_settings(study):
        if (s.osr, s.dig_filt) not in seen:
            seen.add((s.osr, s.dig_filt))
            yield s


def hall_chip(study: Study, setting: ChipSetting | None = None) -> HallChip:
    """The Hall chip of ``study``: its ``[hall]`` figures, zeros filled from the chip's data.

    For a chip with a setting table and the setting fixed (or a chip with one setting, or a
    design's ``setting`` given), the setting's range and noise (upper end of its interval);
    for a setting magtact picks per design, the widest range the fixed fields allow and no
    noise (``picked``).

    Raises
    ------
    StudyError
        For a ``custom`` chip without a range (the range has no default).
    """
    h = study.hall
    table = chip_part(h.chip).table
    if table is not None:
        at_setting = setting is not None and setting.gain_sel is not None
        cands = [setting] if at_setting else list(candidate_settings(study))
        if len(cands) == 1:
            fig = setting_figures(study, cands[0])
            own = any(v > 0 for v in (h.noise_x, h.noise_z, h.range_x, h.range_z))
            return HallChip(fig.chip, fig.sigma_x[1], fig.sigma_z[1], fig.range_x, fig.range_z,
                            fig.words, fig.source + ("; figures given in the study replace the "
                                                     "chip data's" if own else ""),
                            figures=fig)
        pairs = {(s.gain_sel, s.res) for s in cands}
        ranges = [tuple(min(table.output_limit(r) * v, table.B_sat) for v in table.lsb(g, r))
                  for g, r in pairs]
        rx = h.range_x or max(r[0] for r in ranges)
        rz = h.range_z or max(r[1] for r in ranges)
        fixed = fixed_setting(study)
        given = ChipSetting(**{k: fixed.get(k) for k in MLX_FIELDS}).words()
        words = ("picked per design: the lowest force noise whose range holds the field over "
                 "the stable region" + (f", with {given}" if fixed else ""))
        nx, nz = own_noise(study)  # measured figures hold whatever the setting
        return HallChip(table.name, nx, nz, rx, rz, words, table.data["document"], picked=True)
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


__all__ = ["HALL_PRESETS", "HallChip", "HallPreset", "candidate_settings", "check_hall",
           "fixed_setting", "hall_chip", "own_noise", "setting_figures"]
