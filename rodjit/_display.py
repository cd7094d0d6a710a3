"""How rodjit's objects show themselves: a few lines of text (``repr``) and the same as a
small HTML table (``_repr_html_``, what Jupyter displays), from one list of rows."""
from __future__ import annotations

import html
import math

__all__ = ["text", "html_table", "number", "aligned"]


def number(value, spec: str = ".4g") -> str:
    """A number for display; NaN (not measured) as '-'."""
    value = float(value)
    return "-" if math.isnan(value) else format(value, spec)


def text(title: str, rows: list[tuple[str, str]]) -> str:
    """``title`` then one indented ``label  value`` line per row."""
    width = max((len(label) for label, _ in rows), default=0)
    return "\n".join([title] + [f"  {label:<{width}}  {value}" for label, value in rows])


def html_table(title: str, rows: list[tuple[str, str]]) -> str:
    """The same rows as an HTML table with ``title`` as its caption."""
    body = "".join(f"<tr><th style='text-align:left'>{html.escape(label)}</th>"
                   f"<td style='text-align:left'>{html.escape(value)}</td></tr>"
                   for label, value in rows)
    return (f"<table><caption style='text-align:left'><b>{html.escape(title)}</b></caption>"
            f"{body}</table>")


def aligned(head: list[str], rows: list[list[str]]) -> list[str]:
    """A header line and one line per row, each column right-aligned to its widest cell."""
    widths = [max(len(h), *(len(r[j]) for r in rows)) if rows else len(h)
              for j, h in enumerate(head)]
    return ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in [head, *rows]]
