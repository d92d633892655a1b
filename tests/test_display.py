"""How results print and show in a notebook: a few lines in mN, N, mm and kPa, every number to
3 significant figures (the one helper, :func:`magtact._display.sig`), and the same rows as an
HTML table."""

from __future__ import annotations

import math
import re
from html.parser import HTMLParser

import pytest
from hypothesis import given
from hypothesis import strategies as st

import magtact
from magtact._card import Card
from magtact._display import MAX_LINES, round_text, sig, significant_digits

#: A decimal number as the displays write one (not a dotted version, not inside a word).
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:e-?\d+)?(?![\w.]*\d)")


def digits(text: str) -> int:
    """Significant digits as written, counted independently of the code under test."""
    mantissa = text.lstrip("-").split("e")[0]
    if "." not in mantissa:
        return len(mantissa.lstrip("0").rstrip("0"))
    return len(mantissa.replace(".", "").lstrip("0"))


def decimals(text: str) -> list[str]:
    return [m.group() for m in NUMBER.finditer(text) if "." in m.group() or "e" in m.group()]


class Cells(HTMLParser):
    def __init__(self):
        super().__init__()
        self.cells, self._in = [], False

    def handle_starttag(self, tag, attrs):
        if tag in ("th", "td"):
            self._in = True
            self.cells.append("")

    def handle_endtag(self, tag):
        self._in = False if tag in ("th", "td") else self._in

    def handle_data(self, data):
        if self._in:
            self.cells[-1] += data


def cells(html: str) -> list[str]:
    p = Cells()
    p.feed(html)
    return p.cells


# ---- the number helper -----------------------------------------------------------------------
@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e30, max_value=1e30))
def test_sig_writes_three_significant_figures_that_read_back(v):
    text = sig(v)
    assert digits(text) <= 3
    if v == 0 or abs(v) < 1e-300:
        return
    assert float(text) == pytest.approx(v, rel=5.01e-3, abs=1e-300)


def test_sig_special_values_and_counts():
    assert (sig(1113.51), sig(22.5693), sig(-5.98402e-06), sig(0.0320411)) == \
        ("1110", "22.6", "-5.98e-6", "0.0320")
    assert (sig(9.996), sig(-0.0), sig(7), sig(float("nan")), sig(float("inf"))) == \
        ("10.0", "0", "7", "not a number", "∞")
    assert sig("text") == "text" and significant_digits("0.0320") == 3


@given(st.floats(min_value=1e-6, max_value=1e6), st.integers(1, 9), st.integers(0, 9))
def test_round_text_shortens_long_numbers_only(v, major, minor):
    long = f"{v:.9f}"
    out = round_text(f"G {long} kPa, version {major}.{minor}.2, mesh coarse_x1.5")
    assert f"version {major}.{minor}.2" in out and "coarse_x1.5" in out
    shown = out.split()[1]
    assert digits(shown) <= 4 and float(shown) == pytest.approx(v, rel=5.01e-3)


# ---- the displays -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def result(magone_design):
    return magone_design


def check_block(text: str, html: str, units: tuple[str, ...]):
    lines = text.splitlines()
    assert 2 <= len(lines) <= MAX_LINES
    assert all(u in text for u in units)
    assert [d for d in decimals(text) if digits(d) > 3] == []
    assert "<table>" in html and "<caption" in html
    shown = cells(html)
    starts = [line for line in lines[1:] if not line.startswith("    ")]  # a row's first line
    assert len(shown) == 2 * len(starts)  # one row per row of the text (long values wrap)
    for line in starts:
        assert re.sub(r"\s+", " ", line.strip()).split(" ", 1)[0] in " ".join(shown)


def test_result_prints_in_user_units(result):
    text, html = str(result), result._repr_html_()
    check_block(text, html, ("mm", "kPa", "mN", " N"))
    a = result.chosen
    H, G = re.search(r"chosen design\s+H (\S+) mm, G (\S+) kPa", text).groups()
    assert float(H) == pytest.approx(1e3 * a.H, rel=5e-3)
    assert float(G) == pytest.approx(1e-3 * a.G, rel=5e-3)
    worst = re.search(r"σ_Fz unloaded / worst\s+\S+ mN / (\S+) mN", text).group(1)
    assert float(worst) == pytest.approx(1e3 * a.resolution.sigma_z_worst, rel=5e-3)
    assert "Γ_r,max" in text and "Gamma_r" not in text


def test_the_budget_prints_largest_first_in_mN(magone_budgets):
    b = magone_budgets[0]
    text, html = str(b), b._repr_html_()
    check_block(text, html, ("mm", "kPa", "mN"))
    shown = []
    for line in text.splitlines()[2:]:
        m = re.search(r"worst (\S+) (mN|N),", line)
        if m:
            shown.append(float(m.group(1)) * (1e-3 if m.group(2) == "mN" else 1.0))
    finite = sorted((r.worst for r in b.rows if math.isfinite(r.worst)), reverse=True)
    assert shown == sorted(shown, reverse=True)
    assert shown == pytest.approx(finite[:len(shown)], rel=5e-3)


def test_the_calibration_prints_its_target_and_firmware(result):
    cal = magtact.calibrate(result, degrees=(8,), table_sizes=(16,))
    text, html = str(cal), cal._repr_html_()
    check_block(text, html, ("mm", "kPa", "mN"))
    assert f"{cal.firmware.chosen.bytes} bytes" in text
    from magtact.report import calibration_figure

    fig = calibration_figure(cal)  # three panels and two colour bars, units in brackets
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert len(fig.axes) == 5 and sum(lab.endswith("[mN]") for lab in labels) == 2
    assert "shear angle θ [rad]" in labels and "largest error / $\\sigma_F$" in labels


def test_the_result_card_leads_with_its_verdict_and_parts(result, magone_budgets):
    card = magtact.card(result, magone_budgets)
    text = str(card)
    assert isinstance(card, dict) and len(text.splitlines()) <= MAX_LINES
    if result.chosen.verdict is not None:
        assert [v["met"] for v in card["verdict"]] == [
            r.met for r in result.chosen.verdict.requirements]
        first = text.splitlines()[1].strip()
        assert first.startswith("✓" if card["verdict"][0]["met"] else "✗")
    assert "<table>" in card._repr_html_()


def test_the_card_prints_its_verdict_and_parts_first_in_25_lines():
    rows = [[f"row {k}", f"{k + 0.123456:.6f} mN", "x"] for k in range(40)]
    card = Card({"header": ["", "chosen", "original"], "rows": rows,
                 "verdict": [{"requirement": "reads 0–5 N", "met": False,
                              "text": "no, saturates at 1.15432 N"}],
                 "parts": [["magnet", "N45"]]})
    text, html = str(card), card._repr_html_()
    lines = text.splitlines()
    assert len(lines) == MAX_LINES and lines[-1].strip().startswith("…")
    assert lines[1].strip().startswith("✗ reads 0–5 N") and "1.15 N" in lines[1]
    assert lines[2].split() == ["magnet", "N45"]
    assert "0.123 mN | x" in text and "0.123456" not in text
    assert isinstance(card, dict) and card["parts"] == [["magnet", "N45"]]
    assert "<table>" in html and "✗ reads 0–5 N" in html and len(cells(html)) == 2 * 42


@pytest.mark.long
def test_result_figures_include_the_budget_and_the_calibration(result, magone_budgets):
    figs = magtact.figures(result, magone_budgets)
    assert {"budget_chosen", "calibration", "pareto_set"} <= set(figs)
