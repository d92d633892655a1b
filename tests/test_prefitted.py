"""The metamodel fit shipped for the bundled DOE: used only for the same data and settings."""

from dataclasses import replace

import pytest

from magtact.doe import load_bundled
from magtact.metamodel import copy_prefitted, find_prefitted, prefitted_dir
from magtact.study import magone


@pytest.fixture(scope="module")
def ds():
    return load_bundled()


def test_shipped_fit_matches_bundled_data_and_default_settings(ds):
    assert find_prefitted(magone(), ds) == prefitted_dir()


def test_other_settings_or_data_are_not_served(ds):
    s = magone()
    assert find_prefitted(replace(s, metamodel=replace(s.metamodel, generations=7)), ds) is None
    other = ds.copy(deep=True)
    other["F_z"][...] = other["F_z"] * 1.001
    assert find_prefitted(s, other) is None


def _errors(models, ds, name):
    """(train, held-out) max |error| / range of one shipped model on the bundled data."""
    from magtact.metamodel._fit import _table, accuracy, holdout_mask

    table = _table(ds)[0]
    model = getattr(models, name)
    y_hat = model.value(table["t"], table["theta"], table["H"])
    test = holdout_mask(table, model.info["accuracy"]["holdout_paths_theta_H"])
    y = table[name]
    return (accuracy(y[~test], y_hat[~test], y).max_abs_err_over_range,
            accuracy(y[test], y_hat[test], y).max_abs_err_over_range)


@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    models, files = copy_prefitted(prefitted_dir(), tmp_path_factory.mktemp("shipped"))
    assert {f.name for f in files} >= {"B_r.json", "B_z.json", "f_r.json", "f_z.json",
                                       "metamodels.md"}
    return models


@pytest.mark.parametrize("name", ["B_r", "B_z", "f_r", "f_z"])
def test_shipped_accuracy_report_is_what_the_models_give(ds, shipped, name):
    """The accuracy written into each shipped file is recomputed from its expression, and the
    training error is within the fit's target (docs/method.md §5; F data are rough at ~1 %)."""
    train, test = _errors(shipped, ds, name)
    report = getattr(shipped, name).info["accuracy"]
    assert train == pytest.approx(report["train"]["max_abs_err_over_range"], rel=1e-6)
    assert test == pytest.approx(report["test"]["max_abs_err_over_range"], rel=1e-6)
    assert train < (0.01 if name.startswith("B") else 0.02)


@pytest.mark.parametrize("name", ["B_r", "B_z", "f_r", "f_z"])
def test_shipped_held_out_accuracy_within_targets(ds, shipped, name):
    """Max |error| ≤ 1 % of range for B, ≤ 2 % for F/G on held-out (θ, H) paths."""
    assert _errors(shipped, ds, name)[1] <= (0.01 if name.startswith("B") else 0.02)


@pytest.mark.parametrize("path", sorted(prefitted_dir().parent.glob("*/*.json")),
                         ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shipped_model_file_reads_and_compiles_as_any_other(path):
    """The shipped fits load without the grammar's reading and the check of their two forms
    (``check=False``: compiled from their text, :meth:`Metamodel.from_text`). Here each file
    is read as every other model file is (the grammar; its (t, θ) and (p, q) expressions
    checked against each other), and the model compiled from its text gives the same values
    and derivatives, to rounding; its SymPy forms, built when asked for, are those read."""
    import json

    import numpy as np

    from magtact.metamodel._io import FORMAT, model_from_dict

    data = json.loads(path.read_text(encoding="utf-8"))
    if data.get("format") != FORMAT:
        pytest.skip(f"{data.get('format')}: not a closed-form model")
    fast, read = model_from_dict(data, str(path), check=False), model_from_dict(data, str(path))
    assert "expr" not in vars(fast)  # nothing built yet
    assert fast.text == read.text == (data["expression"], data["expression_pq"])
    assert fast.geometry == read.geometry
    rng = np.random.default_rng(0)
    t, th, H = rng.uniform(0, 1, 200), rng.uniform(0, 0.45, 200), rng.uniform(2e-3, 1e-2, 200)
    for a, b in ((fast.value(t, th, H), read.value(t, th, H)),
                 *zip(fast.jet(t, th, H, 2), read.jet(t, th, H, 2), strict=True)):
        scale = np.nanmax(np.abs(b), initial=1e-300)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale, equal_nan=True)
    assert fast.expr == read.expr and fast.expr_pq == read.expr_pq


def test_the_agreement_check_finds_two_forms_that_disagree(tmp_path):
    import json

    from magtact import MagtactError
    from magtact.metamodel import load_models

    src = prefitted_dir()
    for k in ("B_r", "B_z", "f_r", "f_z"):
        (tmp_path / f"{k}.json").write_text((src / f"{k}.json").read_text())
    doc = json.loads((tmp_path / "f_z.json").read_text())
    doc["expression_pq"] = f"2*({doc['expression_pq']})"
    (tmp_path / "f_z.json").write_text(json.dumps(doc))
    with pytest.raises(MagtactError, match="describe different models"):
        load_models(tmp_path)
    load_models(tmp_path, check=False)  # the package's own files are loaded unchecked
