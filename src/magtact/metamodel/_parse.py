"""Restricted reading and exact writing of model expressions.

A metamodel file is data, never code. :func:`parse_expression` accepts only numbers, the model
symbols (t, theta, H, p, q), a whitelist of smooth functions and the operators + − × ÷ ** ^ and
parentheses; the text is tokenised and every token checked *before* SymPy builds the expression,
and the builder sees no Python built-ins; constants are read as doubles. Anything else (attribute
access, names such as ``__import__``, commas, brackets, strings) is refused with a ValueError
naming it.

:func:`format_expression` prints every floating-point constant with the shortest decimal that
reads back to the same double, so ``parse_expression(format_expression(e)) == e`` exactly.
"""

from __future__ import annotations

import io
import token
import tokenize

import sympy as sp
from sympy.parsing.sympy_parser import auto_number, parse_expr
from sympy.printing.str import StrPrinter

from ._symbols import SYMBOLS

#: Functions a model expression may call (all smooth on their domain).
FUNCTIONS: dict[str, sp.Function] = {
    "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt, "tanh": sp.tanh,
    "tan": sp.tan, "atan": sp.atan, "sin": sp.sin, "cos": sp.cos,
}
#: Named constants a model expression may contain.
CONSTANTS: dict[str, sp.Expr] = {"E": sp.E, "pi": sp.pi}
#: Operator tokens a model expression may contain (``^`` is read as ``**``, as Operon writes it).
OPERATORS = frozenset({"+", "-", "*", "/", "**", "^", "(", ")"})

_MAX_CHARS = 200_000


def parse_expression(text: str, allowed_symbols=None) -> sp.Expr:
    """Build a SymPy expression from ``text`` through a whitelist grammar.

    Parameters
    ----------
    text : str
        Infix expression, e.g. ``"exp(-0.5*t)*t*tan(theta)/H"`` or an Operon model string.
    allowed_symbols : iterable of str or dict, optional
        Symbol names allowed (default: t, theta, H, p, q), or a mapping name → SymPy symbol.

    Returns
    -------
    sympy.Expr

    Raises
    ------
    ValueError
        If the text contains anything outside the grammar (the message names the offending
        token), is empty, too long, or does not form one expression.
    """
    if not isinstance(text, str):
        raise ValueError(f"model expression must be a string, got {type(text).__name__}")
    if not text.strip():
        raise ValueError("model expression is empty")
    if len(text) > _MAX_CHARS:
        raise ValueError(f"model expression longer than {_MAX_CHARS} characters")
    if isinstance(allowed_symbols, dict):
        symbols = dict(allowed_symbols)
    else:
        symbols = {n: SYMBOLS[n] for n in (SYMBOLS if allowed_symbols is None else allowed_symbols)}
    names = set(symbols)
    local = symbols | FUNCTIONS | CONSTANTS
    pieces = []
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, IndentationError, SyntaxError) as exc:
        raise ValueError(f"model expression is not well formed: {exc}") from None
    for tok in tokens:
        kind, s = tok.type, tok.string
        if kind in (token.NEWLINE, token.NL, token.ENDMARKER, token.INDENT, token.DEDENT):
            continue
        if kind == token.NUMBER:
            if any(c in s.lower() for c in "jx_") or s.lower().startswith(("0o", "0b")):
                raise ValueError(f"model expression: number {s!r} is not allowed")
        elif kind == token.NAME:
            if s not in local:
                raise ValueError(f"model expression: name {s!r} is not allowed (allowed: "
                                 f"symbols {sorted(names)}, functions {sorted(FUNCTIONS)}, "
                                 f"constants {sorted(CONSTANTS)})")
        elif kind == token.OP:
            if s not in OPERATORS:
                raise ValueError(f"model expression: operator {s!r} is not allowed")
            s = "**" if s == "^" else s
        else:
            raise ValueError(f"model expression: token {s!r} is not allowed")
        pieces.append(s)
    safe = " ".join(pieces)
    try:
        expr = parse_expr(safe, local_dict=local,
                          global_dict={"__builtins__": {}, "Integer": sp.Integer,
                                       "Float": _double, "Rational": sp.Rational},
                          transformations=(auto_number,))
    except (SyntaxError, TypeError, tokenize.TokenError, ZeroDivisionError) as exc:
        raise ValueError(f"model expression is not well formed: {exc}") from None
    if not isinstance(expr, sp.Expr) or expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ValueError(f"model expression does not evaluate to a finite expression: {text!r}")
    return expr


def _double(text: str) -> sp.Float:
    """A constant read as the nearest double (53-bit Float, whatever its number of digits)."""
    return sp.Float(float(text))


class _ExactPrinter(StrPrinter):
    """String printer writing each Float as the shortest decimal of its double (exact)."""

    def _print_Float(self, expr):
        return repr(float(expr))


def format_expression(expr: sp.Expr) -> str:
    """Text of ``expr`` that :func:`parse_expression` reads back exactly.

    Raises
    ------
    ValueError
        If ``expr`` contains an infinite or undefined constant.
    """
    if expr.has(sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise ValueError(f"cannot write a non-finite constant in {expr}")
    return _ExactPrinter(dict(order=None)).doprint(expr)
