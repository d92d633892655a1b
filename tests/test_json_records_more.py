"""Records of the card's tables of the parts compared and of the fitted models' ``info``, the
chip's setting fields taken from their declaration, and files written through the atomic
writer (the models' JSON, the seed study section's captions)."""

import json
import math

import numpy as np
import pytest

from magtact._records import from_json, keys, to_json


# ---- card.json's tables of the parts compared ---------------------------------------------------
def test_the_card_tables_are_left_out_where_empty_and_keep_their_order():
    from magtact._card import SILICONES_KEY, SIZES_KEY, CardChoices

    assert keys(CardChoices) == (SILICONES_KEY, SIZES_KEY) == ("silicones", "magnet_sizes")
    assert to_json(CardChoices()) == {}
    assert to_json(CardChoices([], [["4x2", "best"]])) == {"magnet_sizes": [["4x2", "best"]]}
    both = to_json(CardChoices([["Ecoflex 00-30", "a"]], [["4x2", "b"], ["6x3", "c"]]))
    assert list(both) == ["silicones", "magnet_sizes"]
    assert json.dumps(both) == ('{"silicones": [["Ecoflex 00-30", "a"]], '
                                '"magnet_sizes": [["4x2", "b"], ["6x3", "c"]]}')


def test_the_card_tables_are_read_from_any_card_document():
    from magtact._card import CardChoices

    card = {"header": ["", "chosen"], "rows": [], "silicones": [["a", "b"], "not a row"],
            "magnet_sizes": {"forged": "object"}}
    choices = CardChoices.of(card)
    assert choices.silicones == (["a", "b"], "not a row")  # the readers keep the pairs
    assert choices.magnet_sizes == ()
    assert CardChoices.of({}) == CardChoices() == CardChoices.of("not a card")


def test_the_printed_card_and_the_report_show_the_tables():
    from magtact._card import Card
    from magtact.report._html import _choices

    card = {"header": ["", "chosen"], "rows": [], "silicones": [["with Ecoflex", "σ_F 1"]],
            "magnet_sizes": [["⌀4 × 2 mm", "σ_F 2"], ["broken"]]}
    text = str(Card(card))
    assert "with Ecoflex" in text and "⌀4 × 2 mm" in text and "broken" not in text
    page = _choices(card)
    assert page.index('id="magnet_sizes"') < page.index('id="silicones"')
    assert "σ_F 2" in page and "broken" not in page
    assert _choices({"header": [], "rows": []}) == ""


def test_write_card_writes_the_tables_through_the_record(tmp_path, monkeypatch):
    import magtact.designer
    from magtact.report import _card

    class Verdictless:  # what write_card reads of an answer besides card_rows's
        verdict = None

    monkeypatch.setattr(_card, "card_rows", lambda answers, constraints=None, rtol=1e-2: (
        ["", "chosen"], [["height H", "3 mm"]]))
    monkeypatch.setattr(magtact.designer, "answer_json", lambda a: {"answer": 1})
    path = _card.write_card([Verdictless()], tmp_path, silicones=[["s", "t"]],
                            sizes=[["z", "w"]])
    none = _card.write_card([Verdictless()], tmp_path / "none")
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert list(doc) == ["header", "rows", "answers", "silicones", "magnet_sizes"]
    assert doc["silicones"] == [["s", "t"]] and doc["magnet_sizes"] == [["z", "w"]]
    assert list(json.loads(none.read_text(encoding="utf-8"))) == ["header", "rows", "answers"]


# ---- the fitted models' info ---------------------------------------------------------------------
def _report(test=True):
    from magtact.metamodel._fit import Accuracy, FitReport

    acc = Accuracy(0.99, 1e-3, 0.01, 0.05, 40)
    return FitReport("f_z", "anchor_0", ("p", "q", "h"), 3, 2, 1.5, 40, acc,
                     Accuracy(0.98, 2e-3, 0.02, math.nan, 8) if test else None,
                     ("anchor_0, seed 2: too large",))


def _old_info(rep, hold, settings, omitted, definition):
    """The info as the models' files have always held it, spelled out."""
    from dataclasses import asdict

    info = {
        "transform": rep.transform, "features": list(rep.features),
        "accuracy": {"train": asdict(rep.train),
                     "test": asdict(rep.test) if rep.test else None,
                     "holdout_paths_theta_H": [list(h) for h in hold]},
        "settings": settings, "seed": rep.seed, "tries": rep.tries,
        "rejected": list(rep.rejected), "fit_time_s": rep.fit_time_s,
        "data_hash": "abc", "G_spread": 0.25,
    }
    if omitted:
        info["omitted_points"] = omitted
        info["failed_jobs"] = "job 1: diverged"
    if definition is not None:
        info["definition"] = definition
    return info


@pytest.mark.parametrize("test, omitted, definition",
                         [(True, 0, "jacobian"), (False, 3, None), (True, 2, "published")])
