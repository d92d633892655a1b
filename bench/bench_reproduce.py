"""The seed study against the publication: spread across GP seeds under both definitions of Γ.

Usage::

    python bench/bench_reproduce.py [--seeds 8] [--workers 2]

Runs :func:`magtact.publication.reproduce` on the bundled MagOne DOE (force models refitted
with each seed under the Jacobian and the published definition, field models shared), writes
its files and figures to ``bench/results/reproduce/`` and the summary (wall time, spread per
definition, the comparison table) to ``bench/results/reproduce.json``, at the seed study's
default GP budget (``SEED_GENERATIONS``); with ``--generations N`` another budget goes to
``reproduce_gN``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from dataclasses import replace
from pathlib import Path

from magtact.publication import (
    SEED_GENERATIONS,
    Reproduction,
    cell_text,
    comparison,
    publication_text,
    reproduce,
    spread,
)
from magtact.report import publication_figures
from magtact.study import load_study

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--generations", type=int, default=SEED_GENERATIONS,
                        help="GP generations of every fit; another budget than the default "
                             "goes to reproduce_g<N> instead of reproduce")
    parser.add_argument("--cache", default=None,
                        help="folder of finished records (default: none, every fit is timed)")
    parser.add_argument("--summarise", metavar="FOLDER", default=None,
                        help="rebuild the summaries from FOLDER/publication.json of an earlier "
                             "run (e.g. of `magtact reproduce`; no fitting, its wall time is "
                             "kept)")
    args = parser.parse_args()
    study = load_study("magone")
    name = "reproduce"
    if args.generations != SEED_GENERATIONS:
        name = f"reproduce_g{args.generations}"
    if args.summarise:
        doc = json.loads((Path(args.summarise) / "publication.json").read_text())
        recs = doc["records"]
        study = replace(study, metamodel=replace(study.metamodel, generations=args.generations))
        result = Reproduction(study, tuple(doc["seeds"]), recs, spread(recs), comparison(recs),
                              doc["wall_time_s"], doc["workers"])
    else:
        result = reproduce(study, seeds=args.seeds, workers=args.workers, cache=args.cache,
                           generations=args.generations, log=print)
    folder = RESULTS / name
    result.write(folder)
    publication_figures(folder)
    summary = {
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
        "seeds": list(result.seeds), "workers": result.workers,
        "wall_time_s": result.wall_time_s, "target_s": 600.0,
        "fit_time_s": {r["definition"] + f"/{r['seed']}": r.get("fit_time_s")
                       for r in result.records},
        "spread": {d: {k: {x: v[x] for x in ("label", "unit", "min", "max", "max_over_min",
                                             "n") if x in v} | ({"counts": v["counts"]}
                                                                if "counts" in v else {})
                       for k, v in figs.items()} for d, figs in result.spread.items()},
        "comparison": [{"quantity": r["quantity"], "unit": r["unit"],
                        "scale_free": r["scale_free"],
                        "publication": publication_text(r["publication"])}
                       | {k: cell_text(v) for k, v in r.items() if "/" in k}
                       for r in result.comparison],
    }
    summary["gp"] = {"generations": result.study.metamodel.generations,
                     "population": result.study.metamodel.population}
    (RESULTS / f"{name}.json").write_text(json.dumps(summary, indent=1, ensure_ascii=False)
                                            + "\n")
    print(f"wall time {result.wall_time_s:.0f} s")


if __name__ == "__main__":
    main()
