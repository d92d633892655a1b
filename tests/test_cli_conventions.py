"""Conventions every command follows: ``--version``; one option name per idea; the study as an
argument; commands in pipeline order in ``--help``; results on stdout and diagnostics on
stderr; progress in a terminal only."""

from __future__ import annotations

import io
import re
from collections import defaultdict

import pytest
import typer.main
from rich.console import Console
from typer.testing import CliRunner

import magtact
from magtact.cli import app

COMMAND = typer.main.get_command(app)
#: Unit suffixes an option's name may carry; without them two spellings are one idea.
SUFFIXES = ("-mm", "-kpa", "-ut", "-mt", "-n", "-s")


def visible_options() -> dict[str, dict[str, str]]:
    """Per command: long option name → its help, hidden options left out."""
    out = {}
    for name, cmd in COMMAND.commands.items():
        out[name] = {o: p.help or "" for p in cmd.params
                     if p.param_type_name == "option" and not p.hidden
                     for o in p.opts if o.startswith("--")}
    return out


def idea(option: str) -> str:
    key = option.lower()
    for s in SUFFIXES:
        key = key.removesuffix(s)
    return key


def test_version():
    r = CliRunner().invoke(app, ["--version"])
    assert r.exit_code == 0 and r.stdout.strip() == f"magtact {magtact.__version__}"


def test_one_option_name_per_idea_across_the_commands():
    names = defaultdict(set)
    users = defaultdict(set)
    for command, options in visible_options().items():
        for option in options:
            names[idea(option)].add(option)
            users[option].add(command)
    assert {k: v for k, v in names.items() if len(v) > 1} == {}
    # the ideas that several commands share, by the one name each has
    assert {"fit", "budget", "calibrate", "simulate", "validate"} <= users["--H"]
    assert {"fit", "budget", "calibrate", "simulate", "validate"} <= users["--G"]
    assert {"optimise", "compare", "budget", "calibrate", "validate"} <= users["--models"]
    assert {"run", "doe", "reproduce"} <= users["--workers"]
    assert {"fit", "reproduce"} <= users["--data"]
    assert set(COMMAND.commands) - {"report", "study", "compare"} <= users["--out"]
    # a height in mm and a modulus in kPa, said in the help
    for command, options in visible_options().items():
        for option, unit in (("--H", "[mm]"), ("--G", "[kPa]")):
            if option in options:
                assert unit in options[option], (command, option, options[option])


def test_the_study_is_an_argument_of_every_command():
    for name, cmd in COMMAND.commands.items():
        arguments = [p.name for p in cmd.params if p.param_type_name == "argument"]
        assert "--study" not in visible_options()[name], name
        if name == "report":  # a results folder names its study
            assert arguments == ["folder"]
        elif name == "validate":  # [STUDY] DATA...
            assert arguments == ["args"]
        else:
            assert "study" in arguments, name


@pytest.mark.parametrize("args, message", [
    (["fit", "--H-mm", "4"], "--H-mm is now --H"),
    (["fit", "--G-kpa", "20"], "--G-kpa is now --G"),
    (["compare", "3,20", "4,20", "--study", "magone"],
     "--study is now an argument: magtact compare H1,G1 H2,G2 STUDY"),
])
def test_old_option_names_are_refused_naming_the_new_one(args, message):
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2 and message in re.sub(r"\s+", " ", r.stderr.replace("│", ""))


def test_help_lists_the_commands_in_pipeline_order():
    from magtact.cli._app import ORDER

    text = CliRunner().invoke(app, ["--help"]).stdout
    listed = [m.group(1) for m in re.finditer(r"^\s+(\w+)\s{2,}", text, re.M)
              if m.group(1) in COMMAND.commands]
    assert listed == list(ORDER) and set(ORDER) == set(COMMAND.commands)
    assert "--version" in text


def test_compare_writes_its_table_on_stdout_and_nothing_else_on_stderr():
    r = CliRunner().invoke(app, ["compare", "3,20", "4,30", "magone"])
    assert r.exit_code == 0, r.output
    assert "Γ_z,max" in r.stdout and "design 2" in r.stdout
    assert "Warning" not in r.stderr and "Γ_z,max" not in r.stderr


def terminal(monkeypatch, module: str, is_terminal: bool) -> io.StringIO:
    buffer = io.StringIO()
    console = Console(file=buffer, force_terminal=is_terminal, width=120)
    monkeypatch.setattr(f"magtact.cli.{module}.console", console)
    return buffer


class Stop(magtact.MagtactError):
    """Ends a command right after its long step began (the step itself is not under test)."""


@pytest.mark.parametrize("is_terminal", [True, False])
def test_simulate_shows_its_progress_in_a_terminal_only(monkeypatch, tmp_path, is_terminal):
    import time

    def path(*args, progress, **kwargs):
        for t in (0.25, 0.5):
            progress(t)
            time.sleep(0.15)  # rich redraws a few times a second
        raise Stop("stopped after t = 0.5")

    monkeypatch.setattr("magtact.mechanics.simulate_path", path)
    shown = terminal(monkeypatch, "_simulate", is_terminal)
    r = CliRunner().invoke(app, ["simulate", "--H", "4", "--theta", "0", "--out",
                                 str(tmp_path / "o")])
    assert isinstance(r.exception, Stop)
    assert ("simulate H = 4 mm" in shown.getvalue()) is is_terminal
    assert ("t = 0.50" in shown.getvalue()) is is_terminal


@pytest.mark.parametrize("is_terminal", [True, False])
def test_calibrate_shows_its_progress_in_a_terminal_only(monkeypatch, tmp_path, is_terminal,
                                                         magone_design):
    import time

    def calibrate(*args, **kwargs):
        time.sleep(0.3)
        raise Stop("stopped while calibrating")

    monkeypatch.setattr("magtact.calibration.calibrate", calibrate)
    monkeypatch.setattr("magtact.design", lambda *args, **kwargs: magone_design)
    shown = terminal(monkeypatch, "_calibrate", is_terminal)
    r = CliRunner().invoke(app, ["calibrate", "--H", "3", "--G", "22", "--out",
                                 str(tmp_path / "o")])
    assert isinstance(r.exception, Stop), r.output
    assert ("calibrating: the map" in shown.getvalue()) is is_terminal
    assert "the chosen sensor with the options given: H 3 mm" in shown.getvalue()
