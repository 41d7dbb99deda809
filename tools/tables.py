"""Plain-text tables for terminals and logs, laid out by rich (no hand-aligned columns)."""
from __future__ import annotations

from io import StringIO

from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text


def text_table(columns: list[str], rows: list[list], *, right: set[str] | frozenset = frozenset(),
               title: str | None = None) -> list[str]:
    """The lines of a table: a header, a rule, one line per row. Columns named in ``right`` are
    right-aligned (numbers); None shows as ``-``.

    >>> for line in text_table(["map", "steps [s]"], [["lt-1", 79], ["a-long-name", None]], right={"steps [s]"}):
    ...     print(line)
     map           steps [s]
    ─────────────────────────
     lt-1                 79
     a-long-name           -
    """
    table = Table(box=box.SIMPLE_HEAD, show_edge=False, title=title, title_justify="left", pad_edge=True)
    for name in columns:  # Text: brackets in names and cells are not markup
        table.add_column(Text(name), justify="right" if name in right else "left", no_wrap=True)
    for row in rows:
        table.add_row(*(Text("-" if v is None else str(v)) for v in row))
    console = Console(file=StringIO(), width=10_000, color_system=None, legacy_windows=False)
    console.print(table)
    return [line.rstrip() for line in console.file.getvalue().splitlines() if line.strip()]
