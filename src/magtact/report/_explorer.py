"""The design explorer of the report: H and G moved in the browser, σ_F, the force ranges, where
the chip saturates and the verdict read live, offline.

The page computes no physics. Python evaluates the designer's answer
(:meth:`magtact.Result.evaluate`) on a grid of designs (H, G) and writes every number into
``optimise/explorer.json`` (per unit G, with the G it was computed at, so the file states the
forces' proportionality to G); the sliders move over the grid's heights and moduli, so every
number the page shows is one Python computed. G is a grid axis, not a factor: with a force
requirement the chip setting a design uses depends on G (the load that must be read grows as
the body softens), so σ_F is not G times one function of H. The Pareto set's points carry
their own design card, evaluated the same way.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._files import write_json
from ..study import from_si, kpa, mm
from ._fragments import escape as _e
from ._fragments import load_json
from ._labels import sig

FORMAT = "magtact-explorer/1"
#: Base heights and shear moduli of the grid (the chosen and the original design's are added).
N_H = 5
N_G = 5
#: Pareto points given a design card in the explorer (evenly spaced along the set).
N_PARETO = 4


def _per_G(answer) -> dict:
    """The numbers of one designer's answer per unit G [SI / Pa], and those that do not scale."""
    d, s, r = answer.design, answer.saturation, answer.resolution
    G = answer.G
    out = {"H_mm": float(mm(answer.H)),
           "F_z_max": d.F_z_max / G, "F_r_min": d.F_r_min / G,
           "Gamma_r_max": d.Gamma_r_max / G, "Gamma_z_max": d.Gamma_z_max / G,
           "t_m": float(d.t_m), "theta_m": float(d.theta_m),
           "saturates": bool(s.saturates), "saturates_in_region": bool(s.in_region),
           "sat_axis": s.axis, "sat_t": s.t,
           "sat_F_z": None if s.F_z is None else s.F_z / G,
           "sat_F_r": None if s.F_r is None else s.F_r / G,
           "B_max_x_mT": float(from_si(s.B_max_x, "mT")),
           "B_max_z_mT": float(from_si(s.B_max_z, "mT")),
           "setting": None if answer.chip.figures is None else answer.chip.figures.words}
    if r is not None:
        out |= {"sigma_r_0": r.sigma_r_0 / G, "sigma_z_0": r.sigma_z_0 / G,
                "sigma_r_worst": r.sigma_r_worst / G, "sigma_z_worst": r.sigma_z_worst / G}
    return out


