"""The sensor problem chooses the silicone: G within the range of the chosen silicone's cited
figures, the best sensor of each silicone beside it, and a study that names one silicone
fixes its range."""

from __future__ import annotations

import numpy as np
import pytest

import magtact
from magtact.metamodel import prefitted_dir
from magtact.optimise import optimise_sensor, sweep
from magtact.parts import SILICONES
from magtact.study import StudyError, study_from_dict

#: Specifications (requirements and design ranges, as in a study file) the built-in magnet,
#: body and chip answer with different silicones and G.
SPECS = [
    {},
    {"requirements": {"F_z_N": 3.0, "F_r_N": 0.5}, "design": {"G_kPa": [10.0, 120.0]}},
    {"requirements": {"F_z_N": 2.0, "F_r_N": 0.1}},
    {"requirements": {"F_z_N": 8.0, "F_r_N": 0.3}, "design": {"G_kPa": [10.0, 120.0]}},
    {"requirements": {"F_z_N": 1.0, "F_r_N": 0.05}, "design": {"G_kPa": [10.0, 250.0]}},
]


@pytest.fixture(scope="module")
def models():
    return magtact.models_for(magtact.load("magone"), models=prefitted_dir())[0]


def _holds(name: str, G: float) -> bool:
    lo, hi = SILICONES[name].G_range
    return lo * (1 - 1e-12) <= G <= hi * (1 + 1e-12)


@pytest.mark.parametrize("spec", SPECS)
def test_the_named_silicone_holds_the_chosen_G(models, spec):
    study = magtact.load("magone", **spec)
    opt = optimise_sensor(models, study, sweep(models, study), nsga2=False)
    c = opt.choice
    assert _holds(c.silicone, c.G), (c.silicone, c.G)
    lo, hi = study.design.G
    assert lo <= c.G <= hi
    # every silicone's best lies in its own range, and none is better than the choice
    assert opt.silicones and len(opt.per_silicone) == len(opt.silicones)
    for name, d in zip(opt.silicones, opt.per_silicone, strict=True):
        if d is not None:
            assert d.silicone == name and _holds(name, d.G)
            if c.feasible:
                assert c.sigma <= d.sigma * (1 + 1e-9)
    # the sensor built from the choice is cast from that silicone
    assert c.sensor(study).silicone == c.silicone


def test_the_silicones_outside_the_design_range_are_not_offered(models):
    study = magtact.load("magone")
    opt = optimise_sensor(models, study, sweep(models, study), nsga2=False)
    lo, hi = study.design.G
    offered = [n for n in study.design.silicones
               if SILICONES[n].G_range[0] <= hi and SILICONES[n].G_range[1] >= lo]
    assert list(opt.silicones) == offered
    assert "Dragon Skin 20" not in opt.silicones  # 113 kPa, above the 10-50 kPa range


def test_a_study_that_names_its_silicone_chooses_it_alone():
    s = study_from_dict({"material": {"silicone": "Ecoflex 00-50"}})
    assert s.design.silicones == ("Ecoflex 00-50",)
    assert study_from_dict({"material": {"silicone": "none"}}).design.silicones == ()
    both = study_from_dict({"material": {"silicone": "Ecoflex 00-50"},
                            "design": {"silicones": ["Ecoflex 00-30", "Ecoflex 00-50"]}})
    assert both.design.silicones == ("Ecoflex 00-30", "Ecoflex 00-50")


def test_no_silicone_in_the_design_range_is_refused_naming_the_ranges():
    with pytest.raises(StudyError, match=r"design\.silicones.*Dragon Skin 10 50\.56 kPa.*"
                                         r"widen design\.G_kPa"):
        study_from_dict({"material": {"silicone": "Dragon Skin 10"}})


def test_without_silicones_G_is_free_over_the_design_range(models):
    study = magtact.load("magone", design={"silicones": []})
    opt = optimise_sensor(models, study, sweep(models, study), nsga2=False)
    assert opt.silicones == (study.material.silicone,)
    lo, hi = study.design.G
    assert lo <= opt.choice.G <= hi


def test_the_card_names_the_silicone_with_its_range_and_each_silicones_best(magone_design,
                                                                           magone_budgets):
    card = magtact.card(magone_design, magone_budgets)
    c = magone_design.sensor_design.choice
    lo, hi = SILICONES[c.silicone].G_range
    parts = dict(card["parts"])
    assert parts["silicone"].startswith(f"{c.silicone} (G {c.G / 1e3:.3g} kPa; its range ")
    assert f"{lo / 1e3:.3g}–{hi / 1e3:.3g} kPa" in parts["silicone"]
    rows = dict(card["silicones"])
    assert len(rows) == len(magone_design.sensor_design.silicones)
    chosen = [v for v in rows.values() if v.endswith("the chosen silicone")]
    assert len(chosen) == 1 and f"G {c.G / 1e3:.3g} kPa" in chosen[0]
    for name, d in zip(magone_design.sensor_design.silicones,
                       magone_design.sensor_design.per_silicone, strict=True):
        text = next(v for k, v in rows.items() if k.startswith(f"best with {name} ("))
        assert (d is None) == (text == "no sensor meets the problem")
    assert "best with" in str(card)
    assert np.isfinite(c.sigma)


def test_a_complete_study_file_written_before_the_silicones_leaves_G_free():
    import tomllib

    data = tomllib.loads(magtact.load("magone").to_toml())
    data["base"] = "none"
    del data["design"]["silicones"]
    assert study_from_dict(data).design.silicones == ()
    data["design"]["grades"] = "N42"  # other keys stay checked
    with pytest.raises(StudyError, match=r"design\.grades"):
        study_from_dict(data)
