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
    # the relaxation's Prony terms: the quasi-static path reads the relaxed material only
    relaxing = replace(study, material=replace(study.material, relaxation_g1=0.3,
                                               relaxation_tau1=2.0))
    assert _keys(relaxing) == (field, paths)
    stiffer = replace(study, material=replace(study.material,
                                              bulk_ratio=2 * study.material.bulk_ratio))
    assert set(_keys(stiffer)[1]).isdisjoint(paths)


def test_a_comment_in_the_mechanics_does_not_change_the_key(tmp_path):
    """The same keys from this source and from a copy of it with a comment added."""
    copy = tmp_path / "src"
    shutil.copytree(SRC, copy / "magtact", ignore=shutil.ignore_patterns("__pycache__", "*.nc",
                                                                         "*.png", "*.svg"))
    model = copy / "magtact" / "mechanics" / "_model.py"
    model.write_text(model.read_text() + "\n# a comment that changes nothing\n")

    def run(path):
        out = subprocess.run([sys.executable, "-c", KEYS + "; import magtact; "
                              "print(magtact.__file__)"], capture_output=True, text=True,
                             env={"PYTHONPATH": str(path), "PATH": "/usr/bin:/bin"},
                             timeout=300, check=True).stdout.splitlines()
        assert Path(out[1]).resolve().is_relative_to(path.resolve())  # that source ran
        return out[0]

    assert run(copy) == run(SRC.parent)


def _installed(monkeypatch, change):
    """Pretend the installed versions are ``change(name, version)`` of the real ones."""
    import magtact._versions as v

    real = v.package_versions
    monkeypatch.setattr(v, "package_versions",
                        lambda names: {n: change(n, x) for n, x in real(names).items()})


def test_magpylib_and_patch_releases_leave_the_keys_alone(monkeypatch):
    study = load_study("magone")
    keys = _keys(study)
    _installed(monkeypatch, lambda n, x: "absent" if n == "magpylib" else x)
    assert _keys(study) == keys  # the test extra removed
    monkeypatch.undo()
    _installed(monkeypatch, lambda n, x: "9.9.9" if n in ("magpylib", "xarray", "dask") else x)
    assert _keys(study) == keys  # packages that compute nothing of a job
    monkeypatch.undo()
    for name in ("numpy", "scipy", "felupe", "scikit-fem", "gmsh"):
        _installed(monkeypatch, lambda n, x, name=name: x + "1" if n == name else x)  # x.y.z1
        assert _keys(study) == keys, name
        monkeypatch.undo()


def test_a_minor_release_of_a_computing_package_renews_the_keys(monkeypatch):
    study = load_study("magone")
    field, paths = _keys(study)

    def bump(n, x, name):
        major, minor = x.split(".")[:2]
        return f"{major}.{int(minor) + 1}.0" if n == name else x

    _installed(monkeypatch, lambda n, x: bump(n, x, "felupe"))
    f2, p2 = _keys(study)
    assert f2 == field and set(p2).isdisjoint(paths)  # FElupe computes the paths only
    monkeypatch.undo()
    _installed(monkeypatch, lambda n, x: bump(n, x, "scikit-fem"))
    f3, p3 = _keys(study)
    assert f3 != field and p3 == paths
    monkeypatch.undo()
    _installed(monkeypatch, lambda n, x: bump(n, x, "numpy"))
    f4, p4 = _keys(study)
    assert f4 != field and set(p4).isdisjoint(paths)
    monkeypatch.undo()
    _installed(monkeypatch, lambda n, x: "absent" if n == "pypardiso" else x)
    assert set(_keys(study)[1]).isdisjoint(paths)  # another linear solver computes the paths


def test_minor_version():
    from magtact._versions import minor_version

    assert minor_version("2.4.6") == "2.4" and minor_version("2.4.6.post1") == "2.4"
    assert minor_version("2026.8.0") == "2026.8" and minor_version("0.4.7") == "0.4"
    assert minor_version("1.17rc1") == "1.17" and minor_version("absent") == "absent"
    assert minor_version("11") == "11"
