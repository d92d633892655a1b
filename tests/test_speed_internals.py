"""The fast paths of the sensor problem against the plain formulas they replace, to the bit:
the exact reduction's noise and range over a grid's points (optimise._sensor), Bulirsch's
iteration in blocks (magnetics._exact) and the bundled data set's outline (doe._dataset)."""

import subprocess
import sys

import numpy as np
import pytest

from magtact.chip import SensorGrid
from magtact.magnetics import _exact
from magtact.optimise import _sensor


def _random_grid(rng, n=7, shape=(9, 4), zero_field=False):
    """A grid of n designs with random per-unit responses: f_z growing along the load levels
    from 0, shear forces of either sign, a field that may vanish at some points."""
    s = (n, *shape)
    f_z = np.cumsum(rng.uniform(0.0, 2e-5, s), axis=1)
    f_z[:, 0] = 0.0
    f_z[:, 3] = f_z[:, 2]  # equal forces: an empty piece
    f_r = rng.normal(0.0, 1e-5, s)
    b_x, b_z = rng.normal(0.0, 3e-8, s), rng.normal(0.0, 6e-8, s)
    if zero_field:
        b_x[:, 0] = 0.0
        b_z[:, 0, 0] = 0.0
    j = rng.normal(0.0, 1e3, s + (2, 2))
    return SensorGrid(np.zeros(s), np.zeros(s), f_r, f_z, b_x, b_z, j)


def _least_plain(grid, noise, M_z, G_low, G_high, F_z, F_r):
    """The least σ over G from the worst noise of every piece (the square root taken at each
    point, the running maximum over all of them, every piece compared)."""
    within = _sensor._Within(grid)
    n = within.order.shape[0]
    S = grid.unit_noise(*noise).reshape(n, -1, 2)
    cm = np.maximum.accumulate(np.take_along_axis(S, within.order[..., None], axis=1), axis=1)
    cm = np.concatenate([np.zeros((n, 1, 2)), cm], axis=1)
    W = np.hypot(cm[..., 0], cm[..., 1])
    rows = np.arange(n)
    M = np.broadcast_to(np.asarray(M_z, float), (n,))
    G_low = np.broadcast_to(np.asarray(G_low, float), (n,))
    lowest, cap = within.bounds(F_z, F_r, G_high)
    G = np.maximum(lowest, G_low[:, None])
    with np.errstate(invalid="ignore"):
        value = np.where(G <= cap, G * W, np.inf)
    j = np.argmin(value, axis=1)
    best = value[rows, j] / M
    return best, np.where(np.isfinite(best), G[rows, j], G_low)


@pytest.mark.parametrize("seed", range(6))
def test_the_least_noise_over_G_equals_the_plain_formula(seed):
    rng = np.random.default_rng(seed)
    grid = _random_grid(rng, n=11)
    within = _sensor._Within(grid)
    F_z, G_high = 2.0, 4e5
    shear = within.most_shear(0.0, G_high, F_z)[0]
    for F_r in (0.0, 0.5 * float(np.median(shear)), 2.0 * float(shear.max())):
        noises = [(1e-7, 3e-7), (4e-7, 1e-7), (rng.uniform(1e-7, 5e-7, 11),
                                               rng.uniform(1e-7, 5e-7, 11))]
        for noise in noises:
            kept = within.noise(*noise) if np.ndim(noise[0]) == 0 else _sensor._Noise(within,
                                                                                     noise)
            for M_z, G_low in ((1.1e6, 1e4), (rng.uniform(8e5, 1.3e6, 11),
                                              rng.uniform(0.0, 5e5, 11))):
                got = kept.least(M_z, G_low, G_high, F_z, F_r)
                want = _least_plain(grid, noise, M_z, G_low, G_high, F_z, F_r)
                for a, b in zip(got, want, strict=True):
                    np.testing.assert_array_equal(a, b)


def test_a_chip_noise_is_kept_per_grid_and_gives_the_same_answer_again():
    rng = np.random.default_rng(7)
    grid = _random_grid(rng)
    assert _sensor._within_of(grid) is _sensor._within_of(grid)
    within = _sensor._within_of(grid)
    first = within.noise(1e-7, 2e-7)
    assert within.noise(1e-7, 2e-7) is first
    a = first.least(1e6, 1e4, 3e5, 2.0, 0.0)
    b = _sensor._Noise(_sensor._Within(grid), (1e-7, 2e-7)).least(1e6, 1e4, 3e5, 2.0, 0.0)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("seed", range(4))
def test_G_range_in_the_order_of_need_equals_the_grids(seed):
    rng = np.random.default_rng(seed)
    grid = _random_grid(rng, n=13, zero_field=seed % 2 == 1)
    for F_z in (0.5, 3.0):
        reading = grid.read_order(F_z)
        need = grid.read_need(F_z)
        for rx, rz in ((5e-3, 5e-3), (2e-2, 8e-3), (1.0, 1.0)):
            least = reading.least_limit(rx, rz)
            limit = grid.M_limit(rx, rz)
            # from no point saturated to all of them, and between
            q = [0.001, 0.005, 0.01, 0.02, 0.05, 0.3, 0.95]
            Ms = np.concatenate([[0.0, 1e-3, np.inf], np.quantile(limit[np.isfinite(limit)], q)])
            for M in Ms:
                np.testing.assert_array_equal(reading.G_range(least, M),
                                              grid.G_range_at(limit, M, need))


