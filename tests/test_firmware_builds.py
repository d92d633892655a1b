"""force.h compiled for float and double, with and without -ffast-math: the largest error its
top states for each build is what the compiled code gives against force_table.csv, a float
build whose error exceeds σ_F does not compile, the tare averages n readings, and a reading or
a tare that is not a finite number is refused under any flags."""

from __future__ import annotations

import csv
import re
import shutil
import subprocess
from dataclasses import replace

import numpy as np
import pytest

from magtact.calibration import (
    UnitParameters,
    c_header,
    firmware_approximation,
    sensor_map,
    write_table_csv,
)
from magtact.calibration._firmware import BUILDS, C_RETURN
from magtact.optimise import per_design
from magtact.study import load_study

CC = shutil.which("cc") or shutil.which("gcc")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on this machine: "
                                                   "apt-get install gcc")
H, G = 3.2e-3, 24e3
WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
OK, NO_FIELD = C_RETURN["MAGTACT_FORCE_OK"], C_RETURN["MAGTACT_FORCE_NO_FIELD"]

#: Reads "tare n" then n readings, or one reading per line; prints rc and the force.
MAIN = r"""#include <stdio.h>
#include <string.h>
#include "force.h"
int main(void)
{
    char word[64];
    double x, y, z;
    MAGTACT_REAL off[3] = {0, 0, 0}, o[3], b[64][3];
    int n, k;
    while (scanf("%63s", word) == 1) {
        int rc;
        if (strcmp(word, "tare") == 0) {
            if (scanf("%d", &n) != 1 || n > 64)
                return 1;
            for (k = 0; k < n; k++) {
                if (scanf("%lf %lf %lf", &x, &y, &z) != 3)
                    return 1;
                b[k][0] = (MAGTACT_REAL)x;
                b[k][1] = (MAGTACT_REAL)y;
                b[k][2] = (MAGTACT_REAL)z;
            }
            rc = magtact_force_tare(b, n, off);
            printf("%d %.17g %.17g %.17g\n", rc, (double)off[0], (double)off[1], (double)off[2]);
            continue;
        }
        x = strtod(word, NULL);
        if (scanf("%lf %lf", &y, &z) != 2)
            return 1;
        rc = magtact_force((MAGTACT_REAL)x, (MAGTACT_REAL)y, (MAGTACT_REAL)z, off, o);
        printf("%d %.17g %.17g %.17g\n", rc, (double)o[0], (double)o[1], (double)o[2]);
    }
    return 0;
}
""".replace("#include <string.h>", "#include <string.h>\n#include <stdlib.h>")


def headers():
    """(name, header, map) of the default design and a built unit (the two-stage form)."""
    from magtact.metamodel import load_models, prefitted_dir

    models = load_models(prefitted_dir())
    study = load_study(None)
    smap = sensor_map(models, study, H, G, design=per_design(models, H, G, study))
    unit = replace(smap, field_source="exact").with_unit(
        UnitParameters(0.93, 1.04, (1.5e-4, -5e-5, 0.0)))
    out = []
    for name, m, sigma in (("design", smap, (5e-6, 2e-5)), ("unit", unit, (2e-5, 5e-5))):
        choice = firmware_approximation(m, sigma, degrees=(10,), table_sizes=(), n_test=1500)
        out.append((name, c_header(choice.chosen, m, choice, noise=(1e-6, 1e-6)), m))
    return out


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return [(name, header, m, tmp_path_factory.mktemp(name)) for name, header, m in headers()]


def compile_main(folder, header: str, real: str, acc: str, flags=(), allow=True):
    (folder / "force.h").write_text(header, encoding="utf-8")
    (folder / "m.c").write_text(MAIN, encoding="utf-8")
    exe = folder / f"m_{real}_{acc}_{len(flags)}"
    extra = ["-DMAGTACT_ALLOW_FLOAT"] if allow else []
    return subprocess.run([CC, *WARN, "-O2", *flags, *extra, f"-DMAGTACT_REAL={real}",
                           f"-DMAGTACT_ACC={acc}", "-o", str(exe), str(folder / "m.c"), "-lm"],
                          capture_output=True, text=True), exe


def run(exe, lines: list[str]) -> np.ndarray:
    r = subprocess.run([str(exe)], input="\n".join(lines) + "\n", capture_output=True,
                       text=True, check=True)
    return np.array(r.stdout.split(), dtype=float).reshape(-1, 4)


