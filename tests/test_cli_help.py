"""The CLI's help text shows every unit and bracketed note its options carry."""

from __future__ import annotations

import re

import pytest
import typer
from typer.testing import CliRunner

from magtact.cli import app

COMMAND = typer.main.get_command(app)
NAMES = sorted(COMMAND.commands)


def _help(*args: str) -> str:
    result = CliRunner().invoke(app, [*args, "--help"], terminal_width=100)
    assert result.exit_code == 0, result.output
    return result.output


def test_simulate_help_shows_its_units():
    text = _help("simulate")
    assert "Body height H [mm]" in text
    assert "Shear modulus G [kPa]" in text
    assert "Shear angle θ [rad]" in text


@pytest.mark.parametrize("name", NAMES)
def test_every_bracketed_note_of_every_command_survives(name):
    """Each ``[...]`` of a command's help strings (units, keys) appears in its --help."""
    command = COMMAND.commands[name]
    texts = [command.help or ""] + [getattr(p, "help", None) or "" for p in command.params]
    notes = {m for t in texts for m in re.findall(r"\[[^\]\s]+\]", t)}
    shown = _help(name)
    missing = sorted(n for n in notes if n not in shown)
    assert not missing, f"magtact {name} --help drops {missing}"


def test_the_commands_with_units_have_them():
    """The commands whose options are physical quantities name a unit in their help."""
    units = {n: set(re.findall(r"\[(mm|kPa|rad|mN|mT|µT|N|T)\]", _help(n))) for n in NAMES}
    assert {"mm", "kPa", "rad"} <= units["simulate"]
    assert any(units.values())
