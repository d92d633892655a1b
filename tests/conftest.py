"""Helpers shared by several test modules: reference formulas, stand-in solvers and data sets.

Test modules import them by name (``from conftest import synthetic_doe``; pytest puts this folder
on ``sys.path``), so that no test module imports another.
"""

from __future__ import annotations

import os

# The suite runs one worker per core (pytest-xdist, -n auto): each computes with one BLAS and
# MKL thread, so that the workers do not oversubscribe the cores (threads of the processes the
# tests start too).
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
if os.environ["OPENBLAS_NUM_THREADS"] == "1":  # a plugin may have loaded NumPy's BLAS already
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
import xarray as xr
from threadpoolctl import threadpool_limits

from magtact.doe import run_doe
from magtact.geometry import hall_from_magnet_centre, loading_path
from magtact.metamodel import H as Hs
from magtact.metamodel import ModelSet
from magtact.metamodel import p as ps
from magtact.metamodel import q as qs
from magtact.study import study_from_dict

threadpool_limits(1)  # libraries loaded before the environment above was read


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """One worker per core where pytest-xdist is installed and ``-n`` was not given; without
    it, the suite runs in this process."""
    if (config.pluginmanager.hasplugin("xdist") and not hasattr(config, "workerinput")
            and config.getoption("numprocesses", None) is None):
        config.option.numprocesses = "auto"

# ---- the magnet of the built-in study, and its field computed independently of magtact ---------
MU0 = 1.257e-6  # docs/method.md §1
R_M, H_M, M_Z, H_G, DZ_SAT = 2.5e-3, 2e-3, 1.2e6, 4.97e-3, 2.97e-3


def acceptance_points():
    """Points below, above and beside the magnet (magnet frame) [m]."""
    r = np.linspace(0.0, 3e-3, 13)
    gap = np.linspace(2.97e-3, 12e-3, 20)
    rr, gg = np.meshgrid(r, gap)
    below = (rr.ravel(), -H_M / 2 - gg.ravel())
    above = (rr.ravel(), H_M / 2 + gg.ravel())
    rb, zb = np.meshgrid(R_M + gap, np.linspace(-H_M / 2 - 2e-3, H_M / 2 + 2e-3, 9))
    beside = (rb.ravel(), zb.ravel())
    return {"below": below, "above": above, "beside": beside}


def rel_diff(B, ref):
    return np.linalg.norm(np.subtract(B, ref), axis=0) / np.linalg.norm(ref, axis=0)


def spec_hall_field(t, theta, H, placement="covered"):
    """B (B_x, B_z) at the Hall point (the origin) from docs/method.md §1, with magpylib.

    Unloaded, Δz0 = H + H_g − H_m is the height of the magnet's centre ("covered") or of its
    lower face ("flush"); the magnet moves by u_z = t (Δz_sat + H_m − H − H_g) and
    u_r = −u_z tan θ along +x.
    """
    magpy = pytest.importorskip("magpylib")
    t, theta, H = np.broadcast_arrays(t, theta, H)
    u_z = t * (DZ_SAT + H_M - H - H_G)
    u_r = -u_z * np.tan(theta)
    dz = H + H_G - H_M + u_z
    centre_z = dz if placement == "covered" else dz + H_M / 2
    out = np.empty((2,) + t.shape)
    for idx in np.ndindex(t.shape):
        magnet = magpy.magnet.Cylinder(dimension=(2 * R_M, H_M), polarization=(0, 0, MU0 * M_Z),
                                       position=(u_r[idx], 0.0, centre_z[idx]))
        B = magnet.getB((0.0, 0.0, 0.0))
        out[0][idx], out[1][idx] = B[0], B[2]
    return out


# ---- the DOE with analytic stand-in solvers (closed forms instead of FE) -----------------------
C_R, C_Z = 3e-4, -7e-4  # force per unit G [N/Pa] of the stand-in, times a shape function


@dataclass(frozen=True)
class FakePath:
    t: np.ndarray
    u_r: np.ndarray
    u_z: np.ndarray
    F_r: np.ndarray
    F_z: np.ndarray
    G: float
    newton_iterations: int
    cutbacks: int
    wall_time: float
    n_dofs: int
    n_cells: int
    mesh: str


def fake_forces(t, theta, H, G):
    """Closed-form stand-in forces [N], proportional to G like the real model."""
    return (C_R * G * t * np.tan(theta) * H / 3e-3, C_Z * G * t**1.5 * (3e-3 / H))


def fake_path(study, H, theta, *, G=None, mesh=None, t=None, vtu=None):
    if os.environ.get("MAGTACT_TEST_FAIL") and theta > 0 and H == study.H_levels[-1]:
        raise RuntimeError(f"no convergence at theta={theta:.3f}, H={H}")
    G = study.material.G_ref if G is None else G
    t = study.t_levels if t is None else np.asarray(t)
    u_r, u_z = loading_path(study, t, theta, H)
    F_r, F_z = fake_forces(t, theta, H, G)
    return FakePath(t, u_r, u_z, F_r, F_z, G, 3 * len(t), 0, 0.01, 1000, 100, "fake")


