"""The sensor problem chooses the magnet's size from the catalogue: each size's problem answered
from the bundled data that hold it, the size of the least force noise chosen, the best sensor of
every size beside it, and a study that sets its magnet keeps it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import magtact
from magtact.optimise import force_table, optimise_sensor, sweep
from magtact.parts import SILICONES, SIZES
from magtact.study import StudyError, study_from_dict


def test_the_built_in_study_chooses_from_every_catalogue_size():
    assert magtact.load("magone").design.magnet_sizes == tuple(SIZES)


def test_a_study_that_sets_its_magnet_keeps_it():
    assert study_from_dict({"magnet": {"size": "3x2"}}).design.magnet_sizes == ()
    assert study_from_dict({"magnet": {"R_m_mm": 1.5}}).design.magnet_sizes == ()
    both = study_from_dict({"magnet": {"size": "3x2"}, "design": {"magnet_sizes": ["3x2", "6x3"]}})
    assert both.design.magnet_sizes == ("3x2", "6x3")
    # another magnet setting (its grade) leaves the sizes to choose from
    assert study_from_dict({"magnet": {"grade": "N42"}}).design.magnet_sizes == tuple(SIZES)


def test_a_size_not_in_the_catalogue_is_refused_naming_the_sizes():
    with pytest.raises(StudyError, match=r"design\.magnet_sizes.*7x2.*3x1"):
        study_from_dict({"design": {"magnet_sizes": ["3x2", "7x2"]}})


def test_the_problem_at_a_size_has_that_magnet_and_no_other_to_choose():
    s = magtact.load("magone").sized("6x3")
    assert (s.magnet.size, s.magnet.R_m, s.magnet.H_m) == ("6x3", 3e-3, 3e-3)
    assert s.design.magnet_sizes == ()
    # everything else is the problem's
    assert s.requirements == magtact.load("magone").requirements


def test_the_chosen_size_has_the_least_noise_of_every_size(magone_design):
    r = magone_design
    opt = r.sensor_design
    assert opt.sizes == tuple(SIZES)
    done = {n: d for n, d in zip(opt.sizes, opt.per_size, strict=True) if d is not None}
    answered = [n for n, note in zip(opt.sizes, opt.size_notes, strict=True)
                if note != "no bundled data hold this size"]
    assert len(answered) >= 6 and len(done) >= 2, opt.size_notes
    assert opt.size == min(done, key=lambda n: done[n].sigma)
    # the chosen sensor, the result's problem and models are of that size
    z = SIZES[opt.size]
    assert (r.sensor.R_m, r.sensor.H_m) == (z.R_m, z.H_m)
    assert (r.study.magnet.R_m, r.study.magnet.H_m) == (z.R_m, z.H_m)
    # a size without a sensor says why
    for d, note in zip(opt.per_size, opt.size_notes, strict=True):
        if d is None:
            assert note
        else:
            assert note == "" or note.startswith("its fit is poor")
        if d is not None:
            lo, hi = SILICONES[d.silicone].G_range
            assert lo * (1 - 1e-12) <= d.G <= hi * (1 + 1e-12)
    # the original design stays the study's own magnet
    assert math.isclose(r.original.sensor.R_m, magtact.load("magone").magnet.R_m)


def test_each_sizes_best_is_its_own_problems_answer(magone_design):
    """A size's row is the reduction's answer of the problem at that size, solved here on its
    own through the public API (its bundled models, the same force table); the force table
    gives the full sweep's answer."""
    from magtact._front import SIZE_HEIGHTS

    opt = magone_design.sensor_design
    study = magtact.load("magone")
    name = next(n for n, d in zip(opt.sizes, opt.per_size, strict=True)
                if d is not None and n != opt.size)
    st = study.sized(name)
    models = magtact.models_for(st)[0]
    own = optimise_sensor(models, st, force_table(models, st, SIZE_HEIGHTS), nsga2=False).choice
    row = opt.per_size[opt.sizes.index(name)]
    assert (row.grade, row.silicone, row.standoff) == (own.grade, own.silicone, own.standoff)
    np.testing.assert_allclose([row.H, row.G, row.sigma_r, row.sigma_z],
                               [own.H, own.G, own.sigma_r, own.sigma_z], rtol=1e-12)
    full = optimise_sensor(models, st, sweep(models, st), nsga2=False).choice
    np.testing.assert_allclose([full.H, full.sigma_r, full.sigma_z],
                               [own.H, own.sigma_r, own.sigma_z], rtol=1e-3)


def test_the_card_lists_the_best_sensor_of_each_size(magone_design, magone_budgets):
    card = magtact.card(magone_design, magone_budgets)
    rows = card["magnet_sizes"]
    opt = magone_design.sensor_design
    assert len(rows) == len(opt.sizes)
    chosen = [v for _, v in rows if v.endswith("the chosen size")]
    assert len(chosen) == 1
    z = SIZES[opt.size]
    label = f"⌀{2 * z.R_m * 1e3:.3g} × {z.H_m * 1e3:.3g} mm magnet"
    assert dict(rows)[f"nominal best, {label}"] == chosen[0]
    for (_, text), d, note in zip(rows, opt.per_size, opt.size_notes, strict=True):
        assert text == note if d is None else note in text
    assert "nominal best, ⌀" in str(card)


def test_the_report_shows_the_parts_compared(magone_design, magone_budgets, tmp_path):
    import html
    import re

    from magtact._outputs import write_results_into
    from magtact.report._html import build_report

    folder = tmp_path / "res"
    (folder / "optimise").mkdir(parents=True)
    write_results_into(magone_design, folder / "optimise", figures=False, explorer=False,
                       budgets=magone_budgets)
    text = build_report(folder).read_text(encoding="utf-8")
    card = magtact.card(magone_design, magone_budgets)
    for key in ("magnet_sizes", "silicones"):
        table = re.search(rf'<table class="choices" id="{key}">(.*?)</table>', text, re.S)
        assert table is not None, key
        rows = re.findall(r"<tr><th[^>]*>(.*?)</th><td[^>]*>(.*?)</td></tr>", table.group(1))
        assert [html.unescape(k) for k, _ in rows] == [k for k, _ in card[key]]
