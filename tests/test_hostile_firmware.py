"""The firmware header force.h on a real part: it compiles warning-free included and unused or
used, in float and double, in two files linked together; a reading at rest within the chip's
noise is valid and, after a tare, reads a force within 3 σ_F of zero; B = 0, B_z ≤ 0 and
readings that are not numbers give a return code and no NaN (docs/method.md §13.2)."""

from __future__ import annotations

import io
import shutil
import subprocess

import numpy as np
import pytest

from magtact.calibration import c_header, firmware_approximation, sensor_map
from magtact.calibration._firmware import BAND_SIGMAS, C_RETURN, rest_field
from magtact.designer import resolution
from magtact.optimise import per_design
from magtact.study import HallChip, load_study

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="no gcc on this machine")

#: The design of the README and an assumed chip noise of 1 µT per axis (not a datasheet's).
H, G, NOISE = 3e-3, 22.57e3, 1e-6
#: Rounding of an all-float32 build (MAGTACT_ACC float) relative to the force range, as the
#: header states.
FLOAT_ROUNDING = 2e-4
#: MAGTACT_ALLOW_FLOAT: the float builds are measured here, also where the header refuses them
#: (their stated error exceeds the target σ_F).
FLAGS = ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-DMAGTACT_ALLOW_FLOAT"]
OK, OUTSIDE, NO_FIELD = (C_RETURN[k] for k in ("MAGTACT_FORCE_OK", "MAGTACT_FORCE_OUTSIDE",
                                               "MAGTACT_FORCE_NO_FIELD"))

