"""Hostile model expressions and model files: a finite SymPy expression or one ValueError, fast.

The property tests generate expressions from the grammar (with huge constants, power towers,
deep nesting, names outside the whitelist) and raw token soup, and check that
:func:`magtact.metamodel.parse_expression` returns an expression whose every constant is a finite
double, or raises ValueError; nothing else may escape and nothing may take long.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import known_set
from magtact.metamodel import load_model, load_models, parse_expression, save_models
from magtact.metamodel._parse import MAX_CHARS, MAX_DEPTH, MAX_EXPONENT, MAX_TOKENS

# A parse or refusal takes milliseconds; evaluating what the bounds refuse takes minutes to
# forever (9**9**8 alone takes ~100 s, 9**9**9 about an hour, sin(exp(exp(30))) exactly never),
# so a few seconds still catch an evaluation and leave a loaded, shared machine ample room.
PARSE_SECONDS = 5.0


def refused(text: str, *fragments: str, seconds: float = PARSE_SECONDS) -> str:
    start = time.perf_counter()
    with pytest.raises(ValueError) as info:
        parse_expression(text)
    assert time.perf_counter() - start < seconds, text[:80]
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert len(message) < 1000
    return message


# ---- the bounds, each with its message --------------------------------------------------------
def test_power_tower_refused_without_evaluating_it():
    refused("9**9**9*t", "exponent '387420489'", f"largest allowed magnitude {MAX_EXPONENT}")
    refused("t**(9**9)", "exponent '387420489'")
    refused("2^2^2^2^2*t", "exponent '65536'")
    refused("t**1e6", f"largest allowed magnitude {MAX_EXPONENT}")


def test_constants_must_be_finite_doubles():
    refused("1e400*t", "number '1e400' is outside the range of a double")
    refused("1" + "0" * 400 + "*t", "outside the range of a double")
    refused("(1e99)**4*t", "constant '1.00000000000000e+99'**'4' is outside the range of a double")
    refused("1e300*1e300*t", "is outside the range of a double")
    refused("0**-1", "outside the range of a double")
    refused("tan(2**60)*t", "integer '1152921504606846976' exceeds 2**53", "e.g. 1.15292e+18")
    refused("(" + "*".join(["2**50"] * 11) + ")**(1/3)*t", "exceeds 2**53")
    assert parse_expression("2**53*t") == 2**53 * parse_expression("t")


def test_constants_are_evaluated_in_double_precision():
    """A constant whose exact value would cost SymPy arbitrary precision is refused fast."""
    refused("t**sin(exp(exp(20)))", "constant 'exp(exp(20))' is beyond the range of a double")
    refused("-2e-05**2 * sin(exp(exp(30))) - 4", "constant 'exp(exp(30))' is beyond the range")
    refused("t**sqrt(-1)", "constant 'I' is not a real number in double precision")
    refused("exp(1000)*t", "constant 'exp(1000)' is beyond the range of a double")
    refused("t**(200*sin(3/2))", "exponent '200*sin(3/2)' exceeds the largest allowed magnitude")
    assert parse_expression("t**sin(2)") == parse_expression("t")**sp.sin(2)


def test_text_length_tokens_and_depth_are_bounded():
    refused("t+" * (MAX_CHARS // 2) + "t", f"at most {MAX_CHARS} are read")
    refused("+".join(["t"] * (MAX_TOKENS // 2 + 1)), f"more than {MAX_TOKENS} tokens")
    refused("(" * (MAX_DEPTH + 1) + "t" + ")" * (MAX_DEPTH + 1),
            f"deeper than {MAX_DEPTH} levels")
    refused("-" * 300 + "t", f"deeper than {MAX_DEPTH} levels")
    refused("exp(" * 300 + "t" + ")" * 300, f"deeper than {MAX_DEPTH} levels")
    refused("+".join(["t"] * 300), f"deeper than {MAX_DEPTH} levels")


def test_functions_must_be_called():
    refused("exp + t", "function 'exp' must be called")


def test_models_within_the_bounds_still_read():
    e = parse_expression("t**100 * 2**-100 + (1.5)**(-3) + sqrt(t)**3 + exp(-H/0.004)")
    assert e.has(sp.Symbol("t"))
    nested = "(" * (MAX_DEPTH - 2) + "t" + ")" * (MAX_DEPTH - 2)
    assert parse_expression(nested) == parse_expression("t")


# ---- model files ------------------------------------------------------------------------------
def tampered(tmp_path, **changes):
    save_models(known_set(), tmp_path)
    path = tmp_path / "f_r.json"
    data = json.loads(path.read_text())
    data.update(changes)
    path.write_text(json.dumps(data))
    return path


def test_model_file_with_power_tower_refused_without_evaluating_it(tmp_path):
    tampered(tmp_path, expression="9**9**9*t", expression_pq="9**9**9*p")
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"f_r.json: model expression: exponent '387420489'"):
        load_models(tmp_path)
    assert time.perf_counter() - start < PARSE_SECONDS


def test_cli_validate_refuses_power_tower_model(tmp_path):
    tampered(tmp_path, expression="9**9**9*t", expression_pq="9**9**9*p")
    res = subprocess.run([sys.executable, "-m", "magtact", "validate", "--models", str(tmp_path),
                          "--out", str(tmp_path / "v")], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2, res.stderr
    assert "f_r.json: model expression: exponent '387420489'" in res.stderr
    assert "Traceback" not in res.stderr


def test_model_finite_nowhere_is_refused(tmp_path):
    path = tampered(tmp_path, expression="sqrt(-1 - t)", expression_pq="sqrt(-1 - p)")
    with pytest.raises(ValueError, match="not finite at any of 16 sample points"):
        load_model(path)
    path = tampered(tmp_path, expression="log(-t)*H", expression_pq="log(-p)*H")
    with pytest.raises(ValueError, match="f_r.json: the model is not finite at any"):
        load_model(path)


def test_model_file_read_errors_name_the_file(tmp_path):
    path = tmp_path / "B_r.json"
    path.write_text("[" * 100_000)
    with pytest.raises(ValueError, match=r"B_r.json: not a model file \(JSON nested too deeply"):
        load_model(path)
    path.write_bytes(b'{"format": "\xff"}')
    with pytest.raises(ValueError, match="B_r.json: is not UTF-8 text"):
        load_model(path)
    path.unlink()
    path.mkdir()
    with pytest.raises(ValueError, match="B_r.json: not a model file: it is a folder"):
        load_model(path)


# ---- property-based: generated expressions ----------------------------------------------------
NAMES = st.sampled_from(["t", "theta", "H", "p", "q", "E", "pi", "x", "__import__", "exp"])
NUMBERS = st.one_of(
    st.integers(0, 12).map(str),
    st.integers(0, 10**400).map(str),
    st.floats(min_value=0, allow_nan=False, allow_infinity=False).map(repr),
    st.sampled_from(["1e400", "1e-400", "5e-324", "0.0", "1_0", "0x10", "1j", "9", "99",
                     "exp(exp(20))", "sin(exp(exp(30)))", "2**100*2**100", "(-1)**(1/2)"]),
)
FUNCS = st.sampled_from(["exp", "log", "sqrt", "tanh", "tan", "atan", "sin", "cos", "eval"])
OPS = st.sampled_from(["+", "-", "*", "/", "**", "^"])


def trees(max_leaves: int = 40):
    return st.recursive(
        st.one_of(NAMES, NUMBERS),
        lambda inner: st.one_of(
            st.tuples(inner, OPS, inner).map(lambda x: f"{x[0]} {x[1]} {x[2]}"),
            st.tuples(inner, OPS, inner).map(lambda x: f"({x[0]}){x[1]}({x[2]})"),
            st.tuples(FUNCS, inner).map(lambda x: f"{x[0]}({x[1]})"),
            inner.map(lambda x: f"-{x}"),
            st.tuples(st.integers(1, 300), inner).map(lambda x: "(" * x[0] + x[1] + ")" * x[0]),
            st.tuples(inner, st.integers(2, 6)).map(lambda x: "**".join([x[0]] * x[1])),
        ),
        max_leaves=max_leaves)


SOUP = st.lists(st.sampled_from(["t", "(", ")", "**", "^", "*", "+", "-", "/", "9", "1e308",
                                 "exp", ",", ".", "[", "'", "__", "lambda", " ", "\n", "\\",
                                 "#", "1.5", "H", "pi"]), max_size=60).map("".join)


def parse_or_refuse(text: str):
    """Parse ``text``; return the expression or None if refused with a ValueError."""
    start = time.perf_counter()
    try:
        expr = parse_expression(text)
    except ValueError as exc:
        assert len(str(exc)) < 1000
        return None
    finally:
        assert time.perf_counter() - start < PARSE_SECONDS, text[:200]
    assert_accepted(expr)
    return expr


def assert_accepted(expr) -> None:
    """The oracle of an accepted expression: a finite expression of finite doubles, which
    evaluates numerically without raising."""
    assert isinstance(expr, sp.Expr)
    assert not expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan)
    for number in expr.atoms(sp.Number):
        assert math.isfinite(float(number)), number
    with np.errstate(all="ignore"):
        f = sp.lambdify(sorted(expr.free_symbols, key=str), expr, "numpy")
        f(*([np.linspace(0.1, 1.0, 3)] * len(expr.free_symbols)))


SETTINGS = settings(max_examples=300, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@SETTINGS
@given(st.one_of(trees(), SOUP))
def test_generated_expressions_give_finite_expressions_or_value_errors(text):
    parse_or_refuse(text)
