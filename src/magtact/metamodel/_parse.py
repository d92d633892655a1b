"""Restricted reading and exact writing of model expressions.

A metamodel file is data, never code. :func:`parse_expression` accepts only numbers, the model
symbols (t, theta, H, p, q), a whitelist of smooth functions and the operators + − × ÷ ** ^ and
parentheses; the text is tokenised and every token checked, then parsed into a Python syntax
tree that is turned into SymPy objects node by node (nothing is evaluated by Python, no built-in
is reachable); constants are read as doubles. Anything else (attribute access, names such as
``__import__``, commas, brackets, strings) is refused with a ValueError naming it.

The cost of reading is bounded before and while the expression is built: at most
:data:`MAX_CHARS` characters, :data:`MAX_TOKENS` tokens and :data:`MAX_DEPTH` levels of nesting;
a constant exponent of magnitude at most :data:`MAX_EXPONENT` (``9**9**9`` is refused at once
instead of computing a 370-million-digit integer); integers of magnitude at most
:data:`MAX_INTEGER`; and every constant is also evaluated in double precision as it is built,
refused unless it is a finite real double (``exp(exp(30))``, ``sqrt(-1)``), so SymPy never needs
arbitrary precision to compare it.

:func:`format_expression` prints every floating-point constant with the shortest decimal that
reads back to the same double, so ``parse_expression(format_expression(e)) == e`` exactly.
"""

from __future__ import annotations

import ast
import io
import math
import token
import tokenize

import sympy as sp
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

#: Longest expression text [characters]. The shipped models have at most 1.6k; SymPy's cost of
#: building an expression grows faster than its length (a few seconds at this bound for the
#: worst shapes, a tenth of a second for the shipped models).
MAX_CHARS = 10_000
#: Most tokens (numbers, names, operators) in one expression.
MAX_TOKENS = 2_500
#: Deepest nesting of the expression tree (parentheses, operators, function calls).
MAX_DEPTH = 200
#: Largest magnitude of a constant exponent.
MAX_EXPONENT = 100
#: Largest magnitude of an integer constant (larger integers are not exact doubles, and numerical
#: libraries cannot evaluate functions of them).
MAX_INTEGER = 2**53

_BINARY = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}

#: Operator sets (all smooth: no abs, min/max, floor, or powers with kinks).
OPERATOR_SETS: dict[str, str] = {
    "smooth": "add,sub,mul,div,exp,log,sqrt,tanh",
    "rational": "add,sub,mul,div",
}


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
    if len(text) > MAX_CHARS:
        raise ValueError(f"model expression has {len(text)} characters; at most {MAX_CHARS} "
                         "are read")
    if isinstance(allowed_symbols, dict):
        symbols = dict(allowed_symbols)
    else:
        symbols = {n: SYMBOLS[n] for n in (SYMBOLS if allowed_symbols is None else allowed_symbols)}
    names = set(symbols)
    local = symbols | FUNCTIONS | CONSTANTS
    pieces = []
    depth = 0
    try:
        tokens = tokenize.generate_tokens(io.StringIO(text).readline)
        for tok in tokens:
            kind, s = tok.type, tok.string
            if kind in (token.NEWLINE, token.NL, token.ENDMARKER, token.INDENT, token.DEDENT):
                continue
            if kind == token.NUMBER:
                if any(c in s.lower() for c in "jx_") or s.lower().startswith(("0o", "0b")):
                    raise ValueError(f"model expression: number {s!r} is not allowed")
                if not math.isfinite(float(s)):
                    raise ValueError(f"model expression: number {_short(s, 40)} is outside the "
                                     "range of a double")
            elif kind == token.NAME:
                if s not in local:
                    raise ValueError(f"model expression: name {s!r} is not allowed (allowed: "
                                     f"symbols {sorted(names)}, functions {sorted(FUNCTIONS)}, "
                                     f"constants {sorted(CONSTANTS)})")
            elif kind == token.OP:
                if s not in OPERATORS:
                    raise ValueError(f"model expression: operator {s!r} is not allowed")
                s = "**" if s == "^" else s
                depth += (s == "(") - (s == ")")
                if depth > MAX_DEPTH:
                    raise ValueError(f"model expression nests parentheses deeper than "
                                     f"{MAX_DEPTH} levels")
            else:
                raise ValueError(f"model expression: token {s!r} is not allowed")
            pieces.append(s)
            if len(pieces) > MAX_TOKENS:
                raise ValueError(f"model expression has more than {MAX_TOKENS} tokens")
    except (tokenize.TokenError, IndentationError, SyntaxError) as exc:
        raise ValueError(f"model expression is not well formed: {exc}") from None
    try:
        tree = ast.parse(" ".join(pieces), mode="eval")
    except (SyntaxError, ValueError) as exc:
        raise ValueError(f"model expression is not well formed: {exc}") from None
    except (RecursionError, MemoryError):
        raise ValueError(f"model expression nests deeper than {MAX_DEPTH} levels") from None
    _check_depth(tree.body)
    try:
        expr = _build(tree.body, local)
    except (TypeError, ZeroDivisionError, OverflowError, RecursionError, MemoryError) as exc:
        raise ValueError(f"model expression is not well formed: {type(exc).__name__}: "
                         f"{str(exc)[:200]}") from None
    if not isinstance(expr, sp.Expr) or expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ValueError(f"model expression does not evaluate to a finite expression: "
                         f"{_short(text)}")
    for number in expr.atoms(sp.Number):
        if not math.isfinite(_as_float(number)):
            raise ValueError(f"model expression: constant {_short(str(number))} is outside the "
                             "range of a double")
    return expr


