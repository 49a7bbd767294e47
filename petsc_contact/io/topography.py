"""Reading measured height maps: the package's own formats, and instrument files through
SurfaceTopography.

:func:`read_topography` returns a :class:`Topography`: the heights (``nx x ny``, NaN where
the instrument recorded nothing), and the physical sides and height unit when the file
carries them.  Read without any optional package:

- ``.npy`` (memory-mapped, so that under MPI each rank reads only its rows) and ``.npz``
  (the array ``heights``, or the only 2-D array);
- text matrices (``.txt``, ``.dat``, ``.csv``; whitespace or commas, ``#`` comments);
- HDF5 (``.h5``, ``.hdf5``): the dataset ``heights``, or the only 2-D dataset; attributes
  ``length`` (one value or two) and ``unit`` are read when present.  This includes the
  package's own output files, whose ``heights`` are the input surface;
- NetCDF (``.nc``): through SurfaceTopography when it is installed (its NetCDF files carry
  the physical sizes and unit), else as HDF5 (NetCDF-4) or through scipy (NetCDF-3).

Every other extension (``.di``, ``.opd``, ``.sur``, ``.x3p``, ``.plu``, ``.nid``, ``.ibw``,
``.gwy``, ``.datx``, ... about 40 formats) is read by SurfaceTopography, the field's
maintained reader, which the README's set-up installs; without it such a file gives a
one-line error naming the install step.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from importlib import metadata
from typing import Any

import numpy as np

from ..conventions.grid import sides
from ..conventions.units import unit_name

TEXT = (".txt", ".dat", ".csv", ".asc")
HDF5 = (".h5", ".hdf5")
NETCDF = (".nc", ".nc4")
INSTALL_HINT = (
    "pip install 'numpy<2' 'numba>=0.59' SurfaceTopography==1.18.2 into the venv "
    "(the README's set-up does this)"
)


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
        Unit of the sides and heights from the file (the package's spelling), or ``None``.
    reader
        What read it (``numpy``, ``text``, ``hdf5``, ``SurfaceTopography x.y``).
    """

    heights: np.ndarray
    lengths: tuple[float, float] | None = None
    unit: str | None = None
    reader: str = "numpy"


def read_topography(path: str) -> Topography:
    """Read ``path`` (see the module docstring); ``OSError``/``ValueError`` with one line."""
    if not os.path.isfile(path):
        raise OSError(f"heights file '{path}' does not exist")
    if not os.access(path, os.R_OK):
        raise OSError(f"heights file '{path}' is not readable")
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext in (".npy", ".npz"):
            topo = _numpy(path)
        elif ext in TEXT:
            topo = Topography(_text(path), reader="text")
        elif ext in HDF5 or (ext in NETCDF and not surface_topography_available()):
            topo = _hdf5(path)
        else:
            topo = _surface_topography(path)
    except (OSError, ValueError):
        raise
    except Exception as exc:  # a reader's own failure: one line, with the file
        raise OSError(f"cannot read heights from '{path}': {_one_line(exc)}") from None
    return _checked(topo, path)


def surface_topography_available() -> bool:
    """Whether SurfaceTopography can be imported (without importing it)."""
    import importlib.util

    return importlib.util.find_spec("SurfaceTopography") is not None


def _numpy(path: str) -> Topography:
    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise OSError(f"cannot read heights from '{path}': {_one_line(exc)}") from None
    if isinstance(data, np.ndarray):
        return Topography(data)
    with data:
        return Topography(_only_2d(dict(data), path))


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _text(path: str) -> np.ndarray:
    try:
        return np.loadtxt(path, delimiter="," if path.endswith(".csv") else None, ndmin=2)
    except ValueError as exc:
        raise ValueError(
            f"'{path}' is not a numeric matrix ({_one_line(exc)}); an x y z point list is not a map"
        ) from None


