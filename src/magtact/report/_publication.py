"""The report's section "magtact and the publication", from ``<run>/publication``."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..publication import PublicationFile
from ._fig_publication import (
    fig_conditioning,
    fig_gamma_over_H,
    fig_gamma_z_along_t,
    fig_resolution_range,
    fig_seed_spread,
)

#: Captions of the section's figures (file stem → caption).
CAPTIONS = {
    "seed_spread": "Γ_r,max and Γ_z,max of the original design and the chosen height H* for "
                   "every GP seed, per sensitivity definition (log scale for Γ). The Jacobian "
                   "is a property of the sensor; the published partial derivative is a "
                   "property of the fitted expression; a seed whose expression does not use "
                   "B has Γ = 0, below the log scale.",
    "gamma_z_along_t": "Γ_z along the loading path at the largest H and θ_max, one line per "
                       "seed; the publication reports Γ_z increasing monotonically with t.",
    "gamma_over_H": "Γ_r,max and Γ_z,max over H at the original design's G, one line per seed "
                    "and definition.",
    "resolution_range": "The resolution–range trade-off: a design (H, G) has Γ = G γ(H) and "
                        "F = G f(H), so over G it moves along a line through the origin whose "
                        "slope is fixed by H (solid: the G bounds). Lower slope: less "
                        "sensitivity to field noise per newton of range.",
    "conditioning": "How well-posed the stable-shear bound is: t_m (minimum of F_r) against the "
                    "smallest t at which F_r is within 1 % of its range of the minimum, and the "
                    "drop of F_z,max between the two.",
}


def publication_figures(folder: str | Path) -> list[Path]:
    """Draw the section's figures from ``folder/publication.json``; write ``captions.json``."""
    folder = Path(folder)
    from .._files import read_result, write_text

    doc = PublicationFile.from_json(read_result(folder / "publication.json", "json"))
    records = list(doc.records) if doc is not None else []
    files = fig_seed_spread(records, folder / "seed_spread")
    files += fig_gamma_z_along_t(records, folder / "gamma_z_along_t")
    own = doc.reference_record() if doc is not None else None
    if own is not None:
        files += fig_gamma_over_H(records, own.original_G, folder / "gamma_over_H")
        if own.sweep is not None and doc.G_range is not None:
            files += fig_resolution_range(own.sweep, doc.G_range, folder / "resolution_range")
        if own.conditioning is not None:
            files += fig_conditioning(own.conditioning, folder / "conditioning")
    write_text(folder / "captions.json", json.dumps(CAPTIONS, indent=1, ensure_ascii=False))
    return files


