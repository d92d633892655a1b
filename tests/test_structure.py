"""The package's structure: import graph between sub-packages, private modules, repository
layout, and no history or external-document references in code and tests.

The import graph is read from the source (``ast``), so it holds every import, also those inside
functions, which a run-time check would miss until the function runs.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "magtact"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path, modules=None) -> list[tuple[str, int]]:
    """Absolute names of the magtact modules ``path`` imports, with their line numbers.

    With ``modules`` (the names of every module), ``from X import a`` is the module ``X.a`` if
    there is one, else ``X``; without, both ``X.a`` and ``X`` (the names may be modules)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text("utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names if a.name.startswith("magtact")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            if not name.startswith("magtact"):
                continue
            if modules is not None:
                out += [(f"{name}.{a.name}" if f"{name}.{a.name}" in modules else name,
                         node.lineno) for a in node.names]
            else:  # "from . import x" / "from .report import fig_doe"
                out += [(f"{name}.{a.name}", node.lineno) for a in node.names]
                out.append((name, node.lineno))
    return out


def _unit(module: str) -> str | None:
    """The sub-package (or top-level module) of ``magtact`` that ``module`` belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def _sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def import_graph() -> dict[str, dict[str, list[str]]]:
    """unit → imported unit → ["file:line", ...] over the whole package."""
    units = {p.name if p.is_dir() else p.stem for p in PACKAGE.iterdir()
             if (p.is_dir() and (p / "__init__.py").is_file()) or p.suffix == ".py"}
    graph: dict[str, dict[str, list[str]]] = {}
    for path in _sources():
        src = _unit(_module_name(path))
        if src is None or src == "__init__":
            continue
        for name, line in _imports(path):
            dst = _unit(name)
            if dst is None or dst == src or dst not in units:
                continue
            where = f"{path.relative_to(ROOT)}:{line}"
            sites = graph.setdefault(src, {}).setdefault(dst, [])
            if where not in sites:
                sites.append(where)
    return graph


def find_cycle(graph: dict[str, dict[str, list[str]]]) -> list[str] | None:
    """One cycle of ``graph`` as a list of units (first = last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(u: str) -> list[str] | None:
        state[u] = 1
        stack.append(u)
        for v in sorted(graph.get(u, {})):
            if state.get(v) == 1:
                return stack[stack.index(v):] + [v]
            if v not in state and (cycle := visit(v)):
                return cycle
        stack.pop()
        state[u] = 2
        return None

    for u in sorted(graph):
        if u not in state and (cycle := visit(u)):
            return cycle
    return None


def test_find_cycle_finds_a_cycle_and_only_a_cycle():
    assert find_cycle({"a": {"b": []}, "b": {"c": []}, "c": {"a": []}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b": [], "c": []}, "b": {"c": []}}) is None


def test_relative_imports_resolve_to_absolute_module_names():
    imports = dict(_imports(PACKAGE / "optimise" / "_run.py"))
    assert "magtact.metamodel" in imports and "magtact.optimise._design" in imports


def test_no_import_cycle_between_sub_packages():
    graph = import_graph()
    assert "report" in graph and "pipeline" in graph  # the graph was read
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle " + " -> ".join(cycle) + ": " + "; ".join(
        f"{a} -> {b} at {', '.join(graph[a][b])}" for a, b in zip(cycle, cycle[1:], strict=False))


# ---- the graph between modules -------------------------------------------------------------
def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in _sources()}


@functools.cache
def module_graph() -> dict[str, dict[str, list[int]]]:
    """module → imported module → line numbers, over every module of the package (imports
    inside functions included)."""
    modules = _modules()
    graph: dict[str, dict[str, list[int]]] = {}
    for name, path in modules.items():
        for target, line in _imports(path, modules):
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target != name:
                graph.setdefault(name, {}).setdefault(target, []).append(line)
    return graph


def private_import(importer: str, imported: str) -> bool:
    """True if ``importer`` reaches into a private ``_module`` of a package it is not part
    of (``magtact.a._b`` is private to ``magtact.a``)."""
    parts = imported.split(".")
    for k in range(1, len(parts)):
        parent = ".".join(parts[:k])
        if parts[k].startswith("_") and not (importer == parent
                                             or importer.startswith(parent + ".")):
            return True
    return False


def test_the_module_graph_sees_circles_and_private_imports():
    graph = module_graph()
    assert "magtact.metamodel._symbols" in graph["magtact.metamodel._fit"]
    assert "magtact.study" in graph["magtact.mechanics._simulate"]
    assert private_import("magtact.cli._report", "magtact.report._html")
    assert not private_import("magtact.report", "magtact.report._html")
    assert not private_import("magtact.report._html", "magtact.report._card")
    assert not private_import("magtact.doe._jobs", "magtact._versions")
    assert private_import("magtact.pipeline", "magtact.optimise._run")
    assert find_cycle({"m._a": {"m._b": [1]}, "m._b": {"m._a": [2]}}) == ["m._a", "m._b", "m._a"]


def test_no_import_circle_between_modules():
    graph = module_graph()
    cycle = find_cycle(graph)
    assert cycle is None, "import circle " + " -> ".join(cycle) + ": " + "; ".join(
        f"{a} -> {b} at line {graph[a][b]}" for a, b in zip(cycle, cycle[1:], strict=False))


def test_no_module_imports_another_packages_private_module():
    offenders = [f"{a} imports {b} (line {', '.join(map(str, lines))})"
                 for a, targets in module_graph().items() for b, lines in targets.items()
                 if private_import(a, b)]
    assert offenders == []


def test_stages_do_not_import_the_report():
    """Stages return data; figures come from ``magtact.report`` through the callers."""
    graph = import_graph()
    stages = ("study", "geometry", "magnetics", "mechanics", "doe", "metamodel", "sensitivity",
              "optimise", "validation")
    offenders = {s: graph[s]["report"] for s in stages if "report" in graph.get(s, {})}
    assert offenders == {}


def test_private_figure_modules_are_imported_only_inside_report():
    pattern = re.compile(r"report\._fig_|from \._fig_")
    offenders = []
    for path in _sources() + sorted((ROOT / "tests").glob("*.py")):
        if path.parent.name == "report" and path.is_relative_to(PACKAGE):
            continue
        for name, line in (_imports(path) if path.is_relative_to(PACKAGE) else []):
            if "._fig_" in name:
                offenders.append(f"{path.relative_to(ROOT)}:{line}")
        if not path.is_relative_to(PACKAGE) and path.name != Path(__file__).name:
            text = path.read_text("utf-8")
            offenders += [f"{path.relative_to(ROOT)}:{text[:m.start()].count(chr(10)) + 1}"
                          for m in pattern.finditer(text)]
    assert offenders == []


def test_library_code_does_not_read_the_repository_layout():
    offenders = [f"{p.relative_to(ROOT)}:{n}" for p in _sources()
                 for n, line in enumerate(p.read_text("utf-8").splitlines(), start=1)
                 if "parents[" in line]
    assert offenders == []


#: References to documents outside the repository or to the project's history. The words are
#: assembled so that a plain grep of the sources does not find this file.
_DOC, _TICKET, _ITEM = "SP" + "EC", "[Ii]" + "ssue", "accept" + "ance item"
HISTORY = re.compile(rf"\b{_DOC}\b|(?<![A-Za-z]){_TICKET}[ _#]?\d|\b{_ITEM}")


@pytest.mark.parametrize("folder", ["src", "tests"])
def test_no_history_or_outside_references(folder):
    offenders = []
    for path in sorted((ROOT / folder).rglob("*")):
        if path.suffix not in (".py", ".md", ".toml"):
            continue
        for n, line in enumerate(path.read_text("utf-8").splitlines(), start=1):
            if HISTORY.search(line):
                offenders.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert offenders == []


@pytest.mark.parametrize("text, found", [
    ("see " + "SP" + "EC section 6", True), ("limits of is" + "sue 5", True),
    ("meets_is" + "sue_5", True), ("accept" + "ance item 1", True),
    ("spec = {key_of(f): f}", False), ("tissues of 3 mm", False), ("tissue_3", False),
])
def test_history_pattern(text, found):
    assert bool(HISTORY.search(text)) is found


def test_no_backend_is_chosen_at_import():
    """Library code draws on Figure objects; it never selects a matplotlib backend."""
    offenders = [f"{p.relative_to(ROOT)}:{n}" for p in _sources()
                 for n, line in enumerate(p.read_text("utf-8").splitlines(), start=1)
                 if re.search(r"matplotlib\.use\(|import matplotlib\.pyplot|"
                              r"from matplotlib import pyplot", line)]
    assert offenders == []


def test_the_chip_has_one_home():
    """The setting choice, the range margin, the saturation scan and the check that the chip's
    noise is known are each defined once, in ``magtact.chip``; no other module raises the
    missing-noise error itself."""
    import magtact

    src = Path(magtact.__file__).parent
    wanted = ("setting_for", "chip_margin", "saturation", "check_rest_field", "require_noise",
              "chip_options")
    homes = {name: [] for name in wanted}
    raisers = []
    for path in src.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        rel = path.relative_to(src).as_posix()
        for name in wanted:
            if re.search(rf"^def {name}\(", text, re.M):
                homes[name].append(rel)
        if re.search(r"StudyError\(\s*\"hall\.noise_x_uT\"", text) and "needs the" in text:
            raisers.append(rel)
    for name, where in homes.items():
        assert len(where) == 1 and where[0].startswith("chip/"), (name, where)
    assert raisers == ["chip/_options.py"]


def _result_module() -> Path:
    """The module that defines ``magtact.Result`` (a class ``Result`` at its top level)."""
    homes = [p for p in _sources()
             if any(isinstance(n, ast.ClassDef) and n.name == "Result"
                    for n in ast.parse(p.read_text("utf-8")).body)]
    assert len(homes) == 1, homes
    return homes[0]


def test_the_result_is_a_plain_record():
    """``magtact.Result`` holds what was computed and nothing the report makes of it: the
    module that defines it imports no report code, not even inside a function nor through the
    modules it imports, and the class caches no computation (the card, the error budgets and
    the figures are functions of it: ``magtact.card``, ``error_budgets``, ``figures``)."""
    path = _result_module()
    module = _module_name(path)
    direct = [f"{name} (line {line})" for name, line in _imports(path)
              if name == "magtact.report" or name.startswith("magtact.report.")]
    assert direct == [], f"{module} imports the report: {direct}"
    graph, seen, todo = module_graph(), set(), [module]
    while todo:  # every module it reaches, imports inside functions included
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo += list(graph.get(m, {}))
    assert not [m for m in seen if m == "magtact.report" or m.startswith("magtact.report.")]
    tree = ast.parse(path.read_text("utf-8"))
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Result")
    members = {n.name: n for n in cls.body
               if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)}
    cached = [name for name, f in members.items() for d in f.decorator_list
              if "cached_property" in ast.unparse(d)]
    assert cached == [], f"Result caches {cached}"
    assert "cached_property" not in path.read_text("utf-8")
    assert not {"card", "budgets", "figures"} & members.keys()


# ---- chips are asked what they have, not compared by name -----------------------------------
#: Comparisons a chip name on one side makes a name test.
_EQUALITY = (ast.Eq, ast.NotEq, ast.In, ast.NotIn)
#: Names that are also a magnet's grade or size: a chip's only where the other side is one.
_SHARED = frozenset({"custom"})


def chip_names() -> frozenset[str]:
    """The names a study may give its chip (the choices of ``[hall] chip``: the chips with a
    data file, the presets and "custom") and the names the chips' data files give them."""
    import dataclasses

    from magtact.parts import chip_part
    from magtact.study import Study

    hall = Study.__dataclass_fields__["hall"].default_factory
    choices = next(f.metadata["choices"] for f in dataclasses.fields(hall) if f.name == "chip")
    tables = [chip_part(n).table for n in choices]
    return frozenset(choices) | {t.name for t in tables if t is not None} | _SHARED


def _strings(node: ast.AST) -> set[str]:
    """The strings of a constant, or of the constants in a tuple, list or set."""
    items = node.elts if isinstance(node, ast.Tuple | ast.List | ast.Set) else [node]
    return {e.value for e in items if isinstance(e, ast.Constant) and isinstance(e.value, str)}


def _names_a_chip(const: ast.AST, other: ast.AST, names: frozenset[str]) -> bool:
    found = _strings(const) & names
    return bool(found - _SHARED) or bool(found) and bool(
        re.search(r"chip|hall", ast.unparse(other), re.I))


def chip_name_comparisons(source: str, names: frozenset[str]) -> list[int]:
    """Lines of ``source`` that compare a value with a chip's name (``==``, ``!=``, ``in``,
    ``not in``, or a ``match`` case) instead of asking the chip's part what it has."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            for op, a, b in zip(node.ops, sides, sides[1:], strict=False):
                if isinstance(op, _EQUALITY) and (_names_a_chip(a, b, names)
                                                  or _names_a_chip(b, a, names)):
                    lines.append(node.lineno)
        elif isinstance(node, ast.Match):
            lines += [v.lineno for case in node.cases for v in ast.walk(case.pattern)
                      if isinstance(v, ast.MatchValue)
                      and _names_a_chip(v.value, node.subject, names)]
    return sorted(lines)


def test_the_chip_name_scan_finds_name_comparisons():
    names = frozenset({"MLX90393", "TLV493D", "TLE493D", "custom"})
    found = chip_name_comparisons(
        'if h.chip == "MLX90393":\n    pass\n'
        'ok = x in ("TLV493D",)\n'
        'flat = study.hall.chip not in ["custom", "TLE493D"]\n'
        'match h.chip:\n    case "custom":\n        pass\n', names)
    assert found == [1, 3, 4, 6]
    assert chip_name_comparisons(
        'grade = "no grade named" if p.grade == "custom" else p.grade\n'
        'table = chip_table("MLX90393")\n'
        'if part.custom and part.has_settings:\n    pass\n', names) == []


def test_no_module_outside_the_chip_package_compares_chip_names():
    """Chip identity is the chip part's (``magtact.parts.chip_part``: its table, setting
    fields, rate data, tolerances, whether it is custom); code outside ``magtact.chip`` asks the
    part instead of testing the study's chip name."""
    names = chip_names()
    assert {"MLX90393", "TLV493D", "custom", "Melexis MLX90393"} <= names
    offenders = []
    for path in _sources():
        text = path.read_text("utf-8")
        # only a source that spells a chip's name can compare with it: parse just those
        if "chip" not in path.relative_to(PACKAGE).parts[:-1] and any(n in text for n in names):
            offenders += [f"{path.relative_to(ROOT)}:{n}"
                          for n in chip_name_comparisons(text, names)]
    assert offenders == []