def _short(text: str, n: int = 80) -> str:
    return repr(text) if len(text) <= n else repr(text[:n]) + f"... ({len(text)} characters)"


def _check_depth(root: ast.AST) -> None:
    """Refuse a tree deeper than :data:`MAX_DEPTH` (checked without recursion)."""
    stack = [(root, 1)]
    while stack:
        node, d = stack.pop()
        if d > MAX_DEPTH:
            raise ValueError(f"model expression nests deeper than {MAX_DEPTH} levels")
        stack.extend((child, d + 1) for child in ast.iter_child_nodes(node))


def _as_float(value: sp.Expr) -> float:
    """A SymPy number as a double (inf beyond the double range)."""
    try:
        return float(value)
    except (OverflowError, TypeError, ValueError):
        return math.inf


def _checked(value: sp.Expr) -> sp.Expr:
    """``value``, refused if it is a number beyond the double range or an integer beyond
    :data:`MAX_INTEGER` (so that constants never grow into huge numbers while the expression is
    built)."""
    if value.is_Number and value.is_finite is not False and not math.isfinite(_as_float(value)):
        raise ValueError(f"model expression: constant {_short(str(value), 40)} is outside the "
                         "range of a double")
    if value.is_Integer and abs(int(value)) > MAX_INTEGER:
        raise ValueError(f"model expression: integer {_short(str(value), 40)} exceeds 2**53 (not "
                         "exact in double precision); write it as a decimal number, e.g. "
                         f"{float(value):.6g}")
    return value


#: Double-precision counterparts of :data:`FUNCTIONS` and :data:`CONSTANTS`.
_MATH = {"exp": math.exp, "log": math.log, "sqrt": math.sqrt, "tanh": math.tanh,
         "tan": math.tan, "atan": math.atan, "sin": math.sin, "cos": math.cos}
_MATH_CONSTANTS = {"E": math.e, "pi": math.pi}


def _float_op(fn, *args) -> float:
    """``fn(*args)`` in double precision: inf on overflow, NaN if the result is not real."""
    try:
        result = fn(*args)
    except (OverflowError, ZeroDivisionError):
        return math.inf
    except ValueError:
        return math.nan
    return float(result) if isinstance(result, (int, float)) else math.nan


def _build(node: ast.AST, local: dict) -> sp.Expr:
    """SymPy object of a checked syntax tree (numbers, names, + - * / **, unary ±, calls)."""
    return _node(node, local)[0]


