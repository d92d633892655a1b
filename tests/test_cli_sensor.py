"""``magtact calibrate`` and ``magtact budget`` act on the chosen sensor, and are the API calls
``magtact.calibrate(result, ...)`` and ``magtact.error_budget(result, ...)``: on the built-in
study and on a what-if of the chosen sensor (grade N42, the chip 1.0 mm below the body, Dragon
Skin 10) the files they write are those of the API (``force.h`` byte for byte, the JSON numbers
to relative 1e-9).

The commands run in this process (typer's runner); their ``magtact.design`` of the built-in
study is the session's (the same call, computed once per test process)."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest
from typer.testing import CliRunner

import magtact
from magtact import MagtactError, Sensor
from magtact.cli import app

#: The what-if: the options and the same change of the chosen sensor through the API.
WHAT_IF_OPTIONS = ["--grade", "N42", "--standoff-mm", "1.0", "--silicone", "Dragon Skin 10"]
WHAT_IF = {"grade": "N42", "standoff": 1.0e-3, "silicone": "Dragon Skin 10"}


@pytest.fixture
def cli(magone_design, monkeypatch):
    """Run ``magtact ARGS`` in this process; the command's design of the built-in study is the
    session's ``magtact.design()`` (checked to be asked for that study and those models)."""
    real = magtact.design

    def design(study=None, **kwargs):
        if study == magone_design.study and not any(kwargs.get(k) for k in
                                                    ("data", "models", "refit")):
            return magone_design
        return real(study, **kwargs)

    monkeypatch.setattr(magtact, "design", design)

    def run(*args: str) -> str:
        got = CliRunner().invoke(app, list(args))
        assert got.exit_code == 0, (got.output, got.exception)
        return got.output
    return run


