"""The published sensitivity definition against exact answers, independent of genetic programming.

A synthetic sensor: the field B(p, q) is an exact invertible map and the force f(p, q) exact.
Two force expressions f̂(B_r, B_z, p, q) that agree along the sensor's path but use B and (p, q)
differently give the same Jacobian Γ (a property of the sensor) and different published Γ (a
property of the expression).
"""

import json

import numpy as np
import pytest
import sympy as sp

from magtact.metamodel import (
    ComposedForce,
    FieldForceModel,
    Metamodel,
    ModelSet,
    load_models,
    save_models,
)
from magtact.metamodel._field_force import B_r, B_z
from magtact.metamodel._symbols import H, p, q
from magtact.sensitivity import Responses, dF_dB, gamma

# field: B_r linear in q, B_z quadratic in p (invertible for p in [0, 1]); H scales both
b1, b0, b2, b3 = sp.Float(0.04), sp.Float(0.2), sp.Float(-0.05), sp.Float(0.01)
FIELD = {"B_r": b1 * q * (1 + H * 100), "B_z": b0 + b2 * p + b3 * p**2 + H}
# force per unit G along the path, and the same in field variables
F_PQ = {"f_r": sp.Float(-2e-5) * q * (1 + p), "f_z": sp.Float(3e-5) * p + sp.Float(1e-5) * q**2}
q_of_B = B_r / (b1 * (1 + H * 100))
F_B = {"f_r": sp.Float(-2e-5) * q_of_B * (1 + p),
       "f_z": sp.Float(3e-5) * p + sp.Float(1e-5) * q_of_B**2}


def _field_models():
    return [Metamodel.from_expr(k, FIELD[k], "T") for k in ("B_r", "B_z")]


def _published(forces: dict) -> ModelSet:
    Br, Bz = _field_models()
    return ModelSet(B_r=Br, B_z=Bz, **{k: ComposedForce(FieldForceModel.from_expr(k, e), Br, Bz)
                                       for k, e in forces.items()})


def _jacobian(forces: dict) -> ModelSet:
    """The Jacobian model set of the forces along the path (B substituted symbolically)."""
    Br, Bz = _field_models()
    sub = {B_r: FIELD["B_r"], B_z: FIELD["B_z"]}
    return ModelSet(B_r=Br, B_z=Bz,
                    **{k: Metamodel.from_expr(k, sp.expand(e.xreplace(sub)), "N/Pa")
                       for k, e in forces.items()})


@pytest.fixture(scope="module")
def grid():
    rng = np.random.default_rng(1)
    return rng.uniform(0.05, 1, 40), rng.uniform(0.0, 0.4, 40), rng.uniform(3e-3, 7e-3, 40)


def test_equal_forces_equal_jacobian_different_published(grid):
    t, th, h = grid
    in_pq = {k: e for k, e in F_PQ.items()}  # no field symbol: the partial in B is zero
    in_b = F_B
    a, b = _published(in_pq), _published(in_b)
    assert a.definition == b.definition == "published"
    # the two expressions are equal along the path
    for k in ("f_r", "f_z"):
        np.testing.assert_allclose(a[k].value(t, th, h), b[k].value(t, th, h), rtol=1e-12)
    # same Jacobian Γ
    ja, jb = gamma(_jacobian(in_pq), t, th, h, 20e3), gamma(_jacobian(in_b), t, th, h, 20e3)
    assert _jacobian(in_pq).definition == "jacobian"
    for x, y in zip(ja, jb, strict=True):
        np.testing.assert_allclose(x, y, rtol=1e-10)
        assert np.all(x > 0)
    # different published Γ: zero for the expression without B, the Jacobian's for the other
    pa, pb = gamma(a, t, th, h, 20e3), gamma(b, t, th, h, 20e3)
    np.testing.assert_array_equal(pa[0], 0.0)
    np.testing.assert_array_equal(pa[1], 0.0)
    assert np.all(pb[0] > 0) and np.all(pb[1] > 0)
    assert not np.allclose(pb[1], jb[1], rtol=1e-3)