def explorer_data(result, n_H: int = N_H, n_G: int = N_G, n_pareto: int = N_PARETO
                  ) -> dict | None:
    """The explorer's numbers of a :class:`magtact.Result` (None over geometric design
    variables, where a design is more than H, G and M_z).

    ``grid[k][j]`` is the answer at (``H_mm[k]``, ``G_kPa[j]``) with the chosen design's magnet
    and chip standoff; each force-like number is stored per unit G (``F_z_max`` [N/Pa],
    ``sigma_z_worst`` [N/Pa], ``sat_F_z`` [N/Pa] ...): times that G it is the answer.
    """
    study = result.study
    if study.geometric_variables:
        return None
    chosen, original = result.chosen, result.original
    lo, hi = study.design.H
    heights = sorted({*(float(h) for h in np.linspace(lo, hi, n_H)), chosen.H, original.H})
    M_z = chosen.design.M_z
    # the chosen design's magnet and chip standoff stay fixed while H and G move
    fixed: dict = {} if M_z is None else {"M_z_A_per_m": float(M_z)}
    if chosen.parts is not None and chosen.parts.grade not in (None, "custom") and (
            chosen.parts.grade != study.magnet.grade):
        fixed["grade"] = chosen.parts.grade
    if "standoff" in result.variables:
        fixed["standoff_mm"] = float(mm(result.variables["standoff"]))
    glo, ghi = study.design.G
    moduli = sorted({*(float(g) for g in np.linspace(glo, ghi, n_G)), chosen.G, original.G})
    G_levels = [float(kpa(g)) for g in moduli]
    H_levels = [float(mm(h)) for h in heights]
    grid = [[_per_G(result.evaluate(H_mm=h, G_kPa=g, **fixed)) for g in G_levels]
            for h in H_levels]
    p = result.pareto
    n = len(p.H)
    picks = sorted({int(round(k)) for k in np.linspace(0, n - 1, min(n, n_pareto))}) if n else []
    pareto = []
    for k in range(n):
        point = {"H_mm": float(mm(p.H[k])), "G_kPa": float(kpa(p.G[k])),
                 "Gamma_r_max": float(p.Gamma_r_max[k]), "Gamma_z_max": float(p.Gamma_z_max[k]),
                 "F_r_min": float(p.F_r_min[k]), "F_z_max": float(p.F_z_max[k])}
        if k in picks:
            # a point with its own magnetisation: that magnet (a grade would set another M_z)
            kw = fixed if p.M_z is None else {k_: v for k_, v in fixed.items()
                                              if k_ not in ("grade", "M_z_A_per_m")} | {
                "M_z_A_per_m": float(p.M_z[k])}
            a = result.evaluate(H_mm=point["H_mm"], G_kPa=point["G_kPa"], **kw)
            point["card"] = _per_G(a) | {"G_kPa": point["G_kPa"]}
        pareto.append(point)
    from ..parts import SILICONES

    c = result.constraints
    return {
        "format": FORMAT, "study": study.name,
        "H_mm": H_levels, "G_kPa": G_levels,
        "M_z_A_per_m": None if M_z is None else float(M_z),
        "fixed": fixed, "magnet": None if chosen.parts is None else chosen.parts.grade,
        "chip": chosen.chip.name,
        "constraints": {"F_r_c_N": float(c.F_r_c), "F_z_c_N": float(c.F_z_c)},
        "chosen": {"H_mm": float(mm(chosen.H)), "G_kPa": float(kpa(chosen.G))},
        "original": {"H_mm": float(mm(original.H)), "G_kPa": float(kpa(original.G))},
        "silicones": [[name, float(kpa(s.G_range[0])), float(kpa(s.G_range[1]))]
                      for name, s in SILICONES.items()],
        "grid": grid, "pareto": pareto,
    }


def write_explorer(result, folder: str | Path) -> Path | None:
    """Write ``explorer.json`` (:func:`explorer_data`) into ``folder``; None where there is
    none to write."""
    data = explorer_data(result)
    if data is None:
        return None
    return write_json(Path(folder) / "explorer.json", data, indent=1, ensure_ascii=False)


#: Most heights and moduli of the grid, and most Pareto points, an explorer file may hold (the
#: writer gives N_H + 2, N_G + 2 and the Pareto set of the optimiser's population).
MAX_LEVELS = 64
MAX_PARETO = 10_000
#: Keys of every grid cell (numbers; ``sat_F_z`` may be null).
CELL_NUMBERS = ("H_mm", "F_z_max", "F_r_min", "Gamma_r_max", "Gamma_z_max")
PARETO_NUMBERS = ("H_mm", "G_kPa", "Gamma_r_max", "Gamma_z_max", "F_r_min", "F_z_max")


