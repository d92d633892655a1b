"""The JSON files of a results folder are written and read through the records that declare
them (``magtact._records``): no module spells a key of a file in a string literal outside a
record's declarations (the arguments of :func:`magtact._records.entry`), and JSON files are
written through the atomic writer (``magtact._files``).

The keys are collected from real documents: the bundled MagOne answer written into a folder
(``design.json``, ``chosen.json``, ``sensor.json``, ``budget.json``), its calibration's summary
(``calibration.json``), a run's manifest (``run.json``) and a seed study's file
(``publication.json``, written from records of known values). Every module of the package is
then scanned (``ast``) for those keys as string literals.

Files the report writes itself (``card.json``, ``explorer.json``, ``captions.json``) are its
own to spell. Keys that are one plain word (``rows``, ``label``, ``status``, ``design``) are
left out: they are also the words of the page and of other data (a table's ``rows``, a
figure's ``label``), so a scan for them cannot tell a key from a word; every key with a unit
or a subscript (``at_rest_mN``, ``Gamma_r_max_N_per_T``, ``wall_time_s``, ``run_id``) is
scanned.

Modules whose files are not yet declared as records are listed in :data:`PENDING`: the scan
lets them be, and fails once one of them spells no key any more, so that the list only shrinks.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

import magtact

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "magtact"
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
    "report/_card.py": ("names the seed-spread figures of publication.json it shows on the "
                        "card (magtact.publication's figure names)",
                        {"H_star", "G_star", "Gamma_r_orig", "Gamma_r_star", "Gamma_z_orig",
                         "Gamma_z_star", "sigma_Fr_star", "sigma_Fz_star"}),
    "cli/_budget.py": ("checks the held-out accuracy figures of publication.json's spread "
                       "that budget --seed-study takes (magtact.publication's figure names)",
                       {"acc_f_r", "acc_f_z"}),
    "budget/_fabrication.py": ("the names of the Monte Carlo's inputs and responses, which "
                               "name the entries of budget.json's fabrication maps",
                               {"magnet_diameter", "magnet_height", "chip_x", "chip_y",
                                "chip_z", "tilt_x", "tilt_y", "offset_r", "offset_z",
                                "cal_r", "cal_z", "Gamma_r_0", "Gamma_z_0", "F_r_min",
                                "F_z_max"}),
    "budget/_budget.py": ("the names of the fabrication responses (F_r_min, F_z_max), the "
                          "study's settings its rows cite (environment.earth_field_uT), and "
                          "the seed spread of publication.json it reads (acc_f_z) until that "
                          "file is a record",
                          {"F_r_min", "F_z_max", "remanence_tc", "earth_field",
                           "earth_field_uT", "stray_field_uT", "acc_f_z"}),
    "tolerance/_robust.py": ("the name of a unit's figure (its largest normal force)",
                             {"F_z_max"}),
    "tolerance/_units.py": ("the name of a unit's figure (its largest normal force)",
                            {"F_z_max"}),
    "magnetics/_outputs.py": ("the columns of field.csv (a table, not a JSON file)",
                              {"H_mm", "theta_rad"}),
    "optimise/_pareto.py": ("the attributes of a design (DesignResult) that compare() sets "
                            "side by side (COMPARED)",
                            {"Gamma_r_max", "Gamma_z_max", "F_r_min", "F_z_max"}),
    "_result.py": ("the keyword arguments of Result.evaluate (named in user units), which its "
                   "messages name", {"H_mm", "G_kPa", "M_z_A_per_m", "standoff_mm"}),
    "study/_load.py": ("reads the study file's [design] magnet_sizes (a study setting, declared "
                       "in magtact.study._model.Design), not sensor.json's key",
                       {"magnet_sizes"}),
    "parts/_catalogue.py": ("reads the magnet catalogue's data file (parts/data/magnets.toml: "
                            "each size's D_mm, H_mm), not a JSON file", {"H_mm"}),
    "parts/_chips.py": ("reads the chip data file of a chip with one setting "
                        "(parts/data/tlv493d.toml: its noise_source), not a JSON file",
                        {"noise_source"}),
}

#: Modules that still spell keys of the files because the files they write or read are not
#: yet declared as records (``magtact._records``); each leaves this list once it is. The scan
#: fails for a module listed here that spells no key any more.
PENDING: dict[str, str] = {}

#: Modules that write a JSON file without the atomic writer (``magtact._files``): the lock
#: file, written into the descriptor that holds the lock (a replaced file would not be the
#: locked one).
RAW_JSON_WRITER = "_runfolder.py"
#: Modules that still write JSON files with ``Path.write_text`` (not atomic); each leaves this
#: list once it writes through ``magtact._files``.
PENDING_RAW: dict[str, str] = {}

#: The names of the force metamodels: every module that picks a model spells them, and
#: publication.json keys the models' accuracy by them (names, not keys of a record).
MODEL_NAMES = {"f_r", "f_z"}


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
            if scanned(k) and k not in MODEL_NAMES:
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


def module_name(path: Path) -> str:
    """``budget/_budget.py`` for a module of the package; the path itself otherwise."""
    return str(path.relative_to(PACKAGE)) if path.is_relative_to(PACKAGE) else str(path)


def declarations(tree: ast.AST) -> set[int]:
    """The ids of the string constants that declare a record's field: the arguments of
    ``entry(...)`` (:func:`magtact._records.entry`)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and (
                getattr(node.func, "id", None) == "entry"
                or getattr(node.func, "attr", None) == "entry"):
            for arg in [*node.args, *(k.value for k in node.keywords)]:
                out |= {id(c) for c in ast.walk(arg) if isinstance(c, ast.Constant)}
    return out


