"""What-ifs answered from the bundled data: exact rescalings (forces ∝ G, field ∝ M_z) need no
DOE; only what changes the FE forces or the field asks for one, naming the setting."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from magtact import MagtactError
from magtact.doe import bundled_for, differences, load_bundled, rescaled_for
from magtact.metamodel import find_shipped, prefitted_dir, select_metamodels
from magtact.study import magone, study_from_dict


@pytest.fixture(scope="module")
def ds():
    return load_bundled()


def _study(**sections):
    return study_from_dict({"base": "magone", **sections})


# Other instances than the ones a designer first tried (Dragon Skin 10, N52, G 10-60 kPa).
ANSWERED = {
    "silicone": {"material": {"silicone": "Ecoflex 00-50"}},
    "grade": {"magnet": {"grade": "N42"}},
    "M_z": {"magnet": {"M_z_A_per_m": 0.9e6}},
    "G range": {"design": {"G_kPa": [5.0, 80.0]}},
    "G_ref": {"material": {"G_ref_kPa": 40.0}},
    "H inside": {"design": {"H_mm": [4.0, 6.0], "H_original_mm": 4.0}},
    "chip": {"hall": {"gain_sel": 5, "res": 1}},
    "environment": {"environment": {"delta_T_K": 25.0}},
    "tolerances": {"tolerances": {"G_pct": 8.0}},
    "levels": {"doe": {"n_H": 7, "n_theta": 4}},
    "threads": {"mechanics": {"threads": 2}},
    "together": {"material": {"silicone": "Ecoflex 00-50"}, "magnet": {"grade": "N42"},
                 "design": {"G_kPa": [5.0, 80.0]}, "hall": {"gain_sel": 5, "res": 1},
                 "constraints": {"source": "values", "F_r_c_N": -0.2, "F_z_c_N": 4.0}},
}


@pytest.mark.parametrize("case", list(ANSWERED))
def test_exact_rescalings_are_answered_from_the_bundled_data(ds, case):
    study = _study(**ANSWERED[case])
    assert differences(ds, study) == []
    data = bundled_for(study)
    base = magone()
    # forces per unit G and the field per unit M_z are those computed, exactly
    f = data["F_z"] / data["G"]
    f0 = ds["F_z"].isel(G=0) / ds["G"][0]
    assert np.allclose(f.values, f0.values[..., None], rtol=1e-14, atol=0)
    np.testing.assert_allclose(data["G"].values, study.G_levels, rtol=1e-15)
    k = study.magnet.M_z / base.magnet.M_z
    np.testing.assert_allclose(data["B_z"].values, k * ds["B_z"].values, rtol=1e-14)
    # and the shipped fit serves it, its field scaled by the same factor
    sel = select_metamodels(study, data)
    assert sel.shipped == prefitted_dir() and sel.fit is None
    assert sel.field_scale == pytest.approx(k, rel=1e-15)
    ref = select_metamodels(base, ds).models
    t, th, H = 0.7, 0.3, 4.5e-3
    assert float(sel.models.B_z.value(t, th, H)) == pytest.approx(
        k * float(ref.B_z.value(t, th, H)), rel=1e-12)
    assert float(sel.models.f_r.value(t, th, H)) == float(ref.f_r.value(t, th, H))


NEW_MECHANICS = [
    ({"body": {"R_mm": 7.0, "R_g_mm": 7.0}}, "[body] R_mm = 7"),
    ({"magnet": {"H_m_mm": 1.5}}, "[magnet] H_m_mm = 1.5"),
    ({"mechanics": {"mesh": "coarse"}}, "[mechanics] mesh = 'coarse'"),
    ({"loading": {"mu_f": 0.4, "theta_max_rad": 0.38}}, "[loading] mu_f = 0.4"),
    ({"material": {"bulk_ratio": 2000.0}}, "[material] bulk_ratio = 2000"),
    ({"design": {"H_mm": [3.0, 8.0]}}, "[design] H_mm = [3, 8] reaches outside the data's "
                                       "heights [3, 7] mm"),
]


@pytest.mark.parametrize(("edit", "named"), NEW_MECHANICS)
def test_new_mechanics_is_refused_naming_the_setting(ds, edit, named):
    study = _study(**edit)
    assert differences(ds, study)[0].startswith(named)
    with pytest.raises(MagtactError, match="needs new mechanics") as err:
        bundled_for(study)
    msg = str(err.value)
    assert msg.split("needs new mechanics: ", 1)[1].startswith(named)
    assert "magtact run STUDY --recompute" in msg


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lo=st.floats(1.0, 100.0), span=st.floats(0.0, 400.0), n=st.integers(1, 9),
       M_z=st.floats(2e5, 2e6))
def test_rescaling_is_exact_for_any_G_levels_and_magnetisation(ds, lo, span, n, M_z):
    base = magone()
    study = replace(base, design=replace(base.design, G=(lo * 1e3, (lo + span) * 1e3)),
                    doe=replace(base.doe, n_G=n), magnet=replace(base.magnet, M_z=M_z))
    out = rescaled_for(ds, study)
    G = study.G_levels
    np.testing.assert_allclose(out["G"].values, G, rtol=0)
    per_G = ds["F_r"].isel(G=0).values / ds["G"].values[0]
    np.testing.assert_allclose(out["F_r"].values, per_G[..., None] * G, rtol=1e-13, atol=1e-18)
    np.testing.assert_allclose(out["B_r"].values, ds["B_r"].values * M_z / base.magnet.M_z,
                               rtol=1e-14)
    assert differences(out, study) == []
    # a rescaled data set is recognised as the shipped fit's data, a tampered one is not
    assert find_shipped(study, out) is not None
    bad = out.copy(deep=True)
    bad["F_z"][...] = bad["F_z"] * 1.001
    assert find_shipped(study, bad) is None


# ---- geometric data: a magnet size inside the data's range is answered by binding ----------
@pytest.fixture(scope="module")
def geometric(tmp_path_factory):
    """The (H, R_m) data set of bench/ with a deliberately short fit standing in for a shipped
    fit of geometric data (the plumbing, not the accuracy, is under test)."""
    from pathlib import Path

    from magtact.doe import load_dataset
    from magtact.metamodel import fit_models, save_models
    from magtact.study import load_study

    root = Path(__file__).resolve().parents[1] / "bench"
    ds = load_dataset(root / "results" / "geometry_doe.nc")
    s = load_study(root / "magone_geometry.toml")
    s = replace(s, metamodel=replace(s.metamodel, generations=2, population=40))
    folder = tmp_path_factory.mktemp("geometric_fit")
    save_models(fit_models(ds, s).model_set(s), folder)
    return ds, folder


def test_a_fixed_magnet_inside_geometric_data_is_served_by_its_fit(geometric, monkeypatch):
    import magtact.metamodel._prefitted as P

    ds, folder = geometric
    monkeypatch.setattr(P, "SHIPPED", {"geo": "geometry_doe.nc"})
    monkeypatch.setattr(P, "prefitted_dir", lambda name="magone": folder)
    study = _study(magnet={"R_m_mm": 2.0})
    assert differences(ds, study) == []
    sel = select_metamodels(study, ds)
    assert sel.shipped == folder and sel.fit is None
    from magtact.metamodel import ExactField, load_models

    fitted = load_models(folder)
    t, th, H = 0.6, 0.2, 5e-3
    assert float(sel.models.f_z.value(t, th, H)) == pytest.approx(
        float(fitted.f_z.value(t, th, H, R_m=2e-3)), rel=1e-12)
    assert float(sel.models.B_z.value(t, th, H)) == pytest.approx(
        float(ExactField(study, "B_z").value(t, th, H)), rel=1e-12)
    # outside the data's magnet radii it needs new mechanics
    assert differences(ds, _study(magnet={"R_m_mm": 4.0}))[0].startswith(
        "[magnet] R_m_mm = 4 outside the data's range [1.5, 3.5] mm")


# ---- the broad data set shipped with magtact ---------------------------------------------
def test_a_catalogue_magnet_and_a_tall_body_are_answered_from_the_broad_data():
    """A 3 x 1 mm magnet over H in [3, 9] mm: no DOE, the broad data set and its shipped fit;
    the same study with the MagOne magnet needs new mechanics, named."""
    from magtact.metamodel import prefitted_dir

    study = _study(magnet={"R_m_mm": 1.5, "H_m_mm": 1.0, "grade": "N45"},
                   design={"H_mm": [3.0, 9.0], "G_kPa": [15.0, 45.0]})
    ds = bundled_for(study)
    assert ds.attrs["rescaled_from"] == "broad_3x1_doe.nc"
    assert float(ds["H"].min()) <= 3e-3 and float(ds["H"].max()) >= 9e-3
    sel = select_metamodels(study, ds)
    assert sel.shipped == prefitted_dir("broad_3x1") and sel.fit is None
    assert not sel.poor_fit, sel.quality.message()
    with pytest.raises(MagtactError, match=r"needs new mechanics: \[design\] H_mm = \[3, 9\] "
                                           r"reaches outside the data's heights \[3, 7\] mm"):
        bundled_for(_study(design={"H_mm": [3.0, 9.0]}))


@pytest.mark.parametrize("size", ["3x2", "3x3", "6x1", "6x3"])
def test_each_broad_magnet_size_is_answered_from_its_own_data(size):
    D, H_m = (float(x) for x in size.split("x"))
    study = _study(magnet={"R_m_mm": D / 2, "H_m_mm": H_m, "grade": "N42"},
                   design={"H_mm": [2.5, 9.5]})
    ds = bundled_for(study)
    assert ds.attrs["rescaled_from"] == f"broad_{size}_doe.nc"
    assert find_shipped(study, ds)[0] == prefitted_dir(f"broad_{size}")


def test_a_magnet_between_the_bundled_heights_is_refused_naming_the_sizes_held():
    """The bundled sizes have three magnet heights: a magnet between them is not interpolated
    (along the height the forces do not interpolate on three levels, docs/method.md §10)."""
    with pytest.raises(MagtactError) as info:
        bundled_for(_study(magnet={"R_m_mm": 2.0, "H_m_mm": 1.5}))
    msg = str(info.value)
    assert "needs new mechanics: [magnet] H_m_mm = 1.5" in msg
    for held in ("a 5 × 2 mm magnet over H [3, 7] mm", "a 3 × 1 mm magnet over H [2, 10] mm",
                 "a 6 × 3 mm magnet over H [2, 10] mm"):
        assert held in msg, msg


@pytest.mark.long
def test_the_3x2_fit_predicts_a_direct_fe_path_between_its_heights():
    """A 3 x 2 mm magnet at H = 5.5 mm (between the data's levels 4.67 and 7.33 mm) and
    θ = 0.3 rad (between its θ levels): the shipped fit against a direct FE path of the same
    model (``magtact simulate``'s solver): F_z within 2 % of the path's range over the whole
    path, F_r within 3 % up to its minimum (the stable part a design reads; past it the body
    slips and the fit, like its held-out paths, is off by more)."""
    import numpy as np

    from magtact.mechanics import simulate_path
    from magtact.metamodel import load_models

    study = _study(magnet={"R_m_mm": 1.5, "H_m_mm": 2.0}, design={"H_mm": [3.0, 9.0]})
    ds = bundled_for(study)
    folder, _ = find_shipped(study, ds)
    models = load_models(folder)
    H, theta = 5.5e-3, 0.3
    path = simulate_path(study, H, theta)
    G = path.G
    stable = path.t <= path.t[np.argmin(path.F_r)]
    for name, F, part, within in (("f_z", path.F_z, slice(None), 0.02),
                                  ("f_r", path.F_r, stable, 0.03)):
        pred = G * np.asarray(models[name].value(path.t, theta, H), dtype=float)
        span = float(F.max() - F.min())
        assert np.max(np.abs(pred - F)[part]) < within * span, (name, pred, F)