def _number(v) -> bool:
    import math

    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def explorer_problem(data) -> str | None:
    """What is wrong with an explorer document's shape (None where it is the shape
    :func:`explorer_data` writes): the format, the levels (numbers, at most
    :data:`MAX_LEVELS`), a grid of exactly one cell per height and modulus, the chosen and the
    original design, the constraints, and at most :data:`MAX_PARETO` Pareto points."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        return f"is not an explorer file (format {FORMAT})"
    H, G, grid = data.get("H_mm"), data.get("G_kPa"), data.get("grid")
    for name, levels in (("H_mm", H), ("G_kPa", G)):
        if not isinstance(levels, list) or not 1 <= len(levels) <= MAX_LEVELS or not all(
                _number(v) and v > 0 for v in levels):
            n = len(levels) if isinstance(levels, list) else "no"
            return (f"{name} must be 1 to {MAX_LEVELS} positive numbers (the file has {n} "
                    "entries or other values)")
    if not isinstance(grid, list) or len(grid) != len(H) or not all(
            isinstance(row, list) and len(row) == len(G) for row in grid):
        return f"grid must be {len(H)} rows of {len(G)} cells (one per H_mm and G_kPa)"
    for row in grid:
        for cell in row:
            if not isinstance(cell, dict) or not all(_number(cell.get(k))
                                                     for k in CELL_NUMBERS):
                return f"a grid cell lacks one of the numbers {', '.join(CELL_NUMBERS)}"
            if not isinstance(cell.get("saturates_in_region"), bool):
                return "a grid cell's saturates_in_region is not true or false"
            if not (cell.get("sat_F_z") is None or _number(cell.get("sat_F_z"))):
                return "a grid cell's sat_F_z is not a number"
            for k in ("sigma_r_worst", "sigma_z_worst", "sigma_r_0", "sigma_z_0"):
                if k in cell and not _number(cell[k]):
                    return f"a grid cell's {k} is not a number"
    for name in ("chosen", "original"):
        d = data.get(name)
        if not isinstance(d, dict) or not (_number(d.get("H_mm")) and _number(d.get("G_kPa"))):
            return f"{name} must hold the numbers H_mm and G_kPa"
    c = data.get("constraints")
    if not isinstance(c, dict) or not all(_number(c.get(k)) for k in ("F_r_c_N", "F_z_c_N")):
        return "constraints must hold the numbers F_r_c_N and F_z_c_N"
    pareto = data.get("pareto", [])
    if not isinstance(pareto, list) or len(pareto) > MAX_PARETO:
        return f"pareto must be a list of at most {MAX_PARETO:,} points"
    if not all(isinstance(q, dict) and all(_number(q.get(k)) for k in PARETO_NUMBERS)
               for q in pareto):
        return f"a Pareto point lacks one of the numbers {', '.join(PARETO_NUMBERS)}"
    fixed = data.get("fixed", {})
    if not isinstance(fixed, dict) or ("standoff_mm" in fixed
                                       and not _number(fixed["standoff_mm"])):
        return "fixed must be a table (standoff_mm a number)"
    if not (data.get("M_z_A_per_m") is None or _number(data.get("M_z_A_per_m"))):
        return "M_z_A_per_m must be a number or null"
    return None


def read_explorer(folder: Path) -> dict | None:
    """``folder/explorer.json`` read through the bounded reader and checked against the
    shape :func:`explorer_data` writes (:func:`explorer_problem`); None where it is missing,
    and noted in the report where it is damaged."""
    return load_json(folder / "explorer.json", explorer_problem)


def explorer_section(folder: Path) -> str:
    """The explorer's HTML (controls, live table, verdict, Pareto set with its cards) from
    ``folder/explorer.json``; nothing without the file."""
    data = read_explorer(folder)
    if data is None:
        return ""
    heights, moduli = data["H_mm"], data["G_kPa"]
    chosen = data["chosen"]
    start = min(range(len(heights)), key=lambda k: abs(heights[k] - chosen["H_mm"]))
    start_G = min(range(len(moduli)), key=lambda j: abs(moduli[j] - chosen["G_kPa"]))
    rows = [("x-sigma-r", "shear resolution σ_Fr, unloaded / worst"),
            ("x-sigma-z", "normal resolution σ_Fz, unloaded / worst"),
            ("x-Fz", "normal force range (largest F_z in the stable region)"),
            ("x-Fr", "shear force range (|F_r| before shear turns unstable)"),
            ("x-sat", f"where the {data.get('chip', 'chip')} saturates"),
            ("x-setting", "chip setting"),
            ("x-silicone", "silicones whose G range holds G")]
    table = "".join(f'<tr><th class="l">{_e(t)}</th><td class="l" id="{i}"></td></tr>'
                    for i, t in rows)
    payload = json.dumps(data, ensure_ascii=True).replace("</", "<\\/")
    return f"""<section id="explorer"><h2>Design explorer</h2>
