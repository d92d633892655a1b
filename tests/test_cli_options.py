"""One meaning and one spelling per option across the commands: every option that several
commands share says the same thing in each (the table below, kept with the commands), takes
the same values, and an enumerated option lists its choices; a study may be based on a file."""

from __future__ import annotations

import enum
from collections import defaultdict

import pytest
import typer.main
from typer.testing import CliRunner

from magtact.cli import app

COMMAND = typer.main.get_command(app)

#: Each option several commands share, by idea: words its help holds everywhere (most at the
#: beginning).
IDEAS = {
    "--out": "Output folder (created if needed)",
    "--data": "DOE data set (.nc, magtact doe)",
    "--models": "Folder of metamodel files (B_r.json, B_z.json, f_r.json, f_z.json; magtact "
                "fit)",
    "--workers": "Worker processes of the FE jobs",
    "--cache": "Job cache folder of the FE jobs",
    "--H": "Body height H [mm]",
    "--G": "Shear modulus G [kPa]",
    "--generations": "GP generations of the fit",
    "--noise-uT": "RMS field noise [µT]",
    "--solver": "'fe': axisymmetric finite elements; 'exact': closed form",
    "--mesh": "Mesh density",
    "--grade": "Magnet grade",
    "--standoff-mm": "The chip's distance below the body [mm]",
    "--setting": "The chip's setting",
    "--silicone": "The silicone's catalogue name",
    "--recompute": "own FE DOE",
}
#: Options whose values are words from a list (not an Enum type): the choices their help or
#: metavar lists.
WORDS = {"--definition": ("jacobian", "published"), "--force-source": ("fe", "models", "auto")}


def options():
    """(command, long option name, parameter) of every visible option."""
    for name, cmd in sorted(COMMAND.commands.items()):
        for p in cmd.params:
            if p.param_type_name == "option" and not p.hidden:
                for o in p.opts:
                    if o.startswith("--"):
                        yield name, o, p


def annotation(p):
    return getattr(getattr(p, "type_descriptor", None), "annotation", None)


def test_every_shared_option_has_one_meaning_and_one_kind_of_value():
    users = defaultdict(list)
    for command, option, p in options():
        users[option].append((command, p))
    shared = {o: u for o, u in users.items() if len(u) > 1}
    assert set(shared) <= set(IDEAS), f"shared options without an entry in IDEAS: " \
                                      f"{sorted(set(shared) - set(IDEAS))}"
    for option, uses in shared.items():
        for command, p in uses:
            assert IDEAS[option] in (p.help or ""), (command, option, p.help)
        kinds = {(str(annotation(p)), p.min, p.max, p.multiple) for _, p in uses}
        assert len(kinds) == 1, (option, kinds)


def test_out_has_a_default_in_every_command():
    outs = [(c, p) for c, o, p in options() if o == "--out"]
    assert len(outs) >= 10
    for command, p in outs:
        assert not p.required, command


def test_every_enumerated_option_lists_its_choices():
    runner = CliRunner()
    seen = set()
    for command, option, p in options():
        kind = annotation(p)
        if isinstance(kind, type) and issubclass(kind, enum.Enum):
            text = " ".join(runner.invoke(app, [command, "--help"]).stdout.split())
            listed = "|".join(m.value for m in kind)
            assert f"<{listed}>" in text or f"[{listed}]" in text, (command, option, text)
            seen.add(option)
        elif option in WORDS:
            shown = f"{p.metavar or ''} {p.help or ''}"
            assert all(w in shown for w in WORDS[option]), (command, option, shown)
            seen.add(option)
    assert {"--solver", "--mesh", "--definition", "--force-source"} <= seen


@pytest.mark.parametrize("command, args", [("run", []), ("doe", []), ("reproduce", [])])
def test_workers_refuses_a_negative_count_in_every_command(command, args):
    r = CliRunner().invoke(app, [command, "--workers", "-1", *args])
    assert r.exit_code == 2 and "--workers" in r.stderr


def test_run_names_the_validation_data_measured(tmp_path):
    r = CliRunner().invoke(app, ["run", "--data", "x.csv", "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "--data is now --measured" in " ".join(r.stderr.split())


# ---- a study based on a file -----------------------------------------------------------------
def test_a_study_may_be_based_on_another_study_file(tmp_path):
    import magtact
    from magtact.study import StudyError

    (tmp_path / "mine.toml").write_text('name = "mine"\n[requirements]\nF_z_N = 4.0\n',
                                        encoding="utf-8")
    (tmp_path / "sub").mkdir()
    child = tmp_path / "sub" / "child.toml"
    child.write_text('base = "../mine.toml"\nname = "child"\n[magnet]\ngrade = "N42"\n',
                     encoding="utf-8")
    s = magtact.load(child)
    assert (s.name, s.requirements.F_z, s.magnet.grade) == ("child", 4.0, "N42")
    assert s.constraints.F_z_c == 4.0  # the base's requirement, with what follows from it
    loop = tmp_path / "loop.toml"
    loop.write_text('base = "loop.toml"\n', encoding="utf-8")
    with pytest.raises(StudyError, match=r"\[base\] the study files name each other as base"):
        magtact.load(loop)
    bad = tmp_path / "bad.toml"
    bad.write_text('base = "mine"\n', encoding="utf-8")
    with pytest.raises(StudyError, match=r"or a study file \(\.toml\)"):
        magtact.load(bad)
