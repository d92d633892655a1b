"""The self-contained HTML report of a results folder.

The report is built from the files a run leaves in its folder, never from memory, so that
``magtact report DIR`` can rebuild it at any time and a missing stage is reported as missing:

* ``run.json`` — the manifest written by :func:`magtact.pipeline.run_study`: per stage its
  status (``ok``, ``failed``, ``skipped``), wall time and message; versions; timings.
* ``study.toml`` — the full study settings.
* one folder per stage (``field``, ``doe``, ``metamodel``, ``optimise``, ``validation``) with its
  figures (PNG, embedded as base64), tables (CSV), text (TXT, TEX) and summaries (JSON); an
  optional ``captions.json`` maps a file name without suffix to its caption.
* ``evidence/*.json`` — accuracy and convergence benchmarks (``magtact run --evidence DIR``).
"""

from __future__ import annotations

import csv
import json
import math
import re
from datetime import UTC, datetime
from pathlib import Path

from .._card import SILICONES_KEY, SIZES_KEY, CardChoices
from .._errors import MissingFileError
from .._runfolder import MANIFEST, RunManifest, StageRecord
from ..study import from_si
from ._card import UNITS_ROW, read_card
from ._explorer import explorer_section
from ._fragments import collecting, damaged_section, load_captions, load_record, read_text
from ._fragments import escape as _e
from ._fragments import figure as _figure
from ._fragments import load_json as _load_json
from ._labels import label, round_text, sig, value_text
from ._markdown import mathml, render_markdown
from ._publication import publication_section