def _only_2d(arrays: dict[str, Any], path: str) -> np.ndarray:
    """The array ``heights``, or the only 2-D array of a container."""
    if "heights" in arrays:
        return np.asarray(arrays["heights"])
    maps = [name for name, a in arrays.items() if getattr(a, "ndim", 0) == 2]
    if len(maps) != 1:
        raise ValueError(
            f"'{path}' has no 'heights' array and {len(maps)} 2-D arrays"
            + (f" ({', '.join(maps)})" if maps else "")
        )
    return np.asarray(arrays[maps[0]])


def _hdf5(path: str) -> Topography:
    import h5py

    try:
        f = h5py.File(path, "r")
    except OSError:
        return _netcdf3(path)
    with f:
        if isinstance(f.get("heights"), h5py.Dataset):
            dataset = f["heights"]
        else:
            arrays: list[Any] = []
            f.visititems(lambda _, item: arrays.append(item) if _is_map(item) else None)
            dataset = _pick_dataset(arrays, path)
        heights = np.asarray(dataset[()], dtype=float)
        attrs = {**dict(f.attrs), **dict(dataset.attrs)}
    sides = _lengths(attrs.get("lengths", attrs.get("length")), heights.shape)
    return Topography(heights, sides, _unit(attrs.get("unit") or attrs.get("length_unit")), "hdf5")


def _is_map(item: Any) -> bool:
    return getattr(item, "ndim", 0) == 2 and hasattr(item, "dtype")


def _pick_dataset(maps: list[Any], path: str) -> Any:
    if len(maps) != 1:
        raise ValueError(f"'{path}' has no 'heights' dataset and {len(maps)} 2-D datasets")
    return maps[0]


def _netcdf3(path: str) -> Topography:
    """A classic (NetCDF-3) file, through scipy."""
    from scipy.io import netcdf_file

    try:
        f = netcdf_file(path, "r", mmap=False)
    except Exception:
        raise ValueError(f"'{path}' is neither HDF5 nor NetCDF") from None
    with f:
        heights = _only_2d({k: v[:] for k, v in f.variables.items()}, path).astype(float)
    return Topography(heights, reader="netcdf")


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


def _surface_topography(path: str) -> Topography:
    """An instrument file through SurfaceTopography (its first channel)."""
    try:
        from SurfaceTopography import open_topography
    except ImportError:
        ext = os.path.splitext(path)[1] or "(no extension)"
        raise ValueError(
            f"format {ext} of '{path}' needs SurfaceTopography: {INSTALL_HINT}"
        ) from None
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):  # its sniffers' noise
            warnings.simplefilter("ignore")
            reader = open_topography(path)
            channel = reader.default_channel
            sized = channel.physical_sizes is not None  # else: a stand-in, not reported
            topo = reader.topography(
                channel_index=channel.index, physical_sizes=None if sized else (1.0, 1.0)
            )
    except Exception as exc:
        raise ValueError(f"unknown or unreadable format: '{path}' ({_one_line(exc)})") from None
    if topo.dim != 2:
        raise ValueError(f"'{path}' holds a line scan, not a map")
    heights = np.ma.filled(np.ma.asarray(topo.heights(), dtype=float), np.nan)
    unit = topo.unit
    sides = tuple(float(s) for s in topo.physical_sizes) if sized else None
    return Topography(
        heights,
        sides,  # type: ignore[arg-type]
        _unit(unit) if isinstance(unit, str) and sized else None,
        f"SurfaceTopography {metadata.version('SurfaceTopography')}",
    )


def _checked(topo: Topography, path: str) -> Topography:
    h = topo.heights
    if h.ndim != 2:
        raise ValueError(f"heights must be a 2-D array, '{path}' has shape {h.shape}")
    if min(h.shape) < 2:
        raise ValueError(f"heights need at least 2 x 2 points, '{path}' has shape {h.shape}")
    if not np.issubdtype(h.dtype, np.number) or np.iscomplexobj(h):
        raise ValueError(f"heights must be real numbers, '{path}' holds {h.dtype}")
    return topo