def _cel_plain(kc, sets):
    """Bulirsch's iteration over all points at once, stopping when every point has
    converged."""
    k = np.abs(kc)
    state = []
    for p, c, s in sets:
        pos = p > 0
        pp = np.where(pos, np.sqrt(np.where(pos, p, 1.0)), 0.0)
        cc = c.copy()
        ss = np.where(pos, s / np.where(pos, pp, 1.0), s)
        if not np.all(pos):
            pg = np.where(pos, 0.0, p)
            f = kc * kc
            q = 1.0 - f
            g = 1.0 - pg
            f = f - pg
            q = q * (s - c * pg)
            pn = np.sqrt(f / g)
            cn = (c - s) / g
            sn = -q / (g * g * pn) + cn * pn
            pp, cc, ss = np.where(pos, pp, pn), np.where(pos, cc, cn), np.where(pos, ss, sn)
        f = cc
        cc = cc + ss / pp
        g = k / pp
        ss = 2.0 * (ss + f * g)
        pp = g + pp
        state.append([cc, ss, pp])
    em = np.ones_like(k)
    g = em
    em = k + em
    kk = k
    while not np.all(np.abs(g - k) <= g * _exact._CEL_TOL):
        k = 2.0 * np.sqrt(kk)
        kk = k * em
        for st in state:
            cc, ss, pp = st
            f = cc
            cc = cc + ss / pp
            gp = kk / pp
            st[:] = cc, 2.0 * (ss + f * gp), gp + pp
        g = em
        em = k + em
    return [0.5 * np.pi * (ss + cc * em) / (em * (em + pp)) for cc, ss, pp in state]


@pytest.mark.parametrize("shape, slow", [((), None), ((5,), -1), ((3, 1000), 7),
                                         ((2, 3 * _exact._CEL_BLOCK + 17), -1),
                                         ((2, 3 * _exact._CEL_BLOCK + 17), 0),
                                         ((2, 3 * _exact._CEL_BLOCK + 17), 2 * _exact._CEL_BLOCK)])
def test_bulirschs_iteration_in_blocks_equals_one_pass(shape, slow):
    rng = np.random.default_rng(len(shape))
    kc = rng.uniform(0.05, 1.0, shape)
    p = rng.uniform(0.0, 2.0, shape)
    if slow is not None:
        kc.flat[slow] = 1e-9  # one slow point: every block takes the steps of its block
        p.flat[:3] = 0.0  # the general branch
    sets = [(p, np.ones(shape), -np.ones(shape)), (p * p, rng.normal(size=shape),
                                                   rng.normal(size=shape))]
    with np.errstate(invalid="ignore", divide="ignore"):
        got, want = _exact._cel_sets(kc, sets), _cel_plain(kc, sets)
    for a, b in zip(got, want, strict=True):
        assert a.shape == np.shape(kc)
        np.testing.assert_array_equal(a, b)


def test_the_cylinder_field_over_many_points_equals_one_pass(monkeypatch):
    rng = np.random.default_rng(3)
    r = rng.uniform(0.0, 8e-3, 40_000)
    z = rng.uniform(-8e-3, 8e-3, 40_000)
    r[:4], z[:4] = 2.5e-3, (1e-3, -1e-3, 0.5e-3, 3e-3)  # the rims (NaN) and the mantle line
    got = _exact.cylinder_field(r, z, 2.5e-3, 2e-3, 1.1e6)
    monkeypatch.setattr(_exact, "_cel_sets", _cel_plain)
    want = _exact.cylinder_field(r, z, 2.5e-3, 2e-3, 1.1e6)
    for a, b in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)


def test_the_outline_and_the_whole_of_a_bundled_data_set_do_not_import_dask():
    code = ("import sys\n"
            "from magtact.doe._dataset import BUNDLED_NAME, _outline, load_bundled\n"
            "ds = _outline(BUNDLED_NAME)\n"
            "assert ds['H'].values.dtype == float and ds.attrs\n"
            "ds = load_bundled()\n"
            "print('dask' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_a_data_set_read_with_its_indexes_made_from_pandas_equals_xarrays_reading():
    import xarray as xr

    from magtact.doe._dataset import BUNDLED_NAMES, bundled_path, load_dataset

    names = [n for n in BUNDLED_NAMES if bundled_path(n).is_file()]
    assert names
    for name in names:
        with xr.open_dataset(bundled_path(name), engine="h5netcdf") as ds:
            want = ds.load()
        got = load_dataset(bundled_path(name))
        assert got.identical(want), name
        assert list(got.variables) == list(want.variables)
        assert list(got.xindexes) == list(want.xindexes)
        for k in want.xindexes:
            assert type(got.xindexes[k]) is type(want.xindexes[k])
            assert got.xindexes[k].equals(want.xindexes[k])
        # how the file stored each array (its encoding) is not kept: nothing reads it
        for k in want.variables:
            assert type(got[k].variable) is type(want[k].variable)
            assert got[k].attrs == want[k].attrs and got[k].dtype == want[k].dtype