def fake_field(study, t, theta, H, solver="fe"):
    u_r, u_z = loading_path(study, t, theta, H)
    return 1e3 * u_r, 0.1 + 1e2 * u_z


def tiny(**doe):
    levels = {"n_t": 4, "n_theta": 2, "n_H": 2, "n_G": 3, **doe}
    return study_from_dict({"doe": levels})


def run(study, tmp_path=None, **kw):
    kw.setdefault("workers", 0)
    return run_doe(study, cache=tmp_path, path_solver=kw.pop("path_solver", fake_path),
                   field_solver=kw.pop("field_solver", fake_field), **kw)


# ---- an analytic DOE-layout data set (for fitting metamodels without FE) -----------------------
# B is the field of a point dipole at the magnet's centre (exact, smooth away from it); f is a
# smooth function of the displacement with the symmetries of the real responses (f_r odd in u_r,
# f_r = f_z = 0 unloaded).
K_DIPOLE = 1e-12  # μ0 m / 4π [T·m³]
AREA = np.pi * 6e-3**2


def dipole(x, z):
    r2 = x**2 + z**2
    return K_DIPOLE * 3 * x * z / r2**2.5, K_DIPOLE * (3 * z**2 - r2) / r2**2.5


def forces(u_r, u_z, H):
    e, s = -u_z / H, u_r / H
    f_z = AREA * e * (1 + 1.5 * e) * (1 + 0.2 * s**2)
    f_r = -AREA * s * (1 - 2.0 * e**2) * 0.8
    return f_r, f_z


def synthetic_doe(study, n_t: int = 11) -> xr.Dataset:
    """A DOE-layout data set over the study's (θ, H, G) levels with ``n_t`` levels of t."""
    t = np.linspace(0.0, 1.0, n_t)
    th, H, G = study.theta_levels, study.H_levels, study.G_levels
    T, TH, HH = np.meshgrid(t, th, H, indexing="ij")
    ur, uz = loading_path(study, T, TH, HH)
    x, z = hall_from_magnet_centre(study, ur, uz, HH)
    br, bz = dipole(x, z)
    fr, fz = forces(ur, uz, HH)
    d3, d4 = ("t", "theta", "H"), ("t", "theta", "H", "G")
    return xr.Dataset(
        {"u_r": (d3, ur, {"units": "m"}), "u_z": (d3, uz, {"units": "m"}),
         "B_r": (d3, br, {"units": "T"}), "B_z": (d3, bz, {"units": "T"}),
         "F_r": (d4, fr[..., None] * G, {"units": "N"}),
         "F_z": (d4, fz[..., None] * G, {"units": "N"})},
        coords={"t": t, "theta": th, "H": H, "G": G},
        attrs={"synthetic": "analytic test stand-in", "study_toml": study.to_toml()})


# ---- metamodel sets given as known formulas ----------------------------------------------------
def known_set() -> ModelSet:
    h = Hs * 1000
    return ModelSet.from_exprs({
        "B_r": sp.Float(0.0123456789012345) * qs * sp.exp(-0.5 * ps) / h,
        "B_z": 0.05 * sp.exp(0.8 * ps / h) + 0.001 * qs**2,
        "f_r": -0.3e-4 * qs + 1e-5 * ps * qs,
        "f_z": -1e-4 * ps - 3e-5 * ps**2 * h + 1e-6 * qs**2,
    })


# synthetic_models has a stable-shear minimum f_r,min known in closed form: with
# c = 0.4 + 100 H, f_r = k_r [(p − c)² − c² + 4 (q − 0.12)² − 0.0576] (p = t, q = t tan θ) is
# smallest at p = c, q = 0.12 while c ≤ 1 (interior: t_m = c, θ_m = atan(0.12 / c)) and on the
# edge t = 1 beyond (H > 6 mm: t_m = 1, θ_m = atan(0.12)). f_z grows with p and q, so its maximum
# is the corner (t_m, θ_m).
K_Z = 1.5e-4


def synthetic_models(f_r=None) -> ModelSet:
    """B models with an invertible Jacobian everywhere; f_r, f_z as in the notes above."""
    c = sp.Rational(2, 5) + 100 * Hs
    a_r = 0.08 * sp.exp(-(Hs - 3e-3) / 2e-3)
    a_z = -0.1 * (Hs / 3e-3)
    f_r_default = 6e-5 * (3e-3 / Hs) * ((ps - c) ** 2 - c**2 + 4 * (qs - sp.Rational(3, 25)) ** 2
                                        - sp.Rational(36, 625))
    return ModelSet.from_exprs({
        "B_r": a_r * qs * (1 + sp.Rational(3, 10) * ps),
        "B_z": 0.05 + a_z * ps * (1 + ps / 5) + a_z * qs**2 / 10,
        "f_r": f_r_default if f_r is None else f_r,
        "f_z": K_Z * (ps**2 + ps / 2 + 3 * qs**2 / 10),
    })