def test_published_gamma_is_the_partial_derivative_of_its_expression(grid):
    t, th, h = grid
    ms = _published(F_B)
    S = dF_dB(ms, t, th, h, 1.0)
    Br, Bz = ms.fields(t, th, h)
    pv, qv = t, t * np.tan(th)
    for i, k in enumerate(("f_r", "f_z")):
        f = sp.lambdify((B_r, B_z, p, q, H), F_B[k], "numpy")
        for j, (dr, dz) in enumerate(((1, 0), (0, 1))):
            eps = 1e-6 * 0.1
            fd = (f(Br + dr * eps, Bz + dz * eps, pv, qv, h)
                  - f(Br - dr * eps, Bz - dz * eps, pv, qv, h)) / (2 * eps)
            np.testing.assert_allclose(S[..., i, j], fd, rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("name", ["f_r", "f_z", "gamma_r", "gamma_z"])
def test_published_responses_derivatives_match_differences(grid, name):
    t, th, h = grid
    R = Responses(_published(F_B)).at(h)
    g, Hs = R.grad(name, t, th), R.hess(name, t, th)
    e = 1e-6
    for k, (dt, dth) in enumerate(((e, 0), (0, e))):
        fd = (R.value(name, t + dt, th + dth) - R.value(name, t - dt, th - dth)) / (2 * e)
        np.testing.assert_allclose(g[..., k], fd, rtol=1e-5, atol=1e-9 * np.abs(fd).max())
        fd2 = (R.grad(name, t + dt, th + dth) - R.grad(name, t - dt, th - dth)) / (2 * e)
        # round-off of the differenced gradient: ~1e-10 of its size
        np.testing.assert_allclose(Hs[..., k, :], fd2, rtol=1e-5,
                                   atol=1e-8 * np.abs(g).max())


def test_model_files_round_trip_and_refuse_the_other_definition(tmp_path, grid):
    t, th, h = grid
    ms = _published(F_B)
    save_models(ms, tmp_path)
    back = load_models(tmp_path, definition="published")
    np.testing.assert_array_equal(gamma(back, t, th, h, 1.0)[1], gamma(ms, t, th, h, 1.0)[1])
    with pytest.raises(ValueError, match=r"serve the 'published' sensitivity definition.*"
                                         r"\[sensitivity\] definition is 'jacobian'"):
        load_models(tmp_path, definition="jacobian")
    jac = tmp_path / "jac"
    save_models(_jacobian(F_B), jac)
    with pytest.raises(ValueError, match=r"serve the 'jacobian' sensitivity definition.*"
                                         r"\[sensitivity\] definition is 'published'"):
        load_models(jac, definition="published")


# ---- the published definition on real data, the seed study's pieces, bad input -----------
TINY = {"generations": 3, "population": 40, "retries": 0, "threads": 1, "holdout_paths": 2}


def _tiny(study):
    from dataclasses import replace

    return replace(study, metamodel=replace(study.metamodel, **TINY))


def test_published_fit_on_the_bundled_data_runs_through_the_optimiser():
    from magtact.doe import load_bundled
    from magtact.metamodel import fit_models, load_field_models, prefitted_dir
    from magtact.optimise import heights_batch
    from magtact.study import load_study

    study = _tiny(load_study("magone"))
    fit = fit_models(load_bundled(), study, definition="published",
                     field_models=load_field_models(prefitted_dir()))
    assert set(fit.models) == {"f_r", "f_z"}
    assert all(isinstance(m, FieldForceModel) for m in fit.models.values())
    assert {s.name for s in fit.models["f_z"].expr.free_symbols} <= {"B_r", "B_z", "p", "q",
                                                                     "H"}
    assert fit.models["f_r"].info["definition"] == "published"
    ms = fit.model_set(study)
    assert ms.definition == "published"
    from magtact.sensitivity import gamma

    def responses(t, theta, height):
        """(Γ_r, Γ_z, f_r, f_z) per unit G of the published models."""
        return (*gamma(ms, t, theta, height, 1.0), *ms.forces(t, theta, height, 1.0))

    heights = [3e-3, 5e-3]
    table = heights_batch(ms, heights, study)
    assert table.converged.all()
    for i, height in enumerate(heights):
        # the optimiser's extrema over the stable box are the extrema of the published models:
        # each is the models' value at its reported location, inside the box, and no point of
        # a grid over the box does better
        t_m, theta_m = table.t_m[i], table.theta_m[i]
        assert 0 < t_m <= 1 and 0 < theta_m <= study.loading.theta_max + 1e-12
        t, th = np.meshgrid(np.linspace(0, t_m, 41), np.linspace(0, theta_m, 21), indexing="ij")
        grid = responses(t, th, height)
        for k, best, loc in ((0, table.gamma_r_max[i], table.loc_gamma_r[i]),
                             (1, table.gamma_z_max[i], table.loc_gamma_z[i]),
                             (3, table.f_z_max[i], table.loc_f_z[i])):
            assert 0 <= loc[0] <= t_m + 1e-12 and 0 <= loc[1] <= theta_m + 1e-12
            assert float(responses(*loc, height)[k]) == pytest.approx(best, rel=1e-9)
            assert best >= grid[k].max() * (1 - 1e-9) and best > 0
        assert table.f_r_min[i] <= grid[2].min() * (1 - 1e-9) and table.f_r_min[i] < 0
    # a lower body is stiffer in compression
    assert table.f_z_max[0] > table.f_z_max[1]


def test_shipped_fit_is_not_used_for_the_other_definition():
    from dataclasses import replace

    from magtact.doe import load_bundled
    from magtact.metamodel import find_prefitted
    from magtact.study import load_study

    study = load_study("magone")
    ds = load_bundled()
    assert find_prefitted(study, ds) is not None
    pub = replace(study, sensitivity=replace(study.sensitivity, definition="published"))
    assert find_prefitted(pub, ds) is None


def test_branches_and_trend():
    from magtact.publication import count_branches, trend

    assert count_branches([0, 1, 1, 0, 0, 1, 0, 1, 1]) == 3
    assert count_branches([1, 1, 1]) == 1
    assert count_branches([0, 0]) == 0
    assert trend([0, 1, 2]) == "increasing"
    assert trend([2, 1, 1]) == "decreasing"
    assert trend([0, 2, 1]) == "mixed"
    assert trend([1, 1, 1]) == "constant"


def test_conditioning_of_the_shear_bound_against_its_exact_answer():
    """f_r = (p − 0.5)² has its minimum at t = 0.5 and range 0.25 over t ∈ [0, 1]: within
    1.1 % of the range of the minimum from |t − 0.5| ≤ 0.0524, first grid point t = 0.45;
    with f_z = p the largest F_z drops by (0.5 − 0.45) / 0.5 = 10 %."""
    from magtact.optimise import shear_bound_conditioning
    from magtact.study import load_study

    ms = ModelSet.from_exprs({"B_r": q, "B_z": 1 + p, "f_r": (p - 0.5) ** 2, "f_z": p})
    c = shear_bound_conditioning(ms, load_study("magone"), [3e-3, 6e-3], tol=0.011)
    np.testing.assert_allclose(c.t_m, 0.5)
    np.testing.assert_allclose(c.t_tol, 0.45)
    np.testing.assert_allclose(c.dF_z_rel, 0.1, rtol=1e-12)
    with pytest.raises(ValueError, match=r"tol must be in \(0, 1\)"):
        shear_bound_conditioning(ms, load_study("magone"), 3e-3, tol=0.0)


def test_unknown_definition_is_refused_naming_the_setting(tmp_path):
    from magtact.study import StudyError, load_study

    path = tmp_path / "s.toml"
    path.write_text('[sensitivity]\ndefinition = "partial"\n')
    with pytest.raises(StudyError, match=r"sensitivity\.definition.*'jacobian', 'published'"):
        load_study(path)


def test_cli_bad_input_for_the_seed_study(tmp_path):
    from typer.testing import CliRunner

    from magtact.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["reproduce", "--seeds", "0", "--out", str(tmp_path)])
    assert res.exit_code == 2
    assert "--seeds" in res.output and "at least 1" in res.output
    res = runner.invoke(app, ["reproduce", "--definition", "partial", "--out", str(tmp_path)])
    assert res.exit_code == 2
    assert "[sensitivity] definition" in res.output and "partial" in res.output
    assert "Traceback" not in res.output


