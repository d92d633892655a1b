"""The seed study's files, figures and report section, from records with known values."""

import json

import numpy as np
import pytest

from magtact.publication import (
    Conditioning,
    PublicationFile,
    Reproduction,
    SeedRecord,
    Sweep,
    comparison,
    spread,
)
from magtact.report import build_report, publication_figures
from magtact.study import load_study


def _record(definition: str, seed: int, k: float) -> dict:
    H = np.linspace(3, 7, 11)
    t = np.linspace(0, 1, 5)
    design = {"H_mm": 3.0, "G_kPa": 29.4, "Gamma_r_max": 10 * k, "Gamma_z_max": 40 * k,
              "F_r_min": -0.3, "F_z_max": 6.0, "t_m": 1.0, "theta_m": 0.4}
    return {
        "definition": definition, "seed": seed, "ok": True, "message": "", "fit_time_s": 1.0,
        "accuracy": {"f_r": {"test_max_err_over_range": 0.01, "test_r2": 0.99},
                     "f_z": {"test_max_err_over_range": 0.002, "test_r2": 0.999}},
        "original": design, "fabricated": design | {"H_mm": 4.1, "Gamma_r_max": 5 * k},
        "chosen": design | {"H_mm": 3.0 + seed, "G_kPa": 20.0, "active": ["F_z"]},
        "chosen_reference": design, "branches": 1 + seed, "branches_reference": 1,
        "gamma_z_curve": {"t": t.tolist(), "Gamma_z": (k * (1 + t)).tolist(), "H_mm": 7.0,
                          "theta_rad": 0.42},
        "gamma_z_trend": "increasing",
        "sweep": {"H_mm": H.tolist(), "gamma_r_max": (1e-3 / H).tolist(),
                  "gamma_z_max": (4e-3 / H).tolist(), "f_r_min": (-1e-5 / H).tolist(),
                  "f_z_max": (2e-4 / H).tolist(), "t_m": [1.0] * 11},
        "conditioning": {"H_mm": H.tolist(), "tol": 0.01, "t_m": [0.9] * 11,
                         "t_tol": [0.8] * 11, "dF_z_rel": [0.1] * 11},
    }


@pytest.fixture(scope="module")
def records():
    return [_record("jacobian", 0, 1.0), _record("jacobian", 1, 1.0),
            _record("published", 0, 0.1), _record("published", 1, 0.9)]


def test_spread_and_table(records):
    s = spread(records)
    assert s["jacobian"]["Gamma_r_orig"]["max_over_min"] == pytest.approx(1.0)
    assert s["published"]["Gamma_r_orig"]["max_over_min"] == pytest.approx(9.0)
    assert s["published"]["H_star"]["min"] == 3.0 and s["published"]["H_star"]["max"] == 4.0
    rows = {r["quantity"]: r for r in comparison(records)}
    ratio = rows["original design: Γ_z,max / Γ_r,max"]
    assert ratio["scale_free"] and ratio["jacobian/study"]["median"] == pytest.approx(4.0)
    assert ratio["jacobian/printed"]["median"] == pytest.approx(4.0)  # scale-free
    g = rows["original design: Γ_r,max"]
    assert not g["scale_free"]
    assert g["jacobian/printed"]["median"] == pytest.approx(0.1 * g["jacobian/study"]["median"])
    assert "infeasible" in rows["optimum, default constraints: H*"]["jacobian/printed"]["text"]
    assert g["publication"] == 0.81


def test_files_figures_and_report_section(records, tmp_path):
    study = load_study("magone")
    rep = Reproduction(study, (0, 1), records, spread(records), comparison(records), 12.0, 2)
    folder = tmp_path / "publication"
    files = rep.write(folder)
    assert {p.name for p in files} == {"publication.json", "seeds.csv", "spread.csv",
                                       "comparison.csv"}
    doc = json.loads((folder / "publication.json").read_text())
    assert doc["G_range_Pa"] == list(study.design.G)
    figs = publication_figures(folder)
    stems = {p.stem for p in figs if p.suffix == ".png"}
    assert stems == {"seed_spread", "gamma_z_along_t", "gamma_over_H", "resolution_range",
                     "conditioning"}
    html = build_report(tmp_path).read_text()
    section = html[html.index('id="publication"'):html.index('id="evidence"')]
    assert "scale-free" in section and "publication (G as printed)" in section
    assert section.count("<img") == 5
    assert "resolution–range trade-off" in section
    assert "original design: Γ_z,max / Γ_r,max" in section
    # the method is the report's appendix, linked from its header, with the sensor figure
    method = html[html.index('<h2 id="method">'):]
    assert '<a href="#method">' in html[:html.index('id="summary"')]
    assert "6. Sensitivity" in method and "data:image/svg+xml;base64," in method