def publication_section(folder: Path, run_definition: str | None) -> str:
    """HTML of the section (``folder`` = ``<run>/publication``; absent: how to make it)."""
    from ._fragments import escape as _e
    from ._fragments import figure as _figure

    head = ('<h2 id="publication">magtact and the publication</h2>'
            "<p>de Boer et al. (Sensors 2017) optimise the MagOne sensor with a sensitivity "
            "defined as the partial derivative of a fitted force expression "
            "F(B_r, B_z, t, θ, H) in B at fixed (t, θ, H); magtact's default is the Jacobian "
            "∂F/∂B = (∂F/∂u)(∂B/∂u)⁻¹ through the magnet's displacement, a property of the "
            "sensor (docs/method.md §6). The publication prints G in 1–5 kPa; "
            "<code>magone</code> reads it as 10–50 kPa. "
            + (f"This run used the <b>{_e(run_definition)}</b> definition. "
               if run_definition else "") + "</p>")
    head += saturation_argument()
    from ._fragments import load_record

    doc = load_record(folder / "publication.json", PublicationFile,
                      "a seed study (publication.json)")
    if not doc:
        return (head + '<div class="missing">No seed study in this folder: run '
                "<code>magtact reproduce --out FOLDER</code> (about ten minutes on two cores) "
                "to add the side-by-side table and its figures.</div>")
    cols = doc.columns
    rows = "".join(
        f'<tr><td class="l">{_e(r.quantity)}</td><td>{_e(r.unit)}</td>'
        f'<td>{"yes" if r.scale_free else "no"}</td>'
        f'<td>{_e(r.publication_text())}</td>'
        + "".join(f"<td>{_e(r.cell_text(c))}</td>" for c in cols) + "</tr>"
        for r in doc.comparison)
    labels = "".join(f"<th>magtact, {_e(c.split('/')[0])}, G "
                     f"{'as the study reads it' if c.endswith('study') else 'as printed'}</th>"
                     for c in cols)
    table = ('<table class="publication"><tr><th class="l">quantity</th><th>unit</th>'
             f"<th>scale-free</th><th>publication (G as printed)</th>{labels}</tr>{rows}"
             "</table>")
    spread_rows = "".join(
        f'<tr><td class="l">{_e(f.definition)}</td><td class="l">{_e(f.label)}</td>'
        f'<td>{_e(f.unit)}</td><td>{"" if f.n is None else f.n}</td><td>{_num(f.min)}</td>'
        f'<td>{_num(f.max)}</td><td>{_num(f.max_over_min)}</td></tr>'
        for f in doc.spread)
    spread = ('<table><tr><th class="l">definition</th><th class="l">figure</th><th>unit</th>'
              "<th>seeds</th><th>min</th><th>max</th><th>max / min</th></tr>"
              f"{spread_rows}</table>")
    from ._fragments import load_captions

    captions = load_captions(folder / "captions.json")
    figs = "".join(_figure(folder / f"{k}.png", c) for k, c in captions.items()
                   if k in CAPTIONS and os.path.lexists(folder / f"{k}.png"))
    text = ("<p>Median [min, max] over "
            f"{len(doc.seeds)} GP seeds per definition{_budget(doc)} "
            f"({_seconds(doc.wall_time_s)} s, {'?' if doc.workers is None else doc.workers} "
            "workers). Rows marked scale-free do not depend on how G is "
            "read: they are where magtact and the publication can be compared directly. "
            "Every force and Γ is G times a function of H, so each height has a fixed ratio of "
            "worst sensitivity to measurable force (figure <i>resolution–range</i>): choosing "
            "H chooses that ratio, and G then slides the design along its line.</p>")
    return head + text + table + "<h3>Spread across seeds</h3>" + spread + figs


def saturation_argument() -> str:
    """HTML paragraph: the publication's t = 1 against its Hall chip's saturation onset (the
    MLX90393's), with the exact field of the publication's magnet (docs/method.md §10)."""
    from ..metamodel import ExactField
    from ..parts import chip_table
    from ..study import load_study, mm, mt

    s = load_study("magone")
    H0 = s.design.H_original
    sat = abs(float(ExactField(s, "B_z").value(1.0, 0.0, H0)))
    rest = abs(float(ExactField(s, "B_z").value(0.0, 0.0, H0)))
    chip = chip_table(s.hall.chip)
    t = np.linspace(0.0, 1.0, 1001)
    t_on = float(t[np.argmax(np.abs(ExactField(s, "B_z").value(t, 0.0, H0)) > chip.B_sat)])
    return (
        "<p><b>Where the chip saturates.</b> The publication defines t = 1 by the Hall chip's "
        f"saturation, at a magnet–chip distance Δz_sat = {mm(s.loading.dz_sat):.3g} mm. The "
        f"exact field of its magnet (R_m {mm(s.magnet.R_m):.3g} mm, H_m "
        f"{mm(s.magnet.H_m):.3g} mm, M_z {s.magnet.M_z / 1e6:.3g} MA/m) is "
        f"|B_z| = {mt(sat):.0f} mT there, far beyond the {chip.name}'s saturation onset of "
        f"{mt(chip.B_sat):.0f} mT (its datasheet, Table 9), which the field already reaches "
        f"at t = {t_on:.2f} of the original design (|B_z| = {mt(rest):.0f} mT at rest). Either the "
        f"sensor had a chip of about {mt(sat):.0f} mT range, or a weaker or more distant "
        f"magnet: with the {s.hall.chip}, the part of the loading path the publication "
        "optimises over is read only up to the onset. magtact keeps the publication's t for "
        "the comparison and reports where the chip saturates at the setting used (the design "
        "card).</p>")


def _budget(doc: PublicationFile) -> str:
    return (f" (GP: {doc.generations} generations, population {doc.population})"
            if doc.generations is not None and doc.population is not None else "")


def _seconds(v: float) -> str:
    return f"{v:.0f}" if np.isfinite(v) else "—"


def _num(v) -> str:
    return "—" if v is None else f"{v:.3g}"
