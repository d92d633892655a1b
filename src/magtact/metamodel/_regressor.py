"""Symbolic regression with smooth operators only, as a scikit-learn estimator (pyoperon inside)."""

from __future__ import annotations

import numpy as np
import sympy as sp
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, check_X_y, validate_data

from ._parse import OPERATOR_SETS, format_expression, parse_expression

#: Operon formats constants with this many decimals; inputs and target are scaled to O(1).
_DIGITS = 15


class SymbolicRegressor(RegressorMixin, BaseEstimator):
    """Genetic-programming symbolic regression returning one SymPy expression.

    Reproducible: it stops after a fixed number of ``generations`` (never on wall time or an
    evaluation budget), and the same ``random_state`` gives the same expression (also with
    several threads). The target is standardised before the search and the expression is
    returned in the original units.

    Parameters
    ----------
    generations : int
        Generations of the genetic algorithm.
    population_size : int
        Individuals per generation.
    max_length : int
        Largest expression tree (nodes).
    operators : {"smooth", "rational"}
        ``"smooth"``: add, sub, mul, div, exp, log, sqrt, tanh; ``"rational"``: add, sub, mul, div.
    local_iterations : int
        Levenberg–Marquardt iterations on the constants of each evaluated tree.
    n_threads : int
        Threads of the search.
    random_state : int
        Seed.
    feature_names : sequence of str, optional
        Names of the input columns in the expression (default ``x0, x1, ...``).

    Attributes
    ----------
    expression_ : sympy.Expr
        The fitted model in the symbols ``symbols_``, constants as doubles.
    symbols_ : tuple of sympy.Symbol
    generations_ : int
        Generations actually run (equals ``generations``).
    """

    def __init__(self, generations: int = 60, population_size: int = 400, max_length: int = 40,
                 operators: str = "smooth", local_iterations: int = 5, n_threads: int = 2,
                 random_state: int = 0, feature_names=None):
        self.generations = generations
        self.population_size = population_size
        self.max_length = max_length
        self.operators = operators
        self.local_iterations = local_iterations
        self.n_threads = n_threads
        self.random_state = random_state
        self.feature_names = feature_names

    def fit(self, X, y):
        """Search an expression for ``y`` (n,) over ``X`` (n, d); returns ``self``.

        Raises
        ------
        ValueError
            Unknown operator set, non-finite data, a constant target, or wrong feature names.
        """
        from pyoperon.sklearn import SymbolicRegressor as Operon

        if self.operators not in OPERATOR_SETS:
            raise ValueError(f"operators must be one of {sorted(OPERATOR_SETS)}, "
                             f"got {self.operators!r}")
        X, y = check_X_y(X, y, dtype=np.float64, y_numeric=True)
        self.n_features_in_ = X.shape[1]
        names = (list(self.feature_names) if self.feature_names is not None
                 else [f"x{i}" for i in range(X.shape[1])])
        if len(names) != X.shape[1] or len(set(names)) != len(names) \
                or not all(n.isidentifier() for n in names):
            raise ValueError(f"feature_names must be {X.shape[1]} distinct identifiers, "
                             f"got {names}")
        mu, sd = float(np.mean(y)), float(np.std(y))
        if not sd > 0:
            raise ValueError("the target is constant: nothing to regress")
        gp = Operon(
            allowed_symbols=OPERATOR_SETS[self.operators] + ",constant,variable",
            generations=self.generations, population_size=self.population_size,
            max_length=self.max_length, optimizer_iterations=self.local_iterations,
            n_threads=self.n_threads, random_state=int(self.random_state),
            max_evaluations=2**62, max_time=None,
        )
        gp.fit(X, (y - mu) / sd)
        # Operon's own names are X1..Xd; ours are mapped through the restricted parser.
        gp_names = [f"gpvar{i}" for i in range(X.shape[1])]
        text = gp.get_model_string(gp.model_, _DIGITS, names=gp_names)
        # no assumptions: with real symbols SymPy would turn sqrt(x**2) into the kink |x|
        symbols = tuple(sp.Symbol(n) for n in names)
        expr = parse_expression(text, dict(zip(gp_names, symbols, strict=True)))
        expr = sp.Float(mu) + sp.Float(sd) * expr
        # Canonical form: the expression equals the one read back from its own text.
        self.expression_ = parse_expression(format_expression(expr),
                                            {s.name: s for s in symbols})
        self.symbols_ = symbols
        self.generations_ = int(gp.stats_["generations"])
        self._f = sp.lambdify(symbols, self.expression_, "numpy")
        return self

    def predict(self, X) -> np.ndarray:
        """Evaluate the fitted expression at ``X`` (n, d); returns (n,)."""
        check_is_fitted(self, "expression_")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return np.broadcast_to(self._f(*X.T), (X.shape[0],)).astype(float)
