"""The design card as a value: its tables of the parts compared (a record of ``card.json``) and
the dict that prints as a few lines and shows as a table in a notebook (:func:`magtact.card`)."""

from __future__ import annotations

from dataclasses import dataclass

from ._display import html_block, requirement_rows, round_text, text_block, verdict_title
from ._records import entry, from_json_lenient, keys


@dataclass(frozen=True)
class CardChoices:
    """The tables of ``card.json`` (and of :func:`magtact.card`) that compare the parts the
    sensor problem chose among: the best sensor of each silicone (:func:`silicone_table`) and
    of each magnet size (:func:`size_table`), rows of [label, the sensor in words]. A table
    is left out where the problem chose from one part. The rows are kept as the document gives
    them: a reader shows those that are pairs."""

    silicones: tuple = entry(kind=object, levels=("list",), omit="empty", default=(),
                             doc="the best sensor of each silicone")
    magnet_sizes: tuple = entry(kind=object, levels=("list",), omit="empty", default=(),
                                doc="the best sensor of each magnet size")

    @classmethod
    def of(cls, card) -> CardChoices:
        """The tables of a card document (a table that is not a list: none)."""
        return from_json_lenient(cls, card) or cls()


#: The keys of :class:`CardChoices`' tables in the card (the report's ids of them too).
SILICONES_KEY, SIZES_KEY = keys(CardChoices)


class Card(dict):
    """The design card (:func:`magtact.card`): a dict (``header``, ``rows`` and, where
    the card has them, ``verdict``, ``parts`` and the best sensor of each silicone and of each
    magnet size, :class:`CardChoices`) that prints as a few lines and
    shows as a table in a notebook."""

    def _rows(self) -> tuple[str, list[tuple[str, str]]]:
        header = [str(h) for h in self.get("header", [])]
        verdict = [v for v in self.get("verdict") or [] if isinstance(v, dict)]
        rows = requirement_rows(verdict)
        choices = CardChoices.of(self)
        for p in [*(self.get("parts") or []), *choices.silicones, *choices.magnet_sizes]:
            if isinstance(p, (list, tuple)) and len(p) == 2:
                rows.append((str(p[0]), round_text(str(p[1]))))
        shown = {str(v.get("statement", "")) for v in verdict}  # the verdict's rows, once
        for r in self.get("rows", []):
            if isinstance(r, (list, tuple)) and r and str(r[0]) not in shown:
                rows.append((str(r[0]), " | ".join(round_text(str(c)) for c in r[1:])))
        title = "design card: " + " | ".join(h for h in header if h)
        if verdict:
            title += f"; {header[1] if len(header) > 1 else 'design'}: {verdict_title(verdict)}"
        return title, rows

    def __str__(self) -> str:
        return text_block(*self._rows())

    def _repr_html_(self) -> str:
        return html_block(*self._rows())
