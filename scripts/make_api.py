"""Write docs/api.md: the public names of magtact, as its ``__all__`` lists give them.

For the top level and each sub-package: the first paragraph of its docstring, then each name of
its ``__all__`` (in that order) with its signature (a class: its constructor's; a constant: its
type) and the first paragraph of its docstring (a constant: its ``#:`` comment). Rerun after a
change to a public name, its signature or its docstring::

    python scripts/make_api.py [--out docs/api.md]

``tests/test_api_reference.py`` checks that docs/api.md is what this script writes.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import pkgutil
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WIDTH = 100  # a signature longer than this is written one parameter a line
#: What a value that no ``#:`` comment describes is.
VALUES = {"__version__": "The installed version of magtact (its package metadata)."}


def packages() -> list:
    """magtact and its public sub-packages (not the plain modules such as ``pipeline``)."""
    import magtact

    subs = [m.name for m in pkgutil.iter_modules(magtact.__path__)
            if m.ispkg and not m.name.startswith("_")]
    return [magtact] + [importlib.import_module(f"magtact.{name}") for name in sorted(subs)]


def exported(module) -> list[str]:
    return list(getattr(module, "__all__", None) or [])


def summary(doc: str | None) -> str:
    """The first paragraph of a docstring, its reStructuredText roles as Markdown code."""
    if not doc:
        return ""
    first = inspect.cleandoc(doc).split("\n\n")[0].strip()
    first = re.sub(r":[a-z]+:`~?([^`]+)`", lambda m: f"`{m.group(1)}`", first)
    first = first.replace("``", "`")
    return first.rstrip(":") + ("." if first.endswith(":") else "")


def own_doc(obj) -> str | None:
    """The docstring ``obj`` itself has (not one a dataclass writes for it, not a base's)."""
    if inspect.isclass(obj):
        doc = obj.__dict__.get("__doc__")
        if doc and doc.startswith(f"{obj.__name__}(") and hasattr(obj, "__dataclass_fields__"):
            return None  # the signature dataclasses put where there was none
        return doc
    return getattr(obj, "__doc__", None)


def kind(obj) -> str:
    if inspect.ismodule(obj):
        return "module"
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.isroutine(obj):
        return "function"
    return "constant"


def _annotation(ann) -> str:
    """An annotation as written (a string under ``from __future__ import annotations``), a
    class by its own name rather than the private module that defines it."""
    text = ann if isinstance(ann, str) else inspect.formatannotation(ann)
    return re.sub(r"\b(?:[A-Za-z_]\w*\.)+(?=[A-Z]\w*\b)", "", text) if "magtact" in text else text


def _default(value) -> str:
    text = repr(value)
    text = re.sub(r" at 0x[0-9a-fA-F]+", "", text)  # no memory addresses
    text = re.sub(r"\b(?:Posix|Windows)Path\(", "Path(", text)
    return text if len(text) <= 40 else "..."


def _parameters(sig: inspect.Signature) -> list[str]:
    out, star_done = [], False
    params = list(sig.parameters.values())
    for i, p in enumerate(params):
        if p.kind is p.KEYWORD_ONLY and not star_done:
            out.append("*")
            star_done = True
        if p.kind is p.VAR_POSITIONAL:
            star_done = True
        text = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "") + p.name
        if p.annotation is not p.empty:
            text += f": {_annotation(p.annotation)}"
        if p.default is not p.empty:
            text += (" = " if p.annotation is not p.empty else "=") + _default(p.default)
        out.append(text)
        if p.kind is p.POSITIONAL_ONLY and (i + 1 == len(params)
                                            or params[i + 1].kind is not p.POSITIONAL_ONLY):
            out.append("/")
    return out


def signature(name: str, obj) -> str:
    """``name(parameters) -> return``; one parameter a line where one line is too long."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):  # e.g. an exception class without its own __init__
        return f"{name}(*args)"
    params = _parameters(sig)
    ret = ""
    if sig.return_annotation is not sig.empty and not inspect.isclass(obj):
        ret = f" -> {_annotation(sig.return_annotation)}"
    one = f"{name}({', '.join(params)}){ret}"
    if len(one) <= WIDTH:
        return one
    return f"{name}(\n" + "".join(f"    {p},\n" for p in params) + f"){ret}"


def _comment_above(path: Path, name: str) -> str | None:
    """The ``#:`` comment lines right above the top-level assignment of ``name`` in ``path``."""
    text = path.read_text("utf-8")
    lines = text.splitlines()
    for node in ast.parse(text).body:
        targets = (node.targets if isinstance(node, ast.Assign)
                   else [node.target] if isinstance(node, ast.AnnAssign) else [])
        if any(isinstance(t, ast.Name) and t.id == name for t in targets):
            comment, i = [], node.lineno - 2
            while i >= 0 and lines[i].lstrip().startswith("#:"):
                comment.insert(0, lines[i].lstrip()[2:].strip())
                i -= 1
            return " ".join(comment) or None
    return None


def constant_doc(module, name: str) -> str | None:
    """The ``#:`` comment of a constant, where the package's modules define it."""
    folder = Path(module.__file__).parent
    for path in [folder / "__init__.py", *sorted(folder.glob("_*.py"))]:
        if path.is_file() and (found := _comment_above(path, name)) is not None:
            return found
    return None


def entry(module, name: str) -> list[str]:
    obj = getattr(module, name)
    what = kind(obj)
    full = f"{module.__name__}.{name}"
    out = [f"### `{full}`", ""]
    if what in ("function", "class", "exception"):
        out += ["```python", signature(name, obj), "```", ""]
        if what == "exception":
            out += [f"*exception* (a `{obj.__mro__[1].__name__}`)", ""]
        text = summary(own_doc(obj))
    elif what == "module":
        out += ["*module*", ""]
        text = summary(obj.__doc__)
    else:  # a constant (a builtin value) or another object: its type
        cls = type(obj)
        if cls.__module__ == "builtins":
            out += [f"*{cls.__qualname__}*", ""]
        else:
            out += [f"*an instance of `{cls.__module__}.{cls.__qualname__}`*", ""]
        text = VALUES.get(name) or summary(constant_doc(module, name))
    if text:
        out += [text, ""]
    return out


def document() -> str:
    """docs/api.md as text."""
    pkgs = packages()
    total = sum(len(exported(m)) for m in pkgs)
    out = ["# API reference", "",
           "Generated by `scripts/make_api.py` from each package's `__all__` and docstrings; do "
           "not edit by hand (`tests/test_api_reference.py` checks that it is current).", "",
           "These are the names a user needs: the functions to call, the types they return, the "
           "errors to catch. A sub-package's namespace holds more names, the interface between "
           "magtact's sub-packages; those may change without notice. Units are SI unless a "
           "name says otherwise (docs/CONTRACTS.md).", "",
           f"{total} names in {len(pkgs)} modules:", ""]
    out += [f"- [`{m.__name__}`](#{m.__name__.replace('.', '')}) ({len(exported(m))})"
            for m in pkgs]
    out.append("")
    for module in pkgs:
        out += [f"## {module.__name__}", "", summary(module.__doc__), ""]
        for name in exported(module):
            out += entry(module, name)
    return "\n".join(out).rstrip("\n") + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "api.md")
    args = parser.parse_args()
    args.out.write_text(document(), encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
