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
    assert "12" not in _method_sections() and "6.9" not in _method_sections()


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