def _node(node: ast.AST, local: dict) -> tuple[sp.Expr, float | None]:
    """``(SymPy object, its value in double precision if it is a constant, else None)``.

    Every constant is also evaluated in double precision, which costs the same for any
    argument; a constant that is not a finite real double (``exp(exp(30))``, ``sqrt(-1)``) is
    refused before SymPy, whose arbitrary-precision evaluation costs grow with the argument,
    ever compares it.
    """
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        if isinstance(node.value, float):
            if not math.isfinite(node.value):
                raise ValueError(f"model expression: number {node.value!r} is not a finite "
                                 "double")
            return _double(repr(node.value)), node.value
        value = _checked(sp.Integer(node.value))
        return value, float(node.value)
    if isinstance(node, ast.Name):
        if node.id in FUNCTIONS:
            raise ValueError(f"model expression: function {node.id!r} must be called, as in "
                             f"{node.id}(t)")
        return local[node.id], _MATH_CONSTANTS.get(node.id)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        value, v = _node(node.operand, local)
        if isinstance(node.op, ast.UAdd):
            return value, v
        return -value, (None if v is None else -v)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return _product(node, local)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        (left, lv), (right, rv) = _node(node.left, local), _node(node.right, local)
        const = lv is not None and rv is not None
        if isinstance(node.op, ast.Add):
            expr, v = left + right, (_float_op(lambda a, b: a + b, lv, rv) if const else None)
        elif isinstance(node.op, ast.Sub):
            expr, v = left - right, (_float_op(lambda a, b: a - b, lv, rv) if const else None)
        elif isinstance(node.op, ast.Mult):
            expr, v = left * right, (_float_op(lambda a, b: a * b, lv, rv) if const else None)
        elif isinstance(node.op, ast.Div):
            expr, v = left / right, (_float_op(lambda a, b: a / b, lv, rv) if const else None)
        else:
            expr, v = _power(left, lv, right, rv)
        return _constant(_checked(expr), v)
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id in FUNCTIONS and len(node.args) == 1 and not node.keywords):
        arg, v = _node(node.args[0], local)
        expr = FUNCTIONS[node.func.id](arg)
        return _constant(expr, None if v is None else _float_op(_MATH[node.func.id], v))
    raise ValueError(f"model expression is not well formed: {ast.unparse(node)[:80]!r} is not "
                     "a number, symbol, function call or arithmetic")


def _product(node: ast.BinOp, local: dict) -> tuple[sp.Expr, float | None]:
    """A chain of products ``a * b * c`` as one ``Mul(a, b, c)``, as SymPy prints it: built
    pairwise, ``(a * b) * c``, a number times a sum is distributed over the sum first
    (``1.3 * (x + 1) * (y + 1)`` read back as ``(1.3 x + 1.3) * (y + 1)``), and a saved model
    would not read back as the expression it was."""
    chain = []
    while isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        chain.append(node.right)
        node = node.left
    chain.append(node)
    factors = [_node(n, local) for n in reversed(chain)]
    constants = [(f, fv) for f, fv in factors if fv is not None]
    if constants:  # SymPy multiplies the constants together wherever they stand
        c = constants[0][1]
        for _, fv in constants[1:]:
            c = _float_op(lambda a, b: a * b, c, fv)
        _constant(_checked(sp.Mul(*(f for f, _ in constants))), c)
    v = c if len(constants) == len(factors) else None
    return _constant(_checked(sp.Mul(*(f for f, _ in factors))), v)


def _constant(expr: sp.Expr, value: float | None) -> tuple[sp.Expr, float | None]:
    """Refuse a constant whose double-precision value is not a finite real number (an exact
    infinity such as 1/0 is left to the check of the whole expression)."""
    if value is not None and not math.isfinite(value) and not expr.has(sp.zoo, sp.oo, sp.nan):
        what = ("beyond the range of a double" if math.isinf(value) else
                "not a real number in double precision")
        raise ValueError(f"model expression: constant {_short(str(expr), 40)} is {what}")
    return expr, value


def _power(base: sp.Expr, b: float | None, exponent: sp.Expr,
           e: float | None) -> tuple[sp.Expr, float | None]:
    """``base ** exponent`` (and its double value) with a constant exponent bounded by
    :data:`MAX_EXPONENT`."""
    if e is None:
        return base ** exponent, None
    if not abs(e) <= MAX_EXPONENT:
        raise ValueError(f"model expression: exponent {_short(str(exponent), 40)} exceeds the "
                         f"largest allowed magnitude {MAX_EXPONENT}")
    if b is None:
        return base ** exponent, None
    value = _float_op(math.pow, b, e) if b != 0 or e >= 0 else math.inf
    if math.isinf(value):
        raise ValueError(f"model expression: constant {_short(str(base), 40)}**"
                         f"{_short(str(exponent), 40)} is outside the range of a double")
    return base ** exponent, value


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
