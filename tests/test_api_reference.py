"""The public surface: a bounded number of exported names (``__all__``), each documented and
listed in the generated docs/api.md, which is current; the user documents name only exported
names."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "api.md"
#: The most names magtact exports, the top level and every sub-package together.
MOST_NAMES = 200
#: The documents a user reads whose code may name magtact's sub-packages' names.
USER_DOCS = ("README.md", "docs/usage.md", "docs/method.md")


def _script():
    spec = importlib.util.spec_from_file_location("make_api", ROOT / "scripts" / "make_api.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


make_api = _script()


def _exported() -> list[tuple[object, str]]:
    return [(m, name) for m in make_api.packages() for name in make_api.exported(m)]


def test_at_most_200_names_are_exported():
    counts = {m.__name__: len(make_api.exported(m)) for m in make_api.packages()}
    assert {"magtact", "magtact.study", "magtact.optimise", "magtact.cli"} <= counts.keys()
    assert sum(counts.values()) <= MOST_NAMES, counts


def test_every_exported_name_exists_once_in_its_all():
    for module, name in _exported():
        assert hasattr(module, name), f"{module.__name__}.{name}"
    for module in make_api.packages():
        names = make_api.exported(module)
        assert len(names) == len(set(names)), module.__name__


def test_every_exported_class_and_function_has_its_own_docstring():
    missing = [f"{m.__name__}.{name}" for m, name in _exported()
               if make_api.kind(getattr(m, name)) in ("class", "exception", "function")
               and not make_api.summary(make_api.own_doc(getattr(m, name)))]
    assert missing == []


def test_a_dataclass_without_a_docstring_has_none_of_its_own():
    from dataclasses import dataclass

    @dataclass
    class Bare:
        x: int

    @dataclass
    class Said:
        """Said."""

        x: int

    assert make_api.own_doc(Bare) is None and make_api.own_doc(Said) == "Said."


def test_the_reference_is_what_the_script_writes():
    assert make_api.document() == API.read_text("utf-8"), (
        "docs/api.md is stale: run python scripts/make_api.py")


def test_the_reference_lists_every_exported_name_and_no_other():
    text = API.read_text("utf-8")
    listed = re.findall(r"^### `(magtact[\w.]*)`$", text, flags=re.MULTILINE)
    assert sorted(listed) == sorted(f"{m.__name__}.{name}" for m, name in _exported())


def test_signatures_show_no_memory_address_and_no_private_module():
    text = API.read_text("utf-8")
    assert not re.search(r"0x[0-9a-f]{6,}", text)
    assert not re.search(r"magtact(\.\w+)*\._(?!_)\w+", text)


def test_summaries_are_the_first_paragraph_in_markdown():
    doc = """First line with ``code`` and :func:`magtact.design`,
    :class:`~magtact.study.Study`.

    Parameters
    ----------
    x : int
    """
    assert make_api.summary(doc) == ("First line with `code` and `magtact.design`,\n"
                                     "`magtact.study.Study`.")
    assert make_api.summary(None) == ""


# ---- the documents name only exported names --------------------------------------------------
def _code(text: str) -> list[str]:
    """Each line of a fenced block and each inline code span of a Markdown text."""
    fenced = re.findall(r"^```[^\n]*\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL)
    rest = re.sub(r"^```[^\n]*\n.*?^```", "", text, flags=re.MULTILINE | re.DOTALL)
    return [line for block in fenced for line in block.splitlines()] + re.findall(
        r"`([^`]+)`", rest)


def _named(text: str) -> set[tuple[str, str]]:
    """(package, name) for each ``magtact.<package>.<name>`` and ``from magtact.<package>
    import a, b`` in the code of ``text``."""
    found = set()
    for code in _code(text):
        found |= set(re.findall(r"(?<![\w.])magtact\.([a-z]\w*)\.(\w+)", code))
        for pkg, names in re.findall(r"from magtact\.([a-z]\w*) import ([\w, ]+)", code):
            found |= {(pkg, n.strip()) for n in names.split(",") if n.strip()}
    return found


def _sub_packages() -> set[str]:
    return {m.__name__.split(".", 1)[1] for m in make_api.packages()[1:]}


def _not_exported(pkg: str, name: str) -> bool:
    module = importlib.import_module(f"magtact.{pkg}")
    if name in make_api.exported(module):
        return False
    try:  # a module of the package (``python -m magtact.doe.bundle``): not a name
        importlib.import_module(f"magtact.{pkg}.{name}")
        return False
    except ImportError:
        return True


def _top_named(text: str) -> set[str]:
    """Each ``magtact.<name>`` in the code of ``text`` (a sub-package, a module or a name)."""
    return {n for code in _code(text) for n in re.findall(r"(?<![\w.])magtact\.(\w+)", code)}


def _top_not_exported(name: str) -> bool:
    import magtact

    if name in magtact.__all__:
        return False
    try:  # a sub-package or a module (``magtact.pipeline``)
        importlib.import_module(f"magtact.{name}")
        return False
    except ImportError:
        return True


@pytest.mark.parametrize("doc", USER_DOCS)
def test_the_documents_name_only_exported_names(doc):
    text = (ROOT / doc).read_text("utf-8")
    packages = _sub_packages()
    named = {(p, n) for p, n in _named(text) if p in packages}
    wrong = sorted(f"magtact.{p}.{n}" for p, n in named if _not_exported(p, n))
    wrong += sorted(f"magtact.{n}" for n in _top_named(text) if _top_not_exported(n))
    assert wrong == [], f"{doc} names what magtact does not export"


def test_the_name_check_sees_both_spellings_and_an_internal_name():
    text = ("Use `magtact.doe.load_bundled()` and\n```python\nfrom magtact.study import "
            "load_study, mm\nmagtact.chip.setting_for(m, s, d)\n```\n")
    assert _named(text) == {("doe", "load_bundled"), ("study", "load_study"), ("study", "mm"),
                            ("chip", "setting_for")}
    assert not _not_exported("doe", "load_bundled") and not _not_exported("doe", "bundle")
    assert _not_exported("study", "mm")  # importable, but not a user's name
    assert _top_named("`magtact.design(s)`, `magtact.doe`") == {"design", "doe"}
    assert not _top_not_exported("design") and not _top_not_exported("pipeline")
    assert _top_not_exported("solve_fe")
    assert inspect.ismodule(importlib.import_module("magtact.doe.bundle"))