def test_cli_refuses_models_of_the_other_definition(tmp_path, capsys, monkeypatch):
    """A folder of published-definition models given to a Jacobian study: one line."""
    import sys

    from magtact.cli import main

    save_models(_published(F_B), tmp_path / "m")
    monkeypatch.setattr(sys, "argv", ["magtact", "compare", "3,29.4", "4,29.4", "--models",
                                      str(tmp_path / "m")])
    with pytest.raises(SystemExit) as exc:
        main()
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "[sensitivity] definition is 'jacobian'" in err and "Traceback" not in err


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the tiny GP's models are rough
def test_seed_study_keeps_each_record_and_resumes(tmp_path):
    """A second run of the same seed study reads every record back instead of refitting."""
    from magtact.doe import load_bundled
    from magtact.metamodel import prefitted_dir
    from magtact.publication import seed_study
    from magtact.study import load_study

    study = _tiny(load_study("magone"))
    kw = dict(seeds=[0], definitions=("jacobian", "published"), workers=1, sweep_n=21,
              cache=tmp_path / "fits")
    first = seed_study(study, load_bundled(), prefitted_dir(), **kw)
    assert [r["definition"] for r in first] == ["jacobian", "published"]
    assert len(list((tmp_path / "fits").glob("*.json"))) == 2
    lines = []
    again = seed_study(study, load_bundled(), prefitted_dir(), log=lines.append, **kw)
    assert again == json.loads(json.dumps(first))
    assert lines == [f"2 of 2 fits from {tmp_path / 'fits'}"]
    other = _tiny(load_study("magone"))
    from dataclasses import replace

    other = replace(other, metamodel=replace(other.metamodel, generations=4))
    lines = []
    seed_study(other, load_bundled(), prefitted_dir(), log=lines.append,
               **(kw | {"definitions": ("jacobian",)}))
    assert not any("from" in m for m in lines)  # other settings: nothing reused


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_reproduce_fits_with_the_seed_study_budget(tmp_path):
    """``generations`` sets every fit's budget and the written summary says which it was."""
    from magtact.publication import SEED_GENERATIONS, reproduce
    from magtact.study import load_study

    study = _tiny(load_study("magone"))
    assert SEED_GENERATIONS < load_study("magone").metamodel.generations
    result = reproduce(study, seeds=1, definitions=("jacobian",), workers=1, sweep_n=21,
                       generations=2)
    assert result.study.metamodel.generations == 2
    result.write(tmp_path)
    assert json.loads((tmp_path / "publication.json").read_text())["gp"]["generations"] == 2
    kept = reproduce(study, seeds=1, definitions=("jacobian",), workers=1, sweep_n=21,
                     generations=None)
    assert kept.study.metamodel.generations == TINY["generations"]