#: The original MagOne design (H [m], G [Pa]).
H_ORIGINAL, G_ORIGINAL = 3e-3, 29.4e3


@pytest.fixture(scope="session", autouse=True)
def answers_folder(tmp_path_factory):
    """Solved studies kept for this test session only (shared by the workers, never the
    user's cache): each study is solved once per session, by the first test that asks."""
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "answers"
    old = os.environ.get("MAGTACT_CACHE_DIR")
    os.environ["MAGTACT_CACHE_DIR"] = str(folder)
    yield folder
    if old is None:
        os.environ.pop("MAGTACT_CACHE_DIR", None)
    else:
        os.environ["MAGTACT_CACHE_DIR"] = old


@pytest.fixture(scope="session")
def shipped_models():
    """The metamodels shipped for the bundled MagOne data set."""
    from magtact.metamodel import load_models, prefitted_dir

    return load_models(prefitted_dir())


@pytest.fixture(scope="session")
def models(shipped_models):
    """The models a test works with: the shipped ones unless its module defines others."""
    return shipped_models


@pytest.fixture
def refused(capsys, monkeypatch):
    """Run the command line's entry point on ``args``; check exit 2, one message holding every
    fragment, no traceback; return the message."""
    import signal
    import sys

    def check(args, *fragments):
        from magtact.cli import main

        monkeypatch.setattr(sys, "argv", ["magtact", *args])
        handler = signal.getsignal(signal.SIGTERM)
        try:
            with pytest.raises(SystemExit) as exit_:
                main()
        finally:
            signal.signal(signal.SIGTERM, handler)
        captured = capsys.readouterr()
        assert exit_.value.code == 2, captured
        text = " ".join((captured.err + captured.out).split())
        assert "Traceback" not in text
        for f in fragments:
            assert f in text, (f, text)
        return text
    return check


def deny_open(monkeypatch, locked) -> None:
    """Make ``os.open`` of the file ``locked`` fail as an unreadable file does (whatever the
    user's rights: the tests may run as root)."""
    real_open = os.open

    def deny(path, *args, **kwargs):
        if str(path) == str(locked):
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(os, "open", deny)


@pytest.fixture(scope="session")
def magone_design():
    """``magtact.design()`` of the built-in study (one per test process; read, never changed)."""
    import magtact

    return magtact.design()


@pytest.fixture(scope="session")
def magone_magnet_design():
    """``magtact.design`` of the built-in study with its own magnet (the MagOne ⌀5 × 2 mm, no
    other size to choose: ``[design] magnet_sizes = []``), for tests of that magnet's physics
    (one per test session; read, never changed)."""
    import magtact

    return magtact.design(magtact.load("magone", design={"magnet_sizes": []}))


@pytest.fixture(scope="session")
def magone_budgets(magone_design):
    """``magtact.error_budgets(magone_design)``: a Monte-Carlo computation of a few seconds,
    done once per test process for every test that shows or writes the card."""
    import magtact

    return magtact.error_budgets(magone_design)


#: A ⌀3 × 1 mm N52 magnet asked for 3 N normal, 0.5 N shear at 200 Hz (the bundled data hold the
#: 3 × 1 mm magnet; no body of H 3–7 mm, G 10–50 kPa carries 0.5 N of shear): a specification no
#: design meets. A coarser sweep over H than the preset's keeps the tests short.
TINY_STUDY = """name = "tiny magnet"
[magnet]
size = "3x1"
grade = "N52"
[requirements]
F_z_N = 3.0
F_r_N = 0.5
rate_Hz = 200.0
[optimise]
sweep_n = 201
"""

#: The distribution's Chromium the browser tests drive, and the flags of a browser that talks
#: to nothing but the page.
CHROMIUM = Path("/usr/bin/chromium")
BROWSER_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium (:data:`CHROMIUM`) driven by Playwright, for a test module."""
    playwright = pytest.importorskip("playwright.sync_api")
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=BROWSER_ARGS)
        yield b
        b.close()


def built_run(tmp_path_factory, name: str, *args: str, status: int = 0,
              files: dict[str, str] | None = None) -> Path:
    """The results folder of ``magtact run ARGS --out <folder>``, built once per test session
    under ``name`` (the workers share the base of their temporary folders: the first builds it
    under a lock, the others wait and read). ``files`` (name → text) are written beside it
    first (a study file the run reads); ``status`` is the exit status the run must end with."""
    import fcntl
    import subprocess
    import sys

    base = tmp_path_factory.getbasetemp()
    shared = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / name
    shared.mkdir(exist_ok=True)
    out = shared / "results"
    with open(shared / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (shared / "built").is_file():
            for file, text in (files or {}).items():
                (shared / file).write_text(text, encoding="utf-8")
            done = subprocess.run([sys.executable, "-m", "magtact", "run", *args, "--out",
                                   str(out)], capture_output=True, text=True, timeout=600,
                                  cwd=shared)
            assert done.returncode == status, done.stderr[-3000:]
            (shared / "built").write_text(done.stdout, encoding="utf-8")
    return out
