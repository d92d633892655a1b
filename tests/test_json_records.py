"""The records that read the time entry of ``budget.json`` (``magtact.viscoelastic.TimeRecord``)
and the firmware frontier of ``calibration.json`` (``magtact.calibration.FrontierPoint``) back:
what the writer wrote, in SI, and nothing from a document of another shape."""

from __future__ import annotations

import numpy as np
import pytest

from magtact.calibration import FrontierPoint
from magtact.viscoelastic import SiliconeSweep, TimePress, TimeRecord, unknown_time_json


def _press(theta=0.0):
    return {"theta_rad": theta,
            "loop": {"F_true_mN": [[0.0, 0.0], [-1.0, 20.0], [0.0, 0.0]],
                     "F_read_mN": [[0.0, 0.0], [-0.9, 19.0], [0.1, 1.0]]},
            "creep": {},
            "rate_sweep": {"press_time_s": [0.1, 1.0], "hysteresis_mN": [[0.1, 2.0], [0.2, 3.0]],
                           "peak_mN": [[1.0, 20.0], [1.0, 20.0]]}}


def _entry():
    sweep = SiliconeSweep("cited", np.array([0.1, 1.0, 10.0]), np.array([0.01, 0.05, 0.02]))
    return {"source": "given", "press_time_s": 0.5, "hysteresis_mN": [0.2, 3.0],
            "presses": [_press(0.3), _press(0.0), {"theta_rad": 0.1}],
            "measured": {"hysteresis_pct": 12.0},
            "silicones": {"Ecoflex 00-30": sweep.to_json(), "broken": {"press_time_s": [1.0]}}}


def test_the_time_record_reads_the_entry_in_si():
    t = TimeRecord.from_json(_entry())
    assert t.source == "given" and t.press_time == 0.5
    np.testing.assert_allclose(t.hysteresis, [0.2e-3, 3e-3])
    assert t.measured_hysteresis == pytest.approx(0.12)
    assert [p.theta for p in t.presses] == [0.3, 0.0]  # the press without a loop is left out
    n = t.normal_press
    assert isinstance(n, TimePress) and n.theta == 0.0
    np.testing.assert_allclose(n.F_read[:, 1], [0.0, 19e-3, 1e-3])
    np.testing.assert_allclose(100 * n.gap[:, 1] / n.peak[:, 1], [10.0, 15.0])
    assert list(t.silicones) == ["Ecoflex 00-30"]
    s = t.silicones["Ecoflex 00-30"]
    assert s.source == "cited"
    np.testing.assert_allclose(s.hysteresis, [0.01, 0.05, 0.02])
    np.testing.assert_allclose(s.press_times, [0.1, 1.0, 10.0])


def test_an_unknown_relaxation_reads_without_presses():
    t = TimeRecord.from_json(unknown_time_json("no data", 0.5, 10.0, "long", np.inf, np.nan))
    assert t.presses == () and t.normal_press is None and t.hysteresis is None
    assert t.press_time == 0.5 and t.measured_hysteresis > 0


@pytest.mark.parametrize("doc", [None, {}, [], "time", 3.0])
def test_no_time_record_from_a_document_of_another_shape(doc):
    assert TimeRecord.from_json(doc) is None


@pytest.mark.parametrize("bad", [
    {"loop": {"F_true_mN": [[0.0, 1.0]], "F_read_mN": [[0.0]]}},
    {"loop": {"F_true_mN": "x", "F_read_mN": [[0.0, 1.0]]}},
    {"rate_sweep": {"press_time_s": [1.0, 2.0], "hysteresis_mN": [[0.1, 2.0]],
                    "peak_mN": [[1.0, 20.0]]}},
    {"theta_rad": "0"},
])
def test_a_press_of_another_shape_reads_as_none(bad):
    assert TimePress.from_json(_press() | bad) is None


def test_a_frontier_point_round_trips():
    p = FrontierPoint("poly", 6, "log", 224, 40, 1.5e-3, 2.5e-3, 0.8, True)
    q = FrontierPoint.from_json(p.to_json())
    assert (q.kind, q.degree, q.transform, q.bytes, q.multiplies, q.on_frontier) == \
        ("poly", 6, "log", 224, 40, True)
    assert (q.err_r, q.err_z, q.error_over_sigma) == pytest.approx((1.5e-3, 2.5e-3, 0.8),
                                                                   rel=1e-12)
    doc = p.to_json()
    assert list(doc) == ["kind", "degree_or_n", "transform", "bytes", "multiplies",
                         "max_error_F_r_mN", "max_error_F_z_mN", "error_over_sigma",
                         "on_frontier"]
    for bad in (None, [], doc | {"bytes": "224"}, doc | {"bytes": True},
                doc | {"error_over_sigma": None}):
        assert FrontierPoint.from_json(bad) is None
    assert FrontierPoint.from_json(doc | {"on_frontier": 1}).on_frontier is False


