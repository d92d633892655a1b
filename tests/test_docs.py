"""The documents: README size, the method's sections and figure, the generated verification."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _method_sections() -> set[str]:
    text = (DOCS / "method.md").read_text("utf-8")
    return set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", text, flags=re.MULTILINE))


def test_readme_is_a_front_door():
    text = (ROOT / "README.md").read_text("utf-8")
    assert len(text.splitlines()) <= 150
    for link in ("docs/method.md", "docs/verification.md"):
        assert f"]({link})" in text
    # the two commands that CI runs
    assert ("python3 -m venv .venv && . .venv/bin/activate && python -m pip install -e . && "
            "magtact run --out results") in text
    assert 'python -m pip install -e ".[test]" && python -m pytest' in text


def test_method_has_numbered_sections_one_to_eleven():
    assert {str(n) for n in range(1, 12)} <= _method_sections()


def test_every_citation_of_the_method_names_an_existing_section():
    sections = _method_sections()
    cited = {}
    for path in [*sorted((ROOT / "src").rglob("*.py")), *sorted((ROOT / "src").rglob("*.md")),
                 *sorted((ROOT / "src").rglob("*.toml")), *sorted((ROOT / "tests").glob("*.py"))]:
        for ref in re.findall(r"method\.md §(\d+(?:\.\d+)?)", path.read_text("utf-8")):
            cited.setdefault(ref, path.relative_to(ROOT))
    assert len(cited) >= 9  # the code cites the method throughout
    assert {ref: str(p) for ref, p in cited.items() if ref not in sections} == {}


def test_citation_check_sees_a_missing_section():
    assert "99" not in _method_sections() and "6.9" not in _method_sections()


def test_sensor_figure_is_embedded_and_defines_every_symbol():
    assert "](sensor.svg)" in (DOCS / "method.md").read_text("utf-8")
    svg = (DOCS / "sensor.svg").read_text("utf-8")
    text = re.sub(r"<[^>]+>", "", svg)
    for symbol in ("H (design variable)", "Hg = ", "Rm = ", "Hm = ", "Δzsat = ", "θ",
                   "t ∈ [0, 1]", "Hall point", "R = 6 mm", "upper rigid plate",
                   "lower rigid plate"):
        assert symbol in text, symbol


def test_sensor_figure_is_what_the_script_draws():
    assert _script("make_sensor_svg").draw() == (DOCS / "sensor.svg").read_text("utf-8")


def test_verification_is_generated_from_the_benchmark_results():
    """docs/verification.md is exactly what the script makes of bench/results."""
    made = _script("make_verification").document(ROOT / "bench" / "results")
    assert made == (DOCS / "verification.md").read_text("utf-8"), (
        "docs/verification.md is stale: run python scripts/make_verification.py")


def test_verification_numbers_follow_the_results(tmp_path):
    """Change one benchmark number: the document changes with it."""
    import json
    import shutil

    results = tmp_path / "results"
    shutil.copytree(ROOT / "bench" / "results", results,
                    ignore=shutil.ignore_patterns("*.nc"))
    fit = json.loads((results / "fit.json").read_text("utf-8"))
    fit["gamma_vs_data_fd"]["gamma_r"]["within_5_percent_above_floor"] = 0.5
    (results / "fit.json").write_text(json.dumps(fit), encoding="utf-8")
    text = _script("make_verification").document(results)
    assert "Γ_r agrees within 5 % at 50.0 % of the points on the bundled data" in text


@pytest.mark.parametrize("name", ["method.md", "verification.md", "usage.md"])
def test_documents_cite_no_outside_specification(name):
    assert "SP" + "EC" not in (DOCS / name).read_text("utf-8")


@pytest.mark.parametrize("name", ["method.md", "sensor.svg"])
def test_the_package_ships_the_documents_of_docs_not_a_copy(name):
    """docs/ is the one home of the method and its figure; the package's files are links to
    them (a wheel stores their content), so the two cannot differ."""
    shipped = ROOT / "src" / "magtact" / "report" / name
    assert shipped.is_symlink() and shipped.resolve() == (DOCS / name).resolve()


# ---- the documents name only what exists ---------------------------------------------------
USER_DOCS = ("README.md", "docs/usage.md")


def _code(text: str) -> list[str]:
    """The code of a Markdown text: each line of a fenced block and each inline code span."""
    fenced = re.findall(r"^```[^\n]*\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL)
    rest = re.sub(r"^```[^\n]*\n.*?^```", "", text, flags=re.MULTILINE | re.DOTALL)
    return [line for block in fenced for line in block.splitlines()] + re.findall(
        r"`([^`]+)`", rest)


def _cli():
    import typer

    from magtact.cli import app

    group = typer.main.get_command(app)
    return {name: {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)}
            for name, cmd in group.commands.items()}


def _cli_mentions(text: str) -> list[tuple[str, list[str]]]:
    """(command, options) for every ``magtact COMMAND ...`` in the code of ``text``."""
    found = []
    for code in _code(text):
        for part in re.split(r"&&|;", code.replace("\n", " ")):
            m = re.match(r"\s*magtact\s+([a-z][\w-]*)(.*)", part)
            if m:
                found.append((m.group(1), re.findall(r"(?<![\w-])(--?[a-zA-Z][\w-]*)",
                                                     m.group(2).split("#")[0])))
    return found


@pytest.mark.parametrize("name", USER_DOCS)
def test_every_command_and_option_the_documents_name_exists(name):
    cli = _cli()
    text = (ROOT / name).read_text("utf-8")
    mentions = _cli_mentions(text)
    assert len({c for c, _ in mentions}) >= 8  # the documents walk through the commands
    wrong = [(c, o) for c, opts in mentions for o in ([None] if c not in cli else opts)
             if c not in cli or (o is not None and o not in cli[c] and o != "--help")]
    assert wrong == []
    # an option named on its own (`--f-lo`) belongs to some command
    every = set().union(*cli.values()) | {"--help"}
    alone = {o for code in _code(text) for o in re.findall(r"^(--[a-z][\w-]*)", code.strip())}
    assert sorted(alone - every) == []


def test_the_command_check_sees_a_wrong_command_and_option():
    cli = _cli()
    mentions = _cli_mentions("Run `magtact simulate --H 3 --heigth 4` and\n```bash\n"
                             "magtact simlate --out x  # comment --no\n```\n")
    assert ("simulate", ["--H", "--heigth"]) in mentions and ("simlate", ["--out"]) in mentions
    assert "--heigth" not in cli["simulate"] and "simlate" not in cli


def _python_names(text: str) -> set[str]:
    return set(re.findall(r"(?<![\w./-])(magtact(?:\.[A-Za-z_]\w*)+)", text))


def _resolves(name: str) -> bool:
    import importlib

    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        try:
            for attr in parts[k:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return False
        return True
    return False


@pytest.mark.parametrize("name", USER_DOCS)
def test_every_python_name_the_documents_name_exists(name):
    names = _python_names((ROOT / name).read_text("utf-8"))
    assert len(names) >= 5
    assert sorted(n for n in names if not _resolves(n)) == []


def test_the_name_check_sees_a_missing_name():
    assert _python_names("use `magtact.doe.load_bundled()` or magtact.nothing_here.") == {
        "magtact.doe.load_bundled", "magtact.nothing_here"}
    assert _resolves("magtact.doe.load_bundled") and not _resolves("magtact.nothing_here")
    assert not _resolves("magtact.doe.load_bundeld")


def test_the_bundled_data_readme_lists_the_data_sets_attributes():
    from magtact.doe import load_bundled

    ds = load_bundled()
    text = (ROOT / "src" / "magtact" / "doe" / "data" / "README.md").read_text("utf-8")
    table = text[text.index("| attribute |"):]
    table = table[:table.index("\n\n")]
    named = set(re.findall(r"`([a-z]\w*)`", table)) - {"fe"} - set(ds.data_vars)
    prefixes = set(re.findall(r"`([a-z]\w*_)\*`", table))
    actual = set(ds.attrs)
    assert named <= actual, named - actual
    assert {a for a in actual if not any(a.startswith(p) for p in prefixes)} <= named
    for var in ds.data_vars:
        assert f"`{var}" in text or f" {var}`" in text or f", {var}" in text, var


def test_the_both_heights_table_follows_each_route_to_the_other_height():
    """Routes within the target at the lowest height, cheapest first, and what each gave at
    the other: within, outside (its changes), a stall (its t) or not run; a route outside the
    target at the lowest height is left out."""
    mv = _script("make_verification")

    def point(route, mesh, s, fz, fr):
        return {"route": route, "mesh": mesh, "wall_time_s": s, "change_F_z_t1": fz,
                "change_F_r_min": fr}

    limits = [
        {"H_mm": 3.0, "vs_limit": [point("a", "m", 50, 0.005, 0.01),
                                   point("b", "m", 20, 0.005, 0.01),
                                   point("c", "m", 10, 0.02, 0.01),
                                   point("d", "m", 70, 0.001, 0.001)]},
        {"H_mm": 7.0, "vs_limit": [point("a", "m", 150, 0.002, 0.03),
                                   point("d", "m", 90, 0.001, 0.001)]}]
    failed = [{"route": "b", "variant": "", "mesh": "m", "H_mm": 7.0,
               "error": "structural path failed at t = 0.34091 (theta = 0.4 rad)"}]

    def within(p):
        return p["change_F_z_t1"] <= 0.01 and p["change_F_r_min"] <= 0.02

    rows = [line for line in mv._other_height(limits, failed, within) if line.startswith("| ")]
    assert rows[1:] == ["| b | m | 20 | stalls at t = 0.341 |",
                        "| a | m | 50 | 150 s, outside (0.20 %, 3.00 %) |",
                        "| d | m | 70 | 90 s, within (0.10 %, 0.10 %) |"]
    assert mv._other_height(limits[:1] + [{"H_mm": 7.0, "vs_limit": []}], [],
                            lambda p: False) == []
