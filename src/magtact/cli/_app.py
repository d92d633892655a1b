"""The typer application and helpers shared by every command."""

from __future__ import annotations

import contextlib
import select
import sys
import tempfile
from collections.abc import Iterator
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from typer.core import TyperGroup

from .._errors import MagtactError
from .._numbers import parse_float, parse_int
from .._runfolder import CommandOutputs, command_outputs
from ..study import MESH_DENSITIES, Study, load_study


class BrokenPipeFault(RuntimeError):
    """A pipe to another process (not the terminal's output) broke, e.g. to a worker process
    that failed to start."""


def standard_stream_closed() -> bool:
    """True if the reader of this process's stdout or stderr has gone (``magtact ... | head``).

    A pipe whose reader closed polls as an error on its write end (Linux, macOS); a stream that
    is no file (a test's capture) is never closed.
    """
    for stream in (sys.stdout, sys.stderr):
        try:
            fd = stream.fileno()
            poll = select.poll()
            poll.register(fd, select.POLLOUT)
            if any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poll.poll(0)):
                return True
        except (AttributeError, OSError, ValueError):
            continue
    return False


def strict_numbers(command) -> None:
    """Make the number options and arguments of ``command`` follow the usual grammar
    (:mod:`magtact._numbers`): ``--f-lo 1_0`` is refused, not read as 10."""
    for param in getattr(command, "params", []):
        kind = getattr(getattr(param, "type_descriptor", None), "annotation", None)
        if kind not in (float, int):
            continue
        parse = parse_float if kind is float else parse_int
        hint = ("digits, an optional sign, '.' and exponent, e.g. 2.5 or -1e-3" if kind is float
                else "digits and an optional sign, e.g. 40")

        def process_value(ctx, value, _original=param.process_value, _parse=parse,
                          _param=param, _hint=hint):
            for item in value if isinstance(value, list | tuple) else [value]:
                if isinstance(item, str):
                    try:
                        _parse(item)
                    except ValueError as exc:
                        raise typer.BadParameter(f"{exc} ({_hint})", ctx=ctx,
                                                 param=_param) from None
            return _original(ctx, value)

        param.process_value = process_value


#: Commands in the order of the pipeline (``magtact --help`` lists them so); any other after.
ORDER = ("study", "field", "simulate", "doe", "fit", "optimise", "compare", "budget",
         "calibrate", "validate", "reproduce", "run", "report")