<p>Move the base height H and the shear modulus G over a grid of {len(heights)} × {len(moduli)}
designs: every number below is one Python computed (<code>Result.evaluate</code>, written to
<code>optimise/explorer.json</code>). {_fixed_text(data)}</p>
<div class="xctl"><label for="x-H">H [mm]</label>
<input type="range" id="x-H" min="0" max="{len(heights) - 1}" step="1" value="{start}">
<output id="x-H-value"></output>
<label for="x-G">G [kPa]</label>
<input type="range" id="x-G" min="0" max="{len(moduli) - 1}" step="1" value="{start_G}">
<output id="x-G-value"></output>
<button type="button" id="x-chosen">chosen design</button>
<button type="button" id="x-original">original design</button></div>
<div class="xgrid"><div><table class="xtable">{table}</table>
<p><b>Verdict</b></p><ul id="x-verdict" class="verdict-list"></ul></div>
<div><p><b>Pareto set</b> ({_designs(len(data.get('pareto', [])))}; Γ_r,max against
Γ_z,max [N/T]): hover or click a point for its design card.</p>
<svg id="x-pareto" viewBox="0 0 360 260" width="360" height="260" role="img"
 aria-label="Pareto set"></svg><div id="x-card" class="xcard"></div></div></div>
<script id="x-data" type="application/json">{payload}</script>
<script>{_SCRIPT}</script></section>"""


def _fixed_text(data: dict) -> str:
    """What stays the chosen design's while H and G move, in words."""
    fixed = data.get("fixed") or {}
    parts = []
    if data.get("magnet") not in (None, "custom"):
        parts.append(f"the magnet ({_e(data['magnet'])})")
    elif data.get("M_z_A_per_m") is not None:
        parts.append(f"M_z ({sig(data['M_z_A_per_m'] / 1e6)} MA/m)")
    else:
        parts.append("the magnet")
    if "standoff_mm" in fixed:
        parts.append(f"the chip's standoff ({sig(fixed['standoff_mm'])} mm)")
    verb = "is" if len(parts) == 1 else "are"
    text = " and ".join(parts)
    return (f"{text[0].upper()}{text[1:]} {verb} the chosen design's; the chip setting is "
            "picked for each design as the optimisation picks it.")


def _designs(n: int) -> str:
    return "one design" if n == 1 else f"{n} designs"


