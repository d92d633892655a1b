"""`magtact fit` and `magtact optimise` never use the bundled MagOne data for another study."""

import sys

import pytest

from magtact.cli import main

TALL = """
name = "tall"
[body]
H_g_mm = 6.0
"""


@pytest.mark.parametrize("command", [["fit", "--out", "OUT"], ["optimise", "--out", "OUT"],
                                     ["compare", "3,29.4", "4,29.4"]])  # study: last
def test_other_geometry_is_refused_with_what_to_run(tmp_path, capsys, monkeypatch, command):
    study = tmp_path / "tall.toml"
    study.write_text(TALL)
    args = [a.replace("OUT", str(tmp_path / "out")) for a in command]
    argv = ["magtact", *args, str(study)] if command[0] == "compare" else \
        ["magtact", args[0], str(study), *args[1:]]
    monkeypatch.setattr(sys, "argv", argv)
    with pytest.raises(SystemExit) as exc:
        main()
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "needs new mechanics: [body] H_g_mm = 6" in " ".join(err.split())
    assert "magtact doe" in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