#: Stages in pipeline order: (folder, title, what it is).
STAGES: tuple[tuple[str, str, str], ...] = (
    ("field", "Magnetic field",
     "Field of the magnet (finite elements, checked against the exact closed form) and the "
     "field at the Hall point along the loading paths."),
    ("doe", "Design of experiments",
     "Full-factorial data set of field and forces over (t, θ, H, G)."),
    ("metamodel", "Metamodels",
     "Closed-form expressions fitted by genetic programming, with held-out accuracy."),
    ("optimise", "Optimisation",
     "Per-design extrema, maps over (H, G), Pareto set (NSGA-II) and its exact reduction, "
     "and the chosen design."),
    ("budget", "Error budget",
     "Everything besides the force that moves the field, as a false force in mN."),
    ("calibration", "Calibration: the field-to-force map",
     "The force from the three field readings, for firmware (C, JSON, CSV)."),
    ("validation", "Validation against experiments",
     "Mean ± standard deviation of repeat indentation tests against the model; c_v and ε."),
)
#: File in each stage folder naming the run that wrote it (see :mod:`magtact.pipeline`).
RUN_STAMP = ".magtact-run"
#: JSON files of a stage folder that are not shown as data.
SKIP_JSON = ("captions.json", "chosen.json")
#: Rows of a CSV table shown in the report (the file has them all).
MAX_ROWS = 30

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;max-width:1100px;
margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em}h2{border-bottom:2px solid #ddd;padding-bottom:.2em;
margin-top:2em}h3{font-size:1.05em;margin-top:1.4em}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}
th,td{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#f3f3f3}
td.l,th.l{text-align:left}
figure{margin:1em 0;text-align:center}figure img{max-width:min(100%,900px);border:1px solid #eee}
figcaption{font-size:.85em;color:#555}
img.embedded{display:block;max-width:min(100%,700px);margin:1em auto}
pre{background:#f7f7f7;padding:.7em;overflow-x:auto;font-size:.8em}
.ok{color:#176b2c;font-weight:bold}.failed{color:#b00020;font-weight:bold}
.skipped,.absent{color:#8a6d00;font-weight:bold}
.banner{background:#fff3cd;border:1px solid #e0c060;padding:.6em 1em;margin:1em 0}
.missing{background:#fbe9eb;border:1px solid #e0a0a8;padding:.6em 1em;margin:1em 0}
.design{background:#eef6ee;border:1px solid #9c9;padding:.6em 1em;margin:1em 0}
details{margin:.5em 0}summary{cursor:pointer}
*{box-sizing:border-box}img,svg,table,pre{max-width:100%}
.intro{font-size:.9em;color:#444;margin:.2em 0 .6em}
.front{display:grid;grid-template-columns:minmax(0,3fr) minmax(0,2fr);gap:1.2em;
align-items:start;margin:.6em 0}.front h2{margin-top:.4em}
ul.verdict-list{list-style:none;padding-left:0;margin:.3em 0}
ul.verdict-list li{padding:.25em .5em;margin:.2em 0;border-left:5px solid #999}
li.met{border-color:#2a8a3e!important;background:#eef8f0}
li.unmet{border-color:#c0392b!important;background:#fcecea}
table.parts td,table.parts th,table.choices td,table.choices th{text-align:left}
#choices h3{margin:.6em 0 .2em;font-size:1em}
.glance{display:grid;grid-template-columns:repeat(auto-fit,minmax(420px,1fr));gap:1em}
.glance figure img{max-width:100%;max-height:440px}.glance .span{grid-column:1/-1}
@media print{.glance{grid-template-columns:1fr 1fr}.glance figure img{max-height:300px}}
.xctl{display:flex;flex-wrap:wrap;gap:.6em;align-items:center;margin:.5em 0}
.xctl input[type=range]{width:220px}.xctl input[type=number]{width:7em}
.xgrid{display:grid;grid-template-columns:minmax(0,3fr) minmax(0,2fr);gap:1em}
.xcard table{font-size:.8em}
div.math{overflow-x:auto;margin:.6em 0}td div.math{max-width:60vw}
div.wide{overflow-x:auto;max-width:100%}math{font-size:1.05em}
td,th{overflow-wrap:anywhere}
nav.toc{font-size:.85em}
"""


def build_report(folder: str | Path, *, evidence: str | Path | None = None,
                 damaged: dict[str, str] | None = None) -> Path:
    """Write ``report.html`` for a results folder and return its path.

    The folder's lock is taken while the report is built (a run writing the folder makes this
    refuse, naming it), a swap that a killed run left half done is finished first, and a run
    that stopped before its results were put in place is named as interrupted. An existing
    ``report.html`` that magtact did not write is not replaced.

    Parameters
    ----------
    folder : path
        Results folder of ``magtact run`` (or any folder with the layout in the module
        docstring; absent parts are reported as absent).
    evidence : path, optional
        Folder of benchmark JSON files to show in addition to ``folder/evidence``.
    damaged : dict, optional
        Filled with the files left out of the report (file → what is wrong), which the report
        also lists above its sections.

    Returns
    -------
    Path
        ``folder/report.html``: one file, every figure embedded.

    Raises
    ------
    MissingFileError
        If ``folder`` does not exist.
    magtact._runfolder.FolderInUse
        If a run is writing the folder.
    magtact._runfolder.NotMagtactsFile
        If ``folder/report.html`` exists and is not a report magtact wrote.
    """
    from .._files import file_problem
    from .._runfolder import RunLock, claim, interrupted_runs, recover

    folder = Path(folder)
    problem = file_problem(folder, "folder")
    if problem == "not found":
        raise MissingFileError(f"{folder}: no such results folder")
    if problem is not None:
        raise MissingFileError(f"{folder}: not a results folder: it is {problem}")
    with RunLock(folder, "magtact report"):
        recover(folder)
        doc = report_document(folder, evidence=evidence,
                              interrupted=interrupted_runs(folder, held=True), damaged=damaged)
        return claim(folder, "report.html", doc)


def report_document(folder: Path, *, shown: Path | None = None,
                    evidence: str | Path | None = None,
                    interrupted: list[dict] | None = None,
                    damaged: dict[str, str] | None = None) -> str:
    """The HTML of the report of ``folder`` (see :func:`build_report`).

    ``shown`` is the results folder the report describes when ``folder`` is the staging folder
    of a run (its name is printed, and ``shown/publication`` read); ``interrupted`` are the
    runs of :func:`magtact._runfolder.interrupted_runs`; ``damaged`` (a dict) is filled with
    the files left out (file → what is wrong).
    """
    with collecting(folder) as notes:
        parts, study_name = _document_parts(folder, shown, evidence, interrupted)
    parts.insert(2, damaged_section(notes))
    if damaged is not None:
        damaged.update(notes)
    doc = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
           f"<title>magtact report — {_e(study_name)}</title><style>{CSS}</style></head>"
           "<body>\n" + "\n".join(p for p in parts if p) + "\n</body></html>\n")
    return _live_links(doc)


def _live_links(doc: str) -> str:
    """``doc`` with the navigation's links to sections it does not hold left out (a run that
    stopped early, or found no design, has no explorer or design card)."""
    ids = set(re.findall(r'\sid="([^"]+)"', doc))

    def nav(m: re.Match) -> str:
        links = [a for a in m.group(2).split(" · ")
                 if (h := re.search(r'href="#([^"]+)"', a)) is None or h.group(1) in ids]
        return m.group(1) + " · ".join(links) + m.group(3)

    return re.sub(r'(<nav class="toc">)(.*?)(</nav>)', nav, doc, count=1, flags=re.S)


def _document_parts(folder: Path, shown: Path | None, evidence, interrupted
                    ) -> tuple[list[str], str]:
    """The sections of :func:`report_document` (the first two: the title and the intro) and
    the study's name."""
    shown = folder if shown is None else Path(shown)
    manifest = load_record(folder / MANIFEST, RunManifest, "a run record (run.json)")
    stages = {} if manifest is None else {s.key: s for s in manifest.stages}
    study_name = "unknown study" if manifest is None else manifest.study
    run_id = None if manifest is None else manifest.run_id
    optimise = folder / "optimise" if _of_run(folder / "optimise", run_id) else None
    card = read_card(optimise, shown / "publication") if optimise is not None else None
    parts = [f"<h1>magtact report — {_e(study_name)}</h1>",
             f'<p class="intro">Results folder <code>{_e(shown.resolve())}</code>, built '
             f"{datetime.now(UTC):%Y-%m-%d %H:%M UTC}. Read top-down: the verdict and the "
             "parts, the figures a designer looks at, the explorer, the tables, then the "
             'evidence and <a href="#method">the method</a> (collapsed at the end).</p>']
    parts.extend(_interrupted(r, manifest) for r in interrupted or [])
    if manifest is None:
        parts.append('<div class="missing">No <code>run.json</code> in this folder: the stages '
                     "below are reported from the files present only; statuses and timings are "
                     "unknown.</div>")
    if (_of_run(folder / "validation", run_id)
            and _is_synthetic(folder / "validation")):
        parts.append('<div class="banner"><b>SYNTHETIC validation data.</b> The validation '
                     "section compares the model with a generated example data set (model plus "
                     "noise, drift and scatter), not with measurements.</div>")
    parts.append(_front(card))
    parts.append(_choices(card))
    parts.append(_glance(folder, run_id))
    if optimise is not None:
        parts.append(explorer_section(optimise))
        parts.append(_card(card))
    toc = " · ".join(f'<a href="#{k}">{_e(t)}</a>' for k, t, _ in STAGES)
    parts.append(f'<nav class="toc"><a href="#verdict">Verdict</a> · '
                 '<a href="#glance">Figures</a> · <a href="#explorer">Explorer</a> · '
                 f'<a href="#card">Design card</a> · <a href="#chosen">Chosen design</a> · '
                 f'{toc} · <a href="#publication">The publication</a> · '
                 '<a href="#summary">Run summary</a> · <a href="#evidence">Evidence</a> · '
                 '<a href="#settings">Settings</a> · <a href="#method">Method</a></nav>')
    parts.append(_chosen(optimise))
    for key, title, what in STAGES:
        if key == "budget":  # a section of its own, from budget.json
            parts.append(_budget_section(folder / "budget", run_id))
        elif key == "calibration" and (folder / key).is_dir() and _of_run(folder / key, run_id):
            parts.append(_calibration(folder / key))
        elif _of_run(folder / key, run_id):
            parts.append(_stage(folder / key, key, title, what, stages.get(key)))
        else:
            parts.append(_other_run(folder / key, key, title, what))
    parts.append(publication_section(shown / "publication", _definition(folder)))
    parts.append(_summary(manifest, stages, folder))
    parts.append(_evidence([folder / "evidence"] + ([Path(evidence)] if evidence else [])))
    parts.append(_settings(folder / "study.toml"))
    parts.append(_method())
    parts.append(_versions(manifest))
    return parts, study_name


# ---- sections ------------------------------------------------------------------------------


def _interrupted(run: dict, manifest: RunManifest | None) -> str:
    """The banner of a run that stopped before its results were put in place."""
    m = run.get("manifest")
    done = [] if m is None else m.stages
    titles = {k: t for k, t, _ in STAGES}
    keys = [s.key for s in done]
    at = next((t for k, t in titles.items() if k not in keys), None)
    if m is not None and m.finished:
        where = "after its last stage, before its results were put in place"
    elif at is not None:
        where = f"during the stage <i>{_e(at)}</i>"
    else:
        where = "before it completed"
    finished = ("; finished stages: " + ", ".join(
        f"{_e(titles.get(s.key, s.key))} ({_e(s.status)})" for s in done) if done else "")
    why = f" ({_e(m.interrupted)})" if m is not None and m.interrupted is not None else ""
    command = _e(m.command if m is not None and m.command else "an unknown command")
    last = (f"The results shown are those of the last complete run (run "
            f"{_e(str(manifest.run_id or '?')[:12])}, started "
            f"{_e(manifest.started or '?')})." if manifest is not None and manifest.finished
            else "This folder holds no complete run.")
    started = m.started if m is not None and m.started is not None else "at an unknown time"
    run_id = m.run_id if m is not None and m.run_id is not None else "?"
    return ('<div class="missing"><b>Interrupted run.</b> The run <code>'
            f"{command}</code> started {_e(started)} (run "
            f"{_e(str(run_id)[:12])}) was interrupted {where}{why}{finished}. "
            f"Its partial results, in <code>{_e(run.get('staging'))}/</code>, are not shown; "
            f"the next run into this folder removes them. {last}</div>")


def _front(card: dict | None) -> str:
    """The verdict (one line per requirement, met or not, with its margin) and the parts list,
    side by side: the first thing the report shows. Where no design meets the requirements,
    what binds and what to relax take the parts' place. Nothing where the card has neither."""
    if not isinstance(card, dict):
        return ""
    from .._display import infeasible_rows, requirement_rows

    verdict = [v for v in card.get("verdict") or [] if isinstance(v, dict)]
    parts = [p for p in card.get("parts") or [] if isinstance(p, (list, tuple)) and len(p) == 2]
    infeasible = card.get("infeasible") if isinstance(card.get("infeasible"), dict) else None
    if not verdict and not parts:
        return ""
    items = "".join(
        f'<li class="{"met" if v.get("met") else "unmet"}">{_e(label[:1])} '
        f"<b>{_inline(label[2:])}</b>: {_inline(text)}</li>"
        for v, (label, text) in zip(verdict, requirement_rows(verdict), strict=True))
    title = ("Verdict: no design meets the requirements" if infeasible is not None
             else "Verdict")
    units = next((r[1] for r in card.get("rows") or [] if isinstance(r, (list, tuple))
                  and len(r) > 1 and r[0] == UNITS_ROW and r[1] != "not computed"), None)
    units = (f'<p class="units"><b>Units built that meet every requirement</b>: '
             f"{_inline(units)}</p>" if isinstance(units, str) else "")
    left = (f'<div id="verdict"><h2>{title}</h2><ul class="verdict-list">{items}</ul>{units}'
            "</div>" if verdict else "")
    if infeasible is not None:
        rows = infeasible_rows(infeasible)[1][len(verdict):]
        table = "".join(f'<tr><th class="l">{_inline(k)}</th><td class="l">{_inline(v)}</td>'
                        "</tr>" for k, v in rows)
        right = (f'<div id="parts"><h2>What to relax</h2><table class="parts">{table}</table>'
                 "<p>No parts: no design in the study's ranges of H and G meets every "
                 "requirement together. With the one change above, the design at the figure "
                 "shown meets them.</p></div>")
    else:
        rows = "".join(f'<tr><th class="l">{_inline(k)}</th><td class="l">{_inline(v)}</td>'
                       "</tr>" for k, v in parts)
        right = (f'<div id="parts"><h2>Parts</h2><table class="parts">{rows}</table></div>'
                 if parts else "")
    return f'<section class="front">{left}{right}</section>'


def _choices(card: dict | None) -> str:
    """The parts the sensor problem chose among: the best sensor of each magnet size and of
    each silicone, as the card lists them (nothing where it chose from one of each)."""
    if not isinstance(card, dict):
        return ""
    choices, tables = CardChoices.of(card), []
    for key, table, title in (
            (SIZES_KEY, choices.magnet_sizes, "Best sensor of each magnet size"),
            (SILICONES_KEY, choices.silicones, "Best sensor of each silicone")):
        rows = [r for r in table if isinstance(r, (list, tuple)) and len(r) == 2]
        if rows:
            body = "".join(f'<tr><th class="l">{_inline(str(k))}</th><td class="l">'
                           f"{_inline(str(v))}</td></tr>" for k, v in rows)
            tables.append(f'<h3>{title}</h3><table class="choices" id="{key}">'
                          f"{body}</table>")
    if not tables:
        return ""
    return ('<section id="choices"><h2>The parts compared</h2>' + "".join(tables)
            + "</section>")


def _glance(folder: Path, run_id: str | None) -> str:
    """The figures a designer looks at first: the error budget of the chosen design against
    its resolution, the Pareto set and the calibration's error (each where the run made it)."""
    picks = [("budget", "budget_chosen", "Error budget of the chosen design: false force per "
              "row [mN], log scale; dashed: the resolution (1 σ, worst)"),
             ("optimise", "pareto_set", None), ("optimise", "maps_constraints", None),
             ("calibration", "calibration", "Calibration: error of the firmware map over the "
              "stable region, and the candidates' size against their error")]
    figs = []
    from ._explorer import read_explorer

    explorer = (read_explorer(folder / "optimise") if _of_run(folder / "optimise", run_id)
                else None)
    if explorer is not None:
        from ._fig_explorer import design_curves_png

        figs.append(_figure_bytes(design_curves_png(explorer), "Resolution and normal range "
                                  "over the base height at the chosen G, and where the chip "
                                  "saturates inside the stable region (the explorer's numbers)",
                                  "optimise/explorer.json"))
    for key, stem, caption in picks:
        png = folder / key / f"{stem}.png"
        if png.is_file() and _of_run(folder / key, run_id):
            captions = load_captions(folder / key / "captions.json")
            shown = _figure(png, caption or captions.get(stem))
            # a wide figure (three panels in a row) takes the whole width
            figs.append(f'<div class="span">{shown}</div>' if stem == "calibration" else shown)
    if not figs:
        return ""
    return ('<section id="glance"><h2>The figures a designer looks at</h2>'
            f'<div class="glance">{"".join(figs)}</div></section>')


def _figure_bytes(png: bytes, caption: str, source: str) -> str:
    import base64

    data = base64.b64encode(png).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{_e(caption)}">'
            f"<figcaption>{_e(caption)} <small>({_e(source)})</small></figcaption></figure>")


def _inline(text) -> str:
    """Text of the card as HTML: escaped, numbers to 3 significant figures, `code` as code."""
    return re.sub(r"`([^`<>]+)`", r"<code>\1</code>", _e(round_text(str(text))))


def _card(card: dict | None) -> str:
    """The design card (written by the optimisation stage), or nothing."""
    if not card or not isinstance(card.get("rows"), list) or card.get("infeasible"):
        return ""  # no design: the verdict above says what binds
    head = "".join(f'<th class="l">{_e(h)}</th>' for h in card.get("header", []))
    rows = "".join("<tr>" + "".join(f'<td class="l">{_inline(c)}</td>' for c in r) + "</tr>"
                   for r in card["rows"] if isinstance(r, list))
    return (f'<h2 id="card">Design card</h2><table class="card"><tr>{head}</tr>{rows}</table>'
            "<p>Resolution: 1 σ force noise from the chip's RMS field noise, "
            "σ_F = √diag(J Σ_B Jᵀ) with J = ∂F/∂B; unloaded (t = 0) and worst over the stable "
            "region. Every number in <code>optimise/card.json</code>.</p>")


def _budget_section(folder: Path, run_id: str | None) -> str:
    """The error budget (``budget/budget.json`` and its figures), or nothing without one."""
    from ..budget import BudgetFile

    doc = load_record(folder / "budget.json", BudgetFile, "an error budget (budget.json)")
    if doc is None:
        return ('<h2 id="budget">Error budget</h2><div class="missing">No error budget in this '
                "folder (<code>budget/budget.json</code>: the stage did not run, or failed; "
                "see the run summary).</div>")
    if run_id is not None and doc.run_id != run_id and not (
            (folder / RUN_STAMP).is_file() and _of_run(folder, run_id)):
        return ('<h2 id="budget">Error budget</h2><div class="missing">The error budget in '
                "<code>budget/</code> is not of this run (its <code>budget.json</code> names "
                f"run {_e(str(doc.run_id)[:32])}); nothing of it is shown.</div>")
    out = ['<h2 id="budget">Error budget</h2><p>Everything besides the force that moves the '
           "field the chip reads, as a false force ΔF = J ΔB in mN (J = ∂F/∂B of the "
           "metamodels): at rest (t = 0) and worst over the stable region. Rows far above the "
           "resolution are what limits the sensor, not the noise (method, §12). Every number "
           "in <code>budget/budget.json</code>.</p>"]
    for k, b in enumerate(doc.budgets):
        label = b.label
        start = len(out)
        out.append(f"<h3>{_e(label)}: H = {_fmt(_in(b.H, 'mm'))} mm, G = "
                   f"{_fmt(_in(b.G, 'kPa'))} kPa</h3><p>Noise: {_e(b.noise_source)}.</p>")
        rows = "".join(
            f'<tr><td class="l">{_e(r.name)}</td><td class="l">'
            f'{_e(r.component)}</td><td>{_fmt(_in(r.at_rest, "mN"))}</td>'
            f'<td>{_fmt(_in(r.worst, "mN"))}</td></tr>' for r in b.rows)
        out.append('<table><tr><th class="l">row</th><th class="l">force</th><th>at rest '
                   f"[mN]</th><th>worst [mN]</th></tr>{rows}</table>")
        pitch = b.array.get("smallest_pitch")
        if pitch is not None:
            out.append(f"<p>Smallest {_e(b.array.get('layout'))} array pitch at which the "
                       f"neighbours' crosstalk stays below the resolution: "
                       f"<b>{_fmt(_in(pitch, 'mm'))} mm</b> "
                       f"({_e(b.array.get('criterion', ''))}).</p>")
        slug = re.sub(r"[^A-Za-z0-9]+", "_", label).strip("_") or "design"
        png = folder / f"budget_{slug}.png"
        if png.is_file():
            out.append("<details><summary>its figure</summary>"
                       + _figure(png, f"Error budget of the {label} design: false force per "
                                      "row [mN], log scale; dashed: the resolution (1 σ, "
                                      "worst)") + "</details>")
        notes = "".join(f"<li>{_e(r.name)} ({_e(r.component)}): {_e(r.assumptions)}</li>"
                        for r in b.rows if r.component == "F_r")
        missing = "".join(f"<li>{_e(n)}</li>" for n in b.not_modelled)
        out.append(f"<details><summary>assumptions of each row</summary><ul>{notes}</ul>"
                   f"</details><details><summary>not modelled</summary><ul>{missing}</ul>"
                   "</details>")
        if k > 0:  # another design's budget (the original): behind a details
            out[start:] = [f"<details><summary>the {_e(label)} design's budget</summary>"
                           + "\n".join(out[start:]) + "</details>"]
    for png in sorted(folder.glob("time_*.png")):  # the time rows' figure (method.md §15)
        out.append(_figure(png, "The silicone's relaxation: F_z read against the true F_z over "
                                "a press and release at the study's press time, and the "
                                "hysteresis against the press time"))
    return "\n".join(out)


def _method() -> str:
    """The method (docs/method.md, shipped with the package) as the report's appendix, its
    figures embedded."""
    from importlib import resources

    here = resources.files("magtact.report")
    try:
        text = here.joinpath("method.md").read_text(encoding="utf-8")
    except OSError:
        return ('<h2 id="method">Method</h2><div class="missing">The method document is not '
                "part of this installation.</div>")

    def image(src: str) -> bytes | None:
        name = src.rsplit("/", 1)[-1]
        try:
            return here.joinpath(name).read_bytes() if name == src else None
        except OSError:
            return None

    body = render_markdown(text, anchor_prefix="method-", images=image)
    return ('<h2 id="method">Method</h2><details><summary>The method behind every number, '
            "with its equations and defaults (docs/method.md; click to open)</summary>"
            f"{body}</details>")


def _definition(folder: Path) -> str | None:
    """The sensitivity definition of the run (from its design.json), if recorded."""
    from ..optimise import design_file_definition

    return design_file_definition(_load_json(folder / "optimise" / "design.json"))



def _summary(manifest: RunManifest | None, stages: dict[str, StageRecord], folder: Path
             ) -> str:
    rows = []
    for key, title, _ in STAGES:
        s = stages.get(key)
        if s is None:
            present = (folder / key).is_dir() and any((folder / key).iterdir())
            status, wall = ("files present", "?") if present else ("absent", "")
            msg = "no record of this stage in run.json" if present else "not run"
        else:
            status, wall, msg = s.status, _fmt_time(s.wall_time_s), s.message
        rows.append(f'<tr><td class="l">{_e(title)}</td><td class="l {_e(status)}">'
                    f'{_e(status)}</td><td>{wall}</td><td class="l">{_e(msg)}</td></tr>')
    head = '<h2 id="summary">Run summary</h2>'
    if manifest is not None:
        head += (f"<p>Command <code>{_e(manifest.command)}</code>; started "
                 f"{_e(manifest.started or '?')}, total wall time "
                 f"{_fmt_time(manifest.wall_time_s)}; "
                 f"data set: {_e(manifest.doe_source or 'unknown')}.</p>")
    return (head + '<table><tr><th class="l">stage</th><th class="l">status</th><th>wall time'
            '</th><th class="l">message</th></tr>' + "".join(rows) + "</table>")


def _chosen(folder: Path | None) -> str:
    """The chosen design in words and units (every number in ``optimise/chosen.json``, or
    ``geometry.json`` over geometric design variables)."""
    from ..optimise import ChosenFile, geometry_choice_json

    data = (load_record(folder / "chosen.json", ChosenFile, "a chosen design (chosen.json)")
            if folder else None)
    geo = geometry_choice_json(_load_json(folder / "geometry.json")) if folder else None
    if geo is not None and data is None:
        data, source = ChosenFile.from_json(geo), "geometry.json"
    else:
        source = "chosen.json"
    if data is None and folder is not None and (folder / "card.json").is_file() and isinstance(
            (read_card(folder) or {}).get("infeasible"), dict):
        return ('<h2 id="chosen">Chosen design</h2><p>None: no design meets the requirements '
                '(<a href="#verdict">the verdict</a> says what binds and what to relax).</p>')
    if data is None:
        return ('<h2 id="chosen">Chosen design</h2><div class="missing">No chosen design in '
                "this folder (the optimisation stage did not produce "
                "<code>optimise/chosen.json</code>).</div>")

    def num(v: float | None, unit: str | None = None) -> str:
        return "?" if v is None else sig(v if unit is None else from_si(v, unit))

    rows = []
    if data.design is not None:
        rows.append(("design", data.design))
    if data.H is not None:
        rows += [("base height H", f"{num(data.H, 'mm')} mm"),
                 ("shear modulus G of the elastomer", f"{num(data.G, 'kPa')} kPa")]
    if data.M_z is not None:
        rows.append(("magnetisation M_z", f"{num(data.M_z, 'A_per_m')} A/m"))
    if data.objective == "sigma_F":  # the objective columns hold σ_F [N]
        rows += [("worst shear force noise σ_Fr over the stable region (the objective)",
                  f"{num(data.Gamma_r_max, 'mN')} mN"),
                 ("worst normal force noise σ_Fz over the stable region (the objective)",
                  f"{num(data.Gamma_z_max, 'mN')} mN")]
    else:
        rows += [("worst shear sensitivity Γ_r,max over the stable region",
                  f"{num(data.Gamma_r_max)} N/T"),
                 ("worst normal sensitivity Γ_z,max over the stable region",
                  f"{num(data.Gamma_z_max)} N/T")]
    rows += [("largest stable shear force F_r,min", f"{num(data.F_r_min)} N"),
             ("largest normal force in the stable region F_z,max", f"{num(data.F_z_max)} N")]
    if data.t_m is not None:
        rows.append(("stable region", f"t ≤ {num(data.t_m)}, θ ≤ {num(data.theta_m)} rad"))
    if data.has_constraints:
        rows.append(("force constraints", f"F_r,min ≤ {_plain(data.F_r_c)} N, F_z,max ≥ "
                                          f"{_plain(data.F_z_c)} N "
                                          f"({_plain(data.constraints_source or '?')})"))
    rows.append(("margins to the constraints", f"{num(data.g_r)} N shear, "
                                               f"{num(data.g_z)} N normal (≤ 0: met)"))
    if data.active_constraints is not None:
        rows.append(("active constraints", data.active_constraints))
    if data.degenerate:
        rows.append(("note", round_text(data.degenerate)))
    if data.sensitivity_definition is not None:
        rows.append(("sensitivity Γ", f"{data.sensitivity_definition} definition"))
    body = "".join(f'<tr><td class="l">{_e(k)}</td><td class="l">{_e(v)}</td></tr>'
                   for k, v in rows)
    return (f'<h2 id="chosen">Chosen design</h2><div class="design"><table>{body}</table>'
            f"<p><small>Every number in <code>optimise/{source}</code>.</small></p>"
            f"{_design_rule(data)}</div>")


def _design_rule(chosen) -> str:
    """The resolution–range trade-off of the chosen height, in words (a
    :class:`magtact.optimise.ChosenFile`)."""
    try:
        H, G = from_si(chosen.H, "mm"), from_si(chosen.G, "kPa")
        kz = chosen.Gamma_z_max / chosen.F_z_max
        kr = chosen.Gamma_r_max / abs(chosen.F_r_min)
    except (TypeError, ZeroDivisionError):
        return ""
    return (f"<p><b>Design rule.</b> Forces and sensitivities are both G times a function of "
            f"H, so at H = {H:.3g} mm every newton of normal range costs {kz:.3g} N/T of "
            f"worst normal sensitivity Γ_z,max (and every newton of shear range {kr:.3g} N/T "
            f"of Γ_r,max), whatever G. G = {G:.3g} kPa is the softest elastomer that still "
            "meets the force constraints; a different H changes these ratios (figure "
            "<i>resolution–range</i> in the section on the publication).</p>")


def _stage(folder: Path, key: str, title: str, what: str, info: StageRecord | None) -> str:
    out = [f'<h2 id="{key}">{_e(title)}</h2><p>{_e(what)}</p>']
    if info is not None:
        status = info.status
        out.append(f'<p>Status: <span class="{_e(status)}">{_e(status)}</span>, wall time '
                   f"{_fmt_time(info.wall_time_s)}. {_e(info.message)}</p>")
        for note in info.notes:
            out.append(f"<p>Note: {_e(note)}</p>")
    if not folder.is_dir() or not any(folder.iterdir()):
        reason = info.message if info else "this stage was not run"
        out.append(f'<div class="missing">No results for this stage in the folder ({_e(reason)}).'
                   " Nothing is shown in its place.</div>")
        return "\n".join(out)
    if key == "validation" and _is_synthetic(folder):
        out.append('<div class="banner"><b>SYNTHETIC example data</b> — generated from the model '
                   "with noise, drift and sensor-to-sensor scatter; not a measurement.</div>")
    shown = len(out)  # what follows is the stage's evidence: behind a details (printed closed)
    captions = load_captions(folder / "captions.json")
    files = sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    from .._files import file_problem
    from ._fragments import note

    for p in sorted(folder.iterdir()):  # a FIFO, a device, a link loop: named, never opened
        if not p.name.startswith(".") and not p.is_file() and not p.is_dir():
            note(p, f"is {file_problem(p)}")
    summaries = [p for p in files if p.suffix == ".json" and p.name not in SKIP_JSON]
    for p in summaries:  # a stage's summary (a JSON with a title) comes first
        if isinstance(_load_json(p), dict) and "title" in _load_json(p):
            out.append(_json_summary(p))
    for p in files:
        if p.suffix == ".png":
            out.append(_figure(p, captions.get(p.stem)))
    for p in files:
        if p.suffix == ".md":
            text = read_text(p, "notes")
            if text is not None:
                out.append(render_markdown(text))
    for p in files:
        if p.suffix == ".csv":
            out.append(_csv_table(p, captions.get(p.stem)))
    for p in files:
        if p.suffix in (".txt", ".tex"):
            text = read_text(p)
            if text is not None:
                out.append(f"<details><summary>{_e(p.name)}</summary><pre>{_e(text)}</pre>"
                           "</details>")
    for p in summaries:  # other JSON files (model files, ...): collapsed
        if not (isinstance(_load_json(p), dict) and "title" in _load_json(p)):
            out.append(f"<details><summary>{_e(p.name)}</summary>{_json_summary(p)}</details>")
    others = [p.name for p in files if p.suffix not in (".png", ".csv", ".txt", ".tex", ".md",
                                                        ".json", ".svg")]
    if others:
        out.append(f"<p>Other files: {_e(', '.join(others))}.</p>")
    if len(out) > shown:
        out[shown:] = ['<details class="evidence"><summary>Figures, tables and files of this '
                       "stage</summary>" + "\n".join(out[shown:]) + "</details>"]
    return "\n".join(out)


def _calibration(folder: Path) -> str:
    """The calibration section (docs/method.md §13) from ``calibration/*.json``: the map's
    round trip, the firmware export's size and error against σ_F, a built unit's parameters,
    the error figure and how to use the files."""
    out = ['<h2 id="calibration">Calibration: the field-to-force map</h2>']
    from ..calibration import CalibrationSummary

    for p in sorted(folder.glob("*.json")):
        d = CalibrationSummary.from_json(_load_json(p))
        if d is None:
            continue
        design, fw = d.design, d.firmware
        out.append(
            f"<p>Design H = {_sig(_in(design.H, 'mm'))} mm, "
            f"G = {_sig(_in(design.G, 'kPa'))} kPa; "
            f"stable region t ≤ {_sig(design.t_m)}, θ ≤ "
            f"{_sig(design.theta_m)} rad. Round trip F → B → F: largest error "
            f"{_sig(d.round_trip)} of the force range. Firmware map: "
            f"{_e(fw.kind)} ({_fmt(fw.bytes)} bytes, "
            f"{_fmt(fw.multiplies)} multiplications), largest error over the region "
            f"F_r {_sig(_in(fw.err_r, 'mN'))} mN, "
            f"F_z {_sig(_in(fw.err_z, 'mN'))}"
            f" mN against σ_F {_sig(_in(d.sigma_F[0], 'mN'))} / "
            f"{_sig(_in(d.sigma_F[1], 'mN'))} mN "
            f"(field noise {_e(', '.join(_sig(_in(v, 'uT')) for v in d.noise))} µT from "
            f"{_e(d.noise_source)}): "
            f"{'reached' if fw.reached else 'not reached'}, {_e(fw.rule)}.</p>")
        err = d.force_error
        if err is not None:
            limit = ("not measured" if err.F_r is None else
                     f"F_r {_sig(_in(err.F_r, 'mN'))} mN, "
                     f"F_z {_sig(_in(err.F_z, 'mN'))} mN")
            source = {"models": "the metamodels",
                      "fe": "the DOE's FE paths at H, interpolated"}.get(d.force_source,
                                                                         d.force_source)
            out.append(f"<p>Forces from {_e(source)}; what limits them: "
                       f"{_e(err.kind)}: {limit} (docs/method.md §13.4).</p>")
        if d.unit is not None:
            out.append("<h3>Built unit</h3>" + _dict_table(d.unit.to_json()))
        out.append(f"<p>Use: {_e(d.usage)}. Files in <code>{_e(folder.name)}/</code>: "
                   "<code>force.h</code> (C99), <code>force_map.json</code>, "
                   "<code>force_table.csv</code>.</p>")
        if d.frontier:
            out.append("<details><summary>every firmware candidate (size and error)</summary>"
                       + _records_table("frontier", d.frontier) + "</details>")
    for p in sorted(folder.glob("*.png")):
        out.append(_figure(p, "error of the firmware map over the stable region, and the "
                              "candidates' size against their error"))
    return "\n".join(out)


def _of_run(folder: Path, run_id: str | None) -> bool:
    """True if ``folder`` holds the outputs of the run ``run_id`` (its stamp file names it), or
    if the manifest names no run (a folder laid out by hand)."""
    if run_id is None or not folder.is_dir() or not any(folder.iterdir()):
        return True
    text = read_text(folder / RUN_STAMP, "stamp")
    return text is not None and text.strip() == run_id


def _other_run(folder: Path, key: str, title: str, what: str) -> str:
    """The section of a stage whose folder was written by another run: nothing of it shown."""
    stamp = read_text(folder / RUN_STAMP, "stamp")
    other = (f"run {stamp.strip()[:32]}" if stamp is not None
             else "a run that did not stamp it, or by hand")
    return (f'<h2 id="{key}">{_e(title)}</h2><p>{_e(what)}</p><div class="missing">The files '
            f"in <code>{_e(key)}/</code> are not of this run (the folder was written by "
            f"{_e(other)}); nothing of them is shown. Remove the folder or run into a new "
            "one.</div>")


def _evidence(folders: list[Path]) -> str:
    files = sorted({p.name: p for f in folders if f.is_dir() for p in f.glob("*.json")}.values())
    out = ['<h2 id="evidence">Accuracy and convergence evidence</h2>']
    if not files:
        out.append('<div class="missing">No benchmark results were given to this run '
                   "(<code>magtact run --evidence bench/results</code> in a source checkout)."
                   "</div>")
        return "\n".join(out)
    out.append("<p>Benchmarks measured on this code (bench/results); each table lists the "
               "scalar results, nested values are in the expandable raw file.</p>")
    for p in files:
        out.append(_json_summary(p, level=3))
    return "\n".join(out)


def _settings(path: Path) -> str:
    """The study's settings, section by section: what each setting is (its description in the
    study's schema), its value in its unit, and a value that means "not set" in words."""
    if not path.is_file() and not path.is_symlink() and not path.exists():
        return ('<h2 id="settings">Study settings</h2><div class="missing">No study.toml in this '
                "folder.</div>")
    import tomllib

    text = read_text(path, "toml")
    if text is None:
        return ('<h2 id="settings">Study settings</h2><div class="missing">study.toml '
                "unreadable (see the files left out of this report).</div>")
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        from ._fragments import note

        note(path, "is not TOML" if isinstance(exc, RecursionError) else f"is not TOML: {exc}")
        return (f'<h2 id="settings">Study settings</h2><div class="missing">study.toml '
                f"unreadable ({_e(exc)}).</div>")
    schema = _schema()
    out = ['<h2 id="settings">Study settings</h2><p>The full study (user units), as loaded '
           "and validated; the file is <code>study.toml</code>. A value that means “not set” "
           "is shown as what it means.</p>"]
    top = [(k, v) for k, v in data.items() if not isinstance(v, dict)]
    sections = [(None, top)] + [(k, list(v.items())) for k, v in data.items()
                                if isinstance(v, dict)]
    tables = []
    for section, items in sections:
        if not items:
            continue
        rows = "".join(_setting_row(k, v, schema.get((section, k)))
                       for k, v in items if not isinstance(v, dict))
        head = "" if section is None else f"<h3>{_e(section)}</h3>"
        tables.append(f'{head}<table class="settings"><tr><th class="l">setting</th>'
                      f'<th class="l">value</th><th class="l">what it is</th></tr>{rows}</table>')
    out.append(f"<details><summary>every setting, section by section ({len(tables)} "
               "tables)</summary>" + "\n".join(tables) + "</details>")
    return "\n".join(out)


#: "value: meaning" at the end of a setting's description (``-1: picked``, ``[0, 0]: fixed``).
_UNSET = re.compile(r"(\[[^\]]*\]|-?\d+(?:\.\d+)?): ([^;)]+)")


def _schema() -> dict[tuple[str | None, str], tuple[str, str]]:
    """(section, TOML key) → (unit, description) of every study setting."""
    import dataclasses
    import typing

    from ..study import LABEL, Study

    out = {}
    hints = typing.get_type_hints(Study)
    for f in dataclasses.fields(Study):
        kind = hints.get(f.name)
        if not dataclasses.is_dataclass(kind):
            out[(None, f.name)] = ("", str(f.metadata.get("doc", "")))
            continue
        for g in dataclasses.fields(kind):
            unit = g.metadata.get("unit", "")
            key = f"{g.name}_{unit}" if unit else g.name
            out[(f.name, key)] = (LABEL.get(unit, unit), str(g.metadata.get("doc", "")))
    return out


def _setting_row(key: str, value, schema: tuple[str, str] | None) -> str:
    unit, doc = schema if schema is not None else ("", "")
    shown = None
    for m in _UNSET.finditer(doc):
        try:
            unset = json.loads(m.group(1))
        except ValueError:
            continue
        if _same(value, unset):
            shown = f"<i>{_e(m.group(2).strip())}</i>"
    if shown is None:
        if isinstance(value, list):
            text = ", ".join(_plain(x) for x in value) if all(
                not isinstance(x, (dict, list)) for x in value) else f"{len(value)} entries"
            text = f"[{text}]" if len(value) != 1 else text
        else:
            text = _plain(value)
        text = round_text(text)
        shown = _e(f"{text} {unit}" if unit and unit != "-" and text not in ("", "—") else text)
    what = _UNSET.sub("", doc).rstrip(" ;,(") if shown.startswith("<i>") else doc
    return (f'<tr><td class="l"><code>{_e(key)}</code></td><td class="l">{shown}</td>'
            f'<td class="l">{_inline(what)}</td></tr>')


def _same(value, unset) -> bool:
    """Whether a setting's value is its description's "not set" value (numbers compared as
    numbers, lists element by element)."""
    if isinstance(unset, list):
        return isinstance(value, list) and len(value) == len(unset) if not unset else (
            isinstance(value, list) and len(value) == len(unset)
            and all(_same(a, b) for a, b in zip(value, unset, strict=True)))
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and isinstance(unset, (int, float)) and float(value) == float(unset))


def _versions(manifest: RunManifest | None) -> str:
    versions = None if manifest is None else manifest.versions
    if not versions:
        return ""
    rows = "".join(f'<tr><td class="l">{_e(k)}</td><td class="l">{_e(v)}</td></tr>'
                   for k, v in versions.items())
    return ('<h2 id="versions">Versions and machine</h2><details><summary>Python, the '
            f"platform and the packages of the run</summary><table>{rows}</table></details>")


# ---- pieces --------------------------------------------------------------------------------
def _csv_table(path: Path, caption: str | None) -> str:
    import io

    text = read_text(path, "table")
    if text is None:
        return f"<p>{_e(path.name)}: left out (see the files left out of this report)</p>"
    try:
        rows = [r for r in csv.reader(io.StringIO(text, newline="")) if r
                and not r[0].startswith("#")]
    except csv.Error as exc:
        return f"<p>{_e(path.name)}: unreadable ({_e(exc)})</p>"
    if not rows:
        return f"<p>{_e(path.name)}: empty table</p>"
    head, body = rows[0], rows[1:]
    keep = [k for k in range(len(head))
            if any(k < len(r) and r[k].strip() for r in body[:MAX_ROWS])]  # no empty column
    head, body = [head[k] for k in keep], [[r[k] if k < len(r) else "" for k in keep]
                                           for r in body]
    title = caption or path.stem.replace("_", " ")
    if "synthetic" in path.name.lower():
        title += " (SYNTHETIC data)"
    html_rows = "".join("<tr>" + "".join(f"<td>{_e(_num(c))}</td>" for c in r) + "</tr>"
                        for r in body[:MAX_ROWS])
    table = ("<div style=\"overflow-x:auto\"><table><tr>"
             + "".join(f"<th>{_e(label(h))}</th>" for h in head) + "</tr>" + html_rows
             + "</table></div>")
    if len(body) <= MAX_ROWS:
        return f"<h3>{_e(title)}</h3><p><small>{_e(path.name)}</small></p>{table}"
    # long data tables: collapsed, first rows only (the file has them all)
    return (f"<details><summary><b>{_e(title)}</b> — {_e(path.name)}, {len(body):,} rows (first "
            f"{MAX_ROWS} shown; {len(body) - MAX_ROWS} more rows in {_e(path.name)})</summary>"
            f"{table}</details>")


def _json_summary(path: Path, level: int = 3) -> str:
    data = _load_json(path)
    if data is None:
        return f"<p>{_e(path.name)}: unreadable JSON</p>"
    title = data.get("title", path.stem) if isinstance(data, dict) else path.stem
    body = _dict_table(data) if isinstance(data, dict) else ""
    if isinstance(data, dict):
        body += "".join(_records_table(k, v) for k, v in _record_lists(data))
    return (f"<h{level}>{_e(title)}</h{level}><p><small>{_e(path.name)}: nested values and "
            f"every digit in the file</small></p>{body}")


def _dict_table(data: dict, prefix: str = "", depth: int = 0) -> str:
    rows = []
    for k, v in _flatten(data, prefix, depth):
        shown = (mathml(v) if k.rsplit(".", 1)[-1] == "latex" and isinstance(v, str)
                 else _fmt(v))  # a formula as mathematics
        rows.append(f'<tr><td class="l">{_e(label(k))}</td><td class="l">{shown}</td></tr>')
    return f'<div class="wide"><table>{"".join(rows)}</table></div>' if rows else ""


def _flatten(data: dict, prefix: str, depth: int):
    for k, v in data.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict) and depth < 2:
            yield from _flatten(v, name + ".", depth + 1)
        elif isinstance(v, list):  # long or nested lists: their own table, or in the file
            if v and len(v) <= 6 and all(not isinstance(x, (dict, list)) for x in v):
                yield name, ", ".join(_plain(x) for x in v)
        elif not isinstance(v, dict) and v not in ("", None):  # no empty rows
            yield name, v


def _record_lists(data: dict, prefix: str = "", depth: int = 0):
    """(name, list) of every list of flat dicts (e.g. a convergence study) in ``data``."""
    for k, v in data.items():
        if isinstance(v, list) and v and all(
                isinstance(x, dict) and all(not isinstance(y, (dict, list)) for y in x.values())
                for x in v):
            yield f"{prefix}{k}", v
        elif isinstance(v, dict) and depth < 2:
            yield from _record_lists(v, f"{prefix}{k}.", depth + 1)


def _records_table(name: str, records: list[dict]) -> str:
    """A list of flat dicts as one table (rows = records, columns = the union of keys)."""
    keys = list(dict.fromkeys(k for r in records for k in r))
    rows = "".join("<tr>" + "".join(f"<td>{_fmt(r.get(k, ''))}</td>" for k in keys) + "</tr>"
                   for r in records[:MAX_ROWS])
    more = f"<p><small>{len(records) - MAX_ROWS} more rows</small></p>" if len(
        records) > MAX_ROWS else ""
    return (f"<p><b>{_e(label(name))}</b></p><div style=\"overflow-x:auto\"><table><tr>"
            + "".join(f"<th>{_e(label(k))}</th>" for k in keys)
            + f"</tr>{rows}</table></div>{more}")


def _is_synthetic(folder: Path) -> bool:
    if not folder.is_dir():
        return False
    if any("synthetic" in p.name.lower() for p in folder.iterdir()):
        return True
    return any(isinstance(d := _load_json(p), dict) and d.get("synthetic") is True
               for p in folder.glob("*.json"))


def _plain(v) -> str:
    return value_text(v)


def _fmt(v) -> str:
    """A value in a table cell; an expression or a file's text (model files) as code."""
    if isinstance(v, str) and "\n" in v:
        return (f"<details><summary>text, {v.count(chr(10)) + 1} lines</summary>"
                f"<pre>{_e(v)}</pre></details>")
    if isinstance(v, str) and "*" in v and "(" in v:
        return f"<code>{_e(v)}</code>"
    return _e(round_text(_plain(v)))


def _num(cell: str) -> str:
    """A CSV cell as shown: a whole number as is (a count or a level), any other number to 3
    significant figures, text with its numbers so."""
    if re.fullmatch(r"-?\d+", cell.strip()):
        return cell.strip()
    try:
        return sig(float(cell))
    except ValueError:
        return round_text(cell)


def _sig(v, digits: int = 3) -> str:
    """A measured number to ``digits`` significant figures, escaped (text stays text)."""
    return _e(sig(v, digits)) if isinstance(v, (int, float)) and not isinstance(v, bool) \
        else _e(_plain(v))


def _in(value: float | None, unit: str) -> float | None:
    """An SI value of a file read back, in ``unit`` for the page; None where there is none
    (missing, or not finite), which the page shows as a dash."""
    if value is None or not math.isfinite(value):
        return None
    return from_si(value, unit)


def _fmt_time(seconds) -> str:
    if not isinstance(seconds, (int, float)):
        return "?"
    if seconds < 120:
        return f"{seconds:.1f} s"
    return f"{seconds / 60:.1f} min"