#: The explorer's script: formatting and display only (numbers × G, comparisons with limits).
_SCRIPT = r"""
(function(){
const D = JSON.parse(document.getElementById('x-data').textContent);
const $ = id => document.getElementById(id);
// numbers to 3 significant figures as the report writes them (report/_labels.py sig)
function sig(v){
  if (v === null || v === undefined || !isFinite(v)) return '—';
  if (v === 0) return '0';
  v = Number(v.toExponential(2));
  const a = Math.abs(v);
  if (a >= 1e-3 && a < 1e5) {
    const places = 2 - Math.floor(Math.log10(a));
    return v.toFixed(Math.max(places, 0));
  }
  const [m, e] = v.toExponential(2).split('e');
  return m + 'e' + Number(e);
}
function put(id, text, values){
  const el = $(id); el.textContent = text;
  for (const [k, v] of Object.entries(values || {})) el.dataset[k] = v === null ? '' : v;
}
function cardOf(g, G_kPa){
  const G = G_kPa * 1e3, c = {};
  c.sr0 = g.sigma_r_0 * G; c.srw = g.sigma_r_worst * G;
  c.sz0 = g.sigma_z_0 * G; c.szw = g.sigma_z_worst * G;
  c.Fz = g.F_z_max * G; c.Fr = g.F_r_min * G;
  c.satFz = g.sat_F_z === null ? null : g.sat_F_z * G;
  c.satFr = g.sat_F_r === null ? null : g.sat_F_r * G;
  return c;
}
function satText(g, c){
  if (!g.saturates) return 'never along the paths (largest |B| ' + sig(g.B_max_x_mT) + ' / ' +
    sig(g.B_max_z_mT) + ' mT, x / z)';
  return (g.sat_axis === 'x' ? 'shear' : 'normal') + ' axis at F_z = ' + sig(c.satFz) +
    ' N (t = ' + sig(g.sat_t) + '), ' + (g.saturates_in_region ? 'inside' : 'beyond') +
    ' the stable region';
}
// each requirement of the study against the numbers above: met or not
function verdict(g, c){
  const k = D.constraints, out = [];
  out.push([c.Fz >= k.F_z_c_N, 'normal range at least ' + sig(k.F_z_c_N) + ' N: ' +
            sig(c.Fz) + ' N']);
  const reads = !g.saturates || c.satFz >= k.F_z_c_N;
  out.push([reads, 'reads 0–' + sig(k.F_z_c_N) + ' N normal without saturating: ' +
            (g.saturates ? 'saturates at ' + sig(c.satFz) + ' N' : 'never saturates')]);
  out.push([c.Fr <= k.F_r_c_N, 'shear range at least ' + sig(Math.abs(k.F_r_c_N)) + ' N: ' +
            sig(Math.abs(c.Fr)) + ' N']);
  return out;
}
function silicones(G_kPa){
  const names = D.silicones.filter(s => s[1] <= G_kPa && G_kPa <= s[2]).map(s => s[0]);
  return names.length ? names.join(', ') : 'none in the catalogue';
}
function update(){
  const k = Number($('x-H').value), j = Number($('x-G').value), g = D.grid[k][j];
  const G_kPa = D.G_kPa[j], c = cardOf(g, G_kPa);
  put('x-H-value', sig(D.H_mm[k]) + ' mm', {value: D.H_mm[k]});
  put('x-G-value', sig(G_kPa) + ' kPa', {value: G_kPa});
  put('x-sigma-r', sig(c.sr0 * 1e3) + ' / ' + sig(c.srw * 1e3) + ' mN',
      {zero: c.sr0, worst: c.srw});
  put('x-sigma-z', sig(c.sz0 * 1e3) + ' / ' + sig(c.szw * 1e3) + ' mN',
      {zero: c.sz0, worst: c.szw});
  put('x-Fz', sig(c.Fz) + ' N', {value: c.Fz});
  put('x-Fr', sig(Math.abs(c.Fr)) + ' N', {value: c.Fr});
  put('x-sat', satText(g, c), {fz: c.satFz, fr: c.satFr});
  put('x-setting', g.setting || 'the study\'s');
  put('x-silicone', silicones(G_kPa));
  const ul = $('x-verdict'); ul.innerHTML = '';
  for (const [met, text] of verdict(g, c)) {
    const li = document.createElement('li');
    li.className = met ? 'met' : 'unmet';
    li.textContent = (met ? '✓ ' : '✗ ') + text;
    ul.appendChild(li);
  }
}
// the grid design nearest to (H, G)
function nearest(levels, v){
  let best = 0;
  levels.forEach((x, k) => { if (Math.abs(x - v) < Math.abs(levels[best] - v)) best = k; });
  return best;
}
function setDesign(H_mm, G_kPa){
  $('x-H').value = nearest(D.H_mm, H_mm); $('x-G').value = nearest(D.G_kPa, G_kPa); update();
}
$('x-H').addEventListener('input', update);
$('x-G').addEventListener('input', update);
$('x-chosen').addEventListener('click', () => setDesign(D.chosen.H_mm, D.chosen.G_kPa));
$('x-original').addEventListener('click', () => setDesign(D.original.H_mm, D.original.G_kPa));
// the Pareto set: Γ_r,max (x) against Γ_z,max (y)
const svg = $('x-pareto'), P = D.pareto, NS = 'http://www.w3.org/2000/svg';
function el(name, attrs, text){
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  svg.appendChild(e); return e;
}
function card(p){
  const rows = [['H', sig(p.H_mm) + ' mm'], ['G', sig(p.G_kPa) + ' kPa'],
                ['Γ_r,max / Γ_z,max', sig(p.Gamma_r_max) + ' / ' + sig(p.Gamma_z_max) + ' N/T'],
                ['F_z range', sig(p.F_z_max) + ' N'],
                ['F_r range', sig(Math.abs(p.F_r_min)) + ' N']];
  if (p.card) {
    const c = cardOf(p.card, p.G_kPa);
    // Γ and the forces above are the Pareto set's; these two are Result.evaluate's at the point
    rows.push(['σ_Fr, σ_Fz worst (the magnet and standoff above the grid)',
               sig(c.srw * 1e3) + ', ' + sig(c.szw * 1e3) + ' mN']);
    rows.push(['saturation (the same)', satText(p.card, c)]);
  }
  const div = $('x-card'); div.innerHTML = '';
  const t = document.createElement('table');
  for (const [a, b] of rows) {
    const tr = t.insertRow(); const th = document.createElement('th');
    th.className = 'l'; th.textContent = a; tr.appendChild(th);
    const td = tr.insertCell(); td.className = 'l'; td.textContent = b;
  }
  div.appendChild(t);
  const btn = document.createElement('button'); btn.type = 'button';
  btn.textContent = 'explore the nearest grid design';
  btn.onclick = () => setDesign(p.H_mm, p.G_kPa);
  div.appendChild(btn);
}
if (P.length) {
  const xs = P.map(p => p.Gamma_r_max), ys = P.map(p => p.Gamma_z_max);
  const span = a => { const lo = Math.min(...a), hi = Math.max(...a);
                      const d = (hi - lo) || Math.abs(hi) || 1;
                      return [lo - 0.08 * d, hi + 0.08 * d]; };
  const [x0, x1] = span(xs), [y0, y1] = span(ys);
  const X = v => 50 + 290 * (v - x0) / (x1 - x0), Y = v => 220 - 200 * (v - y0) / (y1 - y0);
  el('line', {x1: 50, y1: 220, x2: 340, y2: 220, stroke: '#888'});
  el('line', {x1: 50, y1: 20, x2: 50, y2: 220, stroke: '#888'});
  el('text', {x: 195, y: 252, 'text-anchor': 'middle', 'font-size': 12}, 'Γ_r,max [N/T]');
  el('text', {x: 12, y: 120, 'font-size': 12, transform: 'rotate(-90 12 120)',
              'text-anchor': 'middle'}, 'Γ_z,max [N/T]');
  el('text', {x: 50, y: 236, 'font-size': 10, 'text-anchor': 'middle'}, sig(x0));
  el('text', {x: 340, y: 236, 'font-size': 10, 'text-anchor': 'end'}, sig(x1));
  el('text', {x: 46, y: 220, 'font-size': 10, 'text-anchor': 'end'}, sig(y0));
  el('text', {x: 46, y: 26, 'font-size': 10, 'text-anchor': 'end'}, sig(y1));
  P.forEach((p, k) => {
    const dot = el('circle', {cx: X(p.Gamma_r_max), cy: Y(p.Gamma_z_max), r: p.card ? 6 : 4,
                              fill: p.card ? '#1f77b4' : '#9ecae1', class: 'x-point',
                              'data-index': k, tabindex: 0});
    dot.addEventListener('mouseenter', () => card(p));
    dot.addEventListener('click', () => card(p));
    dot.addEventListener('focus', () => card(p));
  });
  card(P[0]);
}
update();
})();
"""