class _Group(TyperGroup):
    """The command group: number options follow the usual grammar (:func:`strict_numbers`);
    commands are listed in pipeline order (:data:`ORDER`); a broken pipe is click's quiet exit
    only when it is the terminal's output that closed; any other broken pipe is raised as
    :class:`BrokenPipeFault`, so that the exit says why."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for command in self.commands.values():
            strict_numbers(command)

    def list_commands(self, ctx):
        rank = {name: k for k, name in enumerate(ORDER)}
        return sorted(self.commands, key=lambda n: (rank.get(n, len(ORDER)), n))

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except BrokenPipeError as exc:
            if standard_stream_closed():
                raise
            raise BrokenPipeFault(f"a pipe to another process broke ({exc}): e.g. a worker "
                                  "process failed to start or died") from exc


#: The ``magtact`` command line (typer); each command's module registers its command on it.
app = typer.Typer(
    cls=_Group,
    name="magtact",
    help="Design magnetic soft tactile sensors: field, mechanics, DOE, metamodels, optimisation.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    # Plain help text: option help carries its unit in brackets ("[mm]", "[kPa]"), which
    # rich's markup would read as a style tag and drop.
    rich_markup_mode=None,
)
#: Diagnostics (progress, what a command does, warnings) go to stderr; messages keep their
#: lines whole (paths can be copied from a log); a terminal wraps them.
console = Console(stderr=True, soft_wrap=True)
#: Width of the tables written to a file or a pipe (a terminal's own width otherwise).
TABLE_WIDTH = 160


def tables() -> Console:
    """The console of a command's results (tables): stdout, at the terminal's width or, into a
    file or a pipe, :data:`TABLE_WIDTH` columns so that headers are not cut."""
    out = Console()
    return out if out.is_terminal else Console(width=TABLE_WIDTH)


#: Exit status of a command whose answer is that no design meets the study's requirements
#: (the answer is printed: each requirement's best figure, what binds, what to relax).
EXIT_INFEASIBLE = 3


#: Rows of the card printed where it judges no requirement (the publication's problem).
CARD_ROWS = 8
#: Label of a requirement's answer over the units built (the robust verdict), printed under
#: its nominal answer.
UNITS_LABEL = "units built"


def answer_lines(card: dict, tail: list[tuple[str, str]] | None = None
                 ) -> list[tuple[str, str]]:
    """The answer of a design card (``card.json``: its ``verdict``, ``parts`` and, for a
    specification no design meets, ``infeasible``) as ``(label, value)`` rows: each
    requirement with its answer and margin, then the parts, the force noise and ``tail``."""
    from .._display import infeasible_rows, requirement_rows, round_text

    infeasible = card.get("infeasible")
    if isinstance(infeasible, dict):
        return infeasible_rows(infeasible)[1] + list(tail or [])
    answers = card.get("answers") or [{}]
    first = answers[0] if isinstance(answers[0], dict) else {}
    robust = first.get("robust_verdict")
    built = {r.get("requirement"): r for r in (robust.get("requirements") or [])
             if isinstance(r, dict)} if isinstance(robust, dict) else {}
    rows = []
    items = [v for v in card.get("verdict") or [] if isinstance(v, dict)]
    for v, row in zip(items, requirement_rows(items), strict=True):
        rows.append(row)
        unit = built.get(v.get("requirement"))
        if isinstance(unit, dict) and unit.get("answer"):  # the same line over the units built
            text = str(unit["answer"]).replace(" of units", "", 1)
            rows.append((UNITS_LABEL, round_text(text)))
    parts = [p for p in card.get("parts") or [] if isinstance(p, (list, tuple)) and len(p) == 2]
    rows += [(str(k), round_text(str(v))) for k, v in parts]
    if not rows:  # no requirements judged (the publication's problem): the card's first rows
        rows = [(str(r[0]), round_text(str(r[1]))) for r in (card.get("rows") or [])[:CARD_ROWS]
                if isinstance(r, (list, tuple)) and len(r) > 1]
    s_r, s_z = (first.get(f"sigma_F{a}_required_loads_mN") for a in "rz")
    if isinstance(s_r, float) and isinstance(s_z, float) and s_r == s_r:
        from .._display import sig

        rows.append(("force noise σ_F (1 σ)", f"{sig(s_r)} mN shear, {sig(s_z)} mN normal, "
                                              "worst over the required loads"))
    return rows + list(tail or [])


def answer_title(card: dict, study: str) -> str:
    """The first line of a printed answer: the study and the verdict in a few words."""
    from .._display import verdict_title

    if isinstance(card.get("infeasible"), dict):
        return f"{study}: no design meets the requirements"
    if not card.get("verdict"):
        return f"{study}, chosen design"
    return f"{study}, chosen design: {verdict_title(card.get('verdict'))}"


def answer_text(card: dict, study: str, tail: list[tuple[str, str]] | None = None
                ) -> list[str]:
    """The lines :func:`print_answer` prints: the title, each requirement (mark and statement)
    over its answer and margin, then the parts, the force noise and ``tail``, one per line."""
    lines = [answer_title(card, study)]
    for label, value in answer_lines(card, tail):
        if label[:1] in "✓✗?" and label[1:2] == " ":
            lines += [f"  {label}", f"      {value}"]
        elif label == UNITS_LABEL:
            lines.append(f"      {label}: {value}")
        else:
            lines.append(f"  {label}: {value}" if label else f"  {value}")
    return lines


def print_answer(card: dict, study: str, tail: list[tuple[str, str]] | None = None,
                 out: Console | None = None) -> None:
    """Print the answer of a design card on standard output (:func:`answer_text`), short
    enough to stay on an 80 × 24 terminal's last screen: the verdict with margins, the parts,
    then ``tail`` (where the files are). Lines are whole (a terminal wraps them)."""
    from rich.text import Text

    out = out or tables()
    for k, line in enumerate(answer_text(card, study, tail)):
        out.print(Text(line, style="bold" if k == 0 else ""), soft_wrap=True)


def _version(value: bool) -> None:
    if value:
        from .. import __version__

        typer.echo(f"magtact {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option(
        "--version", is_eager=True, callback=_version,
        help="Print magtact's version and exit.")] = False,
) -> None:
    """magtact: design magnetic soft tactile sensors by simulation and optimisation."""


def renamed(old: str, new: str, usage: str | None = None):
    """A hidden option ``old`` that refuses itself naming ``new`` (an option renamed so that
    one idea has one name across the commands)."""
    def refuse(ctx: typer.Context, value):
        if value is not None:
            raise typer.BadParameter(f"{old} is now {usage or new}", ctx=ctx,
                                     param_hint=old)
        return value

    return typer.Option(old, hidden=True, callback=refuse, expose_value=True,
                        help=f"renamed: {new}")

class Solver(StrEnum):
    """Field solvers of the command line."""

    fe = "fe"
    exact = "exact"


#: Named mesh densities of the half body (``magtact.study.MESH_DENSITIES``).
MeshDensity = StrEnum("MeshDensity", {name: name for name in MESH_DENSITIES})

#: The optional STUDY argument of every command: a TOML file or a preset name.
StudyArg = Annotated[
    str | None,
    typer.Argument(help="Study TOML file or preset ('magone', 'magone-publication', "
                        "'magone-printed'); default: the built-in MagOne study."),
]


def check_out(path: Path | None) -> Path | None:
    """Option callback of ``--out``: refuse, before any work, a path that cannot become a
    folder (it or a parent is a file); None (no folder: print only) passes."""
    if path is None:
        return None
    for parent in (path, *path.parents):
        if parent.exists() and not parent.is_dir():
            raise typer.BadParameter(f"{parent} exists and is not a folder")
    return path


OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Output folder (created if needed).",
                                      callback=check_out)]
#: ``--workers``: worker processes of the FE jobs (DOE, seed study), one meaning everywhere.
WorkersOpt = Annotated[int | None, typer.Option(
    "--workers", "-j", min=0,
    help="Worker processes of the FE jobs (default: the number of cores; 0: run them in this "
         "process).")]
#: ``--cache``: the FE job cache, one meaning everywhere.
CacheOpt = Annotated[Path, typer.Option(
    "--cache", help="Job cache folder of the FE jobs: finished jobs are kept there and never "
                    "recomputed.")]
#: ``--data``: a DOE data set, one meaning everywhere.
DataOpt = Annotated[Path | None, typer.Option(
    "--data", help="DOE data set (.nc, magtact doe); default: the data set bundled with "
                   "magtact.")]
#: ``--models``: model files of ``magtact fit``, one meaning everywhere.
ModelsOpt = Annotated[Path | None, typer.Option(
    "--models", help="Folder of metamodel files (B_r.json, B_z.json, f_r.json, f_z.json; "
                     "magtact fit); default: the fit shipped with magtact where it matches the "
                     "bundled data set, else a new fit to it.")]


def get_study(source: str | None) -> Study:
    """Load the study for a command (errors are reported by :func:`magtact.cli.main`)."""
    return load_study(source)


def out_dir(path: Path) -> Path:
    """Create and return an output folder, checked to be a folder this process can write.

    Raises
    ------
    MagtactError
        If ``path`` (or a parent) exists and is not a folder, or the folder is not writable.
    """
    for parent in (path, *path.parents):
        if parent.exists() and not parent.is_dir():
            raise MagtactError(f"--out {path}: {parent} exists and is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=path, prefix=".magtact-write-test-")
        probe.close()
    except OSError as exc:
        raise MagtactError(f"--out {path}: cannot write there ({exc.strerror or exc})") from None
    return path


@contextlib.contextmanager
def outputs(command: str, path: Path, *expect: str) -> Iterator[CommandOutputs]:
    """The output folder of a command, with the rules of a results folder (docs/method.md §14).

    Creates ``path`` (:func:`out_dir`), takes its lock and yields a
    :class:`magtact._runfolder.CommandOutputs`: the command writes into its ``folder`` (a
    staging folder) and names files with ``final``; at the end of the block the files are put
    in ``path``, never replacing a file magtact did not write there (or a run's results).
    ``command``: the command's name (recorded with its files and in the lock); ``expect``:
    names in ``path`` the command always writes, checked before the work.

    Raises
    ------
    MagtactError
        If ``path`` cannot be a writable folder, another process is writing it, or an output
        would replace a file that is not magtact's (the message names the files).
    """
    made = [p for p in (path, *path.parents) if not p.exists()]
    folder = out_dir(path)
    try:
        with command_outputs(folder, f"magtact {command} --out {path}", expect) as out:
            yield out
    except BaseException:
        for p in made:  # the folders made for the outputs, if still empty
            with contextlib.suppress(OSError):
                p.rmdir()
        raise
