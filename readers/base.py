"""The one interface every run reader implements.

A *run* is what a simulation left on disk. Opening it gives a :class:`Run`:
its :class:`~demsplit.scene.Scene`, the number of frames, random access to
frame ``k`` and iteration that yields one :class:`~demsplit.frame.Frame` at a
time (a frame is the unit of memory). ``describe()`` says what the reader
found: files, kinds, precision, where the overlaps come from.
"""

from __future__ import annotations

from typing import Iterator, Protocol, runtime_checkable

from ..frame import Frame
from ..scene import Scene


@runtime_checkable
class Run(Protocol):
    """A run opened for reading (see module docstring)."""

    scene: Scene

    def __len__(self) -> int: ...

    def frame(self, k: int) -> Frame: ...

    def __iter__(self) -> Iterator[Frame]: ...

    def close(self) -> None: ...
