"""The report reads every file of a results folder through the bounded reader: a forged or
damaged file is named on one line with what is wrong, and the rest of the report renders."""

from __future__ import annotations

import html
import json
import os
import re
import resource
import signal
from contextlib import contextmanager

import pytest

from magtact._errors import MissingFileError
from magtact._files import MAX_BYTES, MAX_JSON_DEPTH, UnreadableFile, read_json_capped
from magtact.report import build_report
from magtact.report._card import card_problem
from magtact.report._explorer import FORMAT, MAX_LEVELS, explorer_problem

CARD = "<h2 id=\"card\">"


@contextmanager
def deadline(seconds: int):
    """Fail instead of hanging (a FIFO opened for reading blocks without a writer)."""
    def boom(*_):
        raise TimeoutError(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def explorer_doc(n_H: int = 3, n_G: int = 4) -> dict:
    """An explorer file of the shape the writer gives, on an n_H × n_G grid."""
    H = [2.0 + k for k in range(n_H)]
    G = [15.0 + 5 * j for j in range(n_G)]
    cell = {"F_z_max": 1e-4, "F_r_min": -4e-5, "Gamma_r_max": 1e-3, "Gamma_z_max": 2e-3,
            "saturates_in_region": False, "sat_F_z": None, "sigma_r_worst": 1e-8,
            "sigma_z_worst": 2e-8}
    return {"format": FORMAT, "study": "s", "H_mm": H, "G_kPa": G, "M_z_A_per_m": None,
            "fixed": {}, "magnet": None, "chip": "MLX90393",
            "constraints": {"F_r_c_N": -0.5, "F_z_c_N": 2.0},
            "chosen": {"H_mm": H[-1], "G_kPa": G[-1]}, "original": {"H_mm": H[0], "G_kPa": G[0]},
            "silicones": [], "grid": [[{**cell, "H_mm": h} for _ in G] for h in H],
            "pareto": [{"H_mm": 3.0, "G_kPa": 20.0, "Gamma_r_max": 1.0, "Gamma_z_max": 2.0,
                        "F_r_min": -1.0, "F_z_max": 3.0}]}


def card_doc() -> dict:
    return {"header": ["", "chosen", "original"],
            "rows": [["height H", "3.1 mm", "3 mm"], ["shear modulus G", "20 kPa", "22 kPa"]],
            "verdict": [{"requirement": "normal range", "met": True, "text": "7.2 N"}],
            "parts": [["magnet", "N35"]]}


def folder_with(tmp_path):
    """A results folder laid out by hand (no run.json): a whole card, explorer and table."""
    folder = tmp_path / "R"
    (folder / "optimise").mkdir(parents=True)
    (folder / "doe").mkdir()
    (folder / "optimise" / "card.json").write_text(json.dumps(card_doc()))
    (folder / "optimise" / "explorer.json").write_text(json.dumps(explorer_doc()))
    (folder / "doe" / "levels.csv").write_text("t,H_mm\n0.1,3\n0.2,4\n")
    return folder


def report(folder) -> str:
    with deadline(60):
        return build_report(folder).read_text(encoding="utf-8")


def left_out(text: str) -> dict[str, str]:
    """The report's lines of files left out: file → what is wrong."""
    m = re.search(r'<div class="missing" id="damaged">.*?<ul>(.*?)</ul>', text, re.S)
    if m is None:
        return {}
    return {html.unescape(k): html.unescape(v)
            for k, v in re.findall(r"<li><code>(.*?)</code>: (.*?)</li>", m.group(1))}


def test_whole_folder_renders_card_explorer_and_table_with_nothing_left_out(tmp_path):
    text = report(folder_with(tmp_path))
    assert left_out(text) == {}
    assert CARD in text and 'id="explorer"' in text and "levels" in text
    assert "Resolution and normal range over the base height" in text  # the explorer's figure


@pytest.mark.parametrize("plant, file, reason", [
    (lambda p: p.write_text('{"rows": ' * 5000 + "1" + "}" * 5000), "optimise/card.json",
     f"more than {MAX_JSON_DEPTH} deep"),
    (lambda p: p.write_text(json.dumps({**card_doc(), "header": 7})), "optimise/card.json",
     "header must be"),
    (lambda p: p.write_text(json.dumps({**card_doc(), "rows": [["a"]] * 3})),
     "optimise/card.json", "row 1 must be 3 texts"),
    (lambda p: os.mkfifo(p), "optimise/card.json", "FIFO"),
    (lambda p: p.symlink_to("/dev/urandom"), "optimise/card.json", "device"),
    (lambda p: p.symlink_to(p), "optimise/card.json", "symbolic link loop"),
    (lambda p: p.write_bytes(b"\xfe\xff{}"), "optimise/card.json", "not UTF-8"),
    (lambda p: os.truncate(p, 3 << 30) if p.exists() else (p.touch(), os.truncate(p, 3 << 30)),
     "optimise/card.json", "at most"),
])
def test_damaged_card_is_named_and_the_rest_renders(tmp_path, plant, file, reason):
    folder = folder_with(tmp_path)
    path = folder / file
    path.unlink()
    plant(path)
    text = report(folder)
    problems = left_out(text)
    assert file in problems and reason in problems[file], problems
    assert CARD not in text  # the card is left out, the rest is there
    assert 'id="explorer"' in text and "levels" in text and "Run summary" in text


@pytest.mark.parametrize("doc, reason", [
    ({**explorer_doc(), "G_kPa": [1.0] * 300_000}, f"1 to {MAX_LEVELS}"),
    ({**explorer_doc(), "grid": explorer_doc()["grid"][:2]}, "grid must be 3 rows of 4 cells"),
    ({**explorer_doc(), "chosen": {"H_mm": "3"}}, "chosen must hold"),
    ({**explorer_doc(), "pareto": [{"H_mm": 1}] * 3}, "a Pareto point lacks"),
    ({**explorer_doc(), "format": "magtact-explorer/0"}, "is not an explorer file"),
    ([explorer_doc()], "is not an explorer file"),
])
def test_forged_explorer_is_named_and_the_rest_renders(tmp_path, doc, reason):
    folder = folder_with(tmp_path)
    (folder / "optimise" / "explorer.json").write_text(json.dumps(doc))
    text = report(folder)
    problems = left_out(text)
    assert reason in problems.get("optimise/explorer.json", ""), problems
    assert 'id="explorer"' not in text and CARD in text


def test_large_figure_notes_and_table_are_left_out_without_reading_them(tmp_path):
    folder = folder_with(tmp_path)
    for name, size in (("huge.png", MAX_BYTES["figure"] + 1), ("notes.md", 900 << 20),
                       ("big.csv", 2 << 30)):
        with open(folder / "doe" / name, "wb") as fh:
            fh.truncate(size)
    (folder / "doe" / "fake.png").write_bytes(b"GIF89a" + b"\0" * 100)
    os.mkfifo(folder / "doe" / "pipe.txt")
    (folder / "doe" / "loop.md").symlink_to(folder / "doe" / "loop.md")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    text = report(folder)
    grown_MB = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    problems = left_out(text)
    assert "at most" in problems["doe/huge.png"] and "at most" in problems["doe/notes.md"]
    assert "at most" in problems["doe/big.csv"]
    assert problems["doe/fake.png"] == "is not a PNG image"
    assert "FIFO" in problems["doe/pipe.txt"] and "loop" in problems["doe/loop.md"]
    assert "levels" in text and CARD in text
    assert grown_MB < 200, grown_MB


def test_forged_stamp_captions_and_study_are_named(tmp_path):
    folder = folder_with(tmp_path)
    (folder / "doe" / "captions.json").write_text("[1, 2]")
    os.mkfifo(folder / "study.toml")
    (folder / "run.json").write_text("[" * 200 + "]" * 200)
    text = report(folder)
    problems = left_out(text)
    assert "captions" in problems["doe/captions.json"]
    assert "FIFO" in problems["study.toml"] and "deep" in problems["run.json"]
    assert "levels" in text


def test_report_on_a_regular_file_says_it_is_a_file(tmp_path):
    path = tmp_path / "results.txt"
    path.write_text("not a folder")
    with pytest.raises(MissingFileError, match="not a results folder: it is a file"):
        build_report(path)


def test_shape_checks_accept_the_writers_shapes_and_refuse_others():
    assert explorer_problem(explorer_doc(1, 1)) is None
    assert explorer_problem(explorer_doc(MAX_LEVELS, 2)) is None
    assert "1 to" in explorer_problem(explorer_doc(MAX_LEVELS + 1, 2))
    assert card_problem(card_doc()) is None
    assert "parts" in card_problem({**card_doc(), "parts": [["a", "b", "c"]]})


def test_json_depth_is_limited_whatever_the_recursion_limit(tmp_path):
    path = tmp_path / "d.json"
    path.write_text("[" * (MAX_JSON_DEPTH + 1) + "]" * (MAX_JSON_DEPTH + 1))
    with pytest.raises(UnreadableFile, match="deep"):
        read_json_capped(path, 1 << 20)
    path.write_text("[" * MAX_JSON_DEPTH + "]" * MAX_JSON_DEPTH)
    assert read_json_capped(path, 1 << 20) is not None


def test_report_command_names_each_file_left_out(tmp_path):
    from test_command_outputs import cli

    folder = folder_with(tmp_path)
    (folder / "optimise" / "card.json").unlink()
    os.mkfifo(folder / "optimise" / "card.json")
    with deadline(60):
        code, text = cli("report", folder)
    assert code == 0, text
    assert "left out optimise/card.json: is a FIFO (named pipe)" in text
    code, text = cli("report", folder / "doe" / "levels.csv")
    assert code == 2 and "not a results folder: it is a file" in text, text
    assert "Traceback" not in text