def spelled(keys, sources: list[Path]) -> list[str]:
    """``file:line: key (file that writes it)`` of every string literal in ``sources`` that is
    one of ``keys``, but those :data:`ALLOWED` in its module and those of record
    declarations."""
    found = []
    for path in sources:
        allowed = ALLOWED.get(module_name(path), ("", set()))[1]
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        declared = declarations(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                    and node.value in keys and node.value not in allowed \
                    and id(node) not in declared:
                where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
                found.append(f"{where}:{node.lineno}: {node.value!r} "
                             f"(written in {', '.join(sorted(keys[node.value]))})")
    return sorted(found)


def sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def by_module(found: list[str]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for line in found:
        path = line.split(":", 1)[0]
        out.setdefault(module_name(ROOT / path), []).append(line)
    return out


def test_the_keys_are_collected_from_every_file(written_keys):
    files = set().union(*written_keys.values())
    assert {"budget.json", "chosen.json", "design.json", "calibration.json",
            "run.json", "publication.json"} <= files
    for key in ("at_rest_mN", "worst_mN", "smallest_pitch_mm", "Gamma_r_max_N_per_T",
                "wall_time_s", "run_id", "F_r_mN", "sigma_F_r_mN", "g_r_N", "G_range_Pa",
                "definition_of_study", "gamma_z_curve", "dF_z_rel", "max_over_min",
                "scale_free", "theta_rad"):
        assert key in written_keys, key


def test_no_module_spells_a_key_outside_the_records(written_keys):
    found = by_module(spelled(written_keys, sources()))
    new = [line for m, lines in found.items() if m not in PENDING for line in lines]
    assert new == [], ("JSON keys spelled outside a record's declarations (declare the file's "
                       "fields with magtact._records.entry and read it through its record):\n"
                       + "\n".join(new))
    done = sorted(set(PENDING) - set(found))
    assert done == [], f"these modules spell no key any more: remove them from PENDING: {done}"


def test_the_listed_exceptions_are_modules_of_the_package():
    for name in [*ALLOWED, *PENDING, *PENDING_RAW, RAW_JSON_WRITER]:
        assert (PACKAGE / name).is_file(), name


def test_the_declarations_are_left_out_of_the_scan(written_keys, tmp_path):
    planted = tmp_path / "declared.py"
    planted.write_text('x: float = entry("at_rest_mN", "mN")\ny = {"worst_mN": 1}\n',
                       encoding="utf-8")
    found = spelled(written_keys, [planted])
    assert len(found) == 1 and ":2: 'worst_mN' (written in budget.json)" in found[0]


def raw_json_writes(path: Path) -> list[int]:
    """The lines of ``path`` that write JSON to a file without the atomic writer:
    ``json.dump(...)``, and a method ``write`` / ``write_text`` / ``write_bytes`` (of a path, a
    file, ``os``) given ``json.dumps(...)``."""
    lines = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        if node.func.attr == "dump" and getattr(node.func.value, "id", None) == "json":
            lines.append(node.lineno)
        elif node.func.attr in ("write", "write_text", "write_bytes") and any(
                isinstance(c, ast.Call) and isinstance(c.func, ast.Attribute)
                and c.func.attr == "dumps" for a in node.args for c in ast.walk(a)):
            lines.append(node.lineno)
    return lines


def test_json_files_are_written_through_the_atomic_writer():
    raw = {module_name(p): lines for p in sources() if (lines := raw_json_writes(p))}
    others = sorted(m for m in raw if m not in PENDING_RAW)
    assert others in ([], [RAW_JSON_WRITER]), (
        "JSON written without magtact._files.write_json / write_text (atomic): "
        + ", ".join(f"{m}:{raw[m]}" for m in others if m != RAW_JSON_WRITER))
    done = sorted(set(PENDING_RAW) - set(raw))
    assert done == [], f"these modules write JSON atomically now: remove them from " \
                       f"PENDING_RAW: {done}"


def test_the_raw_write_scan_finds_a_planted_write(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text("import json, os\nfrom pathlib import Path\n"
                       "Path('a.json').write_text(json.dumps({}))\n"
                       "json.dump({}, open('b.json', 'w'))\n"
                       "write_text(Path('c.json'), json.dumps({}))\n", encoding="utf-8")
    assert raw_json_writes(planted) == [3, 4]


def test_the_scan_finds_a_planted_key(written_keys, tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text('def f(doc):\n    return doc["at_rest_mN"]\n', encoding="utf-8")
    found = spelled(written_keys, [planted])
    assert len(found) == 1 and ":2: 'at_rest_mN' (written in budget.json)" in found[0]
