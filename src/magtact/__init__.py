"""magtact: design magnetic soft tactile sensors by simulation, metamodels and optimisation."""

from importlib.metadata import PackageNotFoundError, version

from ._errors import MagtactError

try:
    __version__ = version("magtact")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"

__all__ = ["MagtactError", "__version__"]
