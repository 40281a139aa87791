"""An mkdocs hook: the pages' formulas, ``$...$`` inline and ``$$...$$`` displayed, written in
LaTeX and rendered to MathML when the site is built (latex2mathml), so that they render in any
browser with no script and no network. Code (fenced blocks, inline spans) is left as it is."""

from __future__ import annotations

import re
from typing import Any

from latex2mathml.converter import convert

CODE = re.compile(r"(^```.*?^```|`[^`\n]+`)", re.S | re.M)
DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.S)
INLINE = re.compile(r"(?<![\\$\w])\$([^$\n]+?)\$(?![\w$])")


def render(markdown: str) -> str:
    """``markdown`` with every formula outside code turned into MathML."""
    parts = CODE.split(markdown)
    for k in range(0, len(parts), 2):  # the parts between code
        text = DISPLAY.sub(lambda m: convert(m.group(1).strip(), display="block"), parts[k])
        parts[k] = INLINE.sub(lambda m: convert(m.group(1)), text)
    return "".join(parts)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    return render(markdown)
