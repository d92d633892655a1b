"""The README's Python example runs and prints the chosen design of the MagOne study."""

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_example(tmp_path):
    text = (ROOT / "README.md").read_text("utf-8")
    section = text[text.index("## Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert code.count("\n") <= 10
    src = str(ROOT / "src")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=600,
                         env={"PYTHONPATH": src, "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg"})
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    # chosen design of the MagOne study: H at its lower bound, the F_r constraint active
    m = re.match(r"H = ([\d.]+) mm, G = ([\d.]+) kPa: Γ_r,max = ([\d.]+) N/T", lines[0])
    assert m and float(m.group(1)) == 3.0 and 10 < float(m.group(2)) < 50
    assert lines[1].startswith("H = 3.000 mm, G = 29.40 kPa")
    assert "F_r" in lines[2] and "shipped" in lines[2]
    assert (tmp_path / "design" / "design.json").is_file()
    assert (tmp_path / "design" / "pareto_set.png").is_file()


def test_help_lists_the_front_door():
    out = subprocess.run([sys.executable, "-c", "import magtact; help(magtact)"],
                         capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin",
                              "PAGER": "cat"})
    assert out.returncode == 0, out.stderr
    for name in ("design(", "load(", "run(", "Design", "DesignSummary", "MagtactError"):
        assert name in out.stdout
