"""The report's answer as a browser shows and prints it (headless Chromium driven by
Playwright): printed on A4 with its details closed it takes at most 12 pages, its visible text
holds no setting key of the study's records, and for a specification no design meets it leads
with the verdict, what binds and what to relax, skips the validation against another sensor's
data and links to no section it does not hold."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import CHROMIUM, TINY_STUDY

playwright = pytest.importorskip("playwright.sync_api")
if not CHROMIUM.is_file():
    pytest.skip("no /usr/bin/chromium (apt-get install chromium; .ci/run installs it)",
                allow_module_level=True)

#: Most A4 pages the printed report may take (details closed: the evidence behind them).
MAX_PAGES = 12


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    from conftest import built_run

    return built_run(tmp_path_factory, "browser-report")


@pytest.fixture(scope="module")
def infeasible(tmp_path_factory) -> Path:
    """``magtact run tiny.toml``: exit status 3, the answer on standard output."""
    from conftest import built_run

    return built_run(tmp_path_factory, "infeasible-report", "tiny.toml", status=3,
                     files={"tiny.toml": TINY_STUDY})


def page_of(browser, folder: Path):
    page = browser.new_page(viewport={"width": 1400, "height": 1200})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto((folder / "report.html").as_uri())
    return page, errors


def setting_keys() -> set[str]:
    """Every key of the study's records (``[section] key`` as a study file writes it) that is
    a name of code rather than a symbol (``relaxation_tau1_s``, ``read_fraction``; not ``F_z``)."""
    from dataclasses import fields, is_dataclass

    from magtact.study import Study
    from magtact.study._model import key_of

    keys = set()
    for section in fields(Study):
        record = section.default_factory() if callable(section.default_factory) else None
        if not is_dataclass(record):
            continue
        for f in fields(record):
            for key in (key_of(f), f.name):
                first, *rest = key.split("_")
                if rest and ((len(first) > 1 and first.islower())
                             or any(len(w) > 2 for w in rest)):
                    keys.add(key)
    return keys


def test_the_printed_report_takes_at_most_12_pages(browser, folder):
    page, errors = page_of(browser, folder)
    assert errors == []
    assert page.evaluate("[...document.querySelectorAll('details')].every(d => !d.open)")
    pdf = page.pdf(format="A4")
    pages = len(re.findall(rb"/Type\s*/Page(?!s)", pdf))
    (folder.parent / "report.pdf").write_bytes(pdf)
    assert 1 <= pages <= MAX_PAGES, pages


def test_the_visible_text_names_no_setting_key(browser, folder):
    page, _ = page_of(browser, folder)
    text = page.evaluate("document.body.innerText")
    keys = setting_keys()
    assert {"relaxation_tau1_s", "read_fraction", "mu_f"} <= keys
    shown = {k for k in keys if re.search(rf"(?<![\w.]){re.escape(k)}(?![\w])", text)}
    assert shown == set(), sorted(shown)
    assert "sigma_F" not in text and "()" not in text and "`" not in text


def test_an_infeasible_specification_leads_with_the_verdict_and_what_to_relax(browser,
                                                                             infeasible):
    stdout = (infeasible.parent / "built").read_text(encoding="utf-8")
    assert stdout.startswith("tiny magnet: no design meets the requirements")
    assert "binds: carries and reads 0–0.5 N shear" in stdout and "relax: " in stdout
    page, errors = page_of(browser, infeasible)
    assert errors == []
    first = page.locator("section.front")
    assert first.bounding_box()["y"] < 600
    front = first.inner_text()
    assert "no design meets the requirements" in front and "✗" in front
    relax = re.search(r"relax: (requirements\.F_r_N = [\d.]+)", stdout)
    assert "What to relax" in front and relax and relax.group(1) in front
    # every link inside the page names a section it holds
    dead = page.evaluate("""[...document.querySelectorAll('a[href^="#"]')]
        .map(a => a.getAttribute('href').slice(1))
        .filter(id => id && !document.getElementById(id))""")
    assert dead == []
    validation = page.locator("#validation").locator("xpath=..").inner_text()
    assert "belong to the MagOne sensor" in validation
    assert "largest ε" not in page.evaluate("document.body.innerText")
