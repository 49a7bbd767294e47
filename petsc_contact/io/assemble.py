"""A run's HDF5 files laid out, and ``OUT.h5`` assembled from the parts when the run ends.

The final file's step table (every step's scalars on the dimension ``step``, with their
units and descriptions), the fields' chunks (:func:`field_layout`), and the assembly: every
part checked against its checksum, then ``OUT.h5`` written by rank 0 a band of rows at a
time, the fields' compressed chunks copied as they are where a slab's rows fall on whole
chunks (:mod:`~petsc_contact.io.store` describes the files).
"""

from __future__ import annotations

import errno
import os
from contextlib import suppress
from typing import TYPE_CHECKING, Any

import numpy as np

from .atomic import StorageError, atomic_h5, check_room, storage
from .names import HEIGHTS_PART, step_part
from .partial import step_columns
from .parts import _steps, part_problem, slab_rows, slabs
from .schema import SECOND_DIMENSION, describe, write_attributes

if TYPE_CHECKING:
    from .store import StepStore

FIELD_CHUNK = 256  # fields are stored in (1, 256, 256) chunks, gzip level 4 with shuffle


def assemble_output(store: StepStore, table: str) -> None:
    """Write the complete ``OUT.h5`` of ``store`` from its parts (rank 0), once every part is
    checked and the disk has room; an earlier run's step table ``table`` is removed first,
    so that it is never beside this run's ``OUT.h5``."""
    _check_parts(store)
    parts = [os.path.join(store.parts, p) for p in os.listdir(store.parts)]
    needed = sum(os.path.getsize(p) for p in [store.partial, *parts])
    check_room(os.path.dirname(os.path.abspath(store.path)), needed, store.path)
    with storage(table), suppress(FileNotFoundError):
        os.remove(table)  # an earlier run's, never left beside this run's OUT.h5
    with atomic_h5(store.path, large=True) as f:
        write_attributes(f, {**store.attributes, "complete": True})
        write_table(store, f)
        if store.maps:
            _copy_maps(store, f)
        for name in store.fields:
            _copy_field(store, f, name)
        _label_maps(store, f)


def _check_parts(store: StepStore) -> None:
    """:class:`StorageError` unless every part the run stores is there, as committed."""
    checks = [(HEIGHTS_PART, "writes it again")] if store.maps else []
    for k in range(1, store.steps + 1) if store.fields else ():
        checks.append((step_part(k), f"computes {_steps(k, store.steps)} again"))
    for name, redo in checks:
        wrong = part_problem(store.parts, name, store.digests)
        if wrong:
            raise StorageError(errno.EIO, f"cannot assemble {store.path}: {wrong}; --resume {redo}")


def write_table(store: StepStore, f: Any) -> None:
    """The scalars of every step, on the dimension ``step`` (1, 2, ...), each with its units
    and description (the complete output's; a ``.partial`` holds them bare,
    :func:`~petsc_contact.io.partial.write_steps`)."""
    # contiguous columns: a chunked column's index and 8 KB chunk made a study piece's file
    # 300 KB instead of 80 KB
    columns = step_columns(store.table)
    step = f.create_dataset("step", data=columns.pop("step"))
    describe(step, store.entry("step"))
    step.make_scale("step")
    for key, values in columns.items():
        d = f.create_dataset(key, data=values)
        describe(d, store.entry(key))
        d.dims[0].attach_scale(step)
        if values.ndim == 2:  # a per-step array: its second axis is a named dimension
            d.dims[1].attach_scale(_scale(store, f, SECOND_DIMENSION[key], values.shape[1]))


def _scale(store: StepStore, f: Any, name: str, size: int) -> Any:
    """The dimension scale ``name`` (bins counted from 0; patch bins by their smallest
    size), made once."""
    if name not in f:
        values = 2 ** np.arange(size) if name == "patch_bin" else np.arange(size)
        scale = f.create_dataset(name, data=values)
        describe(scale, store.entry(name))
        scale.make_scale(name)
    return f[name]


