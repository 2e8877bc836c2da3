"""The readings CSV, the interchange format of the design (``t,sensor,x,y,theta,range``).

One row per reading; two optional columns: ``beam_width`` (radians) and ``max_range`` (metres,
how far the sensor listened), either alone or both. Units: seconds, metres, radians
counter-clockwise from +x. Column order is free on reading; extra columns are ignored. The
writer's order is ``t,sensor,x,y,theta,range``, then ``beam_width`` and ``max_range`` when some
row's value is known. An empty optional cell is unknown (NaN).

No-echo rows: ``range`` = ``inf`` marks a beam that heard nothing up to the row's ``max_range``
(or the run-wide ``max_range`` given to the reader, for rows that leave it empty): free space,
no point. ``inf`` with no max range known is an error, as is a finite range beyond it.

Reading is strict, so that a damaged file fails loudly instead of mapping the wrong numbers:
every line must have as many fields as the header, no column name may appear twice, and a
blank line is an error unless only blank lines follow it (a trailing newline or two at the end
of a file is common and harmless; a blank line in the middle usually marks two logs pasted
together). A UTF-8 byte-order mark, as spreadsheet programs write, is accepted.

Reading streams: :func:`iter_readings_csv` yields the file as validated batches of a few
megabytes each, so a log of any length is read in bounded memory, and
:func:`read_readings_csv` joins them. A block of plain lines (no quotes, no NUL, line breaks
``\\n`` or ``\\r\\n``) that holds only numbers and passes validation is parsed whole by a
compiled parser, or numpy's C parser where it cannot decide (both exactly as ``float``
reads each number: :func:`_parse_numbers`); a plain block
with anything else (an empty cell, ``nan``, spaces, a bad line) is split and converted column
by column (``float`` over a column, no per-row Python code); anything else (quoted fields, a
lone ``\\r``) is read by the :mod:`csv` module from that block on. All give the same values
and errors. The error names the first bad
line of the file (its first problem in the order: field count, a non-numeric cell in column
order, then the checks of :meth:`~sonarcarve.readings.ReadingBatch.validate`), whatever the
block size.
"""

from __future__ import annotations

import csv
import io
import math
import os
import stat
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, NoReturn

import numpy as np

from sonarcarve.errors import ConfigError
from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import InputError, parse_number, shorten
from sonarcarve.io.sanity import csv_shape_hint
from sonarcarve.readings import MAX_READING_RANGE, ReadingBatch, ReadingsError
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "BLOCK_SIZE",
    "MAX_LINE_BYTES",
    "READINGS_COLUMNS",
    "count_data_lines",
    "iter_readings_csv",
    "read_readings_csv",
    "write_readings_csv",
]

#: Required columns, in the order they are written.
READINGS_COLUMNS = ("t", "sensor", "x", "y", "theta", "range")
#: Optional columns, in the order they are written (each only when some value is known).
_OPTIONAL = ("beam_width", "max_range")
#: Bytes read at a time by :func:`iter_readings_csv` (about 15,000 rows of a typical log).
BLOCK_SIZE = 1 << 20
#: Longest line read, bytes: a readings row is about 64 bytes and a header a few hundred, so a
#: longer line means the file is no readings CSV (a binary file, a log without line breaks),
#: and it is refused at once instead of being read whole into memory.
MAX_LINE_BYTES = 1 << 20
_BOM = b"\xef\xbb\xbf"
_LINE_BREAK_BYTES = (ord("\r"), ord("\n"))
_ROW_BYTES = 64  # a typical row's length, to size the csv module's batches like the blocks


