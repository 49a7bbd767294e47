"""Reading measured height maps: the package's own formats, and instrument files through
SurfaceTopography.

:func:`read_topography` returns a :class:`Topography`: the heights (``nx x ny``, NaN where
the instrument recorded nothing), the physical sides and height unit when the file carries
them, and the channel read.  The readers, in the order they are tried for an extension:

- ``.npy`` (memory-mapped, so that under MPI each rank reads only its rows) and ``.npz``
  (the array ``heights``, the one named by ``channel``, or the only 2-D array);
- HDF5 (``.h5``, ``.hdf5``): the dataset ``heights``, the one named by ``channel``, or the
  only 2-D dataset; attributes ``length`` (one value or two) and ``unit`` are read when
  present.  This includes the package's own output files, whose ``heights`` are the input;
- everything else, text included, goes first to SurfaceTopography (about 40 instrument
  formats, the field's maintained reader: sides, unit, undefined points and channels as it
  reads them).  A text matrix (``.txt``, ``.dat``, ``.asc`` separated by whitespace, ``.csv``
  by commas; ``#`` comment lines) is read by the package when SurfaceTopography is not
  installed or cannot parse it; NetCDF (``.nc``) likewise through h5py (NetCDF-4) or scipy
  (NetCDF-3).  Without
  SurfaceTopography (the ``measured`` extra) any other file is refused with an
  ``ImportError`` that says how to install it.

A file the first reader cannot parse goes to the next (a Zygo ``.dat`` is no text matrix,
an ``.h5`` with several maps is read by SurfaceTopography's channels); when none can, the
error gives every reader's whole reason.  A file that parses but is no map (a line scan, a
3-D array, a channel that is not a height) is refused at once.

A text file is checked before any reader reads it (see :func:`text_rows`): a UTF-8 or
UTF-16 byte-order mark is removed (readers would take the first row for a header), any line
ends are read; rows of different lengths, a row with a value that is no number (a decimal
comma, ``NA``, ``-``) and a file with no row of numbers are refused in one line that names
the line, and so is a text with bytes that are no text (NUL: a file damaged or padded
after a crash), which a reader would read with a row dropped as a header.  ``nan``, ``inf``,
``bad`` and an empty ``.csv`` cell are undefined heights (NaN).
"""

from __future__ import annotations

import codecs
import io
import os
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import metadata
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..conventions.grid import sides
from ..conventions.units import unit_name
from ..conventions.warnings import DoubtfulMap, option, user_level
from .paths import check_input

TEXT = (".txt", ".dat", ".csv", ".asc")
HDF5 = (".h5", ".hdf5")
NETCDF = (".nc", ".nc4")
NUMPY = (".npy", ".npz")
INSTALL_HINT = (
    "pip install 'petsc-contact[measured]' "
    "(in the set-up's venv: .venv/bin/pip install 'SurfaceTopography>=1.27')"
)

