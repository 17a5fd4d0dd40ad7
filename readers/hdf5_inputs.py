"""HDF5 inputs hold their data themselves: no external storage, external or soft links, or virtual datasets.

A crafted HDF5 file can point a dataset's storage at another file (``/etc/passwd``), link to another
file, or assemble a virtual dataset from others; h5py follows all of these silently, so the result
would hold bytes that are not in the input (nor in its fingerprint). Every HDF5 input is walked once
when it is opened and refused if it has any of them.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputFormatError


def refuse_foreign_storage(group, path: Path | str, _seen: set | None = None) -> None:
    """Raise :class:`InputFormatError` when ``group`` (an open h5py file or group) or anything below it
    keeps data outside the file. Each group is walked once, whatever hard links lead to it again (a group
    linked into itself made the walk endless); objects that hold no data (named datatypes) are passed."""
    import h5py

    seen = set() if _seen is None else _seen
    seen.add(h5py.h5o.get_info(group.id).addr)
    for name in group:
        link = group.get(name, getlink=True)
        if isinstance(link, (h5py.ExternalLink, h5py.SoftLink)):
            raise InputFormatError(
                f"{group.name.rstrip('/')}/{name} is a {type(link).__name__}: the file refers to data outside itself.",
                file=path,
                fix="give the file as demsplit or YADE wrote it; links are never written.",
            )
        obj = group[name]
        if isinstance(obj, h5py.Group):
            if h5py.h5o.get_info(obj.id).addr not in seen:
                refuse_foreign_storage(obj, path, seen)
        elif isinstance(obj, h5py.Dataset) and (obj.external or obj.is_virtual):
            raise InputFormatError(
                f"dataset {obj.name} is stored outside the file ("
                f"{'virtual' if obj.is_virtual else 'external storage'}).",
                file=path,
                fix="give the file as demsplit or YADE wrote it.",
            )