def read_readings_csv(path: str | Path, *, block_size: int = BLOCK_SIZE,
                      max_range: float | None = None) -> ReadingBatch:
    """Read and validate a readings CSV (:func:`iter_readings_csv`'s batches joined).

    ``block_size`` (bytes read at a time) changes neither the result nor the error;
    ``max_range`` is as for :func:`iter_readings_csv`.

    Raises
    ------
    InputError
        One line naming the file, the line and the column of the first bad line: a missing file
        or column, a duplicated column name, a line with more or fewer fields than the header,
        a blank line before the last data line, a non-numeric, NaN or infinite value, a sensor
        that is not a whole number, range <= 0, beam width outside (0, π), time going
        backwards, ``range`` = ``inf`` with no max range known, a range beyond the max range,
        a value beyond the bounds of :func:`~sonarcarve.readings.check_reading`; a file that is
        not text (a NUL byte) or has a line longer than :data:`MAX_LINE_BYTES`. A missing
        column's message adds a hint when the header looks separated by ``;`` or tabs, or in
        capitals (:func:`~sonarcarve.io.sanity.csv_shape_hint`).
    """
    batches = list(iter_readings_csv(path, block_size=block_size, max_range=max_range))
    if len(batches) == 1:
        return batches[0]
    return ReadingBatch.concatenate(batches) if batches else ReadingBatch.empty()


def iter_readings_csv(path: str | Path, *, block_size: int = BLOCK_SIZE,
                      max_range: float | None = None) -> Iterator[ReadingBatch]:
    """The readings of a CSV as validated batches of about ``block_size`` bytes of text each.

    Each batch is validated with the file's line numbers and the time of the batch before it,
    so the batches joined are what :func:`read_readings_csv` returns, and a bad line raises as
    the iteration reaches it (after the batches before it have been yielded).

    Parameters
    ----------
    path : str or Path
        The readings CSV.
    block_size : int
        Bytes read at a time (at least 1; a longer line is read whole).
    max_range : float, optional
        Run-wide max range, metres (finite, > 0): the ``max_range`` of every no-echo row
        (``inf``) that does not give its own (no column, or an empty cell), so that it is a
        no-echo reading. Echo rows are left as they are: an echo beyond a run-wide value is
        one for a reading filter to drop (``sonarcarve process --max-range``), not a broken
        file, whereas a row's own ``max_range`` below its range is.

    Yields
    ------
    ReadingBatch
        The next rows of the file, in order; never empty.

    Raises
    ------
    InputError
        As :func:`read_readings_csv`.
    ConfigError
        A ``max_range`` that is not a finite number > 0, or ``block_size`` < 1.
    """
    path = Path(path)
    if block_size < 1:
        msg = f"block_size must be at least 1 byte, got {block_size}"
        raise ConfigError(msg)
    if max_range is not None and not (isinstance(max_range, int | float)
                                      and 0.0 < max_range <= MAX_READING_RANGE):
        msg = (f"max_range must be a finite number > 0 metres, at most "
               f"{MAX_READING_RANGE:,.0f}, got {max_range!r}")
        raise ConfigError(msg)
    try:
        handle = path.open("rb")
    except FileNotFoundError:
        msg = f"{path}: no such file"
        raise InputError(msg) from None
    except OSError as err:
        msg = f"{path}: cannot read as CSV ({err.strerror or err})"
        raise InputError(msg) from None
    with handle:
        reader = _Reader(path, _Blocks(path, handle, block_size), block_size, max_range)
        yield from reader.batches()


def count_data_lines(path: str | Path, *, block_size: int = BLOCK_SIZE) -> int:
    """The number of data rows of a readings CSV, counted from its line breaks without parsing.

    Exact for a file :func:`iter_readings_csv` reads without error whose line breaks are ``\\n``
    or ``\\r\\n`` and whose fields hold none (the common case): meant as the total of a progress
    bar. Blank lines at the end are not counted. 0 for a missing or unreadable file, for one
    that is not a regular file (a device or a pipe: counting would never end, or consume it)
    and for one with a NUL byte (which the reader refuses).
    """
    breaks = 0
    tail = 0  # line breaks after the last byte of content
    content = False
    try:
        with Path(path).open("rb") as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                return 0
            while block := handle.read(block_size):
                if b"\0" in block:
                    return 0
                breaks += block.count(b"\n")
                stripped = block.rstrip(b"\r\n")
                if stripped:
                    content = True
                    tail = block.count(b"\n", len(stripped))
                else:
                    tail += block.count(b"\n")
    except OSError:
        return 0
    # Lines up to the last with content: breaks - tail + 1; the header is one of them.
    return breaks - tail if content else 0


