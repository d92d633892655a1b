"""Hall chips as data: a chip setting determines its LSB, range, noise and sample rate
(docs/method.md §10).

The tables live in ``magtact/parts/data/<chip>.toml``, each figure with the table or figure of
the datasheet it comes from. For the MLX90393 a setting is (GAIN_SEL, RES, OSR, DIG_FILT):

- LSB: Table 17 (µT/LSB by GAIN_SEL, RES and axis);
- range: min(output limit × LSB, B_SAT), the limit by RES (Table 21), B_SAT from Table 9;
- conversion time per axis T = 67 + 64 · 2^OSR · (2 + 2^DIG_FILT) µs (Table 8), full TXYZ read
  time and the largest output data rate from Tables 19 and 20;
- noise: the datasheet plots it at GAIN_SEL 7 only (Figures 2 and 3, read off the plot). At
  another gain the analog noise σ_a lies in an interval: its lower end is the gain-7 noise in µT
  (the front end is no quieter at a lower gain), its upper end the gain-7 noise in LSB times the
  setting's µT/LSB (the noise scales with the LSB). The interval collapses at gain 7.

The noise of a reading adds the quantisation of its LSB q: σ = √(σ_a² + q²/12). A noise the
user measured at the setting replaces the interval and is taken as the reading's total noise.

What a chip the study names has (a setting table, setting fields, rate data, datasheet
tolerances, or nothing: a custom chip) is :func:`chip_part`'s answer, read off the data files,
so that callers ask the part instead of comparing chip names.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields
from functools import cache
from importlib import resources

from .._errors import MagtactError

#: Chips with a data file (the study's ``[hall] chip`` names).
CHIP_FILES: dict[str, str] = {"MLX90393": "mlx90393.toml", "TLV493D": "tlv493d.toml"}
#: The study's name of a chip of the user's own: no data, the study gives its noise and range.
CUSTOM_CHIP = "custom"


class SettingError(MagtactError):
    """A chip setting that does not exist or is not permitted; ``key`` names the setting field
    (``gain_sel``, ``res``, ``osr``, ``dig_filt``, ``noise_x``, ``noise_z``)."""

    def __init__(self, key: str, message: str):
        self.key, self.reason = key, message
        super().__init__(f"[{key}] {message}")


@cache
def _data(chip: str) -> dict:
    name = CHIP_FILES[chip]
    return tomllib.loads(resources.files("magtact.parts").joinpath("data", name)
                         .read_text("utf-8"))


def _setting_field(word: str, values: int, pair: bool = False):
    """A setting field of the MLX90393: its name in the datasheet, how many values it takes (0
    to ``values`` - 1) and whether it is one of the pair (OSR, DIG_FILT) whose combinations
    the datasheet permits or not (``conversion.not_permitted`` of the chip's data file)."""
    return field(default=None, metadata={"datasheet": word, "values": values, "pair": pair})


@dataclass(frozen=True)
class ChipSetting:
    """One setting of a programmable chip (None: the chip has no such field)."""

    gain_sel: int | None = _setting_field("GAIN_SEL", 8)
    res: int | None = _setting_field("RES", 4)
    osr: int | None = _setting_field("OSR", 4, pair=True)
    dig_filt: int | None = _setting_field("DIG_FILT", 8, pair=True)

    def words(self) -> str:
        """The setting as the datasheet writes it, e.g. ``GAIN_SEL 7, RES 0, OSR 0, DIG_FILT 2``."""
        parts = [f"{MLX_FIELDS[k][0]} {v}" for k, v in self.__dict__.items() if v is not None]
        return ", ".join(parts) or "the chip's only setting"


#: The MLX90393's setting fields (those of :class:`ChipSetting`, in datasheet order), their
#: datasheet names and how many values each takes.
MLX_FIELDS: dict[str, tuple[str, int]] = {
    f.name: (f.metadata["datasheet"], f.metadata["values"]) for f in fields(ChipSetting)}
#: The setting fields (OSR, DIG_FILT) whose pairs the datasheet permits or not, in the order of
#: the pairs of ``conversion.not_permitted``; the error for a pair not permitted names the
#: second.
PERMITTED_PAIR: tuple[str, str] = tuple(f.name for f in fields(ChipSetting) if f.metadata["pair"])


@dataclass(frozen=True)
class SettingFigures:
    """What a chip reads at one setting (SI: T, s, Hz).

    ``noise_*`` are the analog noise intervals (low, high) [T RMS], equal ends where the source
    states the figure (or the user measured it); ``sigma_*`` add the quantisation LSB/√12 (not
    to a measured figure). ``noise_source`` says where the noise comes from and what each end
    assumes.
    """

    chip: str
    setting: ChipSetting
    lsb_x: float
    lsb_z: float
    range_x: float
    range_z: float
    noise_x: tuple[float, float]
    noise_z: tuple[float, float]
    sigma_x: tuple[float, float]
    sigma_z: tuple[float, float]
    conversion_time: float
    rate: float
    noise_source: str
    source: str

    @property
    def words(self) -> str:
        return self.setting.words()

    @property
    def interval(self) -> bool:
        """Whether the noise is an interval (the ends differ)."""
        return self.sigma_x[0] != self.sigma_x[1] or self.sigma_z[0] != self.sigma_z[1]


def _total(analog: tuple[float, float], lsb: float) -> tuple[float, float]:
    q2 = lsb * lsb / 12.0
    return (math.sqrt(analog[0] ** 2 + q2), math.sqrt(analog[1] ** 2 + q2))


class ChipTable:
    """A chip's datasheet tables (see the module notes); ``ChipTable("MLX90393")``."""

    def __init__(self, chip: str):
        if chip not in CHIP_FILES:
            raise SettingError("chip", f"no table for {chip!r}; known: {', '.join(CHIP_FILES)}")
        self.chip = chip
        self.data = _data(chip)
        #: Whether the chip has settings to choose (its data file lists their fields).
        self.programmable = bool(self.data.get("settings"))

    @property
    def name(self) -> str:
        return self.data["name"]

    # ---- MLX90393 tables ----------------------------------------------------------------------
    def lsb(self, gain_sel: int, res: int) -> tuple[float, float]:
        """(x, z) µT/LSB of Table 17 in T/LSB."""
        s = self.data["sensitivity"]
        return (s["xy_uT_per_LSB"][gain_sel][res] * 1e-6, s["z_uT_per_LSB"][gain_sel][res] * 1e-6)

    def output_limit(self, res: int) -> int:
        return int(self.data["output_limit"]["LSB"][res])

    @property
    def B_sat(self) -> float:
        return self.data["saturation"]["B_sat_mT"] * 1e-3

    def tolerance(self) -> tuple[float, float, float, str] | None:
        """The datasheet's band of the sensitivity (relative, ±) and of the offset on x and z
        [T] over the temperature range, and where they come from; None where the data give
        none."""
        d = self.data.get("tolerance")
        if d is None:
            return None
        x, z = self.lsb(d["offset_gain_sel"], d["offset_res"])
        return (d["sensitivity_percent"] / 100.0, d["offset_LSB"] * x, d["offset_LSB"] * z,
                d["source"])

    @staticmethod
    def axis_time(osr: int, dig_filt: int) -> float:
        """T_CONVM = 67 + 64 · 2^OSR · (2 + 2^DIG_FILT) µs, in s (Table 8)."""
        return (67.0 + 64.0 * 2**osr * (2 + 2**dig_filt)) * 1e-6

    def permitted(self, osr: int, dig_filt: int) -> bool:
        return [osr, dig_filt] not in self.data["conversion"]["not_permitted"]

    def gain7_noise(self, osr: int, dig_filt: int) -> tuple[float, float]:
        """(x, z) RMS noise [T] at GAIN_SEL 7 read off Figures 2 and 3 (NaN: not readable)."""
        n = self.data["noise"]
        return (n["xy_uT"][dig_filt][osr] * 1e-6, n["z_uT"][dig_filt][osr] * 1e-6)

    def settings(self):
        """Every setting the chip permits, in datasheet order."""
        if not self.programmable:
            yield ChipSetting()
            return
        for g in range(8):
            for r in range(4):
                for o in range(4):
                    for d in range(8):
                        if self.permitted(o, d):
                            yield ChipSetting(g, r, o, d)

    @property
    def fastest(self) -> float:
        """The largest sample rate [Hz] of any permitted setting."""
        if not self.programmable:
            return float(self.data["max_rate_Hz"])
        rates = self.data["conversion"]["max_rate_Hz"]
        return max(rates[d][o] for o in range(4) for d in range(8) if self.permitted(o, d))

    def check(self, setting: ChipSetting) -> None:
        """Refuse a setting the chip does not have or does not permit (SettingError)."""
        if not self.programmable:
            for k, v in setting.__dict__.items():
                if v is not None:
                    raise SettingError(k, f"the {self.name} has no {MLX_FIELDS[k][0]} setting; "
                                          "leave it at -1")
            return
        for k, (word, n) in MLX_FIELDS.items():
            v = getattr(setting, k)
            if v is None or not 0 <= v < n:
                raise SettingError(k, f"{word} must be an integer from 0 to {n - 1}, got {v!r}")
        if not self.permitted(setting.osr, setting.dig_filt):
            bad = ", ".join(f"OSR {o} / DIG_FILT {d}"
                            for o, d in self.data["conversion"]["not_permitted"])
            source = self.data["conversion"]["not_permitted_source"]
            raise SettingError(PERMITTED_PAIR[1],
                               f"OSR {setting.osr} with DIG_FILT {setting.dig_filt} is not "
                               f"permitted with HALLCONF = 0xC ({source}; not permitted: {bad})")

    def figures(self, setting: ChipSetting, noise: tuple[float, float] | None = None
                ) -> SettingFigures:
        """LSB, range, noise and rate at ``setting``; ``noise`` = (σ_x, σ_z) [T] measured by the
        user at this setting (None per axis: the datasheet's) replaces the datasheet's.

        Raises
        ------
        SettingError
            For a setting the chip does not have or permit, or a noise ≤ 0.
        """
        self.check(setting)
        noise = (None, None) if noise is None else tuple(noise)
        for k, v in zip(("noise_x", "noise_z"), noise, strict=True):
            if v is not None and not (v > 0 and math.isfinite(v)):
                raise SettingError(k, f"a measured RMS noise must be > 0, got {v!r}")
        d = self.data
        if not self.programmable:
            lsb = d["LSB_uT"] * 1e-6
            rng = d["range_mT"] * 1e-3
            n = d["noise_uT"] * 1e-6
            src = (f"{d['document']}: {d['noise_source']}; quantisation {d['LSB_uT']:g} µT/√12 "
                   "added")
            return self._figures(setting, (lsb, lsb), (rng, rng), ((n, n), (n, n)), noise,
                                 1.0 / d["max_rate_Hz"], d["max_rate_Hz"], src)
        g, r, o, f = setting.gain_sel, setting.res, setting.osr, setting.dig_filt
        lsb = self.lsb(g, r)
        limit = self.output_limit(r)
        rng = tuple(min(limit * v, self.B_sat) for v in lsb)
        n7 = self.gain7_noise(o, f)
        lsb7 = self.lsb(7, r)
        analog = tuple((a, a if g == 7 else a / l7 * lv)
                       for a, l7, lv in zip(n7, lsb7, lsb, strict=True))
        conv = d["conversion"]
        src = (f"{d['document']}: {d['noise']['source']} ({d['noise']['precision']})")
        if g != 7:
            src += (f"; at GAIN_SEL {g} the datasheet states no noise: the interval's lower end "
                    "assumes the gain-7 noise in µT (the front end is no quieter at a lower "
                    "gain), its upper end the gain-7 noise in LSB times this gain's µT/LSB "
                    "(noise scaling with the LSB)")
        src += "; quantisation LSB/√12 added"
        return self._figures(setting, lsb, rng, analog, noise, conv["T_txyz_ms"][f][o] * 1e-3,
                             conv["max_rate_Hz"][f][o], src)

    def _figures(self, setting, lsb, rng, analog, noise, t_conv, rate, src) -> SettingFigures:
        sig = [_total(analog[0], lsb[0]), _total(analog[1], lsb[1])]
        analog = list(analog)
        for k, v in enumerate(noise):
            if v is not None:  # a measured figure: the reading's total noise
                analog[k] = sig[k] = (v, v)
        if all(v is not None for v in noise):
            src = "measured by the user at this setting (the study's hall.noise_x_uT, noise_z_uT)"
        elif any(v is not None for v in noise):
            src = ("measured by the user at this setting along "
                   + " and ".join(a for a, v in zip("xz", noise, strict=True) if v is not None)
                   + "; the other axis: " + src)
        return SettingFigures(self.name, setting, lsb[0], lsb[1], rng[0], rng[1], analog[0],
                              analog[1], sig[0], sig[1], float(t_conv), float(rate), src,
                              self.data["document"])


def chip_table(chip: str) -> ChipTable:
    """The tables of ``chip`` (``"MLX90393"``, ``"TLV493D"``)."""
    return ChipTable(chip)


@dataclass(frozen=True)
class ChipPart:
    """What a Hall chip the study may name has, read off its data file.

    Attributes
    ----------
    name : str
        The study's name of the chip (``[hall] chip``).
    table : ChipTable or None
        The chip's datasheet tables; None for a chip without a data file (a preset of the
        study, which states its range only, or a custom chip).
    custom : bool
        A chip of the user's own: no data at all, the study gives its noise and range.
    """

    name: str
    table: ChipTable | None
    custom: bool

    @property
    def setting_fields(self) -> tuple[str, ...]:
        """The setting fields the chip has (keys of :data:`MLX_FIELDS`), in datasheet order;
        empty for a chip with one setting or no table."""
        if self.table is None:
            return ()
        words = self.table.data.get("settings", ())
        return tuple(k for k, (word, _) in MLX_FIELDS.items() if word in words)

    @property
    def has_settings(self) -> bool:
        """Whether the chip has settings to choose (a table of them)."""
        return self.table is not None and self.table.programmable

    @property
    def has_rate(self) -> bool:
        """Whether the chip's data give its sample rate."""
        if self.table is None:
            return False
        d = self.table.data
        return "max_rate_Hz" in d or "max_rate_Hz" in d.get("conversion", {})

    def tolerance(self) -> tuple[float, float, float, str] | None:
        """The datasheet's sensitivity and offset bands (:meth:`ChipTable.tolerance`); None
        where the chip has no data or its data give none."""
        return None if self.table is None else self.table.tolerance()


@cache
def chip_part(name: str) -> ChipPart:
    """The chip the study names ``name`` (``[hall] chip``): its tables where it has a data
    file, whether it is a custom chip."""
    return ChipPart(name, ChipTable(name) if name in CHIP_FILES else None,
                    custom=name == CUSTOM_CHIP)


def widest(table: ChipTable) -> tuple[float, float]:
    """The widest range (x, z) [T] over the chip's settings."""
    if not table.programmable:
        r = table.data["range_mT"] * 1e-3
        return (r, r)
    lsb = [table.lsb(g, r) for g in range(8) for r in range(4)]
    lim = [table.output_limit(r) for g in range(8) for r in range(4)]
    return tuple(max(min(n * v[k], table.B_sat) for n, v in zip(lim, lsb, strict=True))
                 for k in range(2))
