"""magtact and the publication (de Boer et al., Sensors 2017): the seed study under both
sensitivity definitions, the side-by-side table, and the publication's own numbers."""

from . import _reference as reference
from ._compare import cell_text, comparison, publication_text, spread
from ._file import (
    ComparisonRow,
    Conditioning,
    PublicationFile,
    SeedRecord,
    Sweep,
)
from ._run import SEED_GENERATIONS, Reproduction, reproduce
from ._seeds import DEFINITIONS, count_branches, seed_study, trend

__all__ = ["Reproduction", "reference", "reproduce"]