BOMS = (
    (codecs.BOM_UTF8, "utf-8-sig"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)
"""Byte-order marks a text file may begin with (Windows editors, Excel's Unicode text), and
the codec that removes them."""

UNDEFINED = ("nan", "bad", "inf", "infinite")
"""The words SurfaceTopography's text reader reads as undefined heights (in any case)."""

CONTROL = re.compile(rb"[\x00-\x08\x0e-\x1f\x7f]")
"""Bytes that are in no text: NUL and the control characters but the white space ones."""
TEXT_BYTES = np.zeros(256, dtype=bool)
TEXT_BYTES[[9, 10, 11, 12, 13, *range(32, 127)]] = True
TEXT_SHARE = 0.9
"""A file with :data:`CONTROL` bytes whose other bytes (NULs aside) are at least this share
printable ASCII or white space is a damaged text, not a binary file (an instrument's binary
``.dat`` has about 0.65)."""

DECIMAL_COMMA = re.compile(r"[-+]?\d*,\d+(?:[eE][-+]?\d+)?")

GUESSES = {"HGTReader": (".hgt",)}
"""SurfaceTopography readers that recognise a file by its size alone (any file of 2 n^2 bytes
is an elevation tile to ``HGTReader``): trusted only with their own extensions."""

Channel = str | int | None
"""A channel by name (``"Height"``) or index (``1``, or ``"1"`` when no channel has that
name); ``None`` is the file's default channel."""


class NotAMap(ValueError):
    """The file was parsed, but what it holds cannot be a contact surface."""


class Unparsable(ValueError):
    """This reader cannot parse the file (the next one may)."""


@dataclass(frozen=True)
class TextRows:
    """What a text file holds, as :func:`text_rows` reads it.

    Attributes
    ----------
    text
        The file's text (without its byte-order mark).
    marked
        Whether the file began with a byte-order mark.
    heights
        The map when the file is a bare matrix (rows of numbers and ``#`` comments only; NaN
        where undefined), else ``None``.
    problem
        Why it is no bare matrix (its first header line, ...), ``""`` when it is.
    """

    text: str
    marked: bool
    heights: np.ndarray | None
    problem: str = ""


@dataclass(frozen=True)
class Topography:
    """A height map as read from a file.

    Attributes
    ----------
    heights
        The ``nx x ny`` heights (possibly a read-only memory map; NaN where undefined).
    lengths
        Physical sides ``(Lx, Ly)`` from the file, or ``None`` when it has none.
    unit
        Unit of the heights (and of the sides) from the file (the package's spelling), or
        ``None``.
    reader
        What read it (``numpy``, ``text``, ``hdf5``, ``netcdf``, ``SurfaceTopography x.y``).
    channel
        Name of the channel read (``""`` when the file has one unnamed map).
    channel_index
        Its index among the file's channels.
    channels
        Names of all the file's channels (one entry for a single map).
    default_channel
        Whether the channel read is the file's default (none was asked for).
    guessed
        The header line (``line 1: 'x c1 c2'``) after which its orientation is a guess: a
        text file whose header gave no sides and no unit, read as SurfaceTopography reads
        it (its columns as ``x``, the transpose of its rows as written); sides given for it
        are checked (:func:`check_guessed_sides`).  ``""``: no guess.
    """

    heights: np.ndarray
    lengths: tuple[float, float] | None = None
    unit: str | None = None
    reader: str = "numpy"
    channel: str = ""
    channel_index: int = 0
    channels: tuple[str, ...] = ("",)
    default_channel: bool = True
    guessed: str = ""

    @property
    def undefined(self) -> int:
        """The number of undefined (NaN) heights."""
        return int(np.count_nonzero(~np.isfinite(self.heights)))

    def describe(self) -> str:
        """One line: the channel, its reader, shape, sides and undefined points."""
        nx, ny = self.heights.shape
        parts = [f"{nx} x {ny}"]
        if self.lengths is not None:
            parts.append(f"on {self.lengths[0]:.6g} x {self.lengths[1]:.6g} {self.unit or ''}")
        if len(self.channels) > 1 or self.channel:
            which = "the file's default" if self.default_channel else "asked for"
            parts.append(
                f"channel {self.channel_index} '{self.channel}' of {len(self.channels)} ({which})"
            )
        if self.undefined:
            parts.append(f"{self.undefined} undefined points ({self.undefined / nx / ny:.1%})")
        return ", ".join(parts) + f", read by {self.reader}"


@runtime_checkable
class SurfaceTopographyMap(Protocol):
    """What the package uses of a SurfaceTopography ``Topography`` object (2-D, uniform)."""

    @property
    def dim(self) -> int: ...

    @property
    def physical_sizes(self) -> Any: ...

    @property
    def unit(self) -> Any: ...

    def heights(self) -> Any: ...


def from_surface_topography(topography: SurfaceTopographyMap, reader: str = "") -> Topography:
    """A :class:`Topography` from a SurfaceTopography ``Topography`` object: its heights (NaN
    where its mask says undefined), sides and unit.  ``NotAMap`` for a line scan."""
    if topography.dim != 2:
        raise NotAMap(f"a {topography.dim}-D topography (a line scan) is not a map")
    heights: np.ndarray = np.ma.filled(np.ma.asarray(topography.heights(), dtype=float), np.nan)
    sizes = topography.physical_sizes
    lengths = None if sizes is None else (float(sizes[0]), float(sizes[1]))
    unit = topography.unit
    return Topography(
        heights,
        lengths,
        _unit(unit) if isinstance(unit, str) else None,
        reader or f"SurfaceTopography {_version()}",
    )


Heights = np.ndarray | Topography | SurfaceTopographyMap | str | os.PathLike[str]
"""A height map in any form the package takes: an ``nx x ny`` array (a masked array's masked
points undefined), the package's :class:`Topography` (:func:`read_topography`'s result), a
SurfaceTopography ``Topography``, or the path of a file :func:`read_topography` reads."""


def as_topography(heights: Heights, channel: Channel = None) -> Topography:
    """A height map given in any form (:data:`Heights`) as a :class:`Topography`: a path is
    read (``channel``: which map of the file), a :class:`Topography` is taken as it is, a
    SurfaceTopography ``Topography`` gives its heights, sides and unit, and an array its
    heights alone (reader ``array``).

    Raises
    ------
    ValueError
        A ``channel`` for a form that holds one map; an array that is no map (not 2-D,
        smaller than 2 x 2, not real numbers); what :func:`read_topography` raises.
    """
    if isinstance(heights, (str, os.PathLike)):
        return read_topography(os.fspath(heights), channel)
    if channel not in (None, 0, "0"):
        raise ValueError(f"{_form(heights)} holds one map: it has no channels")
    if isinstance(heights, Topography):
        return heights
    if isinstance(heights, SurfaceTopographyMap):
        return from_surface_topography(heights)
    if isinstance(heights, np.ma.MaskedArray):
        heights = np.ma.filled(heights.astype(float), np.nan)
    return _checked(Topography(np.asarray(heights), reader="array"), "the array")


def _form(heights: Heights) -> str:
    """What ``heights`` is, in words (an array, a Topography)."""
    return f"a {type(heights).__name__}" if hasattr(heights, "heights") else "an array"


def map_and_lengths(
    heights: Heights, length: float | tuple[float, float] | None = None
) -> tuple[np.ndarray, tuple[float, float], str | None]:
    """The map the Python API was given, in any form (:func:`as_topography`), with its sides.

    Parameters
    ----------
    heights
        An ``nx x ny`` array, a :class:`Topography`, a SurfaceTopography ``Topography`` or a
        path (its default channel).  A map with sides of its own gives them; undefined
        points of a topography or file are refused (fill them first); an array's are left
        to the solvers' check.
    length
        The sides (``L`` with square pixels, or ``(Lx, Ly)``); needed when the map has none,
        else optional, and then equal to the map's own.

    Returns
    -------
    heights, lengths, unit
        The ``nx x ny`` heights, the sides ``(Lx, Ly)``, and the unit of both (``None`` when
        the map has none).

    Raises
    ------
    ValueError
        Undefined points, no sides, or sides that contradict the map's.
    """
    topo = as_topography(heights)
    if isinstance(length, str):  # Run and predict_map read a unit; these are the map's numbers
        raise ValueError(
            f"length={length!r}: give the sides as numbers in the map's unit here "
            f"({topo.unit or 'none'}), or describe the run with Run(heights=..., "
            "length=...), which reads a length with its unit"
        )
    check_given(topo, length)
    if topo.lengths is None:
        check_guessed_sides(topo, length)
        return topo.heights, sides(topo.heights.shape, length), topo.unit
    return topo.heights, topo.lengths, topo.unit


def check_given(topo: Topography, length: Any, fill: str = "error", override: bool = False) -> None:
    """``ValueError`` for what the Python API refuses of a map and the sides given with it:
    undefined points of a topography or file unless ``fill`` says how to fill them (an
    array's are left to the solvers' check), no sides (the map has none, none given), and
    sides (numbers) that contradict the map's own unless ``override`` replaces them."""
    if topo.reader != "array" and topo.undefined and fill == "error":
        raise ValueError(
            f"the map has {topo.undefined} undefined points: fill them first "
            "(fill_undefined='mean' or 'harmonic', "
            "petsc_contact.physics.preparation.fill_undefined, or SurfaceTopography's "
            "interpolate_undefined_data())"
        )
    if topo.lengths is None and length is None:
        raise ValueError("the map has no sides of its own: give length=L or length=(Lx, Ly)")
    if topo.lengths is None or length is None or isinstance(length, str) or override:
        return
    if not np.allclose(sides(topo.heights.shape, length), topo.lengths, rtol=1e-6):
        raise ValueError(f"length={length} contradicts the map's own sides {topo.lengths}")


@dataclass(frozen=True)
class Profile:
    """A line scan as read from a file: heights along its length, uniformly spaced."""

    heights: np.ndarray
    length: float | None
    unit: str | None
    reader: str
    note: str = ""  # what was done to it (a nonuniform scan resampled)

    def describe(self) -> str:
        side = f" over {self.length:.6g} {self.unit or ''}" if self.length else ""
        return f"a line scan of {self.heights.size} points{side}, read by {self.reader}{self.note}"


def read_profile(path: str, channel: Channel = None) -> Profile:
    """A line scan (``.csv`` x z pairs, a profilometer's file) through SurfaceTopography; a
    nonuniform one is resampled to as many uniform points (linear interpolation).
    ``ValueError`` for a file that holds a map or nothing SurfaceTopography reads."""
    from SurfaceTopography import open_topography

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            reader = open_topography(path)
        except Exception as exc:
            raise ValueError(f"cannot read a line scan from '{path}': {_flat(exc)}") from None
        names = [str(c.name) for c in reader.channels]
        chosen = (
            reader.default_channel
            if channel is None
            else reader.channels[_channel_index(names, channel, path)]
        )
        if chosen.dim != 1:
            raise ValueError(f"'{path}' holds a map, not a line scan")
        sized = chosen.physical_sizes is not None
        scan = reader.topography(channel_index=chosen.index, physical_sizes=None if sized else 1.0)
        note = ""
        if not scan.is_uniform:
            scan = scan.to_uniform(nb_points=scan.nb_grid_pts[0])
            note = f"; nonuniform, resampled to {scan.nb_grid_pts[0]} uniform points"
    heights: np.ndarray = np.ma.filled(np.ma.asarray(scan.heights(), dtype=float), np.nan)
    unit = scan.unit
    return Profile(
        heights,
        float(scan.physical_sizes[0]) if sized else None,
        _unit(unit) if isinstance(unit, str) else None,
        f"SurfaceTopography {_version()}",
        note,
    )


def read_topography(path: str, channel: Channel = None) -> Topography:
    """Read ``path`` (see the module docstring).

    Parameters
    ----------
    path
        The file.
    channel
        Which map of a file with several (a SurfaceTopography channel, an HDF5 dataset, an
        ``.npz`` array): a name or an index; ``None`` is the file's default.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        It is not a regular, readable, non-empty file (:func:`~petsc_contact.io.paths.check_input`).
    ImportError
        Only SurfaceTopography reads it (an instrument file), and it is not installed.
    ValueError
        No reader can parse it (with each reader's reason), or it holds no usable map.
    """
    check_input(path, "heights file")
    readers = _readers(path)
    if not readers:
        raise ImportError(
            f"'{path}' is read by SurfaceTopography (instrument files; the text, .npy, .npz, "
            f".h5 and .nc readers are the package's own), which is not installed: {INSTALL_HINT}"
        )
    reasons = []
    for name, reader in readers:
        try:
            topo = reader(path, channel)
        except NotAMap:
            raise
        except Unparsable as exc:
            reasons.append(f"{name}: {exc}")
            continue
        except Exception as exc:  # a reader's own failure: the next reader may parse it
            reasons.append(f"{name}: {_flat(exc)}")
            continue
        if _checked(topo, path).guessed:
            _say_guessed(topo, path)
        return topo
    if not surface_topography_available():
        reasons.append(f"SurfaceTopography is not installed ({INSTALL_HINT})")
    raise ValueError(f"cannot read heights from '{path}': " + "; ".join(reasons))


def surface_topography_available() -> bool:
    """Whether SurfaceTopography can be imported (without importing it)."""
    import importlib.util

    return importlib.util.find_spec("SurfaceTopography") is not None


Reader = Callable[[str, Channel], Topography]


def _readers(path: str) -> list[tuple[str, Reader]]:
    """The readers to try for ``path``, most specific first."""
    ext = os.path.splitext(path)[1].lower()
    st: list[tuple[str, Reader]] = []
    if surface_topography_available():
        st = [(f"SurfaceTopography {_version()}", _surface_topography)]
    if ext in NUMPY:
        return [("numpy", _numpy), *st]
    if ext in HDF5:
        return [("hdf5", _hdf5), *st]
    if ext in NETCDF:
        return [*st, ("hdf5/netcdf", _hdf5)]
    if ext in TEXT:
        return [(st[0][0], _text_with_metadata), ("text", _text)] if st else [("text", _text)]
    return st


def _version() -> str:
    return metadata.version("SurfaceTopography")


def _flat(exc: BaseException) -> str:
    """An exception's whole message on one line, without the binary bytes some readers quote."""
    text = "".join(c if " " <= c <= "~" or c in "µÅ" else " " for c in str(exc))
    return re.sub(r"\s+", " ", text).strip() or type(exc).__name__


def _single(channel: Channel, path: str) -> None:
    if channel not in (None, 0, "0"):
        raise NotAMap(f"'{path}' holds one map, it has no channel '{channel}'")


def _numpy(path: str, channel: Channel) -> Topography:
    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise Unparsable(_flat(exc)) from None
    if isinstance(data, np.ndarray):
        _single(channel, path)
        return Topography(data)
    with data:
        return _pick(dict(data), channel, path, "numpy")


def text_rows(path: str) -> TextRows | None:
    """The rows of numbers of a text file, checked; ``None`` for a file that is not text
    (binary, or neither UTF-8 nor marked UTF-16: the readers decide).

    A line is a row of numbers when every field is one (``.csv``: fields between commas, an
    empty one undefined; else: between whitespace), a ``#`` line a comment, and any other
    line a header line (sides, unit) that SurfaceTopography reads.

    Raises
    ------
    NotAMap
        Rows of different lengths in one block of rows; a row of numbers with a value that is
        none (a decimal comma, ``NA``, a comment), which a reader would take for a header line
        and drop (see ``_refuse_broken_row``); a file with no number at all; a text whose
        bytes are not all text (NUL, control characters: ``_refuse_damaged_text``).
    """
    with open(path, "rb") as f:
        data = f.read().rstrip(b"\x1a")  # DOS's end-of-file mark (Ctrl-Z) is no damage
    text, marked = _decoded(data)
    if not marked:  # UTF-16's NULs are its own
        _refuse_damaged_text(path, data)
    if text is None:
        return None
    csv = path.lower().endswith(".csv")
    numbered = [(n, _fields(line, csv)) for n, line in enumerate(text.splitlines(), 1)]
    lines = [(n, fields) for n, fields in numbered if fields]  # blank lines aside
    values = [_numbers(fields) for _, fields in lines]
    others = [i for i, (_, fields) in enumerate(lines) if values[i] is None and fields != ["#"]]
    for i in others:
        _refuse_broken_row(path, *lines[i], _neighbours(lines, values, i))
    _check_lengths(path, lines, values)
    rows = [v for v in values if v is not None]
    first = next((n for (n, _), v in zip(lines, values, strict=True) if v is not None), 0)
    if rows:
        _refuse_labels(path, first, rows[0])
    if not rows and not re.search(r"\d", text):
        raise NotAMap(f"'{path}' holds no numbers, only text: no row of heights")
    if others:
        n = lines[others[0]][0]
        return TextRows(text, marked, None, f"line {n}: '{text.splitlines()[n - 1].strip()[:40]}'")
    if not rows:
        return TextRows(text, marked, None, "no row of numbers")
    if len({v.size for v in rows}) > 1:
        return TextRows(text, marked, None, "blocks of rows of different lengths")
    return TextRows(text, marked, np.array(rows))


def _decoded(data: bytes) -> tuple[str | None, bool]:
    """A file's text and whether it had a byte-order mark; ``None`` when it is not text."""
    for bom, codec in BOMS:
        if data.startswith(bom):
            try:
                return data.decode(codec), True
            except UnicodeDecodeError:
                return None, True
    if b"\0" in data:
        return None, False
    try:
        return data.decode("utf-8"), False
    except UnicodeDecodeError:
        return None, False


def _refuse_damaged_text(path: str, data: bytes) -> None:
    """``NotAMap`` naming the first byte that is no text (NUL, another control character) in
    a file whose other bytes are text (at least :data:`TEXT_SHARE` of those that are not NUL):
    a text file damaged, padded with NULs after a crash, or UTF-16 without a byte-order mark,
    which a reader would read with a row lost or dropped as a header.  A binary file (an
    instrument's) and a text in another encoding (Latin-1's ``µ``) pass: the readers decide."""
    found = CONTROL.search(data)
    if found is None:
        return
    codes = np.frombuffer(data, dtype=np.uint8)
    codes = codes[codes != 0]
    if np.count_nonzero(TEXT_BYTES[codes]) < TEXT_SHARE * codes.size:
        return
    at = found.start()
    line, column = data.count(b"\n", 0, at) + 1, at - data.rfind(b"\n", 0, at)
    byte = data[at]
    raise NotAMap(
        f"'{path}' line {line}, byte {column}: 0x{byte:02x}{' (NUL)' if byte == 0 else ''} is "
        f"not text ({len(CONTROL.findall(data))} such bytes in all): a damaged text file, one "
        "padded with "
        "NULs after a crash, or UTF-16 without a byte-order mark; repair it or save it again "
        "as UTF-8 text"
    )


def _fields(line: str, csv: bool) -> list[str]:
    """A line's fields (``["#"]`` for a comment, ``[]`` for a blank line); a trailing comma of
    a ``.csv`` line ends it, it opens no empty cell."""
    line = line.strip()
    if line.startswith("#"):
        return ["#"]
    if not csv:
        return line.split()
    line = line.removesuffix(",")
    return [field.strip() for field in line.split(",")] if line else []


def _numbers(fields: list[str]) -> np.ndarray | None:
    """The numbers of a line's fields (NaN for an undefined one), ``None`` when one is not."""
    try:
        return np.array([_number(field) for field in fields])
    except ValueError:
        return None


def _number(field: str) -> float:
    if field == "" or field.lower() in UNDEFINED:
        return float("nan")
    return float(field)


def _neighbours(
    lines: list[tuple[int, list[str]]], values: list[np.ndarray | None], i: int
) -> list[int]:
    """The lengths of the rows of numbers just before and after line ``i`` (blank lines
    aside)."""
    near = [j for j in (i - 1, i + 1) if 0 <= j < len(lines)]
    return [len(lines[j][1]) for j in near if values[j] is not None]


def _refuse_broken_row(path: str, n: int, fields: list[str], neighbours: list[int]) -> None:
    """``NotAMap`` when line ``n`` is a row of numbers with a value that is none: at least half
    its values (the fields before a ``#``) are numbers, and a row next to it has as many or it
    lies between two rows of one length; or all are numbers or decimal commas."""
    comment = next((k for k, f in enumerate(fields) if f.startswith("#")), len(fields))
    numeric = [_numbers([f]) is not None or DECIMAL_COMMA.fullmatch(f) is not None for f in fields]
    inside = len(neighbours) == 2 and neighbours[0] == neighbours[1]
    row = sum(numeric[:comment]) * 2 >= comment and (comment in neighbours or inside)
    if not (row or (all(numeric) and len(fields) > 1)):
        return
    k, bad = next((k, f) for k, f in enumerate(fields, 1) if _numbers([f]) is None)
    raise NotAMap(f"'{path}' line {n}: value {k} '{bad}' is not a number ({_hint(bad)})")


def _hint(field: str) -> str:
    """What to write instead of ``field`` in a row of numbers."""
    if DECIMAL_COMMA.fullmatch(field):
        return "a decimal comma: write decimal points"
    if field.startswith("#"):
        return "a comment goes on a line of its own"
    return "an undefined height is written nan"


def _refuse_labels(path: str, n: int, row: np.ndarray) -> None:
    """``NotAMap`` when the first row of numbers is an empty corner and column numbers (0, 1,
    ... or 1, 2, ...): the labels a spreadsheet or ``pandas.DataFrame.to_csv`` writes, not
    heights (its rows then begin with their numbers)."""
    labels = row[1:]
    counting = labels.size > 1 and np.array_equal(labels, labels[0] + np.arange(labels.size))
    if np.isnan(row[0]) and counting and labels[0] in (0, 1):
        raise NotAMap(
            f"'{path}' line {n} is column numbers, not heights (a spreadsheet's labels): "
            "write the map alone (pandas: to_csv(..., header=False, index=False))"
        )


def _check_lengths(
    path: str, lines: list[tuple[int, list[str]]], values: list[np.ndarray | None]
) -> None:
    """``NotAMap`` naming the first row whose length differs from the rows above it in its
    block (rows of numbers between two other lines)."""
    width = 0
    for (n, _), v in zip(lines, values, strict=True):
        if v is None:
            width = 0
        elif not width:
            width = len(v)
        elif len(v) != width:
            raise NotAMap(
                f"'{path}' line {n} has {len(v)} values, the rows above it {width}: "
                "every row of a map has the same number of values"
            )


def _text(path: str, channel: Channel) -> Topography:
    """A bare text matrix (rows of numbers and ``#`` comments only)."""
    rows = text_rows(path)
    if rows is None:
        raise Unparsable("not text (neither UTF-8 nor marked UTF-16)")
    return _bare(rows, path, channel)


def _bare(rows: TextRows, path: str, channel: Channel) -> Topography:
    if rows.heights is None:
        raise Unparsable(f"not a numeric matrix ({rows.problem})")
    _single(channel, path)
    return Topography(rows.heights, reader="text")


def _text_with_metadata(path: str, channel: Channel) -> Topography:
    """A text file as SurfaceTopography reads it (sides and unit from a header, x y z lists,
    line scans), except a bare matrix: with no sides and no unit it keeps the package's
    orientation (rows are x, as numpy reads it; SurfaceTopography takes columns as x).  A
    text file is checked first (:func:`text_rows`), and read without its byte-order mark."""
    rows = text_rows(path)
    if rows is None:
        return _surface_topography(path, channel)
    source = io.BytesIO(rows.text.encode()) if rows.marked else None
    read = _surface_topography(path, channel, source)
    if read.lengths is None and read.unit is None:
        try:
            bare = _bare(rows, path, channel)
        except Unparsable:
            return _guessed(read, rows)
        if bare.heights.shape == read.heights.T.shape:
            return bare
    return read


def _guessed(read: Topography, rows: TextRows) -> Topography:
    """``read`` (a text file with no sides and no unit, as SurfaceTopography reads it)
    marked ``guessed`` with its header line, if it has one."""
    header = rows.problem.startswith("line ")
    return replace(read, guessed=rows.problem) if header else read


def _say_guessed(topo: Topography, path: str) -> None:
    """A :class:`DoubtfulMap` warning that the orientation of ``topo`` is a guess."""
    nx, ny = topo.heights.shape
    warnings.warn(
        f"'{path}' {topo.guessed} is no row of numbers: it is skipped as a header, and the map "
        f"is read as SurfaceTopography reads a text file with a header, its columns as x: "
        f"{nx} x {ny}, the transpose of the rows as written (without the header line, a bare "
        f"matrix's rows are x); sides given ({option('length')}) are for the map as read",
        DoubtfulMap,
        stacklevel=user_level(),
    )


def check_guessed_sides(topo: Topography, length: Any) -> None:
    """``ValueError`` in one line when ``length`` (``(LX, LY)``) fits the transpose of a map
    whose orientation is a guess (:attr:`Topography.guessed`) better than the map as read:
    its pixels' aspect ratio is further from square as read than on the rows as written, so
    the sides were most likely meant for those (docs/measured.md).  One side (square pixels),
    equal sides, a square map and a map read as written pass."""
    values = np.atleast_1d(np.asarray(length, dtype=float))
    if not topo.guessed or values.size != 2:
        return
    (nx, ny), (lx, ly) = topo.heights.shape, values
    as_read, written = abs(np.log(lx * ny / (ly * nx))), abs(np.log(lx * nx / (ly * ny)))
    if written < as_read:
        raise ValueError(
            f"{option('length', f'{lx:g},{ly:g}')} fits the rows as written ({ny} x {nx}: "
            f"pixels {lx / ny:.3g} x {ly / nx:.3g}), not the map as read after its header line "
            f"({nx} x {ny}, columns as x: pixels {lx / nx:.3g} x {ly / ny:.3g}); give "
            f"{option('length', f'{ly:g},{lx:g}')} for the map as read, or remove the header "
            "line"
        )


def _pick(arrays: dict[str, Any], channel: Channel, path: str, reader: str) -> Topography:
    """The array named by ``channel``, else ``heights``, else the only 2-D array."""
    maps = [name for name, a in arrays.items() if getattr(a, "ndim", 0) == 2]
    if channel is not None:
        name = maps[_channel_index(maps, channel, path)]
    elif "heights" in arrays:
        name = "heights"
    elif len(maps) == 1:
        name = maps[0]
    else:
        raise Unparsable(
            f"no 'heights' array and {len(maps)} 2-D arrays"
            + (f" ({', '.join(maps)}: choose one with --channel)" if maps else "")
        )
    names = tuple(maps) or (name,)
    return Topography(
        np.asarray(arrays[name]),
        reader=reader,
        channel=name,
        channel_index=names.index(name) if name in names else 0,
        channels=names,
        default_channel=channel is None,
    )


def _channel_index(names: list[str], channel: Channel, path: str) -> int:
    """The one channel ``channel`` means: an exact name first, then an index."""
    hits = [i for i, n in enumerate(names) if n == str(channel)]
    if len(hits) == 1:
        return hits[0]
    index = _index(channel)
    if not hits and index is not None and 0 <= index < len(names):
        return index
    listing = ", ".join(f"{i} '{n}'" for i, n in enumerate(names))
    problem = "is ambiguous (give its index)" if hits else "does not exist"
    raise NotAMap(f"channel '{channel}' of '{path}' {problem}; its channels: {listing}")


def _index(channel: Channel) -> int | None:
    if isinstance(channel, int):
        return channel
    return int(channel) if isinstance(channel, str) and channel.strip().isdigit() else None


def _hdf5(path: str, channel: Channel) -> Topography:
    import h5py

    try:
        f = h5py.File(path, "r")
    except OSError:
        return _netcdf3(path, channel)
    with f:
        datasets: dict[str, Any] = {}
        f.visititems(lambda name, item: datasets.update({name: item}) if _is_map(item) else None)
        if isinstance(f.get("heights"), h5py.Dataset):
            datasets.setdefault("heights", f["heights"])
        picked = _pick(datasets, channel, path, "hdf5")
        dataset = f[picked.channel]
        heights = np.asarray(dataset[()], dtype=float)
        attrs = {**dict(f.attrs), **dict(dataset.attrs)}
    return replace(
        picked,
        heights=heights,
        lengths=_lengths(attrs.get("lengths", attrs.get("length")), heights.shape),
        unit=_unit(attrs.get("unit") or attrs.get("length_unit")),
    )


def _is_map(item: Any) -> bool:
    return getattr(item, "ndim", 0) == 2 and hasattr(item, "dtype")


def _netcdf3(path: str, channel: Channel) -> Topography:
    """A classic (NetCDF-3) file, through scipy."""
    from scipy.io import netcdf_file

    try:
        f = netcdf_file(path, "r", mmap=False)
    except Exception:
        raise Unparsable("neither HDF5 nor NetCDF") from None
    with f:
        picked = _pick({k: v[:] for k, v in f.variables.items()}, channel, path, "netcdf")
    return replace(picked, heights=np.asarray(picked.heights, dtype=float))


def _lengths(value: Any, shape: tuple[int, ...]) -> tuple[float, float] | None:
    """Sides from an attribute: two values, or one (``Lx``, square pixels)."""
    if value is None:
        return None
    v = np.atleast_1d(np.asarray(value, dtype=float))
    return sides(shape, v) if v.size in (1, 2) else None


def _unit(value: Any) -> str | None:
    if value is None or value == "":
        return None
    return unit_name(value.decode() if isinstance(value, bytes) else str(value))


def _surface_topography(
    path: str, channel: Channel, source: io.BytesIO | None = None
) -> Topography:
    """An instrument file through SurfaceTopography: the channel asked for, else its default.
    ``source``: the file's content to read instead of ``path`` (a text without its
    byte-order mark)."""
    from SurfaceTopography import open_topography

    with warnings.catch_warnings(), np.errstate(all="ignore"):  # its sniffers' noise
        warnings.simplefilter("ignore")
        try:
            reader = open_topography(path if source is None else source)
        except Exception as exc:
            raise Unparsable(_flat(exc)) from None
        kind, ext = type(reader).__name__, os.path.splitext(path)[1].lower()
        if kind in GUESSES and ext not in GUESSES[kind]:
            raise Unparsable(f"only {kind} takes it, by its size alone: a guess, not a reading")
        names = [str(c.name) for c in reader.channels]
        if channel is None:
            chosen = reader.default_channel
        else:
            chosen = reader.channels[_channel_index(names, channel, path)]
        if chosen.dim != 2:
            raise NotAMap(f"'{path}' holds a line scan, not a map (channel '{chosen.name}')")
        if isinstance(chosen.unit, tuple) and chosen.unit[-1] is None:
            listing = ", ".join(f"{i} '{n}'" for i, n in enumerate(names))
            raise NotAMap(
                f"channel {chosen.index} '{chosen.name}' of '{path}' is not a height (its "
                f"values have no length unit); its channels: {listing}"
            )
        sized = chosen.physical_sizes is not None  # else a stand-in, not reported
        topo = reader.topography(
            channel_index=chosen.index, physical_sizes=None if sized else (1.0, 1.0)
        )
    read = from_surface_topography(topo)
    return replace(
        read,
        lengths=read.lengths if sized else None,
        channel=str(chosen.name),
        channel_index=int(chosen.index),
        channels=tuple(names),
        default_channel=channel is None,
    )


def _checked(topo: Topography, path: str) -> Topography:
    h = topo.heights
    if h.ndim != 2:
        raise NotAMap(f"heights must be a 2-D array, '{path}' has shape {h.shape}")
    if min(h.shape) < 2:
        raise NotAMap(f"heights need at least 2 x 2 points, '{path}' has shape {h.shape}")
    if not np.issubdtype(h.dtype, np.number) or np.iscomplexobj(h):
        raise NotAMap(f"heights must be real numbers, '{path}' holds {h.dtype}")
    return topo
