"""The demsplit error hierarchy.

Every error a user can provoke with their input is a :class:`DemsplitError`.
Its message names where the problem is (file, timestep of the frame, line),
what was expected, what was found, and how to fix it, so that the CLI can
print it as is, without a traceback.
"""

from __future__ import annotations

import errno
import os
import re
from pathlib import Path


class DemsplitError(Exception):
    """Base class of every error demsplit raises on bad input or bad options.

    Parameters
    ----------
    message
        What is wrong: what was expected and what was found.
    file, step, line
        Where: the input file, the timestep of the frame being read, and the
        1-based line number in the file (``None`` where it does not apply).
    fix
        How to fix it, in one sentence.
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        step: int | None = None,
        line: int | None = None,
        fix: str | None = None,
    ) -> None:
        self.message = message
        self.file = None if file is None else str(file)
        self.step = step
        self.line = line
        self.fix = fix
        super().__init__(self._format())

    def _format(self) -> str:
        where = []
        if self.file is not None:
            where.append(self.file if self.line is None else f"{self.file}:{self.line}")
        elif self.line is not None:
            where.append(f"line {self.line}")
        if self.step is not None:
            where.append(f"timestep {self.step}")
        text = (", ".join(where) + ": " if where else "") + self.message
        if self.fix:
            text += f" Fix: {self.fix}"
        return text

    def located(
        self,
        *,
        file: str | Path | None = None,
        step: int | None = None,
        line: int | None = None,
    ) -> DemsplitError:
        """Return a copy of this error with missing location facts filled in."""
        return type(self)(
            self.message,
            file=self.file if self.file is not None else file,
            step=self.step if self.step is not None else step,
            line=self.line if self.line is not None else line,
            fix=self.fix,
        )


class InputFormatError(DemsplitError):
    """A dump, export or script does not have the layout its format requires."""


class TruncatedFileError(InputFormatError):
    """A file ends in the middle of a frame or a row."""


class PrecisionError(DemsplitError):
    """The printed precision of the input cannot support the requested result."""


class MaterialError(DemsplitError):
    """A material is missing or has values outside the physical range."""


class ScriptError(DemsplitError):
    """The simulator's input script cannot be understood."""


class UnsupportedModelError(ScriptError):
    """The run uses a contact model demsplit does not implement."""


class ContactError(DemsplitError):
    """A contact is physically or logically inconsistent (e.g. two rigid bodies,
    an unknown particle id, a contact listed twice)."""


class IncompleteRunError(DemsplitError):
    """The run has a source of contact energy (a wall, a mode of the law) that its files do not
    hold, though the simulator could have written it: analysed whole or refused."""


class StoreError(DemsplitError):
    """A result file cannot be written, read or resumed."""


def plain(value):
    """``value`` as a message shows it: a numpy scalar as the Python number or bytes it holds (a message
    says 7, not np.int64(7))."""
    item = getattr(value, "item", None)
    return item() if callable(item) and getattr(value, "shape", None) == () else value


def os_error_cause(exc: OSError) -> str:
    """The cause of an OSError in words, on one line: its ``strerror``, or the system's message inside an HDF5
    error (h5py raises OSErrors whose text holds ``errno = 28, error message = '...'``, with or without an
    errno and a strerror of their own)."""
    text = " ".join((exc.strerror or str(exc)).split())  # HDF5's texts span lines
    found = re.search(r"error message = '([^']*)'", text)
    if found:
        return found.group(1)
    found = re.search(r"errno = (\d+)", text)
    if found:
        return os.strerror(int(found.group(1)))
    return text[:200] or type(exc).__name__


def system_error(exc: OSError, path: str | Path | None = None, *, doing: str = "", note: str = "") -> StoreError:
    """The one error for an OSError of the system (a full disk, a read-only file system, permissions,
    a name too long, a file that vanished): a :class:`StoreError` naming the path (the error's own, else
    ``path``), what was being done (``doing``) and the cause, plus ``note`` (what was kept, e.g. for
    ``--resume``). An error without an
    errno (numpy's and HDF5's short writes) on a file system with no free block is said to be that."""
    where = exc.filename if exc.filename else path
    cause = os_error_cause(exc)
    if exc.errno is None and re.fullmatch(r"\d+ requested and \d+ written", cause):  # numpy's short write
        cause = f"a short write ({cause}): the file system is full, or a quota or file size limit is reached"
    elif exc.errno is None and where is not None and _no_space(Path(where)):
        cause = f"{os.strerror(errno.ENOSPC)} ({cause})"
    return StoreError(
        f"{doing + ': ' if doing else ''}{cause}{note}.",
        file=where,
        fix="free space, or give a path you can write (and read), then run again.",
    )


def _no_space(path: Path) -> bool:
    """Whether the file system of ``path`` (or of its nearest existing parent) has no free block."""
    for p in (path, *path.parents):
        try:
            st = os.statvfs(p)
        except OSError:
            continue
        return st.f_bavail == 0 and st.f_blocks > 0
    return False
