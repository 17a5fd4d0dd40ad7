"""The output policy: which files demsplit may write, and how, so that no file that is not ours is changed
and nothing half-written is left.

Every file any command writes (``run``, ``convert``, ``report -o``, ``export`` in every format,
``prepare``; the YADE state cache) is checked here before anything is written, by
:func:`check_output_path` for one file and :class:`OutputFolder` for a folder of files written together
(an export). An output is refused, named and left untouched (a :class:`~demsplit.errors.StoreError`,
exit 2) when it is:

* **a protected file**: one of the run's inputs and every file its script names, read or not (its
  includes, meshes and dumps: ``Run.named_files()``), or, for ``report`` and ``export``, the store and
  the files its provenance lists. Paths are compared as files, not as names, so a symbolic link, a hard
  link or a ``..`` that leads to a protected file is refused like the file itself;
* **not a new name or a regular file**: an empty name, a directory, a device, a FIFO or a socket, a
  dangling link, a missing directory;
* **a foreign file**: an existing file is replaced only when it is a file of the same
  :class:`OutputKind` that demsplit wrote (a store by a store, a report by a report, a prepared script
  that nobody edited since prepare wrote it: :func:`stamp_script`), or when the caller says so
  (``overwrite=True``: ``--overwrite``). A folder is written into only when it is new, empty, or holds
  only an earlier export of the same kind (its manifest, :data:`EXPORT_MANIFEST`, lists its files),
  which is then replaced whole: nothing of the earlier export's series is left beside the new one.

Every file is written under a temporary name in its directory, flushed to disk and renamed over the
final path only when complete (:func:`atomic_path`, :func:`publish`, :func:`write_atomic`,
:func:`write_output`); on an error the temporary file is removed. A folder's files are all written
before the first is renamed, so a full disk leaves the folder as it was. An error of the system while
writing a command's output (a full disk, a read-only file system) is one message naming the file
(:func:`output_errors`).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from .errors import StoreError, system_error

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
"""The first bytes of every HDF5 file."""
HEAD_BYTES = 4096
"""How much of an existing file is read to tell whether demsplit wrote it."""
OVERWRITE_FIX = "give a new name, or add --overwrite to replace it."


@dataclass(frozen=True)
class OutputKind:
    """A kind of file demsplit writes: ``name`` in words (for messages) and ``ours(path)``: whether the
    existing regular file at ``path`` is one demsplit wrote of this kind, which an output of the kind may
    replace. ``ours`` reads the file without trusting it and answers False for anything it cannot read."""

    name: str
    ours: Callable[[Path], bool]


def hdf5_kind(name: str, format_name: str) -> OutputKind:
    """The :class:`OutputKind` of HDF5 files whose root attribute ``format`` is ``format_name``."""

    def ours(path: Path) -> bool:
        if not _head(path).startswith(HDF5_SIGNATURE):
            return False
        import h5py

        try:
            with h5py.File(path, "r") as h5:
                return text_attribute(h5, "format") == format_name
        except Exception:  # a damaged or foreign HDF5 file, whatever h5py makes of it, is not ours
            return False

    return OutputKind(name, ours)


def text_attribute(h5, name: str) -> str | None:
    """The attribute ``name`` of an open HDF5 object when it is text, else None (a damaged or foreign file's
    attribute may be an array, a number or bytes)."""
    value = h5.attrs.get(name)
    return value if isinstance(value, str) else None


def marked_kind(name: str, marker: bytes) -> OutputKind:
    """The :class:`OutputKind` of files whose first :data:`HEAD_BYTES` bytes hold ``marker``."""
    return OutputKind(name, lambda path: marker in _head(path))


REPORT_GENERATOR = '<meta name="generator" content="demsplit report">'
"""The tag in the head of every HTML report, by which a later report knows it may replace the file."""
REPORT = marked_kind("demsplit HTML report", REPORT_GENERATOR.encode())
"""``demsplit report -o``."""

_STAMP = "# written by demsplit prepare; an edit makes prepare refuse to replace this file; sha256 of what follows: "
_STAMP_LINE = re.compile(re.escape(_STAMP).encode() + rb"([0-9a-f]{64})\n")
MAX_STAMPED_BYTES = 64 << 20
"""A prepared script larger than this is not read to check its stamp (no script is that large)."""


def stamp_script(data: bytes) -> bytes:
    """``data`` (a prepared input script's bytes) with a first comment line holding the sha256 of the rest, by
    which :data:`PREPARED_SCRIPT` tells a prepared script nobody edited since (the simulators skip comments)."""
    return f"{_STAMP}{hashlib.sha256(data).hexdigest()}\n".encode() + data


def _unedited_script(path: Path) -> bool:
    try:
        if os.stat(path).st_size > MAX_STAMPED_BYTES:
            return False
        data = path.read_bytes()
    except OSError:
        return False
    found = _STAMP_LINE.match(data)
    return found is not None and hashlib.sha256(data[found.end() :]).hexdigest().encode() == found.group(1)


PREPARED_SCRIPT = OutputKind("script written by demsplit prepare and not edited since", _unedited_script)
"""``demsplit prepare``'s output."""


def _head(path: Path) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(HEAD_BYTES)
    except OSError:
        return b""


def check_output_path(
    path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = (), *, kind: OutputKind, overwrite: bool = False
) -> Path:
    """``path`` as a :class:`~pathlib.Path`, or the :class:`~demsplit.errors.StoreError` that names it when
    writing it would break the policy (module docstring): it is empty, one of ``inputs`` (the protected
    files), a directory, not a regular file, a dangling link, in a missing directory, or an existing file
    that is not of ``kind`` (unless ``overwrite``)."""
    text = os.fspath(path)
    if not text:
        raise StoreError("the output path is empty.", fix="give a file name with -o.")
    out = Path(text)
    try:
        st = os.stat(out)  # follows links: what would be written over
    except FileNotFoundError:
        if out.is_symlink():
            raise StoreError(
                "the output path is a link to nothing.", file=out, fix="give a new file name, not a dangling link."
            ) from None
        st = None
    except OSError as exc:
        raise StoreError(
            f"the output path cannot be examined ({exc.strerror}).",
            file=out,
            fix="give a file name in a directory you can write.",
        ) from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise StoreError("the output path is a directory.", file=out, fix="give a file name inside it.")
        if not stat.S_ISREG(st.st_mode):
            raise StoreError(
                "the output path is not a regular file (a device, a pipe or a socket): "
                "demsplit replaces outputs whole and will not replace it.",
                file=out,
                fix="give a new file name.",
            )
        protected = _protected_as(out, inputs)
        if protected is not None:
            raise StoreError(
                f"the output is one of the run's inputs or files its script names ({protected}); "
                "writing it would destroy that file.",
                file=out,
                fix="give another output path.",
            )
        if not overwrite and not kind.ours(out):
            raise StoreError(
                f"the output exists and is not a {kind.name}: demsplit replaces only a file of the "
                "kind it writes, and would destroy this one.",
                file=out,
                fix=OVERWRITE_FIX,
            )
    if not out.absolute().parent.is_dir():
        raise StoreError(
            "the output directory does not exist.", file=out.parent, fix="create it, or choose another output path."
        )
    return out


def _protected_as(out: Path, inputs: Iterable[str | os.PathLike]) -> str | None:
    """The first of ``inputs`` that is the same file as ``out`` (which exists), or None."""
    for source in inputs:
        try:
            if os.path.samefile(out, source):
                return os.fspath(source)
        except OSError:  # a protected file that is gone cannot be overwritten
            continue
    return None


@contextmanager
def output_errors(path: str | Path, doing: str = "cannot write the output") -> Iterator[None]:
    """An :class:`OSError` of the system inside the block (a full disk, a read-only file system) becomes the
    one :class:`~demsplit.errors.StoreError` naming ``path`` (the output, not its temporary name) and the
    cause."""
    try:
        yield
    except OSError as exc:
        named = exc.filename and not str(exc.filename).endswith(".tmp")
        raise system_error(exc, None if named else path, doing=doing) from exc


@contextmanager
def atomic_path(path: str | Path, *, durable: bool = True) -> Iterator[Path]:
    """Yield ``path.tmp`` (same directory) to write; on success fsync it and
    rename it to ``path``, on an exception remove it.

    ``durable=False`` skips the fsync: the file then survives a killed process
    (the kernel's page cache outlives it) but not a power cut, which may
    leave it empty or short under its final name; for the store's commit
    record, whose reader names a short one (see :mod:`demsplit.results.writer`)."""
    path = Path(path)
    tmp = temporary(path)
    try:
        yield tmp
        publish(tmp, path, durable=durable)
    finally:
        tmp.unlink(missing_ok=True)


def temporary(path: Path) -> Path:
    """The temporary name under which ``path`` is written before it is renamed."""
    return path.with_name(path.name + ".tmp")


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


def write_output(
    path: str | Path,
    data: str | bytes,
    *,
    kind: OutputKind,
    inputs: Iterable[str | os.PathLike] = (),
    overwrite: bool = False,
) -> Path:
    """Write ``data`` (text is UTF-8) to the command output ``path`` of ``kind``: checked
    (:func:`check_output_path`), written atomically, a system error named with the path."""
    path = check_output_path(path, inputs, kind=kind, overwrite=overwrite)
    with output_errors(path):
        write_atomic(path, lambda f: f.write(data.encode() if isinstance(data, str) else data))
    return path


@contextmanager
def output_files(paths: list[Path]) -> Iterator[dict[Path, Path]]:
    """Several files written all or none: yield ``{final path: temporary path}``; when the block ends every
    temporary file is fsynced, then each renamed to its final path; on an exception (before the renames)
    the temporary files are removed and no final path is touched. The paths must have been checked; the
    block names a file whose writing fails (:func:`output_errors`)."""
    tmps = {path: temporary(path) for path in paths}
    try:
        yield tmps
        for path, tmp in tmps.items():
            with output_errors(path), open(tmp, "rb") as f:
                os.fsync(f.fileno())
        for path, tmp in tmps.items():
            os.replace(tmp, path)
    finally:
        for tmp in tmps.values():
            tmp.unlink(missing_ok=True)


# --------------------------------------------------------------------------- folders

EXPORT_MANIFEST = "demsplit-export.json"
"""The file in every export folder that lists the export's files (``{"format": "demsplit-export", "kind":
..., "files": [...]}``): what a later export of the same kind replaces, and nothing else. Written before
the export's files and again after them, so a folder an export was killed in is still known as one."""
_MANIFEST_FORMAT = "demsplit-export"
_MAX_MANIFEST_BYTES = 16 << 20


EXPORT_FILE = OutputKind("file of a demsplit export", lambda path: True)
"""A file of an export folder: whether it is ours is the folder's to say (its manifest)."""


class OutputFolder:
    """The files ``names`` written together into ``directory``, all or none: an export of ``kind`` (e.g.
    ``"csv"``). The folder is checked when this is made (module docstring), then

    >>> with OutputFolder(directory, names, inputs, kind="csv") as folder:   # doctest: +SKIP
    ...     folder.write("particles.csv", lambda tmp: table.to_csv(tmp))

    writes each file to a temporary path; when the block ends they are fsynced and renamed into place,
    the files of the earlier export that this one does not write are removed, and the manifest lists the
    new export's files. On an exception the temporary files are removed and the folder is as it was (a
    folder this made is removed again). ``overwrite`` (``--overwrite``) writes into a folder that holds
    other files too (they are kept) or an export of another kind (which is replaced)."""

    def __init__(
        self,
        directory: str | Path,
        names: Iterable[str],
        inputs: Iterable[str | os.PathLike] = (),
        *,
        kind: str,
        overwrite: bool = False,
    ) -> None:
        if not os.fspath(directory):
            raise StoreError("the export folder's name is empty.", fix="give a folder name.")
        self.directory = Path(directory)
        self.kind = kind
        self.names = list(dict.fromkeys(names))
        self.earlier: dict | None = None  # the manifest of the export this one replaces
        if os.path.lexists(self.directory) and not self.directory.is_dir():
            raise StoreError(
                "the export folder is not a folder (a file, a dangling link or a device).",
                file=self.directory,
                fix="give a new folder name, or an empty folder.",
            )
        self.existed = self.directory.is_dir()
        if self.existed:
            for name in [*self.names, EXPORT_MANIFEST]:
                check_output_path(self.directory / name, inputs, kind=EXPORT_FILE)
            self._check_contents(overwrite)
        elif not self.directory.absolute().parent.is_dir():
            raise StoreError(
                "the export folder's parent directory does not exist.",
                file=self.directory,
                fix="create it, or choose another folder.",
            )

    def _check_contents(self, overwrite: bool) -> None:
        """Refuse a folder that holds anything but an earlier export of this kind (unless ``overwrite``)."""
        try:
            entries = sorted(os.listdir(self.directory))
        except OSError as exc:
            raise StoreError(
                f"the export folder cannot be listed ({exc.strerror}).",
                file=self.directory,
                fix="give a folder you can read and write.",
            ) from None
        self.earlier = read_manifest(self.directory)
        listed = self.earlier["files"] if self.earlier is not None else []
        ours = {
            temporary(Path(EXPORT_MANIFEST)).name,
            *listed,
            *(temporary(Path(n)).name for n in listed),
            *([EXPORT_MANIFEST] if self.earlier is not None else []),
        }  # a manifest not ours is foreign
        foreign = [
            e
            for e in entries
            if e not in ours or os.path.islink(self.directory / e) or not os.path.isfile(self.directory / e)
        ]
        if overwrite:
            return
        if foreign:
            more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
            raise StoreError(
                f"the export folder holds files that are not a demsplit export, such as "
                f"{foreign[0]!r}{more}: demsplit writes into a new or empty folder, or one that holds "
                "only an earlier export of the same kind.",
                file=self.directory,
                fix="export into a new or empty folder, or add --overwrite to write into this one "
                "(its other files are kept).",
            )
        if self.earlier is not None and self.earlier["kind"] != self.kind:
            raise StoreError(
                f"the export folder holds a demsplit {self.earlier['kind']} export, not a {self.kind} "
                "one: an export replaces only an earlier export of its kind.",
                file=self.directory,
                fix="export into a new or empty folder, or add --overwrite to replace that export.",
            )

    def write(self, name: str, write: Callable[[Path], object]) -> Path:
        """Call ``write(temporary path)`` for the file ``name`` (one of ``names``); a system error names the
        file. Returns the file's final path."""
        path = self.directory / name
        with output_errors(path):
            write(self._tmps[path])
        return path

    def __enter__(self) -> OutputFolder:
        listed = self.earlier["files"] if self.earlier is not None else []
        with output_errors(self.directory / EXPORT_MANIFEST):
            self.directory.mkdir(exist_ok=True)
            self._write_manifest([*listed, *(n for n in self.names if n not in listed)])
        self._files = output_files([self.directory / n for n in self.names])
        self._tmps = self._files.__enter__()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            self._files.__exit__(exc_type, exc, tb)
        except BaseException:
            self._restore()
            raise
        if exc_type is not None:
            self._restore()
            return
        with output_errors(self.directory / EXPORT_MANIFEST):
            for name in self.earlier["files"] if self.earlier is not None else []:
                path = self.directory / name
                if name not in self.names and (path.is_symlink() or path.is_file()):  # (--overwrite: a folder of
                    path.unlink()  # the same name is another's, and kept)
            self._write_manifest(self.names)

    def _restore(self) -> None:
        """Nothing was renamed into place: the folder's manifest as it was (none in a folder this made,
        which is removed)."""
        manifest = self.directory / EXPORT_MANIFEST
        try:
            if self.earlier is not None:
                data = json.dumps(self.earlier, indent=1).encode()
                write_atomic(manifest, lambda f: f.write(data))
            else:
                manifest.unlink(missing_ok=True)
                if not self.existed:
                    self.directory.rmdir()
        except OSError:  # the error being raised names what failed
            pass

    def _write_manifest(self, files: list[str]) -> None:
        data = json.dumps({"format": _MANIFEST_FORMAT, "kind": self.kind, "files": files}, indent=1).encode()
        write_atomic(self.directory / EXPORT_MANIFEST, lambda f: f.write(data))


def read_manifest(directory: Path) -> dict | None:
    """The export manifest of ``directory`` (:data:`EXPORT_MANIFEST`) when it is one demsplit wrote (its
    ``files`` plain names in the folder), else None."""
    path = directory / EXPORT_MANIFEST
    try:
        if path.is_symlink() or not path.is_file() or path.stat().st_size > _MAX_MANIFEST_BYTES:
            return None
        manifest = json.loads(path.read_bytes())
    except (OSError, ValueError):
        return None
    if not (
        isinstance(manifest, dict)
        and manifest.get("format") == _MANIFEST_FORMAT
        and isinstance(manifest.get("kind"), str)
        and isinstance(manifest.get("files"), list)
    ):
        return None
    files = manifest["files"]
    if not all(
        isinstance(f, str) and f and f not in (".", "..", EXPORT_MANIFEST) and "/" not in f and "\0" not in f
        for f in files
    ):
        return None
    return manifest
