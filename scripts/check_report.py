"""Open a magtact HTML report in headless Chromium; check that every figure loads; screenshot it.

Usage::

    python scripts/check_report.py results/report.html [--screenshot docs/report.png]

Chromium (Debian: ``apt-get install -y chromium``) loads a copy of the report into which a small
script is injected. After the page has loaded, the script inspects every ``<img>``
(``complete`` and ``naturalWidth > 0`` means the image decoded) and writes the verdict into the
DOM, which ``--dump-dom`` prints. A second Chromium call takes a full-width screenshot.
Exit status 0 if every image loaded, 1 otherwise, 2 if Chromium is missing.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars", "--mute-audio"]

PROBE = """
<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var res = imgs.map(function (im, i) {
    return {i: i, alt: im.alt, ok: im.complete && im.naturalWidth > 0,
            w: im.naturalWidth, h: im.naturalHeight};
  });
  var pre = document.createElement('pre');
  pre.id = 'magtact-image-check';
  pre.textContent = 'MAGTACT' + '-CHECK:' + JSON.stringify(res) + ':' + 'END';
  document.body.appendChild(pre);
});
</script>
"""


def chromium() -> str | None:
    """Path of a Chromium executable, or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def check_images(report: Path, exe: str, profile: Path) -> list[dict]:
    """Load ``report`` with the probe injected; return one record per ``<img>``."""
    html = report.read_text(encoding="utf-8")
    probed = profile / "probed.html"
    probed.write_text(html.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    out = subprocess.run(
        [exe, *FLAGS, f"--user-data-dir={profile / 'dom'}", "--virtual-time-budget=10000",
         "--dump-dom", probed.as_uri()],
        capture_output=True, text=True, timeout=180, check=False)
    m = re.search(r"MAGTACT-CHECK:(.*?):END", out.stdout, re.S)
    if m is None:
        raise RuntimeError("Chromium did not run the check script:\n" + out.stderr[-2000:])
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))


def screenshot(report: Path, exe: str, profile: Path, target: Path, width: int = 1200,
               height: int = 2400) -> Path:
    """Save a ``width`` × ``height`` screenshot of the top of the report as PNG."""
    target.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(
        [exe, *FLAGS, f"--user-data-dir={profile / 'shot'}", f"--window-size={width},{height}",
         "--virtual-time-budget=10000", f"--screenshot={target.resolve()}", report.as_uri()],
        capture_output=True, text=True, timeout=180, check=False)
    if not target.is_file():
        raise RuntimeError(f"Chromium wrote no screenshot to {target}")
    return target


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", type=Path, help="report.html to check")
    parser.add_argument("--screenshot", type=Path, default=Path("docs/report.png"),
                        help="where to save the screenshot (default docs/report.png)")
    parser.add_argument("--height", type=int, default=2400, help="screenshot height [px]")
    args = parser.parse_args(argv)
    exe = chromium()
    if exe is None:
        print("chromium not found (Debian: apt-get install -y chromium)", file=sys.stderr)
        return 2
    report = args.report.resolve()
    with tempfile.TemporaryDirectory(prefix="magtact-chromium-") as tmp:
        profile = Path(tmp)
        records = check_images(report, exe, profile)
        shot = screenshot(report, exe, profile, args.screenshot, height=args.height)
    bad = [r for r in records if not r["ok"]]
    for r in records:
        state = "ok  " if r["ok"] else "FAIL"
        print(f"{state} img {r['i']:2d} {r['w']:5d} x {r['h']:<5d} {r['alt']}")
    print(f"{len(records) - len(bad)} of {len(records)} images loaded; screenshot: {shot}")
    if not records:
        print("warning: the report has no images", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
