"""The JSON files of a results folder are read through the types that write them: the report
(``magtact.report``) and the command line (``magtact.cli``) spell no key of a file another
module writes.

The keys are collected from real documents: the bundled MagOne answer written into a folder
(``design.json``, ``chosen.json``, ``sensor.json``, ``budget.json``), its calibration's summary
(``calibration.json``), a run's manifest (``run.json``) and a seed study's file
(``publication.json``, written from records of known values). The source of ``report/`` and
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

import magtact

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("report", "cli")
#: Files of a results folder that ``magtact.report`` writes (its own keys).
OWN = {"card.json", "explorer.json", "captions.json"}
#: Modules that spell keys of the collected files for a stated reason: (reason, keys).
ALLOWED: dict[str, tuple[str, set[str]]] = {
    "report/_explorer.py": ("writes and reads explorer.json, its own file, whose design keys "
                            "are named as in chosen.json and the seed records",
                            {"H_mm", "G_kPa", "M_z_A_per_m", "standoff_mm", "t_m", "F_r_c_N",
                             "F_z_c_N", "F_r_min", "F_z_max", "Gamma_r_max", "Gamma_z_max",
                             "theta_m"}),
    "report/_fig_explorer.py": ("draws explorer.json (report/_explorer.py's file)",
                                {"H_mm", "G_kPa", "F_z_c_N", "F_z_max"}),
    "report/_labels.py": ("the display name of a symbol (t_m, G_star, theta_m), one home for "
                          "every label", {"t_m", "G_star", "theta_m"}),
    "report/_fig_metamodel.py": ("the names of the force models, which also key the accuracy "
                                 "of publication.json's records", {"f_r", "f_z"}),
    "report/_card.py": ("names the seed-spread figures of publication.json it shows on the "
                        "card (magtact.publication's figure names)",
                        {"H_star", "G_star", "Gamma_r_orig", "Gamma_r_star", "Gamma_z_orig",
                         "Gamma_z_star", "sigma_Fr_star", "sigma_Fz_star"}),
    "cli/_budget.py": ("checks the held-out accuracy figures of publication.json's spread "
                       "that budget --seed-study takes (magtact.publication's figure names)",
                       {"acc_f_r", "acc_f_z"}),
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
def written_keys(tmp_path_factory, magone_design, magone_budgets) -> dict[str, set[str]]:
    """key → the files of other modules that write it."""
    from magtact._runfolder import RunManifest, StageRecord

    result = magone_design
    folder = tmp_path_factory.mktemp("written")
    docs = {p.name: json.loads(p.read_text(encoding="utf-8"))
            for p in magtact.write_results_into(result, folder, figures=False, budget=True,
                                                budgets=magone_budgets)
            if p.suffix == ".json"}
    docs["calibration.json"] = magtact.calibrate(result, degrees=(4,),
                                                 table_sizes=(16,)).to_json()
    docs["run.json"] = RunManifest(
        "id", "study", "magtact run", "now", stages=[StageRecord("doe", "DOE", "ok", 1.0)],
        doe_source="bundled", wall_time_s=2.0, interrupted="KeyboardInterrupt",
        finished="now").to_json()
    docs["publication.json"] = _publication(tmp_path_factory.mktemp("publication"))
    out: dict[str, set[str]] = {}
    for name, doc in docs.items():
        if name in OWN:
            continue
        for k in keys_of(doc, set()):
            if scanned(k):
                out.setdefault(k, set()).add(name)
    return out


def _publication(folder: Path) -> dict:
    """``publication.json`` of a seed study of known records (no GP fit), with a failed fit,
    an infeasible choice and the chip's σ_F."""
    from magtact.publication import Reproduction, comparison, spread
    from magtact.study import load_study
    from test_publication_report import _record

    records = [_record("jacobian", 0, 1.0), _record("published", 0, 0.5),
               {"definition": "published", "seed": 1, "ok": False, "message": "no model"}]
    records[0]["chosen"] |= {"F_r_c_N": 0.1, "F_z_c_N": 1.0} | {
        f"sigma_F{c}_{w}_mN": 1.0 for c in "rz" for w in ("0", "worst")}
    records[1]["chosen_reference"] = {"infeasible": "no design"}
    Reproduction(load_study("magone"), (0, 1), records, spread(records), comparison(records),
                 1.0, 1).write(folder)
    return json.loads((folder / "publication.json").read_text(encoding="utf-8"))


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
            "run.json", "publication.json"} <= files
    for key in ("at_rest_mN", "worst_mN", "smallest_pitch_mm", "Gamma_r_max_N_per_T",
                "wall_time_s", "run_id", "F_r_mN", "sigma_F_r_mN", "g_r_N", "G_range_Pa",
                "definition_of_study", "gamma_z_curve", "dF_z_rel", "max_over_min",
                "scale_free", "theta_rad"):
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