def _label_maps(store: StepStore, f: Any) -> None:
    """The maps' dimensions ``x`` and ``y`` (pixel centres) and ``step``, as dimension
    scales, so that xarray and netCDF tools read labelled arrays."""
    maps = [name for name in ("heights", "filled") if name in f]
    if not maps and not store.fields:
        return
    scales = {}
    for name, values in zip(("x", "y"), store.grid.positions(), strict=True):
        scales[name] = f.create_dataset(name, data=values)
        describe(scales[name], store.entry(name))
        scales[name].make_scale(name)
    for map_name in maps:
        for axis, name in enumerate("xy"):
            f[map_name].dims[axis].attach_scale(scales[name])
    for field_name in store.fields:
        for axis, scale in enumerate((f["step"], scales["x"], scales["y"])):
            f[field_name].dims[axis].attach_scale(scale)


def _copy_maps(store: StepStore, f: Any) -> None:
    """The heights, and a measured map's filled mask, into ``f``: the one part copied as
    it is, or its slabs' rows a band at a time."""
    import h5py

    files = slabs(HEIGHTS_PART, store.digests)
    for slab in files:
        rows = slab_rows(HEIGHTS_PART, slab, store.grid.shape[0])
        with h5py.File(os.path.join(store.parts, slab), "r") as part:
            for name in part:
                if len(files) == 1:
                    f.copy(part[name], name)
                    continue
                if name not in f:
                    out = f.create_dataset(name, store.grid.shape, dtype=part[name].dtype)
                    out.attrs.update(part[name].attrs)
                for a, b in _bands(rows):
                    f[name][a:b] = part[name][a - rows.start : b - rows.start]


def _copy_field(store: StepStore, f: Any, name: str) -> None:
    """Stack every step's ``name`` into ``f``, slab by slab: their compressed chunks
    copied as they are where the slab's rows are whole chunks of ``f``'s (always on one
    rank), else a band of rows at a time."""
    import h5py

    nx, ny = store.grid.shape
    dtype = bool if name == "contact" else np.float64
    out = f.create_dataset(
        name, shape=(store.steps, nx, ny), maxshape=(None, nx, ny), dtype=dtype,
        **field_layout((nx, ny)),
    )  # fmt: skip
    describe(out, store.entry(name))
    for k in range(store.steps):  # every part checked already (:func:`_check_parts`)
        for slab in slabs(step_part(k + 1), store.digests):
            rows = slab_rows(step_part(k + 1), slab, nx)
            with h5py.File(os.path.join(store.parts, slab), "r") as part:
                source = part[name]
                if not _whole_chunks(source.chunks, out.chunks, rows, nx):
                    for a, b in _bands(rows):
                        out[k, a:b] = source[0, a - rows.start : b - rows.start]
                    continue
                for i in range(source.id.get_num_chunks()):
                    info = source.id.get_chunk_info(i)
                    mask, data = source.id.read_direct_chunk(info.chunk_offset)
                    first, column = info.chunk_offset[1:]
                    out.id.write_direct_chunk((k, rows.start + first, column), data, mask)


def _whole_chunks(chunks: tuple[int, ...], into: tuple[int, ...], rows: slice, nx: int) -> bool:
    """Whether a slab of ``rows`` stored in ``chunks`` is whole chunks of a field stored in
    ``into``: the same chunks, starting on one, ending on one or on the grid's last row."""
    size = into[1]
    ends = rows.stop == nx or rows.stop % size == 0
    return tuple(chunks) == tuple(into) and rows.start % size == 0 and ends


def _bands(rows: slice) -> list[tuple[int, int]]:
    """``rows`` cut on the field chunks' row boundaries: the bands the assembly moves."""
    cuts = range((rows.start // FIELD_CHUNK + 1) * FIELD_CHUNK, rows.stop, FIELD_CHUNK)
    edges = [rows.start, *cuts, rows.stop]
    return list(zip(edges[:-1], edges[1:], strict=True))


def field_layout(shape: tuple[int, ...]) -> dict[str, Any]:
    """How a field of ``shape`` (per step) is stored: in chunks of :data:`FIELD_CHUNK` rows
    and columns, compressed."""
    nx, ny = shape
    return {
        "chunks": (1, min(nx, FIELD_CHUNK), min(ny, FIELD_CHUNK)),
        "compression": "gzip",
        "compression_opts": 4,
        "shuffle": True,
    }