def table(folder, m):
    """The points of force_table.csv inside the region, read from the file as a user would."""
    path = write_table_csv(m, folder / "force_table.csv")
    with path.open() as fh:
        rows = [r for r in csv.DictReader(fh) if r["inside"] == "1"]
    B = np.array([[float(r["B_r_mT"]) * 1e-3, 0.0, float(r["B_z_mT"]) * 1e-3] for r in rows])
    F = np.array([[float(r["F_r_N"]), float(r["F_z_N"])] for r in rows])
    return B, F


def stated(header: str) -> dict[str, tuple[float, float] | None]:
    """The largest errors [mN] the header states per build (None: refused / not measured)."""
    out = {}
    for name, real, acc in BUILDS:
        m = re.search(rf"\*     {re.escape(name)} \(MAGTACT_REAL {real}, MAGTACT_ACC {acc}\): "
                      r"F_r ([0-9.e+-]+) mN, F_z ([0-9.e+-]+) mN", header)
        out[name] = None if m is None else (float(m.group(1)), float(m.group(2)))
    return out


def target(header: str) -> tuple[float, float]:
    m = re.search(r"target sigma_F \(the design's resolution\): F_r ([0-9.e+-]+) mN, F_z "
                  r"([0-9.e+-]+) mN", header)
    return float(m.group(1)), float(m.group(2))


@pytest.mark.parametrize("fast", [False, True], ids=["plain", "fast-math"])
def test_stated_error_is_what_each_build_gives_against_the_table(built, fast):
    flags = ("-ffast-math",) if fast else ()
    for name, header, m, folder in built:
        B, F = table(folder, m)
        said = stated(header)
        assert all(v is not None for v in said.values()), (name, said)
        for build, real, acc in BUILDS:
            r, exe = compile_main(folder, header, real, acc, flags)
            assert r.returncode == 0, (name, build, r.stderr)
            out = run(exe, ["{!r} {!r} {!r}".format(*b) for b in B.tolist()])
            ok = out[:, 0] == OK
            assert ok.mean() > 0.99, (name, build)
            err = (1e3 * np.abs(out[ok, 1] - F[ok, 0]).max(),
                   1e3 * np.abs(out[ok, 3] - F[ok, 1]).max())
            if not fast:  # the build the header was measured with: the same figures
                assert err == pytest.approx(said[build], rel=2e-3, abs=1e-9), (name, build)
            else:  # reassociated sums: the same error to within its own size
                assert err[0] <= 2 * said[build][0] + 1e-6, (name, build, err)
                assert err[1] <= 2 * said[build][1] + 1e-6, (name, build, err)


def test_float_build_above_sigma_is_refused_at_compile_time(built):
    for name, header, _, folder in built:
        said, (tr, tz) = stated(header), target(header)
        for build, real, acc in BUILDS[1:]:
            r, _ = compile_main(folder, header, real, acc, allow=False)
            above = said[build][0] > tr or said[build][1] > tz
            assert (r.returncode != 0) == above, (name, build, said[build], (tr, tz))
            if above:
                assert "exceed_sigma_F" in r.stderr


@pytest.mark.parametrize("fast", [False, True], ids=["plain", "fast-math"])
@pytest.mark.parametrize("real", ["double", "float"])
def test_not_a_number_is_refused_and_the_tare_averages(built, real, fast):
    name, header, m, folder = built[0]
    flags = ("-ffast-math",) if fast else ()
    r, exe = compile_main(folder, header, real, real, flags)
    assert r.returncode == 0, r.stderr
    rest = [float(v) for v in m.at_load(np.array([0.0]), 0.0)[0][0]]
    rng = np.random.default_rng(11)
    readings = np.array(rest) + rng.normal(0, 1e-6, (16, 3)) + np.array([3e-5, -2e-5, 4e-5])
    lines = [f"tare {len(readings)}", *("{!r} {!r} {!r}".format(*b) for b in readings.tolist())]
    lines += [f"nan {rest[1]!r} {rest[2]!r}", "tare 2",
              "{!r} {!r} {!r}".format(*rest), f"{rest[0]!r} {rest[1]!r} nan",
              "tare 0"]
    out = run(exe, lines)
    mean = readings.mean(axis=0) - np.array(rest)
    assert out[0, 0] == OK
    tol = 1e-12 if real == "double" else 1e-6 * np.abs(rest).max()
    np.testing.assert_allclose(out[0, 1:], mean, atol=tol)
    assert out[1, 0] == NO_FIELD and (out[1, 1:] == 0).all()  # a NaN reading
    assert out[2, 0] == NO_FIELD  # a tare with a NaN among its readings
    np.testing.assert_allclose(out[2, 1:], mean, atol=tol)  # offset unchanged
    assert out[3, 0] == NO_FIELD  # a tare of no readings
