"""The JSON files of a results folder are read through the types that write them: the report
(``magtact.report``) and the command line (``magtact.cli``) spell no key of a file another
module writes.

The keys are collected from real documents: the bundled MagOne answer written into a folder
(``design.json``, ``chosen.json``, ``sensor.json``, ``budget.json``), its calibration's summary
(``calibration.json``) and a run's manifest (``run.json``). The source of ``report/`` and
``cli/`` is then scanned (``ast``) for those keys as string literals.

Files the report writes itself (``card.json``, ``explorer.json``, ``captions.json``) are its
own to spell. Keys that are one plain word (``rows``, ``label``, ``status``, ``design``) are
left out: they are also the words of the page and of other data (a table's ``rows``, a
figure's ``label``), so a scan for them cannot tell a key from a word; every key with a unit
or a subscript (``at_rest_mN``, ``Gamma_r_max_N_per_T``, ``wall_time_s``, ``run_id``) is
scanned.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("report", "cli")
#: Files of a results folder that ``magtact.report`` writes (its own keys).
OWN = {"card.json", "explorer.json", "captions.json"}
#: Modules that spell keys of the collected files for a stated reason: (reason, keys).
ALLOWED: dict[str, tuple[str, set[str]]] = {
    "report/_explorer.py": ("writes and reads explorer.json, its own file, whose design keys "
                            "are named as in chosen.json",
                            {"H_mm", "G_kPa", "M_z_A_per_m", "standoff_mm", "t_m", "F_r_c_N",
                             "F_z_c_N"}),
    "report/_fig_explorer.py": ("draws explorer.json (report/_explorer.py's file)",
                                {"H_mm", "G_kPa", "F_z_c_N"}),
    "report/_labels.py": ("the display name of a symbol (t_m), one home for every label",
                          {"t_m"}),
    "report/_publication.py": ("reads publication.json of magtact.publication, whose keys are "
                               "named as these", {"G_kPa", "wall_time_s"}),
    "report/_fig_publication.py": ("draws publication.json of magtact.publication",
                                   {"H_mm", "t_m"}),
}


def keys_of(doc, out: set[str]) -> set[str]:
    """Every key of a JSON document, at every depth."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            out.add(k)
            keys_of(v, out)
    elif isinstance(doc, list):
        for v in doc:
            keys_of(v, out)
    return out


def scanned(key: str) -> bool:
    """A machine key (with a unit or a subscript), not a plain word."""
    return "_" in key


@pytest.fixture(scope="module")
def written_keys(tmp_path_factory, magone_design) -> dict[str, set[str]]:
    """key → the files of other modules that write it."""
    from magtact._runfolder import RunManifest, StageRecord

    result = magone_design
    folder = tmp_path_factory.mktemp("written")
    docs = {p.name: json.loads(p.read_text(encoding="utf-8"))
            for p in result.write_into(folder, figures=False, budget=True)
            if p.suffix == ".json"}
    docs["calibration.json"] = result.calibrate(degrees=(4,), table_sizes=(16,)).to_json()
    docs["run.json"] = RunManifest(
        "id", "study", "magtact run", "now", stages=[StageRecord("doe", "DOE", "ok", 1.0)],
        doe_source="bundled", wall_time_s=2.0, interrupted="KeyboardInterrupt",
        finished="now").to_json()
    out: dict[str, set[str]] = {}
    for name, doc in docs.items():
        if name in OWN:
            continue
        for k in keys_of(doc, set()):
            if scanned(k):
                out.setdefault(k, set()).add(name)
    return out


def spelled(keys, sources: list[Path]) -> list[str]:
    """``file:line: key (file that writes it)`` of every string literal in ``sources`` that is
    one of ``keys`` (but those :data:`ALLOWED` in its module)."""
    found = []
    for path in sources:
        allowed = ALLOWED.get(f"{path.parent.name}/{path.name}", ("", set()))[1] \
            if path.is_relative_to(ROOT / "src") else set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                    and node.value in keys and node.value not in allowed:
                where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
                found.append(f"{where}:{node.lineno}: {node.value!r} "
                             f"(written in {', '.join(sorted(keys[node.value]))})")
    return sorted(found)


def sources() -> list[Path]:
    return sorted(p for d in SCANNED for p in (ROOT / "src" / "magtact" / d).glob("*.py"))


def test_the_keys_are_collected_from_every_file(written_keys):
    files = set().union(*written_keys.values())
    assert {"budget.json", "chosen.json", "design.json", "calibration.json",
            "run.json"} <= files
    for key in ("at_rest_mN", "worst_mN", "smallest_pitch_mm", "Gamma_r_max_N_per_T",
                "wall_time_s", "run_id", "F_r_mN", "sigma_F_r_mN", "g_r_N"):
        assert key in written_keys, key


def test_report_and_cli_spell_no_key_of_another_modules_file(written_keys):
    found = spelled(written_keys, sources())
    assert found == [], ("JSON keys spelled outside the type that writes them (read the file "
                         "through the type's from_json):\n" + "\n".join(found))


def test_the_scan_finds_a_planted_key(written_keys, tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text('def f(doc):\n    return doc["at_rest_mN"]\n', encoding="utf-8")
    found = spelled(written_keys, [planted])
    assert len(found) == 1 and ":2: 'at_rest_mN' (written in budget.json)" in found[0]