def test_an_answer_is_written_from_its_record_and_read_back(magone_design):
    import json

    from magtact._records import RecordError, from_json, keys, to_json
    from magtact.designer import answer_json
    from magtact.designer._answer import AnswerRecord

    for a in (magone_design.chosen, magone_design.original):
        doc = json.loads(json.dumps(answer_json(a)))
        assert set(doc) <= set(keys(AnswerRecord))
        back = from_json(AnswerRecord, doc, "card.json")
        assert back.H == pytest.approx(a.H, rel=1e-15) and back.chip == a.chip.name
        assert json.dumps(to_json(back)) == json.dumps(doc)
    assert back.parts.magnet_grade == a.parts.grade
    with pytest.raises(RecordError, match="card.json: the document: missing key 'standoff_mm'"):
        from_json(AnswerRecord, {k: v for k, v in doc.items() if k != "standoff_mm"},
                  "card.json")


def test_a_time_entry_is_written_from_its_record_and_reads_back_strictly(models):
    import json
    from dataclasses import replace

    from magtact._records import from_json, to_json
    from magtact.study import load_study
    from magtact.viscoelastic import relaxation_of, time_json, time_response
    from magtact.viscoelastic._design import TimeEntry

    study = load_study("magone")
    study = replace(study, material=replace(study.material, relaxation_g1=0.3,
                                            relaxation_tau1=0.8))
    prony, _ = relaxation_of(study, 26e3)
    r = time_response(models, study, 3e-3, 26e3, 0.9, 0.4, prony)
    sweep = SiliconeSweep.of(r.sweeps[0.0], "given")
    doc = json.loads(json.dumps(time_json(r, source="given", silicones={"x": sweep})))
    entry = from_json(TimeEntry, doc, "budget.json")
    assert json.dumps(to_json(entry)) == json.dumps(doc)
    assert entry.measured.hysteresis == r.measured.hysteresis and entry.t_m == 0.9
    t = TimeRecord.from_json(doc)
    assert [p.theta for p in t.presses] == [0.0, 0.4]
    loop = r.loops[0.0]
    k = slice(None, None, -(-len(loop.time) // 201))  # thinned to about 200 samples
    np.testing.assert_allclose(t.normal_press.F_read, loop.F_read[k], rtol=1e-12)
    np.testing.assert_allclose(t.silicones["x"].hysteresis, sweep.hysteresis, rtol=1e-12)


def test_a_run_manifest_round_trips_and_a_forged_one_reads_field_by_field():
    import json

    from magtact._runfolder import RunManifest, StageRecord

    m = RunManifest("id", "study", "magtact run", "now", stages=[
        StageRecord("doe", "DOE", "ok", 1.5, "done", ["a note"])], doe_source="bundled",
        wall_time_s=2.0, finished="later")
    doc = json.loads(json.dumps(m.to_json()))
    assert "interrupted" not in doc and RunManifest.from_json(doc) == m
    forged = {"stages": [{"key": "doe", "status": 3, "wall_time_s": "x", "notes": 5}, 1, None],
              "versions": 3, "run_id": 7, "wall_time_s": "long", "study": "S", "refit": "yes"}
    r = RunManifest.from_json(forged)
    assert (r.run_id, r.study, r.command, r.versions, r.refit, r.wall_time_s) == \
        (None, "S", "", {}, False, None)
    assert r.stages == [StageRecord("doe", "", "unknown", None, "", [])]
    assert RunManifest.from_json({"command": "x"}).study == "unknown study"
    assert RunManifest.from_json({}) is None and RunManifest.from_json([1]) is None


def test_a_seed_record_is_written_from_its_record_and_read_back():
    import json
    import math

    from magtact._records import from_json, keys
    from magtact.publication._file import ChosenRow, DesignRow, SeedRecord

    design = DesignRow(3e-3, 29.4e3, 10.0, 40.0, -0.3, 6.0, 1.0, 0.4)
    rec = SeedRecord("jacobian", 2, True, "", 1.5, None, design, design,
                     chosen=ChosenRow(infeasible="no design"), branches=0,
                     chosen_reference=ChosenRow(*vars(design).values(), active=("F_z",),
                                                F_r_c=-0.25, F_z_c=5.0))
    doc = json.loads(json.dumps(rec.to_json()))
    assert doc["chosen"] == {"infeasible": "no design"} and doc["original"]["H_mm"] == 3.0
    assert doc["chosen_reference"]["F_z_c_N"] == 5.0 and "sweep" not in doc
    assert from_json(SeedRecord, doc) == rec
    back = SeedRecord.from_json(doc)
    assert math.isnan(back.chosen.H) and back.chosen_reference.active == ("F_z",)
    failed = SeedRecord("published", 1, False, "no model").to_json()
    assert list(failed) == list(keys(SeedRecord))[:4]
    assert math.isnan(SeedRecord.from_json(failed).original.G)  # a failed fit: no design
