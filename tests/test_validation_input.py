"""Malformed validation data: every message names the file, the line and the column."""

from __future__ import annotations

import pytest

from magtact.validation import DataError, read_experiment

HEADER = "u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N"
GOOD = [f"{-0.5 * k},0.001,0.04,0.01,-0.5" for k in range(5)]


def write(tmp_path, name, lines):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def good(tmp_path, name="ok.csv", repeat=2):
    return write(tmp_path, name, ["# theta_rad = 0.3", f"# repeat = {repeat}", HEADER, *GOOD])


def check(paths, *fragments):
    with pytest.raises(DataError) as info:
        read_experiment(paths)
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    return message


def test_missing_column(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", "u_z_mm,B_r_T,B_z_T,F_r_N",
                                      *[row.rsplit(",", 1)[0] for row in GOOD]])
    check([good(tmp_path), bad], "bad.csv", "line 2", "missing column 'F_z_N'")


def test_missing_displacement_column(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", "d_mm,B_r_T,B_z_T,F_r_N,F_z_N", *GOOD])
    check(bad, "bad.csv", "line 2", "'u_z_mm'")


def test_non_numeric_cell(tmp_path):
    rows = list(GOOD)
    rows[2] = "-1.0,0.001,abc,0.01,-0.5"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 5", "column 'B_z_T'", "'abc'")


def test_nan_cell(tmp_path):
    rows = list(GOOD)
    rows[3] = "-1.5,0.001,0.04,nan,-0.5"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 6", "column 'F_r_N'", "not a finite number")


def test_empty_cell(tmp_path):
    rows = list(GOOD)
    rows[1] = "-0.5,,0.04,0.01,-0.5"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 4", "column 'B_r_T'", "empty cell")


def test_single_repeat(tmp_path):
    check(good(tmp_path, "only.csv"), "only.csv", "column 'repeat'", "at least 2 repeats")


def test_displacement_not_monotonic(tmp_path):
    rows = list(GOOD)
    rows[3] = "-0.7,0.001,0.04,0.01,-0.5"  # −0, −0.5, −1.0, −0.7, −2.0
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 6", "column 'u_z_mm'", "not strictly monotonic")


def test_repeated_displacement(tmp_path):
    rows = list(GOOD)
    rows[2] = rows[1]
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 5", "column 'u_z_mm'")


def test_mixed_shear_angles_across_files(tmp_path):
    other = write(tmp_path, "other.csv", ["# theta_rad = 0.2", "# repeat = 3", HEADER, *GOOD])
    check([good(tmp_path), other], "mixed shear angles", "other.csv, line 1 (metadata "
          "'theta_rad')", "ok.csv, line 1")


def test_mixed_shear_angles_within_a_column(tmp_path):
    rows = [f"{row},{0.3 if k < 3 else 0.31}" for k, row in enumerate(GOOD)]
    bad = write(tmp_path, "bad.csv", [HEADER + ",theta_rad", *rows])
    check(bad, "bad.csv", "line 5", "column 'theta_rad'", "one file holds one shear angle")


def test_shear_angle_column_disagrees_with_metadata(tmp_path):
    rows = [f"{row},0.25" for row in GOOD]
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER + ",theta_rad", *rows])
    check(bad, "bad.csv", "line 3", "column 'theta_rad'", "line 1 (metadata 'theta_rad')")


def test_no_shear_angle(tmp_path):
    bad = write(tmp_path, "bad.csv", [HEADER, *GOOD])
    check(bad, "bad.csv", "'theta_rad'", "no shear angle")


def test_bad_metadata_value(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# sensor = A", "# theta_deg = twenty", HEADER, *GOOD])
    check(bad, "bad.csv", "line 2", "metadata 'theta_deg'", "'twenty'")


def test_metadata_line_without_key(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# just a remark", HEADER, *GOOD])
    check(bad, "bad.csv", "line 1", "key = value")


def test_empty_file(tmp_path):
    bad = write(tmp_path, "empty.csv", [""])
    check([good(tmp_path), bad], "empty.csv", "empty file")


def test_header_without_rows(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER])
    check([good(tmp_path), bad], "bad.csv", "line 2", "no data rows")


def test_ragged_row(tmp_path):
    rows = list(GOOD)
    rows[4] = "-2.0,0.001,0.04,0.01"
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *rows])
    check([good(tmp_path), bad], "bad.csv", "line 7", "4 cells", "5 columns")


def test_duplicate_column(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER + ",B_z_T",
                                      *[r + ",0.04" for r in GOOD]])
    check(bad, "bad.csv", "line 2", "column 'B_z_T'", "appears twice")


def test_displacement_given_in_two_units(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER + ",u_z_m",
                                      *[r + ",0" for r in GOOD]])
    check(bad, "bad.csv", "line 2", "'u_z_mm', 'u_z_m'")


def test_too_few_samples(tmp_path):
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", HEADER, *GOOD[:3]])
    check([good(tmp_path), bad], "bad.csv", "line 3", "3 samples")


def test_empty_label_in_long_table(tmp_path):
    rows = [f"S1,{'' if k == 2 else 1},{row}" for k, row in enumerate(GOOD)]
    bad = write(tmp_path, "bad.csv", ["# theta_rad = 0.3", "sensor,repeat," + HEADER, *rows])
    check(bad, "bad.csv", "line 5", "column 'repeat'", "empty label")


def test_missing_file_is_reported(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.csv"):
        read_experiment(tmp_path / "nothere.csv")


def test_tests_sharing_no_displacement_range(tmp_path):
    from magtact.validation import PathModel, validate

    shifted = [f"{-0.5 * k - 3.0},0.001,0.04,0.01,-0.5" for k in range(5)]
    far = write(tmp_path, "far.csv", ["# theta_rad = 0.3", "# repeat = 9", HEADER, *shifted])
    exp = read_experiment([good(tmp_path), far])
    model = PathModel(lambda u: {r: 1.0 + 0 * u for r in ("B_r", "B_z", "F_r", "F_z")}, 0.3)
    with pytest.raises(DataError, match=r"share no displacement range.*far\.csv, line 4"):
        validate(exp, model)
