"""The README's Python example runs and prints the chosen design of the MagOne study, the one
the benchmark recorded (bench/results/optimise.json)."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_example(tmp_path):
    text = (ROOT / "README.md").read_text("utf-8")
    section = text[text.index("## Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert code.count("\n") <= 11
    src = str(ROOT / "src")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=600,
                         env={"PYTHONPATH": src, "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg",
                              "MAGTACT_CACHE_DIR": os.environ["MAGTACT_CACHE_DIR"]})
    assert out.returncode == 0, out.stderr
    # each printed object: a title line, then its indented rows
    blocks = re.split(r"\n(?=\S)", out.stdout.strip())
    assert len(blocks) == 5, out.stdout
    chosen, parts, original, evaluated, publication = blocks
    # the sensor problem: the verdict first, each requirement with its margin; the original
    # sensor fails its chip's range
    assert chosen.startswith("verdict: ")
    assert re.search(r"[✓✗] reads 0–5 N normal without saturating +yes, (saturates at|never "
                     r"saturates)", chosen)
    assert re.search(r"[✓✗] carries and reads 0–0.25 N shear", chosen)
    assert re.search(r"✓ samples at 100 Hz or faster +yes, \S+ Hz; margin", chosen)
    assert parts.startswith("parts") and re.search(r"magnet +N\d\d, ⌀\d × \d mm", parts)
    assert re.search(r"✗ reads 0–5 N normal without saturating +no: the chip saturates",
                     original)
    assert evaluated.startswith("verdict: ")
    # the publication's problem: the design the benchmark recorded (3 significant figures)
    from magtact._display import sig

    bench = json.loads((ROOT / "bench" / "results" / "optimise.json").read_text())
    b = bench["default_constraints"]
    assert f"H {sig(b['H_mm'])} mm, G {sig(b['G_kPa'])} kPa" in publication, publication
    assert re.search(rf"Γ_r,max / Γ_z,max +{sig(b['Gamma_r_max_N_per_T'])} / "
                     rf"{sig(b['Gamma_z_max_N_per_T'])} N/T", publication), publication
    assert (tmp_path / "design" / "design.json").is_file()
    assert (tmp_path / "design" / "card.json").is_file()
    assert (tmp_path / "design" / "sensor.json").is_file()
    assert (tmp_path / "design" / "pareto_set.png").is_file()


def test_help_lists_the_front_door():
    out = subprocess.run([sys.executable, "-c", "import magtact; help(magtact)"],
                         capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin",
                              "PAGER": "cat"})
    assert out.returncode == 0, out.stderr
    for name in ("design(", "load(", "run(", "solve(", "Result", "MagtactError"):
        assert name in out.stdout


def _readme_table() -> dict[str, list[str]]:
    """The MagOne table of the README: row label → cells."""
    text = (ROOT / "README.md").read_text("utf-8")
    section = text[text.index("## The MagOne design"):text.index("## magtact and the publication")]
    rows = [ln.strip().strip("|").split("|") for ln in section.splitlines() if ln.startswith("| ")]
    return {r[0].strip(): [c.strip() for c in r[1:]] for r in rows}


def test_readme_magone_table_is_the_benchmarks_result():
    """Every number of the README's MagOne table as bench/results/optimise.json has it."""
    bench = json.loads((ROOT / "bench" / "results" / "optimise.json").read_text())
    c = bench["default_constraints"]
    ref = bench["reference_constraints"]
    o = ref["exact_reduction_choice"]  # the original design, where the reference is itself
    assert (o["H_mm"], o["G_kPa"]) == pytest.approx((3.0, 29.4), rel=1e-12)
    table = _readme_table()

    def num(text):
        return [float(x.replace("−", "-")) for x in re.findall(r"[−-]?\d+\.?\d*", text)]

    assert table["base height H"] == [f"{c['H_mm']:.3f} mm", f"{o['H_mm']:.0f} mm"]
    assert table["shear modulus G"] == [f"{c['G_kPa']:.2f} kPa", f"{o['G_kPa']:.1f} kPa"]
    chosen, original = table["worst-case Γ_r,max / Γ_z,max"]
    assert num(chosen) == [round(c["Gamma_r_max_N_per_T"], 2), round(c["Gamma_z_max_N_per_T"], 2)]
    assert num(original) == [round(o["Gamma_r_max_N_per_T"], 2),
                             round(o["Gamma_z_max_N_per_T"], 2)]
    chosen, original = table["F_r,min / F_z,max"]
    assert num(chosen) == [round(c["F_r_min_N"], 3), round(c["F_z_max_N"], 2)]
    rc = ref["constraints"]  # the original design's own forces
    assert num(original) == [round(rc["F_r_c_N"], 3), round(rc["F_z_c_N"], 2)]
    active = {"F_r": "F_r (shear)", "F_z": "F_z (normal)"}
    assert table["active constraint"][0] == ", ".join(active[k] for k in c["active_constraints"])


def test_readme_magone_card_rows_are_what_the_designer_answers(models):
    """The README's resolution, chip and silicone rows: the designer's answer for the two
    designs of the table, on the shipped models."""
    from magtact import Sensor
    from magtact.designer import answer
    from magtact.study import load_study

    bench = json.loads((ROOT / "bench" / "results" / "optimise.json").read_text())
    c = bench["default_constraints"]
    s = load_study("magone-publication")
    chosen = answer(models, s, Sensor.of_study(s, c["H_mm"] * 1e-3, c["G_kPa"] * 1e3))
    original = answer(models, s, Sensor.of_study(s, 3e-3, 29.4e3))
    table = _readme_table()
    for cell, a in zip(table["resolution σ_Fr / σ_Fz (1 σ, worst over the stable region)"],
                       (chosen, original), strict=True):
        r = a.resolution
        shown = re.findall(r"\d+\.\d+", cell)
        for text, value in zip(shown, (r.sigma_r_worst * 1e3, r.sigma_z_worst * 1e3),
                               strict=True):  # correct to the digits shown
            assert abs(float(text) - value) <= 0.5 * 10.0 ** -len(text.split(".")[1])
    words = table["MLX90393 setting magtact picks, sample rate"][0]
    assert words.startswith(chosen.chip.setting) and words.endswith(
        f"{chosen.chip.figures.rate:.2g} Hz")
    assert original.chip.setting == chosen.chip.setting
    for cell, a in zip(table["the chip (±33 / 50 mT at that setting) saturates at"],
                       (chosen, original), strict=True):
        assert cell == f"t = {a.saturation.t:.2f}, F_z = {a.saturation.F_z:.2f} N"
    assert [a.chip.range_x * 1e3 for a in (chosen, original)] == pytest.approx([33, 33], abs=0.5)
