"""The chip settings a sensor design chooses from (docs/method.md §10).

A setting matters to a design through its range (±range_x, ±range_z), its noise (σ_x, σ_z, the
upper end of the setting's interval: the end that holds under both assumptions) and its sample
rate. Among the permitted settings that reach the required rate, those of one range are
compared by their noise: the one with the least σ_x² + σ_z² (then the fastest) represents the
range, since with the same range a noisier setting is never the better choice.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

from ..parts import SettingFigures
from ..study import HallChip, Study, StudyError, candidate_settings, hall_chip, setting_figures


@dataclass(frozen=True)
class ChipOption:
    """One choice of the chip's setting for a sensor design (SI: T, Hz).

    ``rate`` is NaN where magtact's data give no sample rate (chips without a setting table);
    ``figures`` is None for them.
    """

    range_x: float
    range_z: float
    noise_x: float
    noise_z: float
    rate: float
    words: str
    figures: SettingFigures | None = None


def require_noise(chip: HallChip, what: str) -> tuple[float, float]:
    """The chip's RMS field noise (σ_x, σ_z) [T] for ``what`` (words: "the sensor problem").

    Raises
    ------
    StudyError
        Naming ``hall.noise_x_uT`` where neither the study nor the chip's data give it.
    """
    if chip.noise is None:
        raise StudyError("hall.noise_x_uT", f"{what} needs the {chip.name}'s RMS field noise: "
                                            "give hall.noise_x_uT and hall.noise_z_uT (> 0)")
    return chip.noise


def chip_options(study: Study) -> list[ChipOption]:
    """The settings of the study's chip a design chooses from, one per range (see the module
    notes), among those the study's ``[hall]`` fields allow and that reach
    ``[requirements] rate_Hz``; widest range first.

    Raises
    ------
    StudyError
        Naming ``hall.noise_x_uT`` for a chip whose noise is not known.
    """
    return list(_options(study.hall, study.requirements.rate))


@functools.lru_cache(maxsize=32)
def _options(hall, rate: float) -> tuple[ChipOption, ...]:
    """:func:`chip_options` of a ``[hall]`` section and a required rate [Hz] (they depend on
    nothing else: kept, since every solve of the sensor problem asks for them)."""
    base = Study(hall=hall)
    study = replace(base, requirements=replace(base.requirements, rate=rate))
    chip = hall_chip(study)
    if not chip.picked:
        noise = require_noise(chip, "the sensor problem")
        rate = chip.figures.rate if chip.figures is not None else math.nan
        return (ChipOption(chip.range_x, chip.range_z, *noise, rate, chip.setting,
                           chip.figures),)
    best: dict[tuple[float, float], SettingFigures] = {}
    for s in candidate_settings(study):
        f = setting_figures(study, s)
        if not (f.rate >= study.requirements.rate and math.isfinite(f.sigma_x[1])
                and math.isfinite(f.sigma_z[1])):
            continue
        key = (f.range_x, f.range_z)
        old = best.get(key)
        if old is None or (_power(f), -f.rate) < (_power(old), -old.rate):
            best[key] = f
    options = [ChipOption(f.range_x, f.range_z, f.sigma_x[1], f.sigma_z[1], f.rate, f.words, f)
               for f in best.values()]
    return tuple(sorted(options, key=lambda o: (-o.range_z, -o.range_x, o.noise_z)))


def _power(f: SettingFigures) -> float:
    return f.sigma_x[1] ** 2 + f.sigma_z[1] ** 2
