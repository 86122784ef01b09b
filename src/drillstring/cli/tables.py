"""Tables that never cut a number, whatever the width of the terminal or log.

rich fits a table that is too wide by shrinking its columns and, as a last resort, cutting cells with ``…``:
``0.64…`` in a terminal of 80 columns, ``observa…`` for a header. :func:`print_table` prints a table so that
every cell and every word of a header stays whole:

1. the table at its natural width, when it fits;
2. else the same in a narrower frame (no borders or padding: columns one space apart, a rule under the
   header), when every cell then stays on one line: a row that wraps over two or three lines reads worse than
   a table without borders;
3. else, in that narrower frame, column widths chosen here: each column at least as wide as its longest word
   (a number has no space, so it is never split), the space left going first to the right-justified (number)
   columns so that their cells stay on one line, then to keeping the cells of as many other columns on one
   line as it can (headers wrap first), then to the columns that still wrap (between words);
4. else, when even that does not fit, one block per row of ``header: value`` lines (a vertical layout).

The commands choose their columns for a terminal of 80 columns (what a table leaves out is in ``--json`` and
the report), so that the first layouts are the ones seen.

Numbers are formatted by each command, with the significant digits of their column (:func:`_fmt`).
"""

from __future__ import annotations

from rich import box
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text


def _fmt(value: float | None, spec: str, scale: float = 1.0) -> str:
    """``value × scale`` in the format ``spec``, or ``–`` for a missing value."""
    return "–" if value is None else format(value * scale, spec)


def _text(console: Console, cell) -> Text | None:
    """The cell as rich text (markup read), None for a renderable that is not a string."""
    if isinstance(cell, Text):
        return cell
    if isinstance(cell, str):
        return console.render_str(cell, highlight=False)
    return None


def _longest_line(text: Text) -> int:
    return max((Text(line).cell_len for line in text.plain.splitlines()), default=0)


def _longest_word(text: Text) -> int:
    return max((Text(word).cell_len for word in text.plain.split()), default=0)


def column_widths(console: Console, table: Table, width: int) -> list[int] | None:
    """Content widths of the columns of ``table`` (padding and borders excluded) that fit a total width
    ``width`` with no word cut; None when rich's natural widths already fit, or when no widths do (see
    :func:`fits`). Each column gets at least its longest word (a number has no space: it is never split); the
    space left goes first to the number columns, so that each cell stays on one line ("0.123 ± 0.045"), then
    to keeping the cells of as many other columns on one line (headers may wrap), in both the columns needing
    least first, then to every column that would still wrap, the widest need first."""
    natural, whole, floor = _width_ranges(console, table)
    if natural is None:
        return None
    one_line = _cell_widths(console, table)
    if one_line is None:
        return None
    room = width - _frame_width(table)
    if sum(natural) <= room or sum(floor) > room:
        return None
    widths = list(floor)
    spare = room - sum(widths)
    for target in (whole, one_line):  # number cells on one line, then as many columns' cells as can be
        for i in sorted(range(len(widths)), key=lambda i: target[i] - widths[i]):
            need = target[i] - widths[i]
            if 0 < need <= spare:
                widths[i] += need
                spare -= need
    while spare > 0:
        short = [i for i in range(len(widths)) if widths[i] < natural[i]]
        if not short:
            break
        for i in sorted(short, key=lambda i: natural[i] - widths[i], reverse=True):
            if spare == 0:
                break
            widths[i] += 1
            spare -= 1
    return widths


def _frame_width(table: Table) -> int:
    """Borders and padding of ``table`` (rich's own accounting of them)."""
    return table._extra_width + sum(table._get_padding_width(i) for i in range(len(table.columns)))


def _width_ranges(console: Console, table: Table) -> tuple[list[int] | None, list[int], list[int]]:
    """Per column: its natural content width, the width that keeps each of its number cells on one line, and
    its longest word; (None, [], []) when a cell is not text."""
    natural, whole, floor = [], [], []
    for column in table.columns:
        header = _text(console, column.header) if table.show_header else Text("")
        cells = [_text(console, cell) for cell in column.cells]
        if header is None or any(cell is None for cell in cells):
            return None, [], []
        everything = [header, *cells]
        words = max(max(_longest_word(t) for t in everything), 1)
        natural.append(max(_longest_line(t) for t in everything))
        floor.append(words)
        cells_width = max((_longest_line(t) for t in cells), default=0) if column.justify == "right" else 0
        whole.append(max(words, cells_width))
    return natural, whole, floor


def _cell_widths(console: Console, table: Table) -> list[int] | None:
    """The widest cell line of each column, its header left out (at least its longest word)."""
    widths = []
    for column in table.columns:
        header = _text(console, column.header) if table.show_header else Text("")
        cells = [_text(console, cell) for cell in column.cells]
        if header is None or any(cell is None for cell in cells):
            return None
        widths.append(max([_longest_word(header), *(_longest_line(cell) for cell in cells), 1]))
    return widths


def fits(console: Console, table: Table) -> bool:
    """Whether ``table`` can be printed as a table in the console's width without cutting a word."""
    natural, _, floor = _width_ranges(console, table)
    return natural is None or sum(floor) <= console.width - _frame_width(table)


def _natural_fits(console: Console, table: Table) -> bool:
    """Whether ``table`` fits the console's width with no cell wrapped (rich's natural widths)."""
    natural, _, _ = _width_ranges(console, table)
    return natural is None or sum(natural) <= console.width - _frame_width(table)


def print_table(console: Console, table: Table) -> None:
    """Print ``table`` on ``console`` with no number, cell or header word cut (module docstring). A title
    justified left is printed on its own, wrapped at the console's width rather than the table's."""
    if table.title and table.title_justify == "left":
        console.print(table.title)
        table.title = None
    if not _natural_fits(console, table):
        _compact(table)
        if not fits(console, table):
            _print_vertical(console, table)
            return
    widths = column_widths(console, table, console.width)
    if widths is not None:
        for column, width in zip(table.columns, widths):
            column.width = width
            column.no_wrap = False
            column.overflow = "fold"
    console.print(table)


def _compact(table: Table) -> None:
    """The narrower frame of ``table``: no outer border, no padding, columns apart by one space, a rule under
    the header."""
    table.box = box.SIMPLE_HEAD
    table.show_edge = False
    table.padding = (0, 0)
    table.pad_edge = False


def _print_vertical(console: Console, table: Table) -> None:
    """``table`` as one block per row: ``header: value`` for the first cell, then indented for each other
    non-empty cell (the value on a line of its own, further indented, when both do not fit on one)."""
    if table.title:
        console.print(table.title)
    headers = [column.header if isinstance(column.header, str) else escape(str(column.header))
               for column in table.columns]
    columns = [list(column.cells) for column in table.columns]
    for row in range(table.row_count):
        cells = [(header, str(column[row]) if row < len(column) else "") for header, column in zip(headers, columns)]
        cells = [(header, cell, Text.from_markup(cell).plain.strip() != "") for header, cell in cells]
        continued = not cells[0][2]  # a row without a first cell goes on with the row above: indented too
        cells = [(header, cell) for header, cell, shown in cells if shown]
        for k, (header, cell) in enumerate(cells):
            indent = "  " if k or continued else ""
            line = f"{indent}{header}: {cell}"
            if k and Text.from_markup(line).cell_len > console.width:
                console.print(f"{indent}{header}:")
                line = f"{indent}  {cell}"
            console.print(line)
    if table.caption:
        console.print(table.caption)
