"""Study files: presets, unit conversion at the boundary, validation messages, CLI errors."""

import math
import subprocess
import sys

import numpy as np
import pytest

from magtact.geometry import dz0, hall_from_magnet_centre, loading_path, magnet_span
from magtact.study import Study, StudyError, load_study, magone, magone_printed, study_from_dict


def test_magone_values_are_si():
    s = magone()
    assert s.body.R == pytest.approx(6e-3)
    assert s.body.H_g == pytest.approx(4.97e-3)
    assert s.magnet.M_z == 1.2e6
    assert s.material.G_ref == pytest.approx(29.4e3)
    assert s.loading.theta_max == pytest.approx(math.atan(0.45))
    np.testing.assert_allclose(s.H_levels, [3e-3, 4e-3, 5e-3, 6e-3, 7e-3])
    np.testing.assert_allclose(s.G_levels, [10e3, 20e3, 30e3, 40e3, 50e3])
    assert s.t_levels.shape == (21,) and s.t_levels[-1] == 1.0
    assert s.theta_levels[-1] == s.loading.theta_max


def test_default_is_magone_and_file_equals_dataclass_defaults():
    assert load_study() == magone() == load_study("magone")
    # the shipped file spells out exactly the dataclass defaults (one source of truth each)
    assert magone() == Study(description=magone().description)


def test_printed_preset_differs_only_by_G_factor_10():
    a, b = magone(), magone_printed()
    assert b.material.G_ref == pytest.approx(a.material.G_ref / 10)
    np.testing.assert_allclose(b.G_levels, a.G_levels / 10)
    assert b.design.G_original == pytest.approx(a.design.G_original / 10)
    assert (b.body, b.magnet, b.loading) == (a.body, a.magnet, a.loading)


def test_toml_round_trip_is_exact(tmp_path):
    for s in (magone(), magone_printed()):
        f = tmp_path / "s.toml"
        f.write_text(s.to_toml())
        assert load_study(f) == s


def test_partial_file_inherits_from_base(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('name = "tall"\n[design]\nH_mm = [3.0, 9.0]\n')
    s = load_study(f)
    assert s.name == "tall" and s.design.H == pytest.approx((3e-3, 9e-3))
    assert s.body == magone().body


def test_loading_path_general_form():
    s = magone()
    H, t, theta = 4e-3, 0.5, 0.3
    u_r, u_z = loading_path(s, t, theta, H)
    # docs/method.md §1: u_z = t (dz_sat + H_m - H - H_g); u_r = -u_z tan(theta)
    assert u_z == pytest.approx(0.5 * (2.97e-3 + 2e-3 - 4e-3 - 4.97e-3))
    assert u_r == pytest.approx(-u_z * math.tan(0.3))
    # with the defaults H_g = dz_sat + H_m, so the path is -t H
    assert u_z == pytest.approx(-t * H)
    # t = 1 brings the magnet centre to the saturation distance
    _, z = hall_from_magnet_centre(s, *loading_path(s, 1.0, theta, H), H)
    assert -z == pytest.approx(s.loading.dz_sat)


def test_placements():
    s = magone()
    H = 3e-3
    assert dz0(s, H) == pytest.approx(5.97e-3)
    lo, hi = magnet_span(s, H)
    assert (lo, hi) == pytest.approx((4.97e-3, 6.97e-3))  # 1 mm of cover under a 7.97 mm top
    flush = study_from_dict({"magnet": {"placement": "flush"}})
    lo, hi = magnet_span(flush, H)
    assert hi == pytest.approx(H + s.body.H_g) and lo == pytest.approx(dz0(flush, H))
    # flush: distances to the lower face, so the Hall point is H_m/2 further from the centre
    _, z = hall_from_magnet_centre(flush, 0.0, 0.0, H)
    assert -z == pytest.approx(dz0(flush, H) + 1e-3)


BAD = [
    ({"magnet": {"R_mm": 2.0}}, "magnet.R_mm", "did you mean 'R_m_mm'"),
    ({"geometry": {"R_mm": 2.0}}, "geometry", "unknown section"),
    ({"body": {"R_mm": "six"}}, "body.R_mm", "expected a number in mm"),
    ({"body": {"R_mm": -6.0}}, "body.R_mm", "must be positive"),
    ({"body": {"H_g_mm": 0.0}}, "body.H_g_mm", "must be positive"),
    ({"design": {"H_mm": [7.0, 3.0]}}, "design.H_mm", "range out of order"),
    ({"design": {"G_kPa": [10.0]}}, "design.G_kPa", "a range [low, high] in kPa"),
    ({"magnet": {"R_m_mm": 6.5}}, "magnet.R_m_mm", "narrower than the body"),
    ({"magnet": {"H_m_mm": 4.0}}, "magnet.H_m_mm", "upper part"),
    ({"loading": {"dz_sat_mm": 6.5}}, "loading.dz_sat_mm", "cannot reach"),
    ({"loading": {"dz_sat_mm": 0.5}}, "loading.dz_sat_mm", "Hall sensor plane"),
    ({"loading": {"theta_max_rad": 0.5}}, "loading.theta_max_rad", "atan(mu_f)"),
    ({"doe": {"n_t": 2.5}}, "doe.n_t", "integer"),
    ({"doe": {"n_t": 1}}, "doe.n_t", "at least 2"),
    ({"magnet": {"placement": "glued"}}, "magnet.placement", "'covered', 'flush'"),
    ({"mechanics": {"scale_in_G": "yes"}}, "mechanics.scale_in_G", "true or false"),
    ({"design": {"H_original_mm": 9.0}}, "design.H_original_mm", "outside the design range"),
    ({"base": "magtwo"}, "base", "expected one of"),
    ({"base": "none", "name": "x"}, "body.R_mm", "is missing"),
    ({"base": "none"}, "name", "is missing"),
    ({"body": 3}, "body", "expected a table"),
    ({"material": {"bulk_ratio": 10.0}}, "material.bulk_ratio", "at least 1000"),
    ({"body": {"R_mm": float("nan")}}, "body.R_mm", "finite"),
]


@pytest.mark.parametrize(("data", "key", "text"), BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_bad_study_names_key(data, key, text):
    with pytest.raises(StudyError) as err:
        study_from_dict(data, "bad.toml")
    assert err.value.key == key
    msg = str(err.value)
    assert f"[{key}]" in msg and text in msg and msg.startswith("bad.toml:")


def test_not_toml_and_missing_file(tmp_path):
    f = tmp_path / "broken.toml"
    f.write_text("[body\nR_mm = 3")
    with pytest.raises(StudyError, match=r"broken.toml: \[file\] is not valid TOML"):
        load_study(f)
    with pytest.raises(StudyError, match="study file not found"):
        load_study(tmp_path / "nope.toml")


def test_cli_reports_bad_study_without_traceback(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[magnet]\nR_m_mm = 7.0\n")
    res = subprocess.run([sys.executable, "-m", "magtact", "study", str(f)],
                         capture_output=True, text=True)
    assert res.returncode == 2
    assert "[magnet.R_m_mm]" in res.stderr and "narrower than the body" in res.stderr
    assert "Traceback" not in res.stderr + res.stdout


def test_cli_prints_full_study():
    res = subprocess.run([sys.executable, "-m", "magtact", "study", "magone-printed"],
                         capture_output=True, text=True, check=True)
    assert 'G_kPa = [\n    1.0,\n    5.0,\n]' in res.stdout
