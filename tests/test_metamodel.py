"""Metamodels: expressions, restricted parser, files, regressor, fitting pipeline."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

from conftest import known_set, synthetic_doe
from magtact.metamodel import (
    ExactField,
    Metamodel,
    ModelSet,
    SymbolicRegressor,
    accuracy,
    fit_models,
    format_expression,
    hall_features,
    holdout_paths,
    load_model,
    load_models,
    parse_expression,
    save_model,
    save_models,
)
from magtact.metamodel import H as Hs
from magtact.metamodel import p as ps
from magtact.metamodel import q as qs
from magtact.metamodel import t as ts
from magtact.metamodel import theta as ths
from magtact.study import load_study

STUDY = load_study(None)


# ---- Metamodel / ModelSet -----------------------------------------------------------------
def test_both_forms_agree_and_derivatives_are_exact():
    m = Metamodel.from_expr("f_r", ts * sp.tan(ths) * sp.exp(-ts) * Hs, "N/Pa")
    assert m.expr_pq == qs * sp.exp(-ps) * Hs
    t, th, H = 0.3, 0.2, 4e-3
    assert m.value(t, th, H) == pytest.approx(t * np.tan(th) * np.exp(-t) * H, rel=1e-14)
    g = m.grad(t, th, H)
    assert g == pytest.approx([np.tan(th) * np.exp(-t) * H * (1 - t),
                               t * np.exp(-t) * H / np.cos(th) ** 2,
                               t * np.tan(th) * np.exp(-t)], rel=1e-12)
    hs = m.hess(t, th, H)
    assert hs.shape == (3, 3) and hs[2, 2] == 0.0 and hs[0, 1] == pytest.approx(hs[1, 0])
    jet = m.jet(t, th, H, 3)
    assert jet[1] == pytest.approx([-t * np.tan(th) * np.exp(-t) * H, np.exp(-t) * H])
    assert jet[3][0, 0, 0] == pytest.approx(-t * np.tan(th) * np.exp(-t) * H)


def test_evaluation_broadcasts():
    m = known_set().B_r
    t = np.linspace(0, 1, 5)[:, None]
    th = np.array([0.0, 0.1, 0.2])
    assert m.value(t, th, 4e-3).shape == (5, 3)
    assert m.grad(t, th, 4e-3).shape == (5, 3, 3)
    assert m.hess(t, th, 4e-3).shape == (5, 3, 3, 3)


def test_forces_scale_with_G():
    ms = known_set()
    Fr, Fz = ms.forces(0.5, 0.3, 4e-3, 2e4)
    assert Fr == pytest.approx(2e4 * ms.f_r.value(0.5, 0.3, 4e-3), rel=1e-15)
    assert Fz == pytest.approx(2e4 * ms.f_z.value(0.5, 0.3, 4e-3), rel=1e-15)


@pytest.mark.parametrize("expr, msg", [
    (sp.Symbol("x") + ts, "unknown symbols ['x']"),
    (ts + ps, "mixes (t, theta) and the features (p, q)"),
    (sp.Abs(ts - 0.5), "name 'Abs' is not allowed"),
])
def test_from_expr_rejects_bad_symbols(expr, msg):
    with pytest.raises(ValueError, match=msg.replace("(", r"\(").replace(")", r"\)")
                       .replace("[", r"\[").replace("]", r"\]")):
        Metamodel.from_expr("B_r", expr, "T")


def test_modelset_keys_checked():
    with pytest.raises(ValueError, match=r"missing \['f_z'\], unknown \['g'\]"):
        ModelSet.from_exprs({"B_r": ts, "B_z": ts, "f_r": ts, "g": ts})
    with pytest.raises(KeyError, match="no response 'F_r'"):
        known_set()["F_r"]


def test_jet_order_checked():
    with pytest.raises(ValueError, match="jet order must be 0..3"):
        known_set().B_r.jet(0.1, 0.1, 4e-3, 4)


# ---- parser and files ------------------------------------------------------------------
def test_format_parse_round_trip_is_exact():
    rng = np.random.default_rng(1)
    for _ in range(50):
        a, b, c = rng.normal(size=3) * 10.0 ** rng.integers(-12, 6, size=3)
        e = (sp.Float(a) * ts * sp.exp(sp.Float(b) * sp.tan(ths)) / Hs + sp.sqrt(ts)
             - sp.Rational(1, 3) * sp.tanh(ths) ** 2 + sp.Float(c))
        back = parse_expression(format_expression(e))
        assert back == e and sp.srepr(back) == sp.srepr(e)


def test_parser_reads_operon_syntax():
    e = parse_expression("((-0.5) + (2.0 * (p ^ 2))) / sqrt(q)")
    assert e == (sp.Float(-0.5) + sp.Float(2.0) * ps**2) / sp.sqrt(qs)


@pytest.mark.parametrize("text, msg", [
    ("__import__('os').system('echo hi')", "name '__import__' is not allowed"),
    ("t.__class__", "operator '.' is not allowed"),
    ("exp(t, p)", "operator ',' is not allowed"),
    ("x + 1", "name 'x' is not allowed"),
    ("lambda: 1", "name 'lambda' is not allowed"),
    ("[t]", r"operator '\[' is not allowed"),
    ("'t'", "token \"'t'\" is not allowed"),
    ("1j*t", "number '1j' is not allowed"),
    ("t; p", "operator ';' is not allowed"),
    ("", "is empty"),
    ("(t", "not well formed"),
    ("t +", "not well formed"),
    ("1/0", "finite expression"),
])
def test_parser_refuses(text, msg):
    with pytest.raises(ValueError, match=msg):
        parse_expression(text)


def test_valid_file_round_trips_exactly(tmp_path):
    ms = known_set()
    ms = ModelSet(**{k: replace(m, info={"accuracy": {"r2": 0.99}, "seed": 3})
                     for k, m in ms.items()})
    save_models(ms, tmp_path)
    back = load_models(tmp_path)
    for k, m in ms.items():
        assert back[k].expr == m.expr and back[k].expr_pq == m.expr_pq
        assert back[k].units == m.units and back[k].info == m.info
        x = (np.array([0.0, 0.4, 1.0]), np.array([0.1, 0.2, 0.4]), 5e-3)
        assert np.array_equal(back[k].value(*x), m.value(*x))
    assert json.loads((tmp_path / "B_r.json").read_text())["expression"] == \
        format_expression(ms.B_r.expr)


def test_injected_file_is_refused_and_nothing_runs(tmp_path):
    marker = tmp_path / "pwned"
    path = save_model(known_set().B_r, tmp_path / "B_r.json")
    data = json.loads(path.read_text())
    data["expression"] = f"__import__('os').system('touch {marker}')"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="B_r.json: model expression: name '__import__' is not "
                                         "allowed"):
        load_model(path)
    assert not marker.exists()


@pytest.mark.parametrize("edit, msg", [
    (lambda d: d.update(format="other"), "not a magtact metamodel file"),
    (lambda d: d.pop("expression"), "key 'expression' is missing"),
    (lambda d: d.update(expression="t*tan(theta)*2/H"), "describe different models"),
    (lambda d: d.update(info=[1]), "'info' must be an object"),
    (lambda d: d.update(expression_pq="t"), "name 't' is not allowed"),
])
def test_bad_files_refused(tmp_path, edit, msg):
    path = save_model(known_set().B_r, tmp_path / "B_r.json")
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=msg):
        load_model(path)


def test_bad_json_and_wrong_response(tmp_path):
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_model(tmp_path / "x.json")
    save_models(known_set(), tmp_path)
    (tmp_path / "f_r.json").write_text((tmp_path / "B_r.json").read_text())
    with pytest.raises(ValueError, match=r"holds 'B_r' \[T\], expected 'f_r' \[N/Pa\]"):
        load_models(tmp_path)
    with pytest.raises(FileNotFoundError):
        load_model(tmp_path / "missing.json")
    (tmp_path / "f_r.json").unlink()
    with pytest.raises(FileNotFoundError, match="metamodel file not found: .*f_r.json"):
        load_models(tmp_path)


# ---- regressor ---------------------------------------------------------------------------
def _formula(X):
    return X[:, 0] * np.exp(-X[:, 1]) + X[:, 2] / (1.0 + X[:, 0])


def test_regressor_recovers_known_formula():
    rng = np.random.default_rng(0)
    X, Xt = rng.uniform(0, 1, (300, 3)), rng.uniform(0, 1, (300, 3))
    reg = SymbolicRegressor(generations=60, population_size=300, max_length=30, random_state=0)
    reg.fit(X, _formula(X))
    assert reg.generations_ == 60
    assert reg.score(Xt, _formula(Xt)) > 0.9999
    ops = {type(a).__name__ for a in sp.preorder_traversal(reg.expression_)}
    assert ops <= {"Add", "Mul", "Pow", "exp", "log", "tanh", "Symbol", "Float", "Integer",
                   "Rational", "Half", "NegativeOne", "One", "Zero"}


def test_same_seed_same_expression_and_sklearn_contract():
    from sklearn.base import clone

    rng = np.random.default_rng(2)
    X = rng.uniform(0, 1, (100, 3))
    y = _formula(X)
    kw = dict(generations=8, population_size=60, max_length=20, random_state=7)
    a, b = SymbolicRegressor(**kw).fit(X, y), SymbolicRegressor(**kw).fit(X, y)
    assert a.expression_ == b.expression_
    assert np.array_equal(a.predict(X), b.predict(X))
    c = clone(a)
    assert c.get_params() == a.get_params() and not hasattr(c, "expression_")


@pytest.mark.parametrize("kw, y, msg", [
    (dict(operators="all"), None, "operators must be one of"),
    (dict(feature_names=["a", "a", "b"]), None, "3 distinct identifiers"),
    (dict(), np.ones(20), "the target is constant"),
])
def test_regressor_bad_input(kw, y, msg):
    X = np.random.default_rng(0).uniform(size=(20, 3))
    with pytest.raises(ValueError, match=msg):
        SymbolicRegressor(generations=2, population_size=20, **kw).fit(X, _formula(X) if y is None
                                                                        else y)


# ---- fitting pipeline --------------------------------------------------------------------
def test_hall_features_match_geometry():
    from magtact.geometry import hall_from_magnet_centre, loading_path

    X, Z = hall_features(STUDY)
    t, th, H = 0.37, 0.3, 4.4e-3
    x, z = hall_from_magnet_centre(STUDY, *loading_path(STUDY, t, th, H), H)
    sub = {ps: t, qs: t * np.tan(th), Hs: H}
    assert float(X.subs(sub)) == pytest.approx(x * 1e3, rel=1e-12)
    assert float(Z.subs(sub)) == pytest.approx(z * 1e3, rel=1e-12)


def test_holdout_paths_interior_and_checked():
    th, H = STUDY.theta_levels, STUDY.H_levels
    hold = holdout_paths(th, H, 4, 0)
    assert len(set(hold)) == 4 and hold == holdout_paths(th, H, 4, 0)
    assert all(th[0] < a < th[-1] and H[0] < b < H[-1] for a, b in hold)
    with pytest.raises(ValueError, match="allow at most 9 held-out paths"):
        holdout_paths(th, H, 10, 0)


def test_accuracy_metrics():
    y = np.array([0.0, 1.0, 2.0, 4.0])
    acc = accuracy(y, y + np.array([0.1, 0.0, 0.0, -0.2]))
    assert acc.max_abs_err == pytest.approx(0.2)
    assert acc.max_abs_err_over_range == pytest.approx(0.05)
    assert acc.max_rel_err == pytest.approx(0.05)  # y = 0 is below 5 % of max |y|


def test_fit_pipeline_small(tmp_path):
    ds = synthetic_doe(STUDY)
    cfg = replace(STUDY.metamodel, generations=12, population=150)
    res = fit_models(ds, STUDY, settings=cfg)
    ms = res.model_set()
    assert set(res.reports) == {"B_r", "B_z", "f_r", "f_z"}
    assert {k: r.transform for k, r in res.reports.items()} == {
        "B_r": "anchor_x", "B_z": "log", "f_r": "anchor_q", "f_z": "anchor_0"}
    for k, rep in res.reports.items():
        assert rep.test.n_points == 4 * ds.sizes["t"]
        assert rep.test.r2 > 0.99, (k, rep.test)
        info = ms[k].info
        assert info["data_hash"] == res.data_hash and info["settings"]["generations"] == 12
    # symmetries built in by the transforms: zero on the axis / unloaded
    # (to rounding: the anchor term is evaluated apart from the model's other terms)
    t = np.linspace(0, 1, 7)
    scale = {k: np.abs(ds[k.replace("f", "F")]).max().item() / (1 if k[0] == "B" else 1e4)
             for k in ("B_r", "f_r", "f_z")}
    assert np.all(np.abs(ms.B_r.value(t, 0.0, 4e-3)) <= 1e-12 * scale["B_r"])
    assert np.all(np.abs(ms.f_r.value(t, 0.0, 4e-3)) <= 1e-12 * scale["f_r"])
    assert abs(ms.f_z.value(0.0, 0.3, 4e-3)) <= 1e-12 * scale["f_z"]
    assert np.all(ms.B_z.value(t, 0.2, 5e-3) > 0)
    save_models(ms, tmp_path)
    assert load_models(tmp_path).B_z.expr == ms.B_z.expr


def test_fit_with_exact_field(tmp_path):
    ds = synthetic_doe(STUDY, n_t=6)
    cfg = replace(STUDY.metamodel, generations=3, population=30, b_model="exact")
    res = fit_models(ds, STUDY, settings=cfg)
    assert set(res.models) == {"f_r", "f_z"}
    ms = res.model_set(STUDY)
    assert isinstance(ms.B_r, ExactField)
    save_models(ms, tmp_path)
    back = load_models(tmp_path)
    assert isinstance(back.B_z, ExactField) and back.f_r.expr == ms.f_r.expr
    for k in ("B_r", "B_z"):
        (tmp_path / f"{k}.json").unlink()
    given = load_models(tmp_path, B_model=(ms.B_r, ms.B_z))
    assert given.B_r is ms.B_r and given.f_z.expr == ms.f_z.expr
    x = (np.array([0.0, 0.5]), np.array([0.1, 0.4]), np.array([3e-3, 6e-3]))
    assert np.array_equal(back.B_z.value(*x), ms.B_z.value(*x))
    with pytest.raises(ValueError, match="pass the study for the exact field"):
        res.model_set()


def test_guard_rails_reject_and_refit(monkeypatch):
    """A model with a pole inside the domain is rejected and refitted with the next seed."""

    ds = synthetic_doe(STUDY, n_t=6)
    real = SymbolicRegressor.fit
    seeds = []

    def fake_fit(self, X, y):
        real(self, X, y)
        seeds.append(self.random_state)
        if self.random_state == 0:  # poison the first try with a pole at p = 0.5
            self.expression_ = self.expression_ / (self.symbols_[0] - 0.5)
        return self

    monkeypatch.setattr(SymbolicRegressor, "fit", fake_fit)
    cfg = replace(STUDY.metamodel, generations=2, population=20, retries=1, operators="rational")
    res = fit_models(ds, STUDY, settings=cfg, names=("f_z",))
    rep = res.reports["f_z"]
    assert seeds == [0, 1] and rep.seed == 1 and rep.tries == 2
    assert "seed 0: non-finite" in rep.rejected[0] or "pole" in rep.rejected[0]
    monkeypatch.setattr(SymbolicRegressor, "fit",
                        lambda self, X, y: (real(self, X, y), setattr(
                            self, "expression_", self.expression_ / (self.symbols_[0] - 0.5)),
                            self)[-1])
    with pytest.raises(RuntimeError, match="f_z: every fit failed the guard rails"):
        fit_models(ds, STUDY, settings=cfg, names=("f_z",))


def test_incomplete_data_refused():
    ds = synthetic_doe(STUDY, n_t=4)
    ds["F_z"][1, 1, 1, 1] = np.nan
    with pytest.raises(ValueError, match="non-finite values of f_z"):
        fit_models(ds, STUDY, settings=replace(STUDY.metamodel, generations=1, population=10))


def test_the_failed_paths_of_an_incomplete_doe_are_left_out_and_recorded():
    from magtact.metamodel import MAX_OMITTED

    ds = synthetic_doe(STUDY, n_t=4)
    n = ds.sizes["t"] * ds.sizes["theta"] * ds.sizes["H"]
    ds["F_z"][:, 1, 1, :] = np.nan  # one whole (θ, H) path
    ds.attrs.update(complete=0, failed_jobs="path θ=x, H=y: structural path failed")
    cfg = replace(STUDY.metamodel, generations=1, population=10, holdout_paths=0)
    res = fit_models(ds, STUDY, settings=cfg, names=("f_z",))
    info = res.models["f_z"].info
    assert info["omitted_points"] == ds.sizes["t"] and "path failed" in info["failed_jobs"]
    assert info["accuracy"]["train"]["n_points"] == n - ds.sizes["t"]
    ds["F_z"][:, :, :, :] = np.nan
    with pytest.raises(ValueError, match=rf"the DOE is incomplete: {n} of {n} points \(1 "
                                         rf"failed job\(s\)\), more than {MAX_OMITTED:.0%}"):
        fit_models(ds, STUDY, settings=cfg, names=("f_z",))


def test_exact_field_matches_hall_field_and_its_derivatives():
    from magtact.magnetics import hall_field

    T, TH, HH = np.array([0.0, 0.3, 0.9]), np.array([0.1, 0.3, 0.42]), np.array([3e-3, 5e-3, 7e-3])
    br, bz = hall_field(STUDY, T, TH, HH, solver="exact")
    fr, fz = ExactField(STUDY, "B_r"), ExactField(STUDY, "B_z")
    assert np.allclose(fr.value(T, TH, HH), br, rtol=1e-13, atol=0)
    assert np.allclose(fz.value(T, TH, HH), bz, rtol=1e-13, atol=0)
    x = np.array([T, TH, HH])
    steps = np.array([1e-5, 1e-5, 1e-8])
    for m in (fr, fz):
        g, h = m.grad(*x), m.hess(*x)
        for i in range(3):
            d = np.eye(3)[i][:, None] * steps[i]
            gfd = (m.value(*(x + d)) - m.value(*(x - d))) / (2 * steps[i])
            hfd = (m.grad(*(x + d)) - m.grad(*(x - d))) / (2 * steps[i])
            assert np.allclose(g[:, i], gfd, rtol=1e-6, atol=1e-9 * np.abs(g).max())
            assert np.allclose(h[:, i, :], hfd, rtol=1e-5, atol=1e-7 * np.abs(h).max())
    with pytest.raises(ValueError, match="must be 'B_r' or 'B_z'"):
        ExactField(STUDY, "f_r")


def test_no_kinks_from_assumptions():
    """sqrt(x**2) must stay smooth-looking (not |x|) in both model and regressor symbols."""
    assert not parse_expression("sqrt(t**2) + sqrt((p - q)**2)").has(sp.Abs)
    assert not parse_expression("sqrt(X**2)", {"X": sp.Symbol("X")}).has(sp.Abs)


def test_seed_search_keeps_best_training_fit(monkeypatch):
    import magtact.metamodel._fit as fitmod

    monkeypatch.setitem(fitmod.TRAIN_TARGET, "f_z", 0.0)  # unreachable: every seed is tried
    ds = synthetic_doe(STUDY, n_t=6)
    cfg = replace(STUDY.metamodel, generations=2, population=20, retries=2, operators="rational")
    rep = fit_models(ds, STUDY, settings=cfg, names=("f_z",)).reports["f_z"]
    assert rep.tries == 3
    errs = []
    for seed in range(3):
        one = replace(cfg, seed=seed, retries=0)
        errs.append(fit_models(ds, STUDY, settings=one, names=("f_z",))
                    .reports["f_z"].train.max_abs_err_over_range)
    assert rep.seed == int(np.argmin(errs))
    assert rep.train.max_abs_err_over_range == min(errs)


def test_transform_fallback_when_signs_change():
    ds = synthetic_doe(STUDY, n_t=6)
    ds["B_z"] = ds["B_z"] - ds["B_z"].mean()  # B_z changes sign: no log
    cfg = replace(STUDY.metamodel, generations=2, population=20, operators="rational")
    res = fit_models(ds, STUDY, settings=cfg, names=("B_z",))
    assert res.reports["B_z"].transform == "identity"


def test_fallback_transform_when_log_fits_fail_the_guard_rails(monkeypatch):
    import magtact.metamodel._fit as fitmod

    ds = synthetic_doe(STUDY, n_t=6)
    real = SymbolicRegressor.fit

    def fake_fit(self, X, y):
        real(self, X, y)
        if np.all(y < 0):  # log B_z (B_z < 1 T) rather than B_z: give it a pole
            self.expression_ = self.expression_ / (self.symbols_[1] + 4.0)
        return self

    monkeypatch.setattr(SymbolicRegressor, "fit", fake_fit)
    monkeypatch.setitem(fitmod.TRAIN_TARGET, "B_z", 1.0)
    cfg = replace(STUDY.metamodel, generations=2, population=20, retries=1, operators="rational")
    rep = fit_models(ds, STUDY, settings=cfg, names=("B_z",)).reports["B_z"]
    assert rep.transform == "identity" and rep.tries == 3  # 2 rejected + 1 reaching the target
    assert rep.rejected[0].startswith("log, seed 0:") and len(rep.rejected) == 2


def test_accuracy_uses_the_reference_range():
    y = np.array([0.0, 1.0, 2.0, 10.0])
    acc = accuracy(y[:3], y[:3] + 0.1, reference=y)
    assert acc.max_abs_err_over_range == pytest.approx(0.01)
    assert acc.max_rel_err == pytest.approx(0.1)  # |y| > 0.5 only


def test_infinite_anchor_is_rejected_and_refitted(monkeypatch):
    import magtact.metamodel._fit as fitmod

    ds = synthetic_doe(STUDY, n_t=6)
    real = SymbolicRegressor.fit

    def fake_fit(self, X, y):
        real(self, X, y)
        if self.random_state == 0:  # g ~ 1/X: g(0, Z) is infinite
            self.expression_ = self.expression_ + 1e-9 / self.symbols_[0]
        return self

    monkeypatch.setattr(SymbolicRegressor, "fit", fake_fit)
    monkeypatch.setitem(fitmod.TRAIN_TARGET, "B_r", 1.0)
    cfg = replace(STUDY.metamodel, generations=2, population=20, retries=1, operators="rational")
    rep = fit_models(ds, STUDY, settings=cfg, names=("B_r",)).reports["B_r"]
    assert rep.seed == 1 and rep.tries == 2
    assert rep.rejected == ("anchor_x, seed 0: infinite constant after the transform (pole on "
                            "the axis?)",)


def test_feature_map_derivatives_match_differences():
    """∂(p, q)/∂(t, θ) and ∂²q/∂(t, θ)² against central differences of the map itself."""
    from magtact.metamodel import feature_jacobian, features, q_hessian

    t, th, h = np.array([0.0, 0.3, 1.0]), np.array([0.0, 0.2, 0.5]), 1e-6
    J, Hq = feature_jacobian(t, th), q_hessian(t, th)
    for k, (dt, dth) in enumerate(((h, 0.0), (0.0, h))):
        d = [(a - b) / (2 * h) for a, b in zip(features(t + dt, th + dth),
                                                features(t - dt, th - dth), strict=True)]
        np.testing.assert_allclose(J[:, 0, k], d[0], atol=1e-9)
        np.testing.assert_allclose(J[:, 1, k], d[1], atol=1e-9)
        dJq = (feature_jacobian(t + dt, th + dth)[:, 1] - feature_jacobian(t - dt, th - dth)[:, 1])
        np.testing.assert_allclose(Hq[:, k], dJq / (2 * h), atol=1e-8)
