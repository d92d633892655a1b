"""The unit fit checks the presses' sign convention and keeps its scales physical: forces in
the load's sign (−F) or a flipped field give a negative scale, which is refused, and so is a
scale outside the range a unit of the design can have."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from magtact._errors import MagtactError
from magtact.calibration import Presses, UnitParameters, calibrate_unit, sensor_map
from magtact.calibration._unit import SCALE_RANGE
from magtact.optimise import per_design
from magtact.study import load_study

H, G = 3.5e-3, 26e3
SIGN = "forces look like the load's sign: F_z must be positive in compression"


@pytest.fixture(scope="module")
def smap(models):
    s = load_study(None)
    return sensor_map(models, s, H, G, design=per_design(models, H, G, s))


def presses_of(smap, unit: UnitParameters, seed: int = 3):
    """Exact presses of a unit over the region (normal and sheared, random azimuths)."""
    rng = np.random.default_rng(seed)
    th = smap.theta_m
    loads = np.array([[t, th * k / 4, rng.uniform(-np.pi, np.pi)]
                      for t, k in [(0.0, 0), (0.3, 0), (0.7, 0), (1.0, 0), (0.5, 4), (0.9, 3),
                                   (0.6, 2), (1.0, 4)]])
    return replace(smap, field_source="exact").with_unit(unit).at_load(*loads.T)


@pytest.mark.parametrize("unit", [UnitParameters(1.12, 0.97, (-1e-4, 5e-5, 0.0)),
                                  UnitParameters(0.7, 1.05)])
def test_forces_in_the_loads_sign_are_refused(smap, unit):
    B, F = presses_of(smap, unit)
    assert calibrate_unit(smap, Presses(B, F)).unit.G_scale == pytest.approx(unit.G_scale,
                                                                              rel=1e-3)
    with pytest.raises(MagtactError, match=SIGN):
        calibrate_unit(smap, Presses(B, -F))
    # only the normal force flipped: still not the map's convention
    with pytest.raises(MagtactError, match="presses"):
        calibrate_unit(smap, Presses(B, F * np.array([1.0, 1.0, -1.0])))


@pytest.mark.parametrize("name, factor", [("B_scale", 2.0), ("G_scale", 8.0)])
def test_scales_outside_the_physical_range_are_refused(smap, name, factor):
    unit = UnitParameters(factor if name == "G_scale" else 1.0,
                          factor if name == "B_scale" else 1.0)
    B, F = presses_of(smap, unit, seed=5)
    lo, hi = SCALE_RANGE[name]
    assert not lo <= factor <= hi
    with pytest.raises(MagtactError, match=rf"fit {name} = .*outside the physical range"):
        calibrate_unit(smap, Presses(B, F))


@pytest.mark.long  # the command designs the sensor first (about a minute on two cores)
def test_press_file_in_the_loads_sign_is_refused_by_the_command(smap, tmp_path, refused):
    from magtact.calibration import write_presses

    B, F = presses_of(smap, UnitParameters(0.9, 1.01))
    path = write_presses(Presses(B, -F), tmp_path / "presses.csv")
    refused(["calibrate", "--out", str(tmp_path / "o"), "--H", "3.5", "--G", "26",
             "--presses", str(path)], SIGN)
    assert not (tmp_path / "o" / "force.h").exists()