# --------------------------------------------------------------------------------------------
# Blocks of lines
# --------------------------------------------------------------------------------------------


@dataclass
class _Block:
    """Whole lines of the file; :meth:`text` (decoded) ends with its last line's break, if any.

    Decoded only when asked: a block of plain numbers is parsed from its bytes (which are then
    ASCII, so valid UTF-8), and decoding a megabyte costs as much as a tenth of parsing it.
    """

    path: Path
    first_line: int  # line number of the first line (lines counted by "\n")
    raw: bytes
    breaks: int  # line breaks ("\n") in ``raw``

    @property
    def lines(self) -> int:
        """Lines in the block (the last one may lack its break)."""
        return self.breaks + (0 if self.raw.endswith(b"\n") else 1)

    def text(self) -> str:
        """The block decoded; :class:`InputError` naming the line of a byte that is not UTF-8."""
        try:
            return self.raw.decode("utf-8")
        except UnicodeDecodeError as err:
            line = self.first_line + self.raw.count(b"\n", 0, err.start)
            msg = (f"{self.path}: line {line}, cannot read as CSV: not UTF-8 text "
                   f"(byte 0x{self.raw[err.start]:02x})")
            raise InputError(msg) from None


class _Blocks:
    """A binary file as :class:`_Block` s of whole lines, ``block_size`` bytes or so each.

    Blank lines at the end of a block are held back and put in front of the next block, so
    that blank lines at the end of the file, which are harmless, are never seen at all: a block
    ends with content, and blank lines are only ever met with content after them.

    A file that is not text stops the iteration as soon as it is read, so that ``/dev/zero`` or
    a binary file fails at once instead of filling the memory: a NUL byte (after the lines
    before its own, so that an earlier bad line is still the one named, whatever the block
    size), or a line longer than :data:`MAX_LINE_BYTES`.
    """

    def __init__(self, path: Path, handle: IO[bytes], block_size: int) -> None:
        self.path = path
        self.handle = handle
        self.block_size = block_size
        self.line = 1

    def __iter__(self) -> Iterator[_Block]:
        pending = b""
        first = True
        while True:
            try:
                data = self.handle.read(self.block_size)
            except OSError as err:
                msg = f"{self.path}: cannot read as CSV ({err.strerror or err})"
                raise InputError(msg) from None
            buffer = pending + data
            if first and (buffer.startswith(_BOM) or not _BOM.startswith(buffer[:3])):
                buffer = buffer.removeprefix(_BOM)  # once the first 3 bytes are known
                first = False
            # Only the new bytes can hold a NUL or end the line that ``pending`` began (0 when
            # a byte-order mark was just dropped from them).
            new = max(0, len(buffer) - len(data))
            nul = buffer.find(b"\0", new) if b"\0" in data else -1
            self._check_line_length(buffer, new, nul)
            if nul >= 0:
                yield from self._not_text(buffer, nul)
            if not data:  # end of file: what is left is the last line(s), blank lines dropped
                content = buffer.rstrip(b"\r\n")
                if content:
                    yield self._block(content)
                return
            # Where the content before the last line break ends (blank lines stripped), found
            # from the end: slicing and stripping the whole buffer would copy a megabyte.
            stop = buffer.rfind(b"\n") + 1
            while stop and buffer[stop - 1] in _LINE_BREAK_BYTES:
                stop -= 1
            if not stop:  # only blank lines so far: keep them for later
                pending = buffer
                continue
            end = stop + (2 if buffer.startswith(b"\r\n", stop) else 1)
            pending = buffer[end:]
            yield self._block(buffer[:end])

    def _check_line_length(self, buffer: bytes, new: int, nul: int) -> None:
        """Raise if the line running through ``buffer[new]`` (the first byte read last) is
        longer than :data:`MAX_LINE_BYTES`, counted up to its end, the NUL or the buffer's end.

        Lines that begin and end within one read are at most ``block_size`` bytes long.
        """
        start = buffer.rfind(b"\n", 0, new) + 1
        stop = buffer.find(b"\n", new)
        stop = len(buffer) if stop < 0 else stop
        if nul >= 0:
            stop = min(stop, nul)
        if stop - start > MAX_LINE_BYTES:
            line = self.line + buffer.count(b"\n", 0, start)
            msg = (f"{self.path}: line {line} is longer than {MAX_LINE_BYTES >> 20} MiB: "
                   "not a readings CSV")
            raise InputError(msg)

    def _not_text(self, buffer: bytes, nul: int) -> Iterator[_Block]:
        """The whole lines before the one with the NUL byte at ``buffer[nul]``, then the error
        (worded as :func:`~sonarcarve.io.errors.read_text` words it)."""
        line = self.line + buffer.count(b"\n", 0, nul)
        content = buffer[: buffer.rfind(b"\n", 0, nul) + 1].rstrip(b"\r\n")
        if content:
            end = len(content) + (2 if buffer.startswith(b"\r\n", len(content)) else 1)
            yield self._block(buffer[:end])
        msg = f"{self.path}: not text (NUL byte at line {line})"
        raise InputError(msg)

    def _block(self, raw: bytes) -> _Block:
        block = _Block(self.path, self.line, raw, raw.count(b"\n"))
        self.line += block.breaks
        return block


