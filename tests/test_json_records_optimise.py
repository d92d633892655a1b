"""geometry.json and maps.csv are written and read through their records
(``magtact.optimise._geometry.GeometryFile``, ``magtact.optimise._run.DesignRecord``)."""

import csv
import json
from types import SimpleNamespace

import numpy as np
import pytest

from magtact._records import check_declarations, from_json, keys, to_json
from magtact.optimise import (
    BoxOptimum,
    ChosenFile,
    DesignMaps,
    DesignSet,
    ForceConstraints,
    GeometricChoice,
    GeometryOptimisation,
    geometry_choice_json,
    write_geometry_outputs,
)
from magtact.optimise._design import HeightResult
from magtact.optimise._geometry import (
    GeometryChoiceRecord,
    GeometryFile,
    SetRecord,
    geometry_json,
)
from magtact.optimise._run import DesignRecord, write_maps


def _set(names, shift):
    values = {"H": np.array([3e-3, 4e-3]) + shift, "G": np.array([1.5e4, 2.25e4]),
              "M_z": np.array([1.1e6, 1.2e6])} | {k: np.array([2e-3, 2.5e-3]) for k in names}
    return DesignSet(values, np.array([10.0, 20.0]) + shift, np.array([30.0, 15.0]))


def _choice(names):
    design = SimpleNamespace(Gamma_r_max=np.float64(10.5), Gamma_z_max=29.0, F_r_min=-0.12,
                             F_z_max=3.9)
    return GeometricChoice({"H": 3e-3, "G": 1.5e4} | dict.fromkeys(names, 2e-3), design,
                           -0.1, -2.9)


def _optimisation(names=("R_m", "R")):
    return GeometryOptimisation(
        names, ("H", "G", "M_z", *names), ForceConstraints(-0.02, 1.0, "values"),
        _set(names, 1e-4), _set(names, 0.0), _choice(names), _choice(names), 0.004,
        {k: np.linspace(1.5e-3, 3.5e-3, 3) for k in names}, 480,
        dict.fromkeys(names, 0.25e-3))


def test_the_records_declare_known_units():
    for cls in (GeometryFile, GeometryChoiceRecord, SetRecord):
        check_declarations(cls)


def test_geometry_json_is_its_record_in_user_units(tmp_path):
    r = _optimisation()
    (path,) = write_geometry_outputs(r, tmp_path)
    text = path.read_text(encoding="utf-8")
    doc = json.loads(text)
    assert text == json.dumps(geometry_json(r), indent=1) + "\n"
    assert list(doc) == list(keys(GeometryFile))
    assert doc["variables"] == ["H", "G", "M_z", "R_m", "R"]
    # a geometric variable that is not a design variable is left out of a set's designs
    assert list(doc["pareto"][0]) == ["H_mm", "G_kPa", "M_z_A_per_m", "R_m_mm", "R_mm",
                                      "Gamma_r_max_N_per_T", "Gamma_z_max_N_per_T"]
    assert doc["pareto"][1]["H_mm"] == pytest.approx(4.0)
    assert doc["exact_front"][1]["H_mm"] == pytest.approx(4.1)
    assert doc["exact_front"][0]["G_kPa"] == pytest.approx(15.0)
    assert doc["exact_grid_mm"]["R_m"] == pytest.approx([1.5, 2.5, 3.5])
    assert doc["exact_resolution_mm"]["R"] == pytest.approx(0.25)
    assert doc["choice"]["design"].startswith("H = 3 mm")
    # read back, the record writes the same document again
    record = from_json(GeometryFile, doc, "geometry.json")
    assert record.pareto[0].R_m == pytest.approx(2e-3) and record.pareto[0].H_m is None
    assert to_json(record) == doc


def test_the_choice_of_geometry_json_reads_as_a_chosen_design(tmp_path):
    (path,) = write_geometry_outputs(_optimisation(), tmp_path)
    doc = json.loads(path.read_text(encoding="utf-8"))
    chosen = ChosenFile.from_json(geometry_choice_json(doc))
    assert chosen.Gamma_r_max == 10.5 and chosen.F_z_max == 3.9 and chosen.g_z == -2.9
    assert (chosen.F_r_c, chosen.F_z_c, chosen.constraints_source) == (-0.02, 1.0, "values")
    assert chosen.design == doc["choice"]["design"] and chosen.H is None
    # a damaged file: what it gives is read, what it lacks is None
    partial = doc | {"choice": {"F_r_min_N": -0.5, "g_r_N": "x"}}
    partial.pop("constraints")
    chosen = ChosenFile.from_json(geometry_choice_json(partial))
    assert chosen.F_r_min == -0.5 and chosen.g_r is None and chosen.Gamma_r_max is None
    assert not chosen.has_constraints
    for damaged in (None, [1], {}, doc | {"choice": [1]}):
        assert geometry_choice_json(damaged) is None


def test_maps_csv_is_written_through_its_row_record(tmp_path):
    def box(value, t=0.5, theta=0.2):
        return BoxOptimum(t, theta, value, t, theta, value, 0, 0.0, ())

    heights = (HeightResult(3e-3, box(-2e-6), box(1e-4), box(3e-4), box(9e-4)),
               HeightResult(4e-3, box(-3e-6, 0.0), box(2e-4), box(4e-4), box(8e-4)))
    maps = DesignMaps(np.array([3e-3, 4e-3]), np.array([1e4, 2e4]), heights)
    with open(write_maps(maps, tmp_path / "maps.csv"), newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert rows[0] == [k for k in keys(DesignRecord) if k != "M_z_A_per_m"] == [
        "H_mm", "G_kPa", "Gamma_r_max_N_per_T", "Gamma_z_max_N_per_T", "F_r_min_N",
        "F_z_max_N", "t_m", "theta_m_rad", "degenerate"]
    assert rows[1] == ["3", "10", "3", "9", "-0.02", "1", "0.5", "0.2", ""]
    assert rows[4][:6] == ["4", "20", "8", "16", "-0.06", "4"] and rows[4][-1] == "t_m = 0"
    np.testing.assert_allclose(maps.Gamma_z_max, [[9.0, 18.0], [8.0, 16.0]])