def test_the_model_info_is_the_file_it_always_was(test, omitted, definition):
    from magtact.metamodel._fit import ModelAccuracy, ModelInfo

    rep = _report(test)
    hold = [(0.1, 0.005), (0.2, 0.006)]
    settings = {"generations": 2, "operators": "smooth"}
    info = to_json(ModelInfo(
        rep.transform, rep.features, ModelAccuracy(rep.train, rep.test, hold), settings,
        rep.seed, rep.tries, rep.rejected, rep.fit_time_s, "abc", 0.25,
        omitted_points=omitted or None, failed_jobs="job 1: diverged" if omitted else None,
        definition=definition))
    old = _old_info(rep, hold, settings, omitted, definition)
    assert json.dumps(info, indent=2) == json.dumps(old, indent=2)
    back = from_json(ModelInfo, json.loads(json.dumps(info)))
    assert back.accuracy.train == rep.train and back.seed == rep.seed
    assert back.accuracy.holdout_paths == tuple(tuple(h) for h in hold)
    assert to_json(back) == json.loads(json.dumps(info))


def test_model_files_are_written_atomically_as_before(tmp_path):
    import sympy as sp

    from magtact.metamodel import Metamodel
    from magtact.metamodel._io import load_model, model_to_dict, save_model
    from magtact.metamodel._symbols import H, t, theta

    m = Metamodel.from_expr("f_z", -2e-4 * t * (1 + 10 * H) * sp.cos(theta), "N/Pa")
    path = save_model(m, tmp_path / "sub" / "f_z.json")
    assert path == tmp_path / "sub" / "f_z.json"
    assert path.read_text() == json.dumps(model_to_dict(m), indent=2) + "\n"
    assert [p.name for p in path.parent.iterdir()] == ["f_z.json"]  # no temporary left
    assert load_model(path).name == "f_z"


def test_captions_are_written_atomically_as_before(tmp_path, monkeypatch):
    from magtact.report import _publication

    monkeypatch.setattr(_publication.PublicationFile, "from_json", staticmethod(lambda d: None))
    for name in ("fig_seed_spread", "fig_gamma_z_along_t"):
        monkeypatch.setattr(_publication, name, lambda records, stem: [])
    (tmp_path / "publication.json").write_text("{}", encoding="utf-8")
    assert _publication.publication_figures(tmp_path) == []
    data = (tmp_path / "captions.json").read_bytes()
    assert data == json.dumps(_publication.CAPTIONS, indent=1, ensure_ascii=False).encode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["captions.json", "publication.json"]


# ---- names taken from their declarations ---------------------------------------------------------
def test_the_chip_setting_fields_come_from_chip_setting():
    from dataclasses import fields

    from magtact._sensor import SETTING_FIELDS
    from magtact.parts import MLX_FIELDS, ChipSetting, chip_table
    from magtact.parts._chips import PERMITTED_PAIR, SettingError

    assert MLX_FIELDS == {"gain_sel": ("GAIN_SEL", 8), "res": ("RES", 4), "osr": ("OSR", 4),
                          "dig_filt": ("DIG_FILT", 8)}
    assert tuple(MLX_FIELDS) == tuple(f.name for f in fields(ChipSetting)) == SETTING_FIELDS
    assert PERMITTED_PAIR == ("osr", "dig_filt")
    assert ChipSetting(7, 0, 0, 2).words() == "GAIN_SEL 7, RES 0, OSR 0, DIG_FILT 2"
    with pytest.raises(SettingError) as info:
        chip_table("MLX90393").check(ChipSetting(0, 0, 1, 0))
    assert info.value.key == "dig_filt" and "OSR 1 with DIG_FILT 0 is not permitted" in str(
        info.value)


def test_the_doe_csv_columns_are_named_by_variable_and_unit(tmp_path):
    import xarray as xr

    from magtact.doe._dataset import CSV_COLUMNS, write_csv

    assert list(CSV_COLUMNS) == ["t", "theta_rad", "H_mm", "G_kPa", "u_r_mm", "u_z_mm",
                                 "B_r_T", "B_z_T", "F_r_N", "F_z_N"]
    dims3, dims4 = ("t", "theta", "H", "R_m"), ("t", "theta", "H", "G", "R_m")
    shape = (2, 1, 1, 1, 2)
    ds = xr.Dataset(
        {**{v: (dims3, np.ones(shape[:3] + shape[4:])) for v in ("u_r", "u_z", "B_r", "B_z")},
         **{v: (dims4, np.ones(shape)) for v in ("F_r", "F_z")}},
        coords={"t": [0.0, 1.0], "theta": [0.1], "H": [3e-3], "G": [3e4],
                "R_m": [1e-3, 2e-3]})
    header = write_csv(ds, tmp_path / "doe.csv").read_text().splitlines()[0]
    assert header == "t,theta_rad,H_mm,G_kPa,R_m_mm,u_r_mm,u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N"
