"""The output policy: where an output may be written, and how it is written so that no half of it is left.

Every command that writes (``run``, ``convert``, ``report -o``, ``export``)
checks each path it will write with :func:`check_output_path` before anything
is written: an output never replaces one of the run's inputs, a directory or a
device. The path is compared with the inputs as files, not as names, so a
symbolic link, a hard link or a ``..`` that leads to an input is refused like
the input itself; an existing path must be a regular file (it is replaced
whole, atomically); its directory must exist.

Every output is then written through :func:`atomic_path`: to a temporary name
in the target directory, flushed to disk, and renamed over the final path only
when complete; on an error the temporary file is removed. The result store,
written over a whole run in its own work directory, is given its final name by
:func:`publish`, the same fsync and rename.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from .errors import StoreError


def check_output_path(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """``path`` as a :class:`~pathlib.Path`, or a :class:`~demsplit.errors.StoreError` that names
    it when it is empty, one of ``inputs``, a directory, not a regular file, or in a missing directory."""
    text = os.fspath(path)
    if not text:
        raise StoreError("the output path is empty.", fix="give a file name with -o.")
    out = Path(text)
    try:
        st = os.stat(out)  # follows links: what would be written over
    except FileNotFoundError:
        if out.is_symlink():
            raise StoreError("the output path is a link to nothing.", file=out,
                             fix="give a new file name, not a dangling link.") from None
        st = None
    except OSError as exc:
        raise StoreError(f"the output path cannot be examined ({exc.strerror}).", file=out,
                         fix="give a file name in a directory you can write.") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise StoreError("the output path is a directory.", file=out, fix="give a file name inside it.")
        if not stat.S_ISREG(st.st_mode):
            raise StoreError("the output path is not a regular file (a device, a pipe or a socket): "
                             "demsplit replaces outputs whole and will not replace it.", file=out,
                             fix="give a new file name.")
        for source in inputs:
            try:
                same = os.path.samefile(out, source)
            except OSError:  # an input that is gone cannot be overwritten
                continue
            if same:
                raise StoreError(f"the output is one of the run's inputs ({source}); writing it would destroy "
                                 "that input.", file=out, fix="give another output path.")
    if not out.absolute().parent.is_dir():
        raise StoreError("the output directory does not exist.", file=out.parent,
                         fix="create it, or choose another output path.")
    return out


@contextmanager
def atomic_path(path: str | Path, *, durable: bool = True) -> Iterator[Path]:
    """Yield ``path.tmp`` (same directory) to write; on success fsync it and
    rename it to ``path``, on an exception remove it.

    ``durable=False`` skips the fsync: the file then survives a killed process
    (the kernel's page cache outlives it) but not a power cut, which may
    leave it empty or short under its final name; for the store's commit
    record, whose reader names a short one (see :mod:`demsplit.results.writer`)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        publish(tmp, path, durable=durable)
    finally:
        tmp.unlink(missing_ok=True)


def publish(tmp: str | Path, path: str | Path, *, durable: bool = True) -> None:
    """Give the complete file ``tmp`` its final name ``path`` (same file system):
    fsync it (unless ``durable=False``), then rename it over ``path``."""
    if durable:
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
    os.replace(tmp, path)


def write_atomic(path: str | Path, write: Callable[[BinaryIO], object], *, durable: bool = True) -> None:
    """Call ``write(file)`` on a temporary binary file that is renamed to ``path`` when complete
    (:func:`atomic_path`)."""
    with atomic_path(path, durable=durable) as tmp, open(tmp, "wb") as f:
        write(f)