def _plain(block: _Block) -> str | None:
    """The block's lines joined by ``\\n`` (no final break) if it can be split on commas and
    line breaks alone, as :mod:`csv` would split it; None otherwise."""
    text = block.text()
    if "\r" in text:
        text = text.replace("\r\n", "\n")
        if "\r" in text:
            return None  # a lone carriage return ends a line for the csv module
    if '"' in text or "\0" in text:
        return None  # quoting, or a NUL, which the csv module refuses
    return text.removesuffix("\n")


# --------------------------------------------------------------------------------------------
# Rows to batches
# --------------------------------------------------------------------------------------------


class _Reader:
    """Turns blocks into validated batches: header first, then plain blocks split in bulk,
    and from the first block that is not plain on, the csv module.

    The generators only yield finished batches: the conversion happens in plain methods, so
    the text and the cells of a block are freed before the caller gets its batch.
    """

    def __init__(self, path: Path, blocks: _Blocks, block_size: int,
                 max_range: float | None = None) -> None:
        self.path = path
        self.max_range = max_range
        self.blocks = iter(blocks)
        self.rows_per_batch = max(1, block_size // _ROW_BYTES)
        self.previous_t = -math.inf
        self.width = 0
        self.indices: dict[str, int] = {}

    def batches(self) -> Iterator[ReadingBatch]:
        first = next(self.blocks, None)
        if first is None:
            msg = f"{self.path}: empty file, expected a header {','.join(READINGS_COLUMNS)}"
            raise InputError(msg)
        plain = _plain(first)
        if plain is None:
            yield from self._csv_batches(first, header=True)
            return
        header, _, body = plain.partition("\n")
        self._header(header.split(","))
        if body:
            raw = first.raw[first.raw.index(b"\n") + 1 :]
            rest = _Block(self.path, 2, raw, first.breaks - 1)
            batch = self._numbers_batch(rest)
            yield self._plain_batch(rest, body) if batch is None else batch
        del first, plain, body
        while (block := next(self.blocks, None)) is not None:
            batch = self._numbers_batch(block)  # the common case: only numbers, all good
            if batch is None:
                plain = _plain(block)
                if plain is None:
                    yield from self._csv_batches(block, header=False)
                    return
                batch = self._plain_batch(block, plain)
                del plain
            del block
            yield batch

    def _header(self, names: list[str]) -> None:
        header = [name.strip() for name in names]
        _check_header(self.path, header)
        self.width = len(header)
        wanted = [*READINGS_COLUMNS, *(name for name in _OPTIONAL if name in header)]
        self.indices = {name: header.index(name) for name in wanted}

    # -- plain blocks: split in bulk --------------------------------------------------------

    def _plain_batch(self, block: _Block, text: str) -> ReadingBatch:
        """The rows of a plain block (``text``: its lines joined by ``\\n``) that
        :meth:`_numbers_batch` did not read: converted cell by cell, and the first bad line's
        error raised."""
        per_line = _fields_per_line(block.raw)
        bad = np.flatnonzero(per_line != self.width)
        problem = None
        if bad.size:
            stop = int(bad[0])
            lines = text.split("\n")
            problem = _shape_problem(self.path, block.first_line + stop, lines[stop], self.width)
            text = "\n".join(lines[:stop])
        fields = text.replace("\n", ",").split(",") if text else []
        columns = {name: fields[i :: self.width] for name, i in self.indices.items()}
        first = block.first_line
        return self._batch(columns, lambda k: first + k, problem)

    def _numbers_batch(self, block: _Block) -> ReadingBatch | None:
        """The block's lines, each of ``width`` fields, parsed in bulk from its bytes
        (:func:`_parse_numbers`); None unless every line has ``width`` fields, every field is a
        number and every row passes validation (then the exact path reads the block again, to
        raise its error about the first bad line)."""
        rows = block.lines
        values = _parse_numbers(block.raw, rows * self.width, self.width)
        if values is None:
            return None
        table = values.reshape(rows, self.width)
        arrays = {name: table[:, i].copy() for name, i in self.indices.items()}
        try:
            batch = self._validated(arrays, block.first_line)
        except ReadingsError:
            return None
        if len(batch):
            self.previous_t = float(batch.t[-1])
        return batch

    # -- everything else: the csv module ------------------------------------------------------

    def _csv_batches(self, block: _Block, *, header: bool) -> Iterator[ReadingBatch]:
        """The rest of the file from ``block`` on, row by row through :mod:`csv`."""
        base = block.first_line - 1
        reader = csv.reader(self._lines(block))
        del block
        try:
            if header:
                self._header(next(reader, []))
            rows: list[list[str]] = []
            lines: list[int] = []
            blank: list[int] = []  # blank lines not yet known to be followed by content
            for row in reader:
                if not row:
                    blank.append(base + reader.line_num)
                    continue
                if blank:
                    self._rows_batch(rows, lines, _blank(self.path, blank[0]))  # raises
                rows.append(row)
                lines.append(base + reader.line_num)
                if len(rows) >= self.rows_per_batch:
                    batch = self._rows_batch(rows, lines, None)
                    rows, lines = [], []
                    yield batch
        except csv.Error as err:
            msg = f"{self.path}: line {base + reader.line_num}, cannot read as CSV ({err})"
            raise InputError(msg) from None
        if rows:
            yield self._rows_batch(rows, lines, None)

    def _lines(self, block: _Block) -> Iterator[str]:
        """The physical lines from ``block`` on, as the csv module wants them."""
        current: _Block | None = block
        while current is not None:
            yield from io.StringIO(current.text(), newline="")
            current = next(self.blocks, None)

    def _rows_batch(self, rows: list[list[str]], lines: list[int],
                    problem: str | None) -> ReadingBatch:
        for k, row in enumerate(rows):
            if len(row) != self.width:
                problem = _shape_problem(self.path, lines[k], "", self.width, fields=len(row))
                rows = rows[:k]
                break
        columns = {name: [row[i] for row in rows] for name, i in self.indices.items()}
        return self._batch(columns, lines.__getitem__, problem)

    # -- both ---------------------------------------------------------------------------------

    def _batch(self, columns: dict[str, list[str]], line_of: Callable[[int], int],
               problem: str | None) -> ReadingBatch:
        """Convert and validate rows that have the right number of fields; raise at the first
        bad one, or else with ``problem`` (about the line after them) if there is one."""
        try:
            arrays = {name: _floats(cells, optional=name in _OPTIONAL)
                      for name, cells in columns.items()}
            batch = self._validated(arrays, line_of(0) if columns["t"] else 1)
        except (ValueError, ReadingsError) as err:
            self._first_problem(columns, line_of, err)
        if problem is not None:
            raise InputError(problem)
        if len(batch):
            self.previous_t = float(batch.t[-1])
        return batch

    def _validated(self, arrays: dict[str, FloatArray], first_line: int) -> ReadingBatch:
        """The batch of ``arrays``; :class:`ReadingsError` if any row breaks a rule."""
        if self.max_range is not None:  # the run-wide max range where a no-echo row gives none
            given = arrays.get("max_range")
            known = np.full(arrays["t"].shape, np.nan) if given is None else given
            unknown = np.isnan(known) & (arrays["range"] == np.inf)
            arrays = {**arrays, "max_range": np.where(unknown, self.max_range, known)}
        batch = ReadingBatch.from_arrays(**arrays, source=str(self.path), first_line=first_line)
        if len(batch) and batch.t[0] < self.previous_t:  # the only rule across batches
            batch[:1].validate(str(self.path), first_line, previous_t=self.previous_t)
        return batch

    def _first_problem(self, columns: dict[str, list[str]], line_of: Callable[[int], int],
                       err: Exception) -> NoReturn:
        """Raise the error of the first bad row (the slow way: only once, on a bad file)."""
        stop, message = len(columns["t"]), str(err)
        for name, cells in columns.items():  # the first cell that is no number, column order
            for k in range(stop):
                text = cells[k]
                if name in _OPTIONAL and not text.strip():
                    continue
                try:
                    parse_number(text, f"{self.path}: line {line_of(k)}", name, finite=False)
                except InputError as bad_cell:
                    stop, message = k, str(bad_cell)
                    break
        arrays = {name: _floats(cells[:stop], optional=name in _OPTIONAL)
                  for name, cells in columns.items()}
        bad = _first_false(stop, lambda k: self._valid(arrays, k))
        if bad < stop:  # a row before the unparseable one breaks a rule: its first rule
            if bad > 0:
                self.previous_t = float(arrays["t"][bad - 1])
            try:
                self._validated({name: values[bad : bad + 1] for name, values in arrays.items()},
                                line_of(bad))
            except ReadingsError as rule:
                message = str(rule)
        raise InputError(message) from None

    def _valid(self, arrays: dict[str, FloatArray], stop: int) -> bool:
        try:
            self._validated({name: values[:stop] for name, values in arrays.items()}, 1)
        except ReadingsError:
            return False
        return True


def _floats(cells: Sequence[str], *, optional: bool) -> FloatArray:
    """``float`` of every cell (an empty optional cell is NaN: the method's default beam width,
    an unknown max range)."""
    try:
        return np.fromiter(map(float, cells), dtype=np.float64, count=len(cells))
    except ValueError:
        if not optional:
            raise
    return np.array([float(text) if text.strip() else math.nan for text in cells],
                    dtype=np.float64).reshape(-1)


#: The bytes of a block that :func:`_parse_numbers` reads (``inf`` aside): digits, signs,
#: the decimal point, the exponent's letter, the field and line separators.
_NUMBER_BYTES = b"0123456789+-.eE,\n"


def _parse_numbers(raw: bytes, count: int, width: int = 0) -> FloatArray | None:
    """The ``count`` comma- or line-separated fields of ``raw`` as floats, in order, exactly
    as ``float`` reads each; None if a byte is not one of :data:`_NUMBER_BYTES` (``inf``
    aside), or a field is not a number, or there are not ``count`` fields, or (``width`` > 0)
    a line has another number of fields than ``width``.

    Two parsers, both exact: the compiled one of :func:`~sonarcarve.io.float_text.parse_floats`
    (about twice numpy's rate on repr-written fields), which decides every field that
    ``repr`` or a short decimal wrote, and for the rest numpy's C parser
    (``PyOS_string_to_double``, Python's own correctly rounded conversion: on those bytes
    exactly what ``float`` gives, overflow to ``inf`` and subnormals included). ``float`` alone
    also reads spaces, underscores, ``nan`` and the other
    spellings of infinity, so a block holding any of them goes to the exact path.
    """
    if b"\r" in raw:
        raw = raw.replace(b"\r\n", b"\n")  # a lone carriage return is refused below
    from sonarcarve.io.float_text import parse_floats  # numba: only once a log is read

    # The compiled parser reads a subset of those bytes' grammar (and checks the lines'
    # widths): what it decides needs no other test.
    values = parse_floats(raw, count, width)
    if values is not None:
        return values
    plain = raw.replace(b"inf", b"") if b"i" in raw else raw
    if plain.translate(None, _NUMBER_BYTES):
        return None
    if width > 0 and np.any(_fields_per_line(raw) != width):
        return None
    try:
        with warnings.catch_warnings():
            # Older numpy warns and returns what it read before bad data; newer numpy raises.
            warnings.simplefilter("error", DeprecationWarning)
            values = np.fromstring(raw.replace(b"\n", b","), dtype=np.float64, sep=",")
    except (ValueError, DeprecationWarning):
        return None
    # numpy stops early without an error at a last, empty field ("...,5," at the very end).
    return values if values.size == count else None


def _first_false(n: int, valid: Callable[[int], bool]) -> int:
    """The least k < n with ``valid(k + 1)`` false (the first bad row), n if none; ``valid``
    says whether the first k rows are all good, which stays false once false."""
    if valid(n):
        return n
    low, high = 0, n  # valid(low) holds, valid(high) does not
    while high - low > 1:
        middle = (low + high) // 2
        if valid(middle):
            low = middle
        else:
            high = middle
    return low


def _fields_per_line(raw: bytes) -> IntArray:
    """Number of comma-separated fields of each line of a plain block (no final break)."""
    buffer = np.frombuffer(raw, dtype=np.uint8)
    if buffer.size and buffer[-1] == ord("\n"):
        buffer = buffer[:-1]
    ends = np.flatnonzero(buffer == ord("\n"))
    commas = np.flatnonzero(buffer == ord(","))
    before_end = np.searchsorted(commas, ends)
    per_line = np.diff(np.concatenate(([0], before_end, [commas.size])))
    return (per_line + 1).astype(np.int64)


def _shape_problem(path: Path, line: int, text: str, width: int,
                   fields: int | None = None) -> str:
    """The message for a line whose number of fields is not the header's."""
    if fields is None:
        fields = len(text.split(",")) if text else 0
    if fields == 0:
        return _blank(path, line)
    count = f"{fields} field{'' if fields == 1 else 's'}"
    return f"{path}: line {line} has {count}, the header has {width}"


def _blank(path: Path, line: int) -> str:
    return f"{path}: line {line} is blank (blank lines are allowed only at the end)"


def _check_header(path: Path, header: list[str]) -> None:
    seen: set[str] = set()
    for name in header:
        if name and name in seen:
            msg = f"{path}: line 1, column {name!r} appears twice (header: {','.join(header)})"
            raise InputError(msg)
        seen.add(name)
    missing = [name for name in READINGS_COLUMNS if name not in header]
    if missing:
        line = ",".join(header)
        hint = csv_shape_hint(line)
        msg = (f"{path}: line 1, missing column(s) {', '.join(missing)} (header: {shorten(line)})"
               f"{'' if hint is None else f'; {hint}'}")
        raise InputError(msg)


def write_readings_csv(batch: ReadingBatch, path: str | Path) -> None:
    """Write ``batch`` as a readings CSV (atomically); ``beam_width`` and ``max_range`` only
    when some row's value is known (an unknown one is an empty cell); a no-echo row's range
    is written ``inf``."""
    with_width = not bool(np.all(np.isnan(batch.beam_width)))
    with_limit = not bool(np.all(np.isnan(batch.max_range)))
    header = [*READINGS_COLUMNS, *(["beam_width"] if with_width else []),
              *(["max_range"] if with_limit else [])]
    with atomic_text(path) as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        for reading in batch:
            row = [_fmt(reading.t), str(reading.sensor), _fmt(reading.x), _fmt(reading.y),
                   _fmt(reading.theta), _fmt(reading.range)]
            if with_width:
                row.append("" if math.isnan(reading.beam_width) else _fmt(reading.beam_width))
            if with_limit:
                row.append("" if math.isnan(reading.max_range) else _fmt(reading.max_range))
            writer.writerow(row)


def _fmt(value: float) -> str:
    """Shortest text that reads back to the same float."""
    return repr(float(value))
