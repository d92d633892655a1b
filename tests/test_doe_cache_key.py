"""The DOE cache key: the inputs and an explicit model version, not the text of the source."""

import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import magtact.magnetics
import magtact.mechanics
from magtact.doe._jobs import plan
from magtact.magnetics import hall_field
from magtact.mechanics import simulate_path
from magtact.study import load_study

SRC = Path(magtact.mechanics.__file__).resolve().parents[1]
KEYS = ("from magtact.doe._jobs import plan; from magtact.magnetics import hall_field; "
        "from magtact.mechanics import simulate_path; from magtact.study import load_study; "
        "f, p = plan(load_study('magone'), simulate_path, hall_field); "
        "print(f.key, *[j.key for j in p])")


def _keys(study):
    f, paths = plan(study, simulate_path, hall_field)
    return f.key, [j.key for j in paths]


def test_model_version_and_settings_change_the_key(monkeypatch):
    study = load_study("magone")
    field, paths = _keys(study)
    monkeypatch.setattr(magtact.mechanics, "MODEL_VERSION", magtact.mechanics.MODEL_VERSION + 1)
    f2, p2 = _keys(study)
    assert f2 == field and set(p2).isdisjoint(paths)
    monkeypatch.undo()
    monkeypatch.setattr(magtact.magnetics, "MODEL_VERSION", magtact.magnetics.MODEL_VERSION + 1)
    f3, p3 = _keys(study)
    assert f3 != field and p3 == paths
    monkeypatch.undo()
    tighter = replace(study, mechanics=replace(study.mechanics, newton_tol=1e-7))
    assert set(_keys(tighter)[1]).isdisjoint(paths)
    # settings a path does not read leave its key alone
    other = replace(study, constraints=replace(study.constraints, F_z_c=4.0))
    assert _keys(other) == (field, paths)


def test_a_comment_in_the_mechanics_does_not_change_the_key(tmp_path):
    copy = tmp_path / "src"
    shutil.copytree(SRC, copy / "magtact", ignore=shutil.ignore_patterns("__pycache__", "*.nc",
                                                                         "*.png", "*.svg"))
    model = copy / "magtact" / "mechanics" / "_model.py"
    model.write_text(model.read_text() + "\n# a comment that changes nothing\n")

    def run(path):
        return subprocess.run([sys.executable, "-c", KEYS], capture_output=True, text=True,
                              env={"PYTHONPATH": str(path), "PATH": "/usr/bin:/bin"},
                              timeout=300, check=True).stdout

    assert run(copy) == run(SRC)
