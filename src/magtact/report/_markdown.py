"""Markdown → HTML for the report (CommonMark with pipe tables, by markdown-it-py).

Used for the method appendix (``docs/method.md``, shipped with the package) and the ``*.md``
files a stage leaves in its folder (e.g. ``metamodels.md``). Raw HTML in the source is escaped,
not passed through. Math (```` ```math ```` fences and ``$$`` blocks, LaTeX) becomes MathML,
which browsers render natively and offline, its coefficients to
:data:`~magtact.report._labels.COEFFICIENT_DIGITS` significant digits; numbers in running text
and tables are written to :data:`~magtact.report._labels.DIGITS` (code keeps every digit).
Images whose source names a file the caller can supply (``images``) are embedded as data URIs
so that the report stays one self-contained file; any other image is shown as its alternative
text.
"""

from __future__ import annotations

import base64
import re
from collections.abc import Callable

from latex2mathml.converter import convert as _latex_to_mathml
from markdown_it import MarkdownIt

from ._fragments import escape
from ._labels import COEFFICIENT_DIGITS, round_text, sig

#: MIME types of the images that can be embedded.
_MIME = {".svg": "image/svg+xml", ".png": "image/png", ".jpg": "image/jpeg",
         ".jpeg": "image/jpeg"}


def slug(text: str) -> str:
    """The anchor of a heading as GitHub writes it: lower case, punctuation dropped, spaces
    to hyphens (``"10. The designer's answer"`` → ``"10-the-designers-answer"``)."""
    text = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return text.replace(" ", "-")


def _dollar_blocks(text: str) -> str:
    """``$$`` … ``$$`` blocks (each ``$$`` on its own line) as ```` ```math ```` fences."""
    out, inside = [], False
    for line in text.splitlines():
        if line.strip() == "$$":
            out.append("```" if inside else "```math")
            inside = not inside
        else:
            out.append(line)
    if inside:
        out.append("```")
    return "\n".join(out)


def render_markdown(text: str, *, shift: int = 2, anchor_prefix: str | None = None,
                    images: Callable[[str], bytes | None] | None = None) -> str:
    """Render Markdown ``text`` to an HTML fragment.

    Parameters
    ----------
    text
        CommonMark with pipe tables; ``$$`` blocks are kept verbatim as math.
    shift
        Heading levels added (``#`` becomes ``<h3>`` with the default), capped at ``<h6>``.
    anchor_prefix
        If given, every heading gets ``id = anchor_prefix + slug(heading)`` and every link to
        ``#anchor`` is rewritten to ``#{anchor_prefix}anchor``, so that a document's own table
        of contents works inside the report without clashing with the report's anchors.
    images
        ``images(src)`` returns the bytes of the image ``src`` names, or ``None``; the image is
        then embedded as a data URI. Without it (or for ``None``) the alternative text is shown.
    """
    md = MarkdownIt("commonmark", {"html": False}).enable("table")
    tokens = md.parse(_dollar_blocks(text))
    for k, tok in enumerate(tokens):
        if tok.type in ("heading_open", "heading_close"):
            level = min(int(tok.tag[1:]) + shift, 6)
            if tok.type == "heading_open" and anchor_prefix is not None:
                inline = tokens[k + 1]
                tok.attrSet("id", anchor_prefix + slug(inline.content))
            tok.tag = f"h{level}"
        for child in tok.children or ():
            if child.type == "link_open" and anchor_prefix is not None:
                href = str(child.attrGet("href") or "")
                if href.startswith("#"):
                    child.attrSet("href", "#" + anchor_prefix + href[1:])
            elif child.type == "image":
                _embed(child, images)
            elif child.type == "text":  # numbers to 3 figures, no internal names
                child.content = _SYMBOL.sub(r"Γ_\2", round_text(child.content))
        if tok.type == "fence" and tok.info.strip() == "math":
            tok.type, tok.content = "html_block", mathml(tok.content)
    return md.renderer.render(tokens, md.options, {})


#: Internal names of the sensitivities in a stage's text (``gamma_r``), read as symbols.
_SYMBOL = re.compile(r"\b(gamma|Gamma)_([rz])\b")
#: A decimal number in LaTeX source (not a command's letters, not an exponent's sign alone).
_LATEX_NUMBER = re.compile(r"(?<![\w.])\d+\.\d+(?:[eE][+-]?\d+)?|(?<![\w.])\d{6,}(?![\w.])")


#: LaTeX commands the MathML converter does not read, and what they write.
_UNKNOWN = {r"\lVert": r"\|", r"\rVert": r"\|"}


def mathml(latex: str, digits: int = COEFFICIENT_DIGITS) -> str:
    """LaTeX ``latex`` as a block of MathML, its decimal numbers to ``digits`` significant
    digits; LaTeX the converter cannot read is shown as preformatted source, so a formula is
    never lost."""
    rounded = _LATEX_NUMBER.sub(lambda m: _tex_number(m.group(), digits), latex.strip())
    for command, plain in _UNKNOWN.items():  # commands the converter does not know
        rounded = rounded.replace(command, plain)
    try:
        return f'<div class="math">{_latex_to_mathml(rounded, display="block")}</div>\n'
    except Exception:  # noqa: BLE001 -- the converter raises many types; the source still shows
        return f"<pre>{escape(latex)}</pre>\n"


def _tex_number(text: str, digits: int) -> str:
    """A number of LaTeX source to ``digits`` significant digits (``1.2e-5`` as
    ``1.2 \\cdot 10^{-5}``)."""
    out = sig(float(text), digits)
    if "e" in out:
        mantissa, exponent = out.split("e")
        return f"{mantissa} \\cdot 10^{{{int(exponent)}}}"
    return out


def _embed(token, images: Callable[[str], bytes | None] | None) -> None:
    """Turn an image token into an embedded image, or into its alternative text."""
    src = str(token.attrGet("src") or "")
    suffix = src[src.rfind("."):].lower() if "." in src else ""
    data = images(src) if images is not None and suffix in _MIME else None
    alt = "".join(c.content for c in token.children or ()) or token.content
    if data is None:
        token.type, token.tag, token.children = "text", "", None
        token.content = f"[image: {alt}]" if alt else ""
        return
    token.attrSet("src", f"data:{_MIME[suffix]};base64,{base64.b64encode(data).decode()}")
    token.attrSet("class", "embedded")
    token.content = alt

