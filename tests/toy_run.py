"""A reader added the way docs/design.md ("How to add a reader") says: one class in one file, registered by
itself when the file is imported, found by ``open_run`` through its ``detect``.

The format is a small text file a test writes (``TOY 1`` on its first line)::

    TOY 1
    law toy:linear stiffness=2000
    material 1 7e10 0.22
    step 100
    p ID TYPE X Y Z RADIUS
    c ID1 ID2

Each ``step`` starts a frame: its particles (``p``, SI units) and the pairs in contact (``c``), whose overlap,
normal and centres the reader computes from the positions (full precision). The law line names a registered
law by its key, with its parameters; the reader's one option, ``stiffness`` (``--toy-stiffness K`` on the
command line), overrides the law's ``stiffness`` parameter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from demsplit.errors import InputFormatError
from demsplit.frame import Frame
from demsplit.readers.base import Option, Run
from demsplit.scene import ContactModel, Material, Scene

SIGNATURE = b"TOY 1\n"


class ToyRun(Run):
    """A toy run (module docstring)."""

    format_name = "toy"
    formats = ("a demsplit toy run (TOY 1)",)
    cli_group = "toy inputs"
    cli_options = (
        Option(
            "stiffness",
            ("--toy-stiffness",),
            "the toy law's stiffness (N/m), instead of the file's",
            {"type": float, "metavar": "K"},
        ),
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return head.startswith(SIGNATURE)

    def __init__(self, path: Path, *, stiffness: float | None = None) -> None:
        lines = Path(path).read_text().splitlines()[1:]
        materials, model, frames = {}, None, []
        for number, line in enumerate(lines, start=2):
            words = line.split()
            if not words:
                continue
            if words[0] == "law":
                model = ContactModel(words[1], {k: float(v) for k, v in (w.split("=") for w in words[2:])})
            elif words[0] == "material":
                materials[int(words[1])] = Material(float(words[2]), float(words[3]))
            elif words[0] == "step":
                frames.append((int(words[1]), [], []))
            elif words[0] == "p" and frames:
                frames[-1][1].append([float(w) for w in words[1:]])
            elif words[0] == "c" and frames:
                frames[-1][2].append([int(w) for w in words[1:]])
            else:
                raise InputFormatError(
                    f"unknown line {line!r}.", file=path, line=number, fix="write law, material, step, p and c lines."
                )
        if model is None:
            raise InputFormatError("no law line.", file=path, fix="name the run's law: law KEY NAME=VALUE ...")
        if stiffness is not None:
            model = ContactModel(model.law, {**model.params, "stiffness": stiffness})
        self.scene = Scene(materials, model)
        self.steps = np.array([step for step, _, _ in frames], dtype=np.int64)
        self.sources = [Path(path)]
        self.notes = []
        self._frames = frames
        self._path = path

    def __len__(self) -> int:
        return len(self._frames)

    def frame(self, k: int) -> Frame:
        step, rows, pairs = self._frames[k]
        p = np.array(rows, dtype=np.float64).reshape(-1, 6)
        particles = {
            "id": p[:, 0].astype(np.int64),
            "type": p[:, 1].astype(np.int32),
            "x": p[:, 2],
            "y": p[:, 3],
            "z": p[:, 4],
            "radius": p[:, 5],
        }
        ids = np.array(pairs, dtype=np.int64).reshape(-1, 2)
        row = {int(i): r for r, i in enumerate(particles["id"])}
        i1 = np.array([row[i] for i in ids[:, 0]], dtype=np.int64)
        i2 = np.array([row[i] for i in ids[:, 1]], dtype=np.int64)
        centres = p[:, 2:5]
        d = centres[i2] - centres[i1]
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        n = d / dist[:, None]
        contacts = {
            "id1": ids[:, 0],
            "id2": ids[:, 1],
            "wall": np.full(len(ids), -1, np.int64),
            "delta": p[i1, 5] + p[i2, 5] - dist,
            "nx": n[:, 0],
            "ny": n[:, 1],
            "nz": n[:, 2],
            "x1": centres[i1, 0],
            "y1": centres[i1, 1],
            "z1": centres[i1, 2],
            "r1": p[i1, 5],
            "r2": p[i2, 5],
        }
        return Frame(step=step, particles=particles, contacts=contacts, source=(str(self._path),))