def test_resolution_range_lines_pass_through_the_origin(records, tmp_path, monkeypatch):
    """Each H's line has slope γ(H) / f(H) and passes through the origin."""
    from magtact.report import _fig_publication as fp

    seen = {}
    monkeypatch.setattr(fp, "save", lambda fig, path: seen.setdefault("fig", fig) and [])
    sweep = records[0]["sweep"]
    fp.fig_resolution_range(Sweep.from_json(sweep), (10e3, 50e3), tmp_path / "rr", n_lines=3)
    ax = seen["fig"].axes[0]
    assert ax.get_xlabel() == r"$F_{z,\max}$ [N]"
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    dotted = [ln for ln in ax.get_lines() if ln.get_linestyle() == ":"]
    assert len(solid) == len(dotted) == 3
    for ln, i in zip(dotted, (0, 5, 10), strict=True):
        x, y = ln.get_data()
        assert x[0] == 0 and y[0] == 0
        np.testing.assert_allclose(y[1:] / x[1:],
                                   sweep["gamma_z_max"][i] / sweep["f_z_max"][i], rtol=1e-12)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["H = 3 mm", "H = 5 mm", "H = 7 mm"]


def test_figures_draw_records_whose_nan_were_written_as_null(records, tmp_path, monkeypatch):
    """JSON writes NaN as null: an infeasible height is a gap in the lines, not an error."""
    from magtact.report import _fig_publication as fp

    r = json.loads(json.dumps(records[0]))
    r["conditioning"]["dF_z_rel"][3] = None
    r["conditioning"]["t_tol"][4] = None
    r["sweep"]["gamma_z_max"][2] = None
    seen = []
    monkeypatch.setattr(fp, "save", lambda fig, path: seen.append(fig) or [])
    fp.fig_conditioning(Conditioning.from_json(r["conditioning"]), tmp_path / "c")
    fp.fig_gamma_over_H([SeedRecord.from_json(r)], 29.4e3, tmp_path / "g")
    fp.fig_resolution_range(Sweep.from_json(r["sweep"]), (10e3, 50e3), tmp_path / "rr",
                            n_lines=11)
    drop = seen[0].axes[1].lines[0].get_ydata()
    assert np.isnan(drop[3]) and np.allclose(np.delete(drop, 3), 10.0)
    assert np.isnan(seen[0].axes[0].lines[1].get_ydata()[4])
    gz = seen[1].axes[1].lines[0].get_ydata()
    assert np.isnan(gz[2]) and gz[1] == pytest.approx(29.4e3 * 4e-3 / 3.4)


def test_the_file_reads_back_through_its_types(records, tmp_path):
    """``publication.json`` reads back in SI through :class:`PublicationFile`."""
    study = load_study("magone")
    Reproduction(study, (0, 1), records, spread(records), comparison(records), 12.0,
                 2).write(tmp_path)
    doc = PublicationFile.read(tmp_path / "publication.json")
    assert doc.study == study.name and doc.seeds == (0, 1) and doc.workers == 2
    assert doc.G_range == tuple(study.design.G) and doc.wall_time_s == 12.0
    assert len(doc.records) == 4 and all(r.ok for r in doc.records)
    own = doc.reference_record()
    assert own.definition == "jacobian" and own.seed == 0
    assert own.original_G == pytest.approx(29.4e3)
    assert own.chosen.H == pytest.approx(3e-3)
    np.testing.assert_allclose(own.sweep.H, np.linspace(3e-3, 7e-3, 11))
    assert own.conditioning.tol == 0.01 and own.gamma_z_curve.H == pytest.approx(7e-3)
    assert doc.columns == ["jacobian/study", "jacobian/printed", "published/study",
                           "published/printed"]
    row = doc.comparison[0]
    assert row.cell_text("jacobian/study") == "10"
    assert {(f.definition, f.figure) for f in doc.spread} >= {("jacobian", "Gamma_r_orig")}


@pytest.mark.parametrize("forged", [
    {}, {"records": "x", "spread": [], "comparison": {}, "seeds": "abc", "gp": 3},
    {"records": [None, {"ok": True, "sweep": {"H_mm": [1, "x"], "gamma_r_max": [1]},
                        "original": {"G_kPa": "a"}}],
     "comparison": [{"quantity": 1, "a/b": {"median": "x"}}],
     "spread": {"d": {"f": {"min": "x", "n": True}}}},
])
def test_a_forged_file_reads_without_error(forged):
    doc = PublicationFile.from_json(forged)
    assert doc is not None
    for r in doc.comparison:
        assert r.cell_text("a/b") == "—"
    assert PublicationFile.from_json([1]) is None


def test_section_of_a_partial_file(tmp_path):
    """A file with only some tables gives the section without an error."""
    from magtact.report._publication import publication_section

    (tmp_path / "publication.json").write_text(json.dumps({"spread": {}, "records": []}))
    html = publication_section(tmp_path, None)
    assert "0 GP seeds" in html and "— s, ? workers" in html
