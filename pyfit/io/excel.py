"""A worksheet of an Excel workbook (.xlsx, .xlsm: what a bench's software or a colleague's spreadsheet saves),
read with openpyxl as the text a CSV export of that sheet would hold, so that the text reader's rules apply
to it unchanged: the header found by the names the sidecar uses (title or settings rows above it), a units row
under it, rows counted as the spreadsheet numbers them. Numbers are written at full precision (a cell holds an
IEEE double: read back bit for bit), dates and times of day as ISO text (the sidecar's time_unit = "clock"),
empty cells empty.
"""
from __future__ import annotations

import datetime
import pathlib


class ExcelFileError(ValueError):
    """The file is not a workbook openpyxl opens, or lacks the sheet asked for."""


def _cell_text(value) -> str:
    """One cell as a CSV export writes it: numbers at full precision (a logical as 0 or 1), dates and times as
    ISO text, text on one line (a line break in a cell as a space: line k stays row k) and quoted where it holds
    a comma or a quote, nothing for an empty cell."""
    if value is None:
        return ""
    if isinstance(value, (bool, int)):
        return str(int(value))
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, datetime.datetime):
        return value.isoformat(sep=" ")
    if isinstance(value, (datetime.time, datetime.date)):
        return value.isoformat()
    text = " ".join(str(value).splitlines())
    return f'"{text.replace(chr(34), chr(34) * 2)}"' if any(c in text for c in ',"') else text


def sheet_text(path: str | pathlib.Path, sheet: str | None = None) -> str:
    """The worksheet `sheet` (default: the workbook's first) as CSV text, one line per spreadsheet row (an
    empty row an empty line, so that line k is row k); raises ExcelFileError for a file openpyxl does not open
    or a sheet the workbook does not hold (naming the sheets it does)."""
    import openpyxl

    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises InvalidFileException, zipfile.BadZipFile, KeyError ...
        raise ExcelFileError(f"{type(exc).__name__}: {exc}") from exc
    try:
        if sheet is not None and sheet not in book.sheetnames:
            raise ExcelFileError(f"no sheet '{sheet}'; sheets: {', '.join(book.sheetnames)}")
        rows = [tuple(r) for r in (book[sheet] if sheet is not None else book.worksheets[0]).iter_rows(
            values_only=True)]
    finally:
        book.close()
    width = max((len(r) for r in rows), default=0)  # every row as wide as the widest (a writer may cut them short)
    return "".join("\n" if all(v is None for v in r) else
                   ",".join(_cell_text(v) for v in r + (None,) * (width - len(r))) + "\n" for r in rows)