# ---- a design's parts travel as a sensor -----------------------------------------------------
#: The study's sections that hold the parts a design chooses (magnet, chip, silicone).
PART_SECTIONS = frozenset({"magnet", "hall", "material"})


def part_replacements(source: str) -> list[int]:
    """Lines of ``source`` that build a study with other parts: a ``replace`` call that sets a
    part section (``replace(study, magnet=...)``) or changes one (``replace(study.hall,
    standoff=...)``)."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""
        if name != "replace" or not node.args:
            continue
        first = node.args[0]
        if any(k.arg in PART_SECTIONS for k in node.keywords) or (
                isinstance(first, ast.Attribute) and first.attr in PART_SECTIONS):
            lines.append(node.lineno)
    return sorted(lines)


def test_the_part_scan_finds_a_study_with_other_parts():
    found = part_replacements(
        "s = replace(study, magnet=replace(study.magnet, M_z=1.0))\n"
        "t = dataclasses.replace(s, hall=h)\n"
        "u = replace(study, requirements=r)\n"
        "v = replace(sensor, grade='N42', standoff=1e-3)\n")
    assert found == [1, 1, 2]


def test_no_module_changes_a_study_to_carry_a_designs_parts():
    """The study describes the problem; a design's magnet, chip setting and standoff and
    silicone travel as a :class:`magtact.Sensor` beside it (``Sensor.of_study`` for the study's
    own). Only ``magtact.study`` builds studies from their sections (loading a file, and
    ``Study.at``, the problem at fixed values of its geometric design variables, whose models
    are bound alike)."""
    offenders = []
    for path in _sources():
        if path.relative_to(PACKAGE).parts[0] == "study":
            continue
        text = path.read_text("utf-8")
        if "replace" in text:
            offenders += [f"{path.relative_to(ROOT)}:{n}" for n in part_replacements(text)]
    assert offenders == []


# ---- the optimisation problems ----------------------------------------------------------------
#: pymoo's problem classes.
PYMOO_PROBLEMS = frozenset({"Problem", "ElementwiseProblem"})


def pymoo_problem_classes(source: str) -> list[str]:
    """Names of the classes in ``source`` that subclass a pymoo problem class (imported from
    pymoo by name, or reached through an imported pymoo module)."""
    tree = ast.parse(source)
    classes, modules = set(), set()  # local names of pymoo's problem classes and modules
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "pymoo":
            for a in node.names:
                (classes if a.name in PYMOO_PROBLEMS else modules).add(a.asname or a.name)
        elif isinstance(node, ast.Import):
            modules |= {a.asname or a.name.split(".")[0] for a in node.names
                        if a.name.split(".")[0] == "pymoo"}

    def pymoo_problem(base: ast.AST) -> bool:
        if isinstance(base, ast.Name):
            return base.id in classes
        if isinstance(base, ast.Attribute) and base.attr in PYMOO_PROBLEMS:
            root = base.value
            while isinstance(root, ast.Attribute):
                root = root.value
            return isinstance(root, ast.Name) and root.id in modules
        return False

    return [n.name for n in ast.walk(tree)
            if isinstance(n, ast.ClassDef) and any(pymoo_problem(b) for b in n.bases)]


def test_the_problem_scan_finds_pymoo_problems():
    source = (
        "from pymoo.core.problem import Problem, ElementwiseProblem as EP\n"
        "import pymoo.core.problem\n"
        "from pymoo.core import problem as pp\n"
        "class A(Problem): pass\n"
        "def f():\n    class B(EP): pass\n"
        "class C(pymoo.core.problem.Problem): pass\n"
        "class D(pp.ElementwiseProblem): pass\n"
        "class E(object): pass\n")
    assert sorted(pymoo_problem_classes(source)) == ["A", "B", "C", "D"]
    assert pymoo_problem_classes("from mylib import Problem\nclass A(Problem): pass\n") == []


def test_at_most_two_pymoo_problems():
    """The sensor design problem and the publication's (H, G) problem; a single box is
    optimised without one (SciPy's differential evolution in ``box_optimum``)."""
    texts = {p: p.read_text("utf-8") for p in _sources()}
    found = [f"{p.relative_to(ROOT)}: {c}" for p, text in texts.items() if "pymoo" in text
             for c in pymoo_problem_classes(text)]
    assert len(found) <= 2, found
