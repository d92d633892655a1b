"""Write ``src/magtact/sensitivity/_phi_code.py``: γ of v = (f_p, f_q, Br_p, Br_q, Bz_p, Bz_q)
and its first and second derivatives as plain NumPy code, from the SymPy derivation
``magtact.sensitivity._gamma._phi_functions`` (deriving them at import took seconds in every
process). ``tests/test_sensitivity.py`` checks the written code against a fresh derivation.

Usage::

    python scripts/make_phi.py
"""

from __future__ import annotations

import inspect
from pathlib import Path

from magtact.sensitivity._gamma import _phi_functions

OUT = Path(__file__).resolve().parents[1] / "src" / "magtact" / "sensitivity" / "_phi_code.py"
NAMES = ("phi", "phi_d1", "phi_d2")


def main() -> None:
    parts = ['"""γ = |row of ∂F/∂B| of v = (f_p, f_q, Br_p, Br_q, Bz_p, Bz_q), its gradient and',
             "Hessian in v (docs/method.md §6), written by ``scripts/make_phi.py`` from the SymPy",
             'derivation ``magtact.sensitivity._gamma._phi_functions``: do not edit."""',
             "", "# ruff: noqa", "from numpy import sqrt", ""]
    for name, fn in zip(NAMES, _phi_functions(), strict=True):
        src = inspect.getsource(fn).replace("def _lambdifygenerated(", f"def {name}(", 1)
        parts += ["", src.rstrip(), ""]
    OUT.write_text("\n".join(parts) + "\n", encoding="utf-8")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
