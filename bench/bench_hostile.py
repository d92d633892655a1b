"""Benchmark: thousands of hostile inputs through the three readers of user files.

Generates study documents (TOML, and raw text/bytes), validation tables (CSV pairs, and raw
text/bytes) and model expressions with the Hypothesis strategies of ``tests/test_hostile_*.py``
and hands each case to a worker process that reads it with magtact
(:func:`magtact.study.load_study`, :func:`magtact.validation.read_experiment`,
:func:`magtact.metamodel.parse_expression`). Each case ends in one of:

``clean``             refused with the project's error (StudyError, DataError, ValueError) whose
                      message is one line;
``accepted``          read, and the result satisfies every documented rule (the tests' oracles);
``wrongly_accepted``  read, but the result breaks a rule (a number out of bounds, a NaN...);
``traceback``         any other exception, or a refusal whose message is not one line;
``hang``              no answer within ``--timeout`` seconds (the worker is killed and restarted).

Writes the counts per reader to ``bench/results/hostile.json``; all but ``clean`` and
``accepted`` should be zero.

    nice -n 10 python bench/bench_hostile.py            # ~3 min on the 2-core machine
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import platform
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

OUTCOMES = ("clean", "accepted", "wrongly_accepted", "traceback", "hang")


# ---- generating the cases ---------------------------------------------------------------------
def generate(strategy, n: int, seed: int) -> list:
    """``n`` examples of a Hypothesis strategy (generation phase only, reproducible)."""
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hseed

    out = []

    @hseed(seed)
    @settings(max_examples=n, phases=[Phase.generate], deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def collect(example):
        out.append(example)

    collect()
    return out


def cases(n: int) -> dict[str, list]:
    from hypothesis import strategies as st

    import test_hostile_csv as hc
    import test_hostile_expressions as he
    import test_hostile_study as hs

    raw = n // 4
    return {
        "study_toml": generate(hs.documents(), n, 1),
        "study_raw": generate(st.one_of(st.lists(hs.TOML_TOKENS, max_size=40).map("".join),
                                        st.binary(max_size=200)), raw, 2),
        "csv_tables": generate(st.tuples(hc.tables(), hc.tables()), n, 3),
        "csv_raw": generate(st.one_of(st.binary(max_size=300), st.text(max_size=300)), raw, 4),
        "expressions": generate(st.one_of(he.trees(), he.SOUP), n, 5),
        "expressions_large": generate(large_expressions(), max(n // 50, 10), 6),
    }


def balanced(leaves: list[str], ops: list[str]) -> str:
    """A balanced tree of ``leaves`` joined by ``ops`` in turn (shallow, however many leaves)."""
    if len(leaves) == 1:
        return leaves[0]
    m = len(leaves) // 2
    return (f"({balanced(leaves[:m], ops)}{ops[len(leaves) % len(ops)]}"
            f"{balanced(leaves[m:], ops)})")


def large_expressions():
    """Valid-looking expressions up to the reader's size bounds (shapes that are costly for
    SymPy to build: sums, quotients and powers of transcendental terms)."""
    from hypothesis import strategies as st

    leaf = st.sampled_from(["exp(0.37*t)*tanh(theta*1.3+H)", "(0.5+t)/(H-0.002)",
                            "sqrt(t+0.1)", "log(1+p)*q", "atan(q/p)", "t**theta"])
    ops = st.sampled_from([["+", "*", "-", "/"], ["/"], ["+", "/"], ["**"], ["*"]])
    return st.builds(balanced, st.lists(leaf, min_size=20, max_size=400), ops)


# ---- reading one case (in the worker) ---------------------------------------------------------
def one_line(message: str) -> bool:
    return "\n" not in message and 0 < len(message) < 2100


def run_case(kind: str, case) -> tuple[str, str]:
    """Read one case; return (outcome, detail)."""
    import tomli_w

    import test_hostile_csv as hc
    import test_hostile_expressions as he
    import test_hostile_study as hs
    from magtact.metamodel import parse_expression
    from magtact.study import StudyError, load_study
    from magtact.validation import DataError, read_experiment

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        try:
            if kind.startswith("study"):
                if kind == "study_toml":
                    try:
                        data = tomli_w.dumps(case).encode("utf-8")
                    except (TypeError, ValueError, OverflowError):
                        return "skip", ""
                else:
                    data = case.encode("utf-8") if isinstance(case, str) else case
                path = folder / "s.toml"
                path.write_bytes(data)
                try:
                    s = load_study(path)
                except StudyError as exc:
                    return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
                hs.assert_within_bounds(s)
                return "accepted", ""
            if kind.startswith("csv"):
                if kind == "csv_tables":
                    paths = []
                    for k, table in enumerate(case):
                        paths.append(folder / f"t{k}.csv")
                        paths[-1].write_bytes(hc.render(*table).encode("utf-8"))
                else:
                    paths = [folder / "raw.csv"]
                    paths[0].write_bytes(case if isinstance(case, bytes)
                                         else case.encode("utf-8", "surrogatepass"))
                try:
                    read_experiment(paths)
                except DataError as exc:
                    return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
                hc.read_or_refuse(paths)  # the oracle (raises AssertionError if a rule fails)
                return "accepted", ""
            try:
                expr = parse_expression(case)
            except ValueError as exc:
                return ("clean" if one_line(str(exc)) else "traceback"), str(exc)[:200]
            he.assert_accepted(expr)
            return "accepted", ""
        except AssertionError as exc:
            return "wrongly_accepted", f"{exc!r}"[:300]
        except Exception as exc:  # noqa: BLE001 - counting every other exception is the point
            return "traceback", f"{type(exc).__name__}: {exc}"[:300]


def worker(conn) -> None:
    while True:
        job = conn.recv()
        if job is None:
            return
        conn.send(run_case(*job))


# ---- the driver ---------------------------------------------------------------------------------
class Pool:
    """One worker process fed case by case; killed and restarted when a case hangs."""

    def __init__(self):
        self.proc = None
        self.start()

    def start(self):
        self.conn, child = mp.Pipe()
        self.proc = mp.get_context("fork").Process(target=worker, args=(child,), daemon=True)
        self.proc.start()

    def run(self, kind, case, timeout: float):
        self.conn.send((kind, case))
        if self.conn.poll(timeout):
            return self.conn.recv()
        self.proc.kill()
        self.proc.join()
        self.start()
        return "hang", repr(case)[:200]

    def close(self):
        self.conn.send(None)
        self.proc.join(5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=3000, help="cases per generated reader")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds before a hang")
    parser.add_argument("--json", default=str(HERE / "results" / "hostile.json"))
    args = parser.parse_args()
    start = time.perf_counter()
    generated = cases(args.n)
    gen_time = time.perf_counter() - start
    pool = Pool()
    pool.run("expressions", "t", args.timeout)  # imports, so that they do not count as a hang
    results = {}
    for kind, items in generated.items():
        counts = dict.fromkeys(("cases", *OUTCOMES, "skipped"), 0)
        examples: dict[str, list[str]] = {o: [] for o in OUTCOMES if o not in ("clean",
                                                                                "accepted")}
        slowest = 0.0
        t0 = time.perf_counter()
        for case in items:
            c0 = time.perf_counter()
            outcome, detail = pool.run(kind, case, args.timeout)
            slowest = max(slowest, time.perf_counter() - c0)
            if outcome == "skip":
                counts["skipped"] += 1
                continue
            counts["cases"] += 1
            counts[outcome] += 1
            if outcome in examples and len(examples[outcome]) < 5:
                examples[outcome].append(detail)
        results[kind] = {**counts, "slowest_case_s": round(slowest, 3),
                         "wall_time_s": round(time.perf_counter() - t0, 1),
                         "examples": {k: v for k, v in examples.items() if v}}
        print(kind, {k: v for k, v in results[kind].items() if k != "examples"}, flush=True)
    pool.close()
    total = {o: sum(r[o] for r in results.values()) for o in ("cases", *OUTCOMES)}
    report = {
        "benchmark": "hostile inputs through the study, CSV and expression readers",
        "cases_per_reader": args.n, "hang_timeout_s": args.timeout,
        "generation_time_s": round(gen_time, 1),
        "wall_time_s": round(time.perf_counter() - start, 1),
        "total": total, "readers": results,
        "machine": {"python": sys.version.split()[0], "platform": platform.platform()},
    }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print("total", total)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