def close(a, b, path="") -> None:
    """JSON documents equal, numbers to relative 1e-9."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), (path, a, b)
        for k in a:
            close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            close(x, y, f"{path}[{k}]")
    elif isinstance(a, float) and not isinstance(a, bool):
        assert isinstance(b, float | int), path
        assert a == b or math.isclose(a, b, rel_tol=1e-9), (path, a, b)
    else:
        assert a == b, (path, a, b)


def _flat(text: str) -> str:
    """The text with its whitespace folded (the console wraps long lines)."""
    return " ".join(text.split())


def _json(path):
    return json.loads(path.read_text(encoding="utf-8"))


def _what_if(result) -> Sensor:
    return result.sensor.changed(**WHAT_IF)


def test_the_chosen_sensor_is_the_chosen_answers(magone_design):
    r = magone_design
    s = r.sensor
    assert isinstance(s, Sensor)
    assert (s.H, s.G, s.M_z, s.standoff) == (r.chosen.H, r.chosen.G, r.variables["M_z"],
                                             r.variables["standoff"])
    assert s.grade == r.sensor_design.choice.grade
    assert s.setting == r.chosen.chip.figures.setting
    assert (s.R, s.R_m, s.H_m) == (r.study.body.R, r.study.magnet.R_m, r.study.magnet.H_m)
    # the silicone chosen, whose cited G range holds G
    assert s.silicone == r.sensor_design.choice.silicone
    lo, hi = magtact.parts.SILICONES[s.silicone].G_range
    assert lo <= s.G <= hi
    # the chosen answer is for this sensor, a design of the study as it was given
    assert r.chosen.sensor == s and r.chosen.study == r.study
    with pytest.raises(AttributeError):
        s.H = 1.0  # a frozen value


def test_a_changed_sensor_changes_only_what_is_named(magone_design):
    s = magone_design.sensor
    w = _what_if(magone_design)
    from magtact.parts import grade

    assert w.M_z == pytest.approx(grade("N42").M_z(magtact.study.MU0)[0], rel=1e-15)
    assert replace(w, grade=s.grade, M_z=s.M_z, standoff=s.standoff, silicone=s.silicone) == s
    with pytest.raises(MagtactError, match="grade: .*N99"):
        s.changed(grade="N99")
    with pytest.raises(MagtactError, match="silicone: 'Ecoflex 99' is not in the catalogue"):
        s.changed(silicone="Ecoflex 99").check(magone_design.study)
    with pytest.raises(MagtactError, match="magnet radius"):
        replace(s, R_m=1e-3).check(magone_design.study)


def test_calibrate_command_is_the_api_call(magone_design, cli, tmp_path):
    out = cli("calibrate", "--out", str(tmp_path / "cli"))
    assert _flat(out).startswith(_flat(f"the chosen sensor: {magone_design.sensor.words()}"))
    api = magtact.calibrate(magone_design)
    magtact.calibration.write_calibration_outputs(api, tmp_path / "api")
    assert (tmp_path / "cli/force.h").read_bytes() == (tmp_path / "api/force.h").read_bytes()
    close(_json(tmp_path / "cli/calibration.json"), _json(tmp_path / "api/calibration.json"))
    # the chosen sensor's magnet and standoff, not the study's own magnet
    design = _json(tmp_path / "cli/calibration.json")["design"]
    sensor = magone_design.sensor
    assert design["M_z_A_per_m"] == pytest.approx(sensor.M_z, rel=1e-12)
    assert (design["magnet_grade"], design["silicone"], design["chip"]) == (
        sensor.grade, sensor.silicone, sensor.chip)
    assert design["standoff_mm"] == pytest.approx(1e3 * sensor.standoff, rel=1e-12)
    assert design["chip_setting"] == {k: getattr(sensor.setting, k)
                                      for k in ("gain_sel", "res", "osr", "dig_filt")}
    assert design["M_z_A_per_m"] != pytest.approx(magone_design.study.magnet.M_z, rel=1e-3)


def test_calibrate_command_on_a_what_if_is_the_api_call(magone_design, cli, tmp_path):
    out = cli("calibrate", "--out", str(tmp_path / "cli"), *WHAT_IF_OPTIONS)
    sensor = _what_if(magone_design)
    said = _flat(f"the chosen sensor with the options given: {sensor.words()}")
    assert _flat(out).startswith(said)
    assert "N42" in said and "Dragon Skin 10" in said and "1 mm below" in said
    api = magtact.calibrate(magone_design, sensor)
    magtact.calibration.write_calibration_outputs(api, tmp_path / "api")
    assert (tmp_path / "cli/force.h").read_bytes() == (tmp_path / "api/force.h").read_bytes()
    close(_json(tmp_path / "cli/calibration.json"), _json(tmp_path / "api/calibration.json"))
    # another sensor than the chosen one: the N42 magnet at 1 mm
    M_z = _json(tmp_path / "cli/calibration.json")["design"]["M_z_A_per_m"]
    assert M_z == pytest.approx(sensor.M_z, rel=1e-12) and sensor != magone_design.sensor


@pytest.mark.parametrize("what_if", [False, True], ids=["built-in", "what-if"])
def test_budget_command_is_the_api_call(magone_design, cli, tmp_path, what_if):
    args = WHAT_IF_OPTIONS if what_if else []
    out = cli("budget", "--out", str(tmp_path / "cli"), *args)
    assert _flat(out).startswith("the chosen sensor")
    api = magtact.error_budget(magone_design, _what_if(magone_design) if what_if else None,
                               dataset=magone_design.dataset)
    magtact.budget.write_budgets([api], magone_design.study, tmp_path / "api")
    close(_json(tmp_path / "cli/budget.json"), _json(tmp_path / "api/budget.json"))
    if what_if:  # the budget of the sensor given: its silicone's time rows, its magnet
        assert api.label == "sensor"
    else:
        assert api.label == "chosen"


def test_the_options_change_only_what_they_name(magone_design, cli, tmp_path):
    """--H alone keeps G, the magnet, the standoff and the setting of the chosen sensor."""
    from magtact.cli._budget import chosen_or_given

    s = magone_design.sensor
    sensor, given = chosen_or_given(magone_design, H=4.0)
    assert given and sensor == replace(s, H=4e-3)
    sensor, given = chosen_or_given(magone_design, setting="RES=1")
    assert given and sensor == replace(s, setting=replace(s.setting, res=1))
    assert chosen_or_given(magone_design) == (s, False)


@pytest.mark.parametrize(("args", "fragments"), [
    (["--grade", "N99"], ["--grade:", "N99"]),
    (["--silicone", "Ecoflex 99"], ["--silicone:", "'Ecoflex 99' is not in the catalogue"]),
    (["--setting", "GAIN=5"], ["--setting must be FIELD=V pairs", "GAIN_SEL"]),
    (["--setting", "RES=x"], ["--setting: RES must be an integer"]),
    (["--setting", "RES=1,RES=2"], ["--setting names RES twice"]),
    (["--setting", "RES=7"], ["--setting:", "RES"]),
    (["--standoff-mm", "-1"], ["--standoff-mm"]),
    (["--H", "0"], ["--H"]),
])
@pytest.mark.parametrize("command", ["budget", "calibrate"])
def test_bad_sensor_options_are_refused_naming_the_option(magone_design, monkeypatch, refused,
                                                          tmp_path, command, args, fragments):
    monkeypatch.setattr(magtact, "design", lambda *a, **k: magone_design)
    refused([command, "--out", str(tmp_path / "o"), *args], *fragments)
    assert not (tmp_path / "o" / ("budget.json" if command == "budget" else "force.h")).exists()