#: Reads "tare bx by bz" (sets the offset) or "bx by bz" lines; prints rc and the force.
MAIN = r"""#include <stdio.h>
#include <string.h>
#include "force.h"
int main(void)
{
    char word[16];
    double x, y, z;
    MAGTACT_REAL off[3] = {0, 0, 0}, o[3];
    while (scanf("%15s %lf %lf %lf", word, &x, &y, &z) == 4) {
        int rc;
        if (strcmp(word, "tare") == 0)
        {
            MAGTACT_REAL b[1][3];
            b[0][0] = (MAGTACT_REAL)x;
            b[0][1] = (MAGTACT_REAL)y;
            b[0][2] = (MAGTACT_REAL)z;
            rc = magtact_force_tare(b, 1, off);
        }
        else
            rc = magtact_force((MAGTACT_REAL)x, (MAGTACT_REAL)y, (MAGTACT_REAL)z, off, o);
        if (strcmp(word, "tare") == 0)
            o[0] = o[1] = o[2] = 0;
        printf("%d %.17e %.17e %.17e\n", rc, (double)o[0], (double)o[1], (double)o[2]);
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def setup(models):
    study = load_study(None)
    design = per_design(models, H, G, study)
    smap = sensor_map(models, study, H, G, design=design)
    r = resolution(models, study, design, HallChip("given", NOISE, NOISE, 1.0, 1.0, "1 µT",
                                                     "assumed"))
    sigma = (r.sigma_r_worst, r.sigma_z_worst)
    choice = firmware_approximation(smap, sigma, degrees=(8, 12), table_sizes=(16,),
                                    n_test=2000)
    return smap, sigma, choice


def _headers(setup):
    """The chosen approximation, one candidate of each kind and one of each transform (the
    C code differs by kind and by the transform of B_z only)."""
    smap, _, choice = setup
    picked = {("chosen", choice.chosen.kind, choice.chosen.transform): choice.chosen}
    for a in choice.candidates:
        if a.kind not in {k[0] for k in picked} or a.transform not in {k[1] for k in picked}:
            picked.setdefault((a.kind, a.transform), a)
    return {k: c_header(a, smap, choice, noise=(NOISE, NOISE)) for k, a in picked.items()}


def _build(tmp_path, header: str, real: str, source: str = MAIN, name: str = "prog"):
    (tmp_path / "force.h").write_text(header, encoding="utf-8")
    (tmp_path / f"{name}.c").write_text(source, encoding="utf-8")
    exe = tmp_path / f"{name}_{real.split()[0]}_{len(real)}"
    r = subprocess.run([*FLAGS, *f"-DMAGTACT_REAL={real}".split(), "-o", str(exe),
                        str(tmp_path / f"{name}.c"), "-lm"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return exe


def _run(exe, lines: list[str]) -> np.ndarray:
    r = subprocess.run([str(exe)], input="\n".join(lines) + "\n", capture_output=True,
                       text=True, check=True)
    return np.loadtxt(io.StringIO(r.stdout), ndmin=2)


def test_header_compiles_unused_and_in_two_files(setup, tmp_path):
    for key, header in _headers(setup).items():
        assert "static inline int magtact_force(" in header and "static int force" not in header
        assert "section 13" in header and "-lm" in header, key
        for real in ("double", "float", "float -DMAGTACT_ACC=float"):
            _build(tmp_path, header, real, "#include \"force.h\"\nint main(void)\n{\n"
                                           "    return 0;\n}\n", "unused")
            # two files that include and call it, linked together: no symbol defined twice
            (tmp_path / "force.h").write_text(header, encoding="utf-8")
            (tmp_path / "other.c").write_text(
                "#include \"force.h\"\nint other(void);\nint other(void)\n{\n"
                "    MAGTACT_REAL o[3];\n    return magtact_force(0, 0, 0, NULL, o);\n}\n")
            (tmp_path / "two.c").write_text(
                "#include \"force.h\"\nint other(void);\nint main(void)\n{\n"
                "    MAGTACT_REAL o[3];\n"
                "    return magtact_force(0, 0, 1, NULL, o) + other() > 100;\n}\n")
            r = subprocess.run([*FLAGS, *f"-DMAGTACT_REAL={real}".split(), "-o",
                                str(tmp_path / "two"),
                                str(tmp_path / "two.c"), str(tmp_path / "other.c"), "-lm"],
                               capture_output=True, text=True)
            assert r.returncode == 0, (key, real, r.stderr)


def test_rest_field_within_noise_is_valid_and_near_zero_after_tare(setup, tmp_path):
    """The rest field ± the chip's noise (every corner and centre of the ±1 σ box, and 200
    readings uniform in it), on a unit whose chip reads a constant offset of 20 µT, 35 µT,
    -50 µT: after a tare at rest every reading is valid (rc 0) and its force within 3 σ_F of
    zero (in double, and with float tables and double sums; all-float builds add the
    rounding of their sums)."""
    smap, sigma, choice = setup
    assert choice.reached
    header = c_header(choice.chosen, smap, choice, noise=(NOISE, NOISE))
    rest = rest_field(smap)
    offset = np.array([20e-6, 35e-6, -50e-6])
    box = np.array(np.meshgrid(*[[-1.0, 0.0, 1.0]] * 3)).reshape(3, -1).T
    rng = np.random.default_rng(11)
    noise = np.concatenate([box, rng.uniform(-1.0, 1.0, (200, 3))]) * NOISE
    readings = rest + offset + noise
    lines = ["tare {:.17e} {:.17e} {:.17e}".format(*(rest + offset))]
    lines += ["read {:.17e} {:.17e} {:.17e}".format(*b) for b in readings]
    # double; float tables with double sums (the default with float); all in float, which
    # adds the rounding the header states (about 2e-4 of the force range from float sums)
    for real in ("double", "float", "float -DMAGTACT_ACC=float"):
        out = _run(_build(tmp_path, header, real), lines)
        assert out[0, 0] == OK
        rc, F = out[1:, 0], out[1:, 1:]
        assert (rc == OK).all(), (real, np.flatnonzero(rc != OK))
        extra = FLOAT_ROUNDING * max(smap.ranges) if "ACC" in real else 0.0
        assert np.abs(np.hypot(F[:, 0], F[:, 1])).max() <= 3 * sigma[0] + extra, real
        assert np.abs(F[:, 2]).max() <= 3 * sigma[1] + extra, real
    # without the tare, the same offset puts the readings outside the band: not valid
    out = _run(_build(tmp_path, header, "double"),
               ["read {:.17e} {:.17e} {:.17e}".format(*b) for b in readings[:27]])
    assert (out[:, 0] != OK).any()


def test_band_is_the_chips_noise(setup, tmp_path):
    """Just inside BAND_SIGMAS σ below the rest field in z: valid; just beyond: outside (the
    rest field is the region's lowest B_z)."""
    smap, _, choice = setup
    rest = rest_field(smap)
    exe = _build(tmp_path, c_header(choice.chosen, smap, choice, noise=(NOISE, NOISE)), "double")
    inside, beyond = (rest - [0, 0, f * BAND_SIGMAS * NOISE] for f in (0.99, 1.5))
    out = _run(exe, ["read {:.17e} {:.17e} {:.17e}".format(*b) for b in (inside, beyond)])
    assert out[:, 0].tolist() == [OK, OUTSIDE]
    assert (out[1, 1:] == 0).all()


def test_no_field_and_not_numbers_give_a_code_not_nan(setup, tmp_path):
    """B = 0, B_z < 0, B_z far below the rest field, NaN and infinities: rc 2 and out zero,
    for every kind of approximation, in float and double; a reading far outside the region:
    rc 1 and out zero (no extrapolated 1e73)."""
    smap, _, _ = setup
    rest = rest_field(smap)
    bad = ["0 0 0", "0 0 -0.01", f"0 0 {-rest[2]:.17e}", f"0.001 0 {0.3 * rest[2]:.17e}",
           "nan 0 0.03", "0 0 nan", "inf 0 0.03", "0 0 inf", "0 -inf 0.03"]
    far = ["1 0 0.03", "0 0 1", "-0.5 0.5 0.2"]
    for key, header in _headers(setup).items():
        for real in ("double", "float", "float -DMAGTACT_ACC=float"):
            out = _run(_build(tmp_path, header, real), [f"read {b}" for b in bad + far])
            assert np.isfinite(out).all(), (key, real)
            assert (out[:len(bad), 0] == NO_FIELD).all(), (key, real, out[:, 0])
            assert (out[len(bad):, 0] == OUTSIDE).all(), (key, real, out[:, 0])
            assert (out[:, 1:] == 0).all(), (key, real)
            # a tare refuses the same readings
            out = _run(_build(tmp_path, header, real), [f"tare {b}" for b in bad[:3]])
            assert (out[:, 0] == NO_FIELD).all()
