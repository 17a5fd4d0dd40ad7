"""Fuzz ``demsplit run`` (and the commands that write) with generated bad inputs and outputs.

Every generated input is a small sample run of ``sample_dumps/`` with one
defect, in one of these families:

``liggghts_text``
    the packing run (full-precision atom dump, ``%g`` pair and wall dumps):
    bytes flipped, the file cut, a line duplicated, dropped or moved, a frame
    written twice, CR LF, a token replaced (``nan``, ``1e200``, ``2^63``, ...).
``liggghts_binary``
    the same run with its LAMMPS binary atom dump: bytes flipped, cut, or a
    header field or a value replaced (a count, NaN, inf, a huge number).
``compressed``
    the run's full-precision dumps compressed (gzip, bzip2, xz): cut, bytes
    flipped, garbage or a cut member appended, or the text inside damaged.
``script``
    the input script: tokens replaced by bad numbers or formulas
    (``$(sqrt(-1))``, ``$(10^400)``, deep nesting, ...), lines dropped,
    duplicated or inserted (``include /etc/passwd``, ...).
``yade_npys`` / ``yade_h5``
    YADE snapshot files (the samples, and the law samples converted): raw
    damage, or a value, a column (dtype, shape, missing, pickled objects), a
    row, the metadata or the snapshot list changed and the file rewritten
    valid (checksums and all); HDF5 links, external storage and virtual
    datasets.
``yade_states`` (run only when named: ``--families yade_states``)
    YADE saved states of ``sample_dumps/yade/simulations.py`` (YADE runs it once per session): a state's bytes
    damaged (cut, flipped, garbage appended, the gzip stream twice), its boost archive damaged inside a valid
    gzip stream, a token of an XML state replaced, an empty or a foreign file named like a state, a state of
    another simulation, a changed or an identical copy of a state, an entry of the converted-state cache
    damaged, odd YADE options. Each input may start YADE (seconds): a few hundred make a run.
``output_path``
    ``-o`` onto an input of the run (its script, any of its dumps, its STL, a
    YADE snapshot, a store for ``report``/``export``) by name, symbolic link,
    hard link or ``..``; a directory, an empty name, a missing directory, a
    FIFO, a socket, a device node (as root), ``/proc``, a name too long, a
    full file system (as root, a small tmpfs).

For each input the promise is checked: ``demsplit`` exits 0 with a store
whose every numeric column is finite, or exits 2 with one message line
(a :class:`~demsplit.errors.DemsplitError`); never exit 3 (another
exception), never a hang (:data:`TIME_LIMIT` s per input) or more memory than
:data:`MEMORY_LIMIT` (``RLIMIT_AS``), never an input file changed (every file
of the case directory hashed before and after, device nodes and FIFOs kept),
and never a file left behind but the output (or, after an error, an
interrupted run's work directory holding committed frames).

Inputs run in process, through ``demsplit.cli.main``, in a worker child per
batch (forked from a parent that compiled the kernels once): the parent kills
a child whose input runs past the time limit and goes on with the next
input; a child that dies (a crash, the memory limit) is reported with its
input. Input ``i`` of a seed is always the same input, so a reported one is
reproduced with ``--only i``.

    python tests/fuzz.py --count 20000 --seed 1 [--families a,b] [--json out.json]
    python tests/fuzz.py --seconds 60          # as many as fit
    python tests/fuzz.py --seed 1 --only 1234  # one input, in this process, with its traceback

prints the counts per family and outcome and every promise broken (with the
input that broke it). Exit status 1 when a promise was broken.
``tests/test_fuzz.py`` draws inputs of every family through hypothesis, bounded.
"""

from __future__ import annotations

import argparse
import bz2
import collections
import contextlib
import copy
import gzip
import hashlib
import io
import json
import lzma
import os
import random
import re
import resource
import shutil
import signal
import socket
import stat
import struct
import sys
import tempfile
import time
import traceback
import warnings
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
SAMPLES = REPO / "sample_dumps"
PACKING = SAMPLES / "liggghts" / "packing"
YADE = SAMPLES / "yade"

FAMILIES = (
    "liggghts_text",
    "liggghts_binary",
    "compressed",
    "script",
    "yade_npys",
    "yade_h5",
    "output_path",
    "store",
    "cache",
    "export",
    "prepare",
)
NAMED_FAMILIES = ("yade_states",)
"""Families run only when named (``--families``): each input of ``yade_states`` may start YADE."""
TIME_LIMIT = 30.0
"""Seconds one input may take (the samples take 0.03-0.2 s)."""
TIME_LIMITS = {"yade_states": 120.0}
"""Seconds one input of these families may take: a YADE conversion or two (YADE's builds in turn), each given
STATE_TIMEOUT s."""
STATE_TIMEOUT = "20"
"""``--yade-timeout`` of the ``yade_states`` inputs: a YADE that hangs on a damaged state is killed well before
the input's time limit."""
STATE_KINDS = ("bytes", "bytes", "archive", "archive", "xml", "xml", "xml", "not_a_state", "other", "cache", "options")
FOREIGN = (
    b"",
    b"ITEM: TIMESTEP\n0\n",
    b"\x00" * 64,
    b"serialization::archive",
    b"<!DOCTYPE boost_serialization>",
    b"<?xml version='1.0'?>\n<html/>\n",
    bytes(range(256)) * 8,
)
MEMORY_LIMIT = 6 << 30
"""Address space of a worker child (RLIMIT_AS), bytes: the samples need well under 1 GB of memory, but the
numba/LLVM runtime and the thread stacks reserve address space they never touch."""
BATCH = 400
"""Inputs per worker child."""

TARGETS = ("atoms_full.txt", "pairs.txt", "wall.txt", "in.packing")
"""The plain-text files of the ``liggghts_text`` family (and ``script``: in.packing)."""
KINDS = ("flip", "truncate", "duplicate_line", "drop_line", "replace_token", "move_line", "crlf", "duplicate_frame")
TOKENS = (
    b"nan",
    b"inf",
    b"-inf",
    b"x",
    b"",
    b"1e400",
    b"-1",
    b"0",
    b"1.5",
    b"99999999",
    b"1.23457e+06",
    b"ITEM:",
    b"  ",
    b"\t",
    b"\r",
    b"1e200",
    b"-1e200",
    b"1e-300",
    b"9223372036854775808",
    b"-9223372036854775809",
    b"0x10",
    b"-0",
    b"NaN",
    b"Infinity",
    b"1,5",
    b"+",
    b"1_000",
    b"\xd9\xa3",
    b"\x00",
    b"1" * 400,
    b"4.9e-324",
    b"2",
    b"1e5",
    b"-0.001",
)
EXPRESSIONS = (
    "$(sqrt(-1))",
    "$(ln(0))",
    "$(10^400)",
    "$(0^(-1))",
    "$(" + "(" * 400 + "1" + ")" * 400 + ")",
    "${nope}",
    "$(1/0)",
    "$(2^63)",
    "$(-1e308*10)",
    "nan",
    "inf",
    "1e400",
    "-0",
    "0",
    "-1",
    "$(v_nparticles*1e300)",
    "${nparticles}${nparticles}",
    "$(exp(1000))",
    "$(asin(2))",
    "$(9223372036854775807+1)",
    "1e-400",
    "$(ceil(1e300))",
    "v_",
    "$",
    "${",
    "$(",
    '"',
    "&",
)
SCRIPT_LINES = (
    "include /etc/passwd",
    "include /etc/hostname",
    "include in.packing",
    "include missing.in",
    "include /dev/zero",
    "include /proc/self/status",
    "variable a equal sqrt(-1)",
    "variable nsettle equal 1e400",
    "variable nparticles equal v_nparticles",
    "variable a equal " + "(" * 600 + "1" + ")" * 600,
    "units lj",
    "boundary p p p",
    "boundary x",
    "timestep 1e400",
    "timestep -1",
    "timestep 0",
    "run -5",
    "run 9223372036854775808",
    "dump dx all custom 2000 atoms_full.txt id",
    "dump datoms17 all custom 0 atoms_full.txt id x",
    "fix m all mesh/surface file /etc/passwd type 1",
    "fix m2 all mesh/surface file floor.stl type 99",
    "pair_style gran model hertz tangential history cohesion sjkr",
    "pair_style gran model jkr",
    "pair_style lj/cut 2.5",
    "atom_style sphere",
    "create_box 0 reg",
    "create_box 1000000000 reg",
    "region reg block 1 0 1 0 1 0 units box",
    "\x00",
    "\u00e9\u00e9",
    "x" * 100000,
    "jump SELF",
    "label a",
    "next a",
    "shell touch /tmp/demsplit-fuzz-shell",
    "fix pp all property/global youngsModulus peratomtype nan nan",
    "fix pp all property/global poissonsRatio peratomtype 0.5 0.5",
    "fix pp all property/global coefficientFriction peratomtypepair 2 1e400 1 1 1",
    "fix m all property/global characteristicVelocity scalar -1",
    "neigh_modify delay 0",
    'dump_modify datoms17 format "%d %d %g"',
    "dump_modify dpair label ATOMS",
    "compute cpgl all pair/gran/local id pos",
    "compute cpgl all pair/gran/local " + "pos " * 50,
    "undump datoms17",
    "clear",
    "processors * * *",
    "read_restart missing.restart",
    "write_restart restart.bin",
    "# comment \\",
    'variable a string "unterminated',
    "&",
    "$(",
    "variable x index " + " ".join(["1"] * 5000),
)
SPECIAL_REALS = (np.nan, np.inf, -np.inf, 0.0, -0.0, -1.0, 1e300, -1e300, 1e-300, 5e-324, 1.0, 1e10, 2.0, 1e200, 1e-12)
SPECIAL_INTS = (-1, 0, 1, 2**31, 2**31 - 1, 2**62, -(2**63), 2**63 - 1, 10**12, 7, 255)
SPECIAL_BYTES = (b"sphere", b"wall", b"facet", b"box", b"clump", b"other", b"", b"\xff\xfe", b"xxxxxxxx")
DTYPES = (
    "int8",
    "uint8",
    "int16",
    "int32",
    "uint64",
    "float16",
    "float32",
    "bool",
    "complex128",
    "S4",
    "U8",
    "object",
    "datetime64[s]",
    "float64",
    "int64",
)
JSON_VALUES = (
    None,
    -1,
    0,
    1e308,
    "x",
    [],
    {},
    True,
    2**64,
    -(2**63),
    1.5,
    "",
    [1, 2],
    {"class": "x"},
    float("nan"),
    float("inf"),
    "Law2_ScGeom_FrictPhys_CundallStrack",
)
LAW_SAMPLES = ("cohfrict", "jcfpm", "adhesion", "capillary", "viscel", "viscofrict", "deresiewitz", "hertz_linear")


def log(*args) -> None:
    print(*args, file=sys.stderr, flush=True)


# ------------------------------------------------------------------ bases: the runs the inputs are made from


def make_run(directory: Path) -> Path:
    """The ``liggghts_text`` base: the packing sample in ``directory`` with plain-text dumps
    (full-precision atoms, %g pairs and walls); return its input script."""
    directory.mkdir(parents=True, exist_ok=True)
    for name in ("in.packing", "floor.stl", "pairs.txt", "wall.txt"):
        shutil.copy(PACKING / name, directory / name)
    with gzip.open(PACKING / "atoms_full.txt.gz", "rb") as f:
        (directory / "atoms_full.txt").write_bytes(f.read())
    return directory / "in.packing"


def make_bases(root: Path, families: tuple[str, ...] = FAMILIES) -> Path:
    """Every family's base files under ``root/base`` (made once per fuzz session; the saved states only for
    ``yade_states``)."""
    base = root / "base"
    if "yade_states" in families:
        state_bases(base)
    if (base / "done").exists():
        return base
    make_run(base / "packing_text")
    d = base / "packing_bin"
    d.mkdir(parents=True)
    for name in ("in.packing", "floor.stl", "pairs.txt", "wall.txt", "atoms.bin"):
        shutil.copy(PACKING / name, d / name)
    d = base / "packing_gz"
    d.mkdir()
    for name in ("in.packing", "floor.stl", "atoms_full.txt.gz", "pairs_full.txt.gz", "wall_full.txt.gz"):
        shutil.copy(PACKING / name, d / name)
    with gzip.open(PACKING / "wall_full.txt.gz", "rb") as f:
        text = f.read()
    (d / "wall_full.txt.bz2").write_bytes(bz2.compress(text))
    (d / "wall_full.txt.xz").write_bytes(lzma.compress(text))
    shutil.copytree(PACKING, base / "packing_all")  # every file the script names, for the output cases
    d = base / "yade"
    d.mkdir()
    from demsplit.readers.yade_snapshot import _open_store

    for name in ("mindlin_box", "cundall_periodic"):
        shutil.copy(YADE / f"{name}.npys", d / f"{name}.npys")
        shutil.copy(YADE / f"{name}.h5", d / f"{name}.h5")
    for law in LAW_SAMPLES:
        shutil.copy(YADE / f"laws_box_{law}.h5", d / f"{law}.h5")
        store = _open_store(YADE / f"laws_box_{law}.h5")
        (d / f"{law}.npys").write_bytes(npys_bytes([store.snapshot(k) for k in range(len(store))]))
        store.close()
    (base / "done").write_text("")
    return base


def state_bases(base: Path) -> Path:
    """The ``yade_states`` base: the states of sample_dumps/yade/simulations.py (YADE runs it) in
    ``base/yade_states``, each converted once into its ``cache``."""
    d = base / "yade_states"
    if (d / "done").exists():
        return d
    import subprocess
    import sysconfig

    from demsplit.readers.yade_state import convert_states, state_files

    d.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "DEMSPLIT_OUT": str(d), "DEMSPLIT_SITE": sysconfig.get_paths()["purelib"]}
    subprocess.run(
        ["yade", "-n", "-j1", "-x", str(YADE / "simulations.py")],
        cwd=d,
        env=env,
        capture_output=True,
        check=True,
        timeout=600,
    )
    converted, failed = convert_states(state_files(d), d / "cache")
    if failed or not converted:
        raise SystemExit(f"the saved states of simulations.py do not convert: {failed}")
    (d / "done").write_text("")
    return d


def yade_bases(base: Path, suffix: str) -> list[Path]:
    return sorted((base / "yade").glob(f"*{suffix}"))


# ------------------------------------------------------------------ byte and text mutations


def mutate(data: bytes, kind: str, where: float, size: int, token: int) -> bytes:
    """One mutation of ``data`` (bytes of a text file). ``where`` in [0, 1) picks the position,
    ``size`` (>= 1) how many bytes are flipped, ``token`` which replacement token of :data:`TOKENS`."""
    n = len(data)
    if n == 0:
        return TOKENS[token % len(TOKENS)] or b"x"
    pos = min(int(where * n), n - 1)
    if kind == "flip":
        a = bytearray(data)
        rng = random.Random(pos * 7919 + size)
        for i in range(pos, min(pos + size, n)):
            a[i] = rng.randrange(256)
        return bytes(a)
    if kind == "truncate":
        return data[:pos]
    if kind == "duplicate_frame":  # the frame around pos written again after the last (a restart appending)
        start = data.rfind(b"ITEM: TIMESTEP", 0, pos + 1)
        end = data.find(b"ITEM: TIMESTEP", pos + 1)
        if start < 0:
            start = 0
        return data + data[start : n if end < 0 else end]
    start = data.rfind(b"\n", 0, pos) + 1
    end = data.find(b"\n", pos)
    end = n if end == -1 else end + 1
    line = data[start:end]
    if kind == "duplicate_line":
        return data[:end] + line + data[end:]
    if kind == "drop_line":
        return data[:start] + data[end:]
    if kind == "crlf":
        return data[:end].rstrip(b"\n") + b"\r\n" + data[end:] if line.endswith(b"\n") else data + b"\r\n"
    if kind == "move_line":
        rest = data[:start] + data[end:]
        at = rest.find(b"\n", (pos * 31 + size * 977) % max(len(rest), 1)) + 1
        return rest[:at] + line + rest[at:]
    if kind == "replace_token":  # the whitespace-separated token around pos
        s = max(data.rfind(b" ", start, pos), start - 1) + 1
        e = data.find(b" ", pos, end)
        e = end - 1 if e == -1 else e
        return data[:s] + TOKENS[token % len(TOKENS)] + data[e:]
    raise ValueError(kind)


def mutate_header(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    """A token of a dump frame's header (the timestep, the count, a box bound, a column name) replaced."""
    starts = [i for i in range(len(data)) if data.startswith(b"ITEM: TIMESTEP", i)][:50] or [0]
    start = rng.choice(starts)
    lines = data[start:].split(b"\n", 9)
    k = rng.choice((1, 1, 3, 3, 4, 5, 6, 7, 8))
    if len(lines) <= k:
        return data, "no header to change"
    tokens = lines[k].split(b" ")
    j = rng.randrange(len(tokens))
    old, tokens[j] = tokens[j], rng.choice(TOKENS)
    lines[k] = b" ".join(tokens)
    what = f"header line {k} of the frame at byte {start}: {old[:30]!r} -> {tokens[j][:30]!r}"
    return data[:start] + b"\n".join(lines), what


def random_text_mutation(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    if data.startswith(b"ITEM: TIMESTEP") and rng.random() < 0.2:
        return mutate_header(rng, data)
    kind = rng.choice(KINDS)
    m = (kind, rng.random(), rng.randint(1, 8), rng.randrange(len(TOKENS)))
    return mutate(data, *m), f"{kind} at {m[1]:.4f} size {m[2]} token {TOKENS[m[3]][:20]!r}"


def flip_bytes(rng: random.Random, data: bytes, count: int | None = None) -> tuple[bytes, str]:
    a = bytearray(data)
    count = count or rng.choice((1, 1, 1, 2, 4, 16))
    where = []
    for _ in range(count):
        if not a:
            break
        i = rng.randrange(len(a))
        a[i] ^= rng.randrange(1, 256)
        where.append(i)
    return bytes(a), f"{count} byte(s) flipped at {where[:4]}"


def cut_bytes(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    """``data`` cut at a random byte (what a killed writer leaves)."""
    pos = rng.randrange(len(data))
    return data[:pos], f"cut at byte {pos}"


# ------------------------------------------------------------------ LAMMPS binary dumps


def binary_fields(data: bytes) -> list[tuple[int, str, str]]:
    """``(offset, struct format, name)`` of every header field and of a sample of values, frame by frame,
    of a LAMMPS binary dump (the layout :class:`demsplit.readers.lammps_dump.BinaryDump` reads)."""
    fields, pos = [], 0
    while pos + 100 <= len(data):
        step, n, tri = struct.unpack_from("=qqi", data, pos)
        nb = 9 if tri else 6
        fields += [(pos, "=q", "step"), (pos + 8, "=q", "rows"), (pos + 16, "=i", "triclinic")]
        fields += [(pos + 20 + 4 * k, "=i", f"boundary{k}") for k in range(6)]
        fields += [(pos + 44 + 8 * k, "=d", f"box{k}") for k in range(nb)]
        head = pos + 44 + 8 * nb
        ncols, nchunk = struct.unpack_from("=ii", data, head)
        fields += [(head, "=i", "columns"), (head + 4, "=i", "chunks")]
        pos = head + 8
        for _ in range(max(nchunk, 0)):
            if pos + 4 > len(data):
                return fields
            (m,) = struct.unpack_from("=i", data, pos)
            fields.append((pos, "=i", "chunk size"))
            values = pos + 4
            fields += [
                (values + 8 * k, "=d", f"value {k} (column {k % max(ncols, 1)})")
                for k in range(0, max(m, 0), max(1, m // 64))
            ]
            pos = values + 8 * max(m, 0)
    return fields


def mutate_binary(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    kind = rng.choice(("flip", "truncate", "field", "field", "field", "append"))
    if kind == "flip":
        return flip_bytes(rng, data)
    if kind == "truncate":
        return cut_bytes(rng, data)
    if kind == "append":
        extra = rng.choice((data[:100], data[: len(data) // 3], bytes(rng.randrange(256) for _ in range(64))))
        return data + extra, f"{len(extra)} bytes appended"
    offset, fmt, name = rng.choice(binary_fields(data))
    if fmt == "=d":
        value = rng.choice(SPECIAL_REALS)
    else:
        value = rng.choice(SPECIAL_INTS + (-5, 3, 4, 16, 100000))
        bits = 8 * struct.calcsize(fmt)
        value = max(min(value, 2 ** (bits - 1) - 1), -(2 ** (bits - 1)))
    a = bytearray(data)
    struct.pack_into(fmt, a, offset, value)
    return bytes(a), f"{name} at byte {offset} = {value!r}"


# ------------------------------------------------------------------ compressed dumps

COMPRESSORS = {
    ".gz": (gzip.decompress, lambda b: gzip.compress(b, 1)),
    ".bz2": (bz2.decompress, bz2.compress),
    ".xz": (lzma.decompress, lzma.compress),
}


def mutate_compressed(rng: random.Random, data: bytes, suffix: str) -> tuple[bytes, str]:
    kinds = ["cut", "cut", "flip", "garbage", "empty", "twice"]
    if suffix == ".gz":
        kinds += ["cut_member", "content", "content", "header"]
    kind = rng.choice(kinds)
    if kind == "cut":
        pos = rng.randrange(len(data))
        return data[:pos], f"cut at byte {pos} of {len(data)}"
    if kind == "flip":
        return flip_bytes(rng, data)
    if kind == "garbage":
        extra = bytes(rng.randrange(256) for _ in range(rng.choice((1, 10, 1000))))
        return data + extra, f"{len(extra)} garbage bytes appended"
    if kind == "empty":
        return b"", "empty file"
    if kind == "twice":
        return data + data, "the whole stream twice (every timestep twice)"
    if kind == "header":
        a = bytearray(data)
        i = rng.randrange(min(10, len(a)))
        a[i] ^= rng.randrange(1, 256)
        return bytes(a), f"gzip header byte {i} flipped"
    text = gzip.decompress(data)
    if kind == "cut_member":
        member = gzip.compress(text[: rng.randrange(1, 4000)], 1)
        cut = rng.randrange(1, len(member))
        return data + member[:cut], f"a second member cut at byte {cut} of {len(member)}"
    mutated, what = random_text_mutation(rng, text)
    return gzip.compress(mutated, 1), f"decompressed text: {what}"


# ------------------------------------------------------------------ YADE snapshots


def npys_bytes(snapshots: list[tuple[dict, dict]], *, allow_pickle: bool = False) -> bytes:
    """A npy-stream snapshot file of ``snapshots`` (``(meta, tables)`` each), with valid record framing
    and checksums (as :func:`demsplit.yade.write_snapshot` writes, without its fsync per record)."""
    from demsplit.yade import NPY_STREAM_MAGIC

    out = [NPY_STREAM_MAGIC]
    for meta, tables in snapshots:
        columns = [[t, c] for t, table in tables.items() for c in table]
        buf = io.BytesIO()
        header = json.dumps({**meta, "columns": columns}).encode()
        np.save(buf, np.frombuffer(header, dtype=np.uint8), allow_pickle=False)
        with warnings.catch_warnings():  # h5py's string dtypes carry metadata np.save drops: nothing to say
            warnings.simplefilter("ignore", UserWarning)
            for t, c in columns:
                np.save(buf, np.asanyarray(tables[t][c]), allow_pickle=allow_pickle)
        payload = buf.getvalue()
        out.append(b"DSREC %016d\n" % len(payload) + payload + b"DSEND %08x\n" % (zlib.crc32(payload) & 0xFFFFFFFF))
    return b"".join(out)


def h5_write(path: Path, snapshots: list[tuple[dict, dict]]) -> None:
    """An HDF5 snapshot file of ``snapshots`` (the layout :func:`demsplit.yade.write_snapshot` writes)."""
    import h5py
    from demsplit.yade import FORMAT_NAME, FORMAT_VERSION

    with h5py.File(path, "w") as f:
        f.attrs["format"] = FORMAT_NAME
        f.attrs["format_version"] = FORMAT_VERSION
        snaps = f.create_group("snapshots")
        for index, (meta, tables) in enumerate(snapshots):
            g = snaps.create_group(f"{index:06d}")
            g.attrs["iter"] = meta.get("iter", 0) if isinstance(meta.get("iter", 0), (int, float)) else 0
            g.attrs["meta_json"] = json.dumps(meta)
            for tname, table in tables.items():
                tg = g.create_group(tname)
                for cname, col in table.items():
                    col = np.asanyarray(col)
                    if col.dtype.kind in "OMmc":  # h5py stores none of these as a plain column: bytes then
                        tg.create_dataset(
                            cname,
                            data=np.frombuffer(
                                col.tobytes() if col.dtype.kind != "O" else b"\x80\x04object", dtype=np.uint8
                            ),
                        )
                    elif col.dtype.kind == "U":
                        tg.create_dataset(cname, data=col.astype("S"))
                    else:
                        tg.create_dataset(cname, data=col)
            g.attrs["complete"] = True


def load_snapshots(path: Path) -> list[tuple[dict, dict]]:
    from demsplit.readers.yade_snapshot import _open_store

    store = _open_store(path)
    try:
        return [store.snapshot(k) for k in range(len(store))]
    finally:
        store.close()


def _json_paths(obj, prefix=()) -> list[tuple]:
    paths = [prefix] if prefix else []
    if isinstance(obj, dict):
        for k, v in obj.items():
            paths += _json_paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:8]):
            paths += _json_paths(v, (*prefix, i))
    return paths


def _special_value(rng: random.Random, col: np.ndarray, table: dict):
    kind = col.dtype.kind
    if kind == "f":
        if rng.random() < 0.2 and len(col):
            return float(col[rng.randrange(len(col))]) * rng.choice((-1.0, 10.0, 1.001, 0.5, 1e6))
        return rng.choice(SPECIAL_REALS)
    if kind in "iu":
        if rng.random() < 0.3 and "id" in table and len(table["id"]):
            return int(table["id"][rng.randrange(len(table["id"]))])  # another body's id
        info = np.iinfo(col.dtype)
        return min(max(rng.choice(SPECIAL_INTS), info.min), info.max)
    if kind == "b":
        return rng.random() < 0.5
    if kind == "S":
        return rng.choice(SPECIAL_BYTES)
    return 0


def mutate_snapshots(rng: random.Random, snaps: list[tuple[dict, dict]]) -> tuple[list, str, bool]:
    """One structured mutation of a snapshot list: ``(snapshots, description, needs pickle)``."""
    snaps = [(copy.deepcopy(m), {t: dict(c) for t, c in tables.items()}) for m, tables in snaps]
    k = rng.randrange(len(snaps))
    meta, tables = snaps[k]
    tname = rng.choice(sorted(tables))
    table = tables[tname]
    cname = rng.choice(sorted(table)) if table else None
    kind = rng.choice(
        (
            "value",
            "value",
            "value",
            "value",
            "values",
            "dtype",
            "dtype",
            "drop_column",
            "extra_column",
            "shape",
            "rename",
            "duplicate_row",
            "drop_row",
            "empty_table",
            "meta",
            "meta",
            "meta_delete",
            "snapshots",
            "ids",
        )
    )
    where = f"snapshot {k} {tname}.{cname}"
    if kind in ("value", "values") and cname is not None:
        col = np.array(table[cname])
        if not len(col):
            return snaps, f"{where}: nothing to change (no rows)", False
        rows = [rng.randrange(len(col))] if kind == "value" else list(range(len(col)))
        value = _special_value(rng, col, table)
        try:
            col[rows] = value
        except (ValueError, OverflowError, TypeError):
            return snaps, f"{where}: {value!r} does not fit {col.dtype}", False
        table[cname] = col
        return snaps, f"{where} rows {rows[:3]}{'...' if len(rows) > 3 else ''} = {value!r}", False
    if kind == "dtype" and cname is not None:
        dtype = rng.choice(DTYPES)
        col = np.asarray(table[cname])
        try:
            with np.errstate(all="ignore"):
                table[cname] = (
                    col.astype(dtype) if dtype != "object" else np.array(list(col) + [None], dtype=object)[:-1]
                )
        except (ValueError, TypeError, OverflowError):
            table[cname] = np.array([str(v) for v in col], dtype=object)
            dtype = "object (str)"
        return snaps, f"{where} as {dtype}", table[cname].dtype.kind == "O"
    if kind == "drop_column" and cname is not None:
        del table[cname]
        return snaps, f"{where} removed", False
    if kind == "extra_column":
        n = len(next(iter(table.values()))) if table else 0
        table["junk"] = np.full(n, rng.choice(SPECIAL_REALS))
        return snaps, f"snapshot {k} {tname}: extra column 'junk'", False
    if kind == "shape" and cname is not None:
        col = np.asarray(table[cname])
        shape = rng.choice(("column", "row", "short", "long", "empty", "scalar"))
        table[cname] = {
            "column": lambda: col.reshape(-1, 1),
            "row": lambda: col[None, :],
            "short": lambda: col[:-1],
            "long": lambda: np.concatenate([col, col[:3]]),
            "empty": lambda: col[:0],
            "scalar": lambda: np.asarray(col[0] if len(col) else 0),
        }[shape]()
        return snaps, f"{where} shape {shape} {table[cname].shape}", False
    if kind == "rename" and cname is not None and len(table) > 1:
        other = rng.choice([c for c in table if c != cname])
        table[cname], table[other] = table[other], table[cname]
        return snaps, f"{where} swapped with {other}", False
    if kind in ("duplicate_row", "drop_row") and table:
        n = len(next(iter(table.values())))
        if n:
            row = rng.randrange(n)
            for c, v in list(table.items()):
                v = np.asarray(v)
                if v.ndim == 1 and len(v) == n:
                    table[c] = np.concatenate([v, v[row : row + 1]]) if kind == "duplicate_row" else np.delete(v, row)
            how = "listed twice" if kind == "duplicate_row" else "gone"
            return snaps, f"snapshot {k} {tname}: row {row} {how}", False
    if kind == "empty_table" and table:
        for c in list(table):
            table[c] = np.asarray(table[c])[:0]
        return snaps, f"snapshot {k} {tname}: no rows", False
    if kind == "ids" and "id" in tables["bodies"]:
        ids = np.array(tables["bodies"]["id"])
        if len(ids):
            row = rng.randrange(len(ids))
            old, new = int(ids[row]), rng.choice((10**9, 10**12, 2**62, -5, int(ids.max()) + 1))
            ids[row] = new
            tables["bodies"]["id"] = ids
            inter = tables["interactions"]
            for c in ("id1", "id2"):
                if c in inter:
                    v = np.array(inter[c])
                    v[v == old] = new
                    inter[c] = v
            return snaps, f"snapshot {k}: body {old} renumbered {new}", False
    if kind == "meta":
        paths = _json_paths(meta)
        path = rng.choice(paths)
        value = rng.choice(JSON_VALUES)
        node = meta
        for p in path[:-1]:
            node = node[p]
        node[path[-1]] = value
        return snaps, f"snapshot {k} meta {list(path)} = {value!r}", False
    if kind == "meta_delete":
        paths = [p for p in _json_paths(meta) if isinstance(p[-1], str)]
        path = rng.choice(paths)
        node = meta
        for p in path[:-1]:
            node = node[p]
        del node[path[-1]]
        return snaps, f"snapshot {k} meta {list(path)} removed", False
    if kind == "snapshots":
        how = rng.choice(("duplicate", "reverse", "one", "none"))
        if how == "duplicate":
            snaps.insert(k + 1, snaps[k])
        elif how == "reverse":
            snaps.reverse()
        elif how == "one":
            snaps = snaps[k : k + 1]
        else:
            snaps = []
        return snaps, f"snapshots: {how} ({k})", False
    return snaps, "unchanged", False


def mutate_npys_raw(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    kind = rng.choice(("flip", "truncate", "length", "length", "tail", "append"))
    if kind == "flip":
        return flip_bytes(rng, data)
    if kind == "truncate":
        return cut_bytes(rng, data)
    heads = [i for i in range(len(data)) if data.startswith(b"DSREC ", i)] or [0]
    at = rng.choice(heads)
    if kind == "length":
        value = rng.choice(
            (
                b"-000000000000100",
                b"9999999999999999",
                b"abcdefghijklmnop",
                b"0000000000000000",
                b"0000000000000001",
                b"-999999999999999",
                b" 00000000000010",
            )
        )
        return data[: at + 6] + value + data[at + 22 :], f"record at byte {at}: length {value!r}"
    if kind == "tail":
        tails = [i for i in range(len(data)) if data.startswith(b"DSEND ", i)] or [len(data) - 15]
        t = rng.choice(tails)
        return data[: t + 6] + b"deadbeef" + data[t + 14 :], f"record end at byte {t}: crc deadbeef"
    return data + data[at : at + rng.randrange(1, 3000)], f"part of the record at byte {at} appended"


FOREIGN_STORAGE = ("external", "link", "virtual", "soft", "hardlink")
"""Ways an HDF5 dataset can hold data that is not its own (:func:`foreign_storage`)."""


def foreign_storage(rng: random.Random, kind: str, target, col: str, secret: Path) -> None:
    """Make ``target[col]`` (removed first) data outside the file (``secret``: external storage, an external
    link, a virtual dataset), a soft link (to itself or another column) or a hard link to another column."""
    import h5py

    if kind == "external":
        secret.write_bytes(b"root:x:0:0:root:/root:/bin/bash\n" * 256)
        target.create_dataset(col, shape=(64,), dtype="f8", external=[(str(secret), 0, 512)])
    elif kind == "link":
        target[col] = h5py.ExternalLink(str(secret), "/x")
    elif kind == "virtual":
        layout = h5py.VirtualLayout(shape=(4,), dtype="f8")
        layout[:] = h5py.VirtualSource(str(secret), "x", shape=(4,))
        target.create_virtual_dataset(col, layout)
    elif kind == "soft":
        others = sorted(target)
        target[col] = h5py.SoftLink(target[rng.choice(others)].name if others else f"{target.name}/{col}")
    elif others := sorted(target):
        target[col] = target[rng.choice(others)]


def mutate_h5_file(rng: random.Random, path: Path) -> str:
    """An HDF5-level change of the snapshot file ``path``, in place."""
    import h5py

    kind = rng.choice(
        (
            "flip",
            "flip",
            "truncate",
            "external",
            "link",
            "virtual",
            "soft",
            "hardlink",
            "complete",
            "format",
            "meta_json",
            "scalar",
            "group",
            "filter",
            "attr_type",
            "snapshots_dataset",
        )
    )
    if kind in ("flip", "truncate"):
        data = path.read_bytes()
        data, what = flip_bytes(rng, data) if kind == "flip" else cut_bytes(rng, data)
        path.write_bytes(data)
        return what
    with h5py.File(path, "a") as f:
        names = sorted(f["snapshots"])
        g = f["snapshots"][rng.choice(names)]
        tname = rng.choice(("bodies", "interactions"))
        col = rng.choice(sorted(g[tname]))
        target = g[tname]
        secret = path.with_name("secret.bin")
        if kind in ("external", "virtual", "link", "soft", "hardlink", "scalar", "group", "filter"):
            del target[col]
        if kind in FOREIGN_STORAGE:
            foreign_storage(rng, kind, target, col, secret)
        elif kind == "scalar":
            target.create_dataset(col, data=rng.choice((1.0, 7, b"x")))
        elif kind == "group":
            target.create_group(col)
        elif kind == "filter":
            n = len(target[sorted(target)[0]]) if sorted(target) else 4
            target.create_dataset(col, data=np.arange(max(n, 8), dtype="f8"), fletcher32=True)
            f.flush()
        elif kind == "complete":
            g.attrs["complete"] = False if rng.random() < 0.5 else "yes"
        elif kind == "format":
            f.attrs["format"] = rng.choice(("x", b"demsplit-yade-snapshot", 7))
        elif kind == "meta_json":
            g.attrs["meta_json"] = rng.choice(("{", "[]", "null", '{"iter": 1}', "\udcff" * 0 + "x", "1e999"))
        elif kind == "attr_type":
            g.attrs["meta_json"] = np.arange(3)
        elif kind == "snapshots_dataset":
            del f["snapshots"][names[-1]]
            f["snapshots"].create_dataset(names[-1], data=np.arange(3))
    if kind == "filter":  # corrupt the checksummed chunk
        data = bytearray(path.read_bytes())
        marker = np.arange(8, dtype="f8").tobytes()
        i = bytes(data).find(marker[:16])
        if i >= 0:
            data[i + 3] ^= 0xFF
            path.write_bytes(bytes(data))
    return f"{kind} ({tname}.{col})"


# ------------------------------------------------------------------ one generated input


@dataclass
class Case:
    """One generated input: the files of ``directory`` (written by ``build``), the command line (paths
    relative to nothing: absolute), where the output goes and what it may be."""

    index: int
    family: str
    what: str
    argv: list[str]
    directory: Path
    output: Path | None = None
    new_ok: list[Path] = field(default_factory=list)  # paths that may appear (the output and what it makes)
    changes_ok: list[Path] = field(default_factory=list)  # existing files that may change (not inputs)
    expect: str | None = None  # "error": the output must be refused; "ok": it must be written
    caches: list[Path] = field(default_factory=list)  # directories of converted YADE states the input may write


def case_rng(seed: int, index: int) -> random.Random:
    return random.Random(f"demsplit-fuzz/{seed}/{index}")


def family_of(seed: int, index: int, families: tuple[str, ...]) -> str:
    return families[index % len(families)]


def build_case(
    base: Path, work: Path, seed: int, index: int, families: tuple[str, ...] = FAMILIES, full_fs: Path | None = None
) -> Case:
    """Input ``index`` of ``seed``: its files written into ``work/case`` (emptied first)."""
    rng = case_rng(seed, index)
    family = family_of(seed, index, families)
    d = work / "case"
    out_dir = work / "out"
    for p in (d, out_dir):
        if p.exists() or p.is_symlink():
            _remove(p)
    out_dir.mkdir(parents=True)
    out = out_dir / "out.h5"
    if family == "liggghts_text":
        shutil.copytree(base / "packing_text", d)
        target = rng.choice(TARGETS[:3])
        data, what = random_text_mutation(rng, (d / target).read_bytes())
        (d / target).write_bytes(data)
        argv = ["run", str(d / "in.packing")]
        what = f"{target}: {what}"
    elif family == "script":
        shutil.copytree(base / "packing_text", d)
        script = d / "in.packing"
        data, what = mutate_script(rng, script.read_bytes())
        script.write_bytes(data)
        argv = ["run", str(script)]
        if rng.random() < 0.2:
            argv += ["--var", rng.choice(("nparticles", "nsettle", "x")), rng.choice(EXPRESSIONS)]
            what += f"; --var {argv[-2]} {argv[-1]!r}"
    elif family == "liggghts_binary":
        shutil.copytree(base / "packing_bin", d)
        data, what = mutate_binary(rng, (d / "atoms.bin").read_bytes())
        (d / "atoms.bin").write_bytes(data)
        argv = ["run", str(d / "in.packing"), "--atoms", str(d / "atoms.bin")]
        what = f"atoms.bin: {what}"
    elif family == "compressed":
        shutil.copytree(base / "packing_gz", d)
        name = rng.choice(
            (
                "atoms_full.txt.gz",
                "pairs_full.txt.gz",
                "wall_full.txt.gz",
                "wall_full.txt.gz",
                "wall_full.txt.bz2",
                "wall_full.txt.xz",
            )
        )
        data, what = mutate_compressed(rng, (d / name).read_bytes(), Path(name).suffix)
        (d / name).write_bytes(data)
        argv = ["run", str(d / "in.packing")]
        if not name.endswith(".gz"):
            argv += ["--walls", str(d / name)]
        what = f"{name}: {what}"
        if rng.random() < 0.3:
            argv += ["--on-bad-frame", "skip"]
            what += " (--on-bad-frame skip)"
    elif family in ("yade_npys", "yade_h5"):
        d.mkdir()
        src = rng.choice(yade_bases(base, ".npys" if family == "yade_npys" else ".h5"))
        snap = d / f"snap{src.suffix}"
        if rng.random() < 0.35:  # raw damage, or an HDF5-level change
            shutil.copy(src, snap)
            if family == "yade_npys":
                data, what = mutate_npys_raw(rng, snap.read_bytes())
                snap.write_bytes(data)
            else:
                what = mutate_h5_file(rng, snap)
        else:
            snaps, what, pickled = mutate_snapshots(rng, load_snapshots(src))
            if family == "yade_npys":
                snap.write_bytes(npys_bytes(snaps, allow_pickle=pickled))
            else:
                h5_write(snap, snaps)
        argv = ["run", str(snap)]
        if rng.random() < 0.15:
            argv.append("--plane-as-plane")
            what += " (--plane-as-plane)"
        what = f"{src.name}: {what}"
    elif family == "output_path":
        return output_case(rng, base, work, d, index, full_fs)
    elif family == "store":
        return store_case(rng, base, d, out_dir, index)
    elif family == "cache":
        return cache_case(rng, base, d, out_dir, index)
    elif family == "export":
        return export_case(rng, base, d, out_dir, index)
    elif family == "prepare":
        return prepare_case(rng, base, d, index)
    elif family == "yade_states":
        return state_case(rng, base, d, out, index)
    else:
        raise ValueError(family)
    if family != "yade_npys" and family != "yade_h5" and rng.random() < 0.1:
        argv += ["--compression", rng.choice(("none", "gzip", "lzf"))]
    return Case(index, family, what, [*argv, "-o", str(out), "-q"], d, out, new_ok=[out])


def state_case(rng: random.Random, base: Path, d: Path, out: Path, index: int) -> Case:
    """A ``yade_states`` input: the facet box's four states (iterations 3000 to 12000) in ``d`` with one defect
    (:data:`STATE_KINDS`), given as a glob, the directory or the list of files, read with the session's cache of
    converted states (or a damaged copy of it, or the default next to the output)."""
    src = base / "yade_states"
    d.mkdir()
    states = sorted(src.glob("facets-*"))
    for p in states:
        shutil.copy(p, d / p.name)
    kind = rng.choice(STATE_KINDS)
    target = d / rng.choice(states).name
    cache = src / "cache"
    options: list[str] = []
    if kind == "bytes":
        data, what = mutate_compressed(rng, target.read_bytes(), ".gz")
        target.write_bytes(data)
    elif kind == "archive":  # a valid gzip stream of a damaged archive: YADE reads it
        raw = gzip.decompress(target.read_bytes())
        data, what = rng.choice((flip_bytes, cut_bytes, random_text_mutation))(rng, raw)
        target.write_bytes(gzip.compress(data, 1))
    elif kind == "xml":  # the XML state of iteration 6000 in place of the binary one, a token or line changed
        (d / "facets-006000.yade.gz").unlink()
        data, what = random_text_mutation(rng, bz2.decompress((src / "again-006000.xml.bz2").read_bytes()))
        target = d / rng.choice(("facets-006000.xml", "facets-006000.xml.bz2"))
        target.write_bytes(bz2.compress(data) if target.name.endswith(".bz2") else data)
    elif kind == "not_a_state":
        target = d / rng.choice(
            ("facets-007000.yade.gz", "facets-007000.xml", "facets-007000.yade", "facets-007000.xml.bz2")
        )
        data = rng.choice(FOREIGN + ((src / "again-006000.xml.bz2").read_bytes(),))
        target.write_bytes(gzip.compress(data) if target.name.endswith(".gz") and rng.random() < 0.5 else data)
        what = f"{len(data)} bytes beginning {data[:20]!r}"
    elif kind == "other":  # another simulation, a changed state, the same state again (named or recompressed)
        other = rng.choice(
            (
                "clumps-004500.yade.gz",
                "seed-003000.yade.gz",
                "changed-006000.yade.gz",
                "again-006000.xml.bz2",
                "viscelcap-000020.yade.gz",
                "recompressed",
            )
        )
        if other == "recompressed":
            target = d / "facets-006000-copy.yade.gz"
            target.write_bytes(gzip.compress(gzip.decompress((src / "facets-006000.yade.gz").read_bytes()), 9))
        else:
            target = d / other
            shutil.copy(src / other, target)
        what = other
    elif kind == "cache":  # a damaged copy of the converted states, in the output's directory
        cache = out.parent / "cache"
        shutil.copytree(src / "cache", cache)
        victim = rng.choice(sorted(cache.iterdir()))
        damage = rng.choice(("cut", "flip", "empty", "swap", "directory", "tmp"))
        if damage == "cut":
            data = victim.read_bytes()
            victim.write_bytes(data[: rng.randrange(len(data))])
        elif damage == "flip":
            victim.write_bytes(flip_bytes(rng, victim.read_bytes())[0])
        elif damage == "empty":
            victim.write_bytes(b"")
        elif damage == "swap":  # another state's conversion under this name
            victim.write_bytes(rng.choice(sorted(cache.iterdir())).read_bytes())
        elif damage == "directory":
            victim.unlink()
            victim.mkdir()
        else:
            victim.with_name(victim.name + ".tmp").write_bytes(victim.read_bytes()[:100])
        what = f"cache entry {victim.name[:16]}...: {damage}"
    else:
        options, what = rng.choice(
            (
                (["--yade-timeout", "0.01"], "a time limit YADE cannot keep"),
                (["--yade", "false"], "--yade false"),
                (["--yade", "nonexistent-yade"], "no such yade"),
                (["--yade", "yade-mpfr150"], "the wrong build"),
                (["--material", "9:1e9:0.3"], "--material of no material"),
                (["--material", "1:1e9:0.3"], "--material"),
                (["--plane-as-plane"], "--plane-as-plane"),
                (["--state-cache", str(target)], "--state-cache onto a state"),
            )
        )
        if options[0] in ("--yade-timeout", "--yade"):
            cache = out.parent / "fresh"  # nothing converted: YADE runs
    form = rng.choice(("glob", "glob", "directory", "list"))
    given = {"glob": [str(d / "facets*")], "directory": [str(d)], "list": [str(p) for p in sorted(d.iterdir())]}[form]
    if rng.random() < 0.15:  # the default: next to the output
        cache = out.with_name(out.name + ".states")
    else:
        options = ["--state-cache", str(cache), *options] if "--state-cache" not in options else options
    if "--yade-timeout" not in options:
        options += ["--yade-timeout", STATE_TIMEOUT]
    if rng.random() < 0.25:
        options += ["--on-bad-frame", "skip"]
    argv = ["run", *given, *options]
    return Case(
        index,
        "yade_states",
        f"{kind} {target.name}: {what} ({form}; {' '.join(options)})"[:300],
        [*argv, "-o", str(out), "-q"],
        d,
        out,
        new_ok=[out],
        caches=[cache],
    )


def cache_state(cache: Path) -> dict[str, tuple[int, int]]:
    """Name -> (size, modification time) of each file in a directory of converted YADE states."""
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in cache.iterdir()} if cache.is_dir() else {}


def cache_problems(cache: Path, before: dict[str, tuple[int, int]]) -> list[str]:
    """What a run did wrong to a directory of converted YADE states (``before``: :func:`cache_state` before it): a
    file it wrote whose content does not give its name, a file it left half-written (``.tmp``)."""
    from demsplit.runtime.hashing import file_digest

    problems = []
    for name, now in cache_state(cache).items():
        if before.get(name) == now:
            continue
        p = cache / name
        if name.endswith(".tmp"):
            problems.append(f"{name}: left half-written")
        elif p.is_file() and not name.endswith(f"-{file_digest(p)}.npys"):
            problems.append(f"{name}: its content does not give its name")
    return problems


def mutate_script(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    kind = rng.choice(("expression", "expression", "insert", "insert", "text", "text"))
    if kind == "text":
        return random_text_mutation(rng, data)
    lines = data.split(b"\n")
    if kind == "insert":
        at = rng.randrange(len(lines) + 1)
        line = rng.choice(SCRIPT_LINES).encode("utf-8", "surrogateescape")
        lines.insert(at, line)
        return b"\n".join(lines), f"line {at + 1} inserted: {line[:60]!r}"
    numbers = [
        (i, j)
        for i, line in enumerate(lines)
        if not line.lstrip().startswith(b"#")
        for j, tok in enumerate(line.split(b" "))
        if tok[:1].isdigit() or tok[:1] in (b"-", b"$")
    ]
    i, j = rng.choice(numbers)
    tokens = lines[i].split(b" ")
    expr = rng.choice(EXPRESSIONS).encode()
    old = tokens[j]
    tokens[j] = expr
    lines[i] = b" ".join(tokens)
    return b"\n".join(lines), f"line {i + 1}: {old[:30]!r} -> {expr[:40]!r}"


def _remove(p: Path) -> None:
    if p.is_symlink() or not p.is_dir():
        p.unlink()
    else:
        for sub in p.iterdir():
            _remove(sub)
        p.rmdir()


OUTPUT_KINDS = (
    "input",
    "input",
    "input",
    "symlink",
    "hardlink",
    "dotdot",
    "directory",
    "empty",
    "missing_dir",
    "fifo",
    "socket",
    "device",
    "dangling",
    "parent_is_file",
    "proc",
    "long_name",
    "new",
    "existing",
    "existing_store",
    "full_fs",
    "report",
    "export",
    "convert",
    "prepare",
    "yade_input",
)


def output_case(rng: random.Random, base: Path, work: Path, d: Path, index: int, full_fs: Path | None) -> Case:
    """``-o`` (or report/export/convert/prepare's output) onto something that is not a new file name."""
    shutil.copytree(base / "packing_all", d)
    script = d / "in.packing"
    files = sorted(p.name for p in d.iterdir())
    kind = rng.choice(OUTPUT_KINDS)
    if kind == "full_fs" and full_fs is None:
        kind = "new"
    victim = d / rng.choice(files)
    command = ["run", str(script)]
    new_ok: list[Path] = []
    changes_ok: list[Path] = []
    expect: str | None = "error"
    if kind == "input":
        out = str(victim)
    elif kind == "symlink":
        (d / "link.h5").symlink_to(victim if rng.random() < 0.5 else Path(victim.name))
        out = str(d / "link.h5")
    elif kind == "hardlink":
        os.link(victim, d / "hard.h5")
        out = str(d / "hard.h5")
    elif kind == "dotdot":
        out = str(d / ".." / d.name / "." / victim.name)
    elif kind == "directory":
        out = str(rng.choice((d, work / "out")))
    elif kind == "empty":
        out = ""
    elif kind == "missing_dir":
        out = str(d / "no" / "such" / "dir" / "x.h5")
    elif kind == "fifo":
        os.mkfifo(d / "fifo.h5")
        out = str(d / "fifo.h5")
    elif kind == "socket":
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(d / "sock.h5"))
        s.close()
        out = str(d / "sock.h5")
    elif kind == "device":
        try:
            os.mknod(d / "null.h5", stat.S_IFCHR | 0o666, os.makedev(1, 3))  # /dev/null's numbers (root only)
            out = str(d / "null.h5")
        except PermissionError:
            out = "/dev/null"
    elif kind == "dangling":
        (d / "dangling.h5").symlink_to(d / "nothing" / "here.h5")
        out = str(d / "dangling.h5")
    elif kind == "parent_is_file":
        out = str(victim / "x.h5")
    elif kind == "proc":
        out = f"/proc/demsplit-fuzz-{index}.h5"
    elif kind == "long_name":
        out = str(d / ("x" * rng.choice((255, 256, 300, 5000)) + ".h5"))
    elif kind == "new":
        out = str(d / "new.h5")
        new_ok, expect = [Path(out)], "ok"
    elif kind == "existing":  # a file that is not a store: replaced only with --overwrite
        (d / "old.h5").write_bytes(b"an earlier result")
        out = str(d / "old.h5")
        if rng.random() < 0.5:
            command.append("--overwrite")
            changes_ok, expect = [Path(out)], "ok"
    elif kind == "existing_store":  # an earlier store: replaced
        shutil.copy(base / "results.h5", d / "old.h5")
        out = str(d / "old.h5")
        changes_ok, expect = [Path(out)], "ok"
    elif kind == "full_fs":
        out = str(full_fs / "out.h5")
    elif kind == "yade_input":
        snap = d / "snap.npys"
        shutil.copy(base / "yade" / "mindlin_box.npys", snap)
        command = ["run", str(snap)]
        choice = rng.choice(("itself", "symlink", "hardlink"))
        if choice == "symlink":
            (d / "snaplink.h5").symlink_to(snap)
        elif choice == "hardlink":
            os.link(snap, d / "snaplink.h5")
        out = str(snap if choice == "itself" else d / "snaplink.h5")
        kind = f"yade_input {choice}"
    else:  # the other commands that write, onto their input (a store, or the script)
        store = d / "results.h5"
        shutil.copy(base / "results.h5", store)
        alias = rng.choice(("itself", "symlink", "hardlink", "other"))
        own = store if kind in ("report", "export") else script  # the command's own input
        if alias == "symlink":
            (d / "alias").symlink_to(own)
        elif alias == "hardlink":
            os.link(own, d / "alias")
        elif alias == "other":  # a hard link to a file of the run that is not this command's input
            os.link(victim, d / "alias")
        target = own if alias == "itself" else d / "alias"
        if alias == "other":
            changes_ok = [d / "alias"]  # replacing a name of a file that is no input leaves the file as it was
        if kind == "report":
            command, out = ["report", str(store)], str(target)
            expect = None if alias == "other" else "error"
        elif kind == "export":
            exp = d / "export"
            exp.mkdir()
            which = rng.choice(("particles.csv", "frames.csv", "provenance.json", "units.csv"))
            os.link(victim if alias == "other" else store, exp / which)
            command, out = ["export", str(store), "--csv", str(exp)], None
            new_ok, changes_ok = [exp], [exp / which]
            expect = None if alias == "other" else "error"
            kind = f"export --csv with {which} a hard link"
        elif kind == "convert":  # every file the run names is its input
            command, out = ["convert", str(script)], str(victim if alias == "itself" else target)
            changes_ok = []
        else:  # prepare reads the script only
            command, out = ["prepare", str(script)], str(target)
            if alias == "other" and victim != script:
                expect = None
            else:
                changes_ok = []
        kind = f"{kind} {alias}"
    argv = [*command, *(["-o", out] if out is not None else []), "-q"]
    return Case(
        index,
        "output_path",
        f"{kind}: -o {out!r}"[:300],
        argv,
        d,
        None if out is None else Path(out),
        new_ok=new_ok,
        changes_ok=changes_ok,
        expect=expect,
    )


# ------------------------------------------------------------------ stores, ingest caches, exports, prepare

H5_DTYPES = (
    "int8",
    "uint8",
    "int16",
    "int32",
    "uint64",
    "float16",
    "float32",
    "bool",
    "S4",
    "complex128",
    "float64",
    "int64",
)
"""Dtypes a damaged HDF5 column is rewritten in."""
ODD_ATTRIBUTES = (
    np.nan,
    -1,
    2**63 - 1,
    1.5,
    "x",
    "[",
    "null",
    "{}",
    '["x"]',
    "[1e308]",
    '{"a": 1}',
    np.arange(2),
    np.array([np.inf, 0.0, 0.0]),
    np.zeros(3),
    b"\xff",
    True,
)
"""Values a damaged HDF5 attribute is given."""
EXPORT_NAME = re.compile(
    r"(particles|contacts|walls|frames|clumps)\.(csv|parquet)|units\.csv|provenance\.json|"
    r"(particles|contacts|walls)_\d{12}\.vtu|(particles|contacts|walls)\.pvd|demsplit-export\.json"
)
"""The names of the files an export writes."""
EXPORT_FORMATS = ("--csv", "--csv", "--vtk", "--parquet", "--dump", "--dump", "report")


def _special_for(rng: random.Random, dtype: np.dtype):
    if dtype.kind == "f":
        return rng.choice(SPECIAL_REALS)
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        return min(max(rng.choice(SPECIAL_INTS), info.min), info.max)
    if dtype.kind == "b":
        return rng.random() < 0.5
    return rng.choice(SPECIAL_BYTES)


def _rewrite(group, name: str, data) -> None:
    del group[name]
    group.create_dataset(name, data=data)


def mutate_column(rng: random.Random, group, name: str) -> str:
    """A column (1-D dataset) of ``group`` changed in place: a value or all of them, its dtype, its shape, or
    removed."""
    d = group[name]
    data = d[()]
    kind = rng.choice(("value", "value", "value", "values", "dtype", "shape", "drop"))
    if kind in ("value", "values") and data.ndim == 1 and len(data):
        rows = [rng.randrange(len(data))] if kind == "value" else slice(None)
        value = _special_for(rng, data.dtype)
        try:
            data[rows] = value
        except (ValueError, OverflowError, TypeError):
            return f"{group.name}/{name}: {value!r} does not fit {data.dtype}"
        d[...] = data
        return f"{group.name}/{name}[{rows if kind == 'value' else ':'}] = {value!r}"
    if kind == "dtype":
        dtype = rng.choice(H5_DTYPES)
        with np.errstate(all="ignore"):
            _rewrite(group, name, data.astype(dtype))
        return f"{group.name}/{name} as {dtype}"
    if kind == "shape":
        shape = rng.choice(("column", "short", "long", "empty", "scalar"))
        new = {
            "column": lambda: data.reshape(-1, 1),
            "short": lambda: data[:-1],
            "long": lambda: np.concatenate([data, data[:3]]),
            "empty": lambda: data[:0],
            "scalar": lambda: data[0] if len(data) else np.float64(0),
        }[shape]()
        _rewrite(group, name, new)
        return f"{group.name}/{name} shape {shape}"
    del group[name]
    return f"{group.name}/{name} removed"


def _mutate_json_attr(rng: random.Random, attrs, name: str) -> str:
    """The JSON attribute ``name``: a value inside it changed or removed, or the whole replaced."""
    try:
        value = json.loads(attrs[name])
    except (KeyError, TypeError, ValueError):
        value = None
    paths = _json_paths(value) if isinstance(value, (dict, list)) else []
    if not paths or rng.random() < 0.2:
        attrs[name] = rng.choice(ODD_ATTRIBUTES)
        return f"attribute {name} = {attrs[name]!r}"
    path = rng.choice(paths)
    node = value
    for step in path[:-1]:
        node = node[step]
    if rng.random() < 0.2:
        del node[path[-1]]
        what = "removed"
    else:
        node[path[-1]] = rng.choice(JSON_VALUES)
        what = f"= {node[path[-1]]!r}"
    attrs[name] = json.dumps(value)
    return f"attribute {name} {list(path)} {what}"


def mutate_store(rng: random.Random, path: Path) -> str:
    """One change of the result store ``path``, in place: raw damage, a column, the index, the attributes,
    data outside the file, a declared length it does not hold, or a particle listed twice."""
    import h5py

    kind = rng.choice(
        (
            "flip",
            "truncate",
            "column",
            "column",
            "column",
            "column",
            "columns_attr",
            "index",
            "index",
            "provenance",
            "provenance",
            "walls_meta",
            "format",
            "foreign",
            "huge",
            "twice",
        )
    )
    if kind in ("flip", "truncate"):
        data, what = flip_bytes(rng, path.read_bytes()) if kind == "flip" else cut_bytes(rng, path.read_bytes())
        path.write_bytes(data)
        return what
    with h5py.File(path, "a") as f:
        table = rng.choice(("particles", "contacts", "walls", "frames"))
        columns = sorted(f[table])
        if kind == "column" or (kind in ("foreign", "twice") and not columns):
            group = f[rng.choice((table, table, table, "index"))]
            return mutate_column(rng, group, rng.choice(sorted(group))) if len(group) else "an empty table"
        if kind == "columns_attr":
            cols = json.loads(f[table].attrs["columns"])
            f[table].attrs["columns"] = rng.choice(
                (
                    "[",
                    '"x"',
                    json.dumps(cols + ["extra"]),
                    json.dumps(cols[:-1]),
                    json.dumps(cols[::-1]),
                    "[1, 2]",
                    json.dumps(cols + cols[:1]),
                )
            )
            return f"{table} columns = {f[table].attrs['columns'][:80]}"
        if kind == "index":
            name = rng.choice(("step", "step", table))
            values = f["index"][name][()]
            how = rng.choice(("twice", "reverse", "value", "value"))
            if how == "twice" and len(values) > 1:
                values[-1] = values[0]
            elif how == "reverse":
                values = values[::-1]
            elif len(values):
                values[rng.randrange(len(values))] = rng.choice((-1, 0, 1, 2**40, 2**62, 7))
            _rewrite(f["index"], name, values)
            return f"index/{name} {how}"
        if kind in ("provenance", "walls_meta"):
            return _mutate_json_attr(rng, f.attrs, kind)
        if kind == "format":
            name = rng.choice(("format", "format_version"))
            f.attrs[name] = rng.choice(("x", b"demsplit-results", 2, "1", -1, 1.5, np.arange(2)))
            return f"attribute {name} = {f.attrs[name]!r}"
        if kind == "foreign":
            col = rng.choice(columns)
            how = rng.choice(FOREIGN_STORAGE)
            del f[table][col]
            foreign_storage(rng, how, f[table], col, path.with_name("secret.bin"))
            return f"{table}/{col}: {how}"
        if kind == "huge":
            rows = rng.choice((1 << 40, 1 << 31, 10**7))
            f["index"][table][-1] = rows
            for col in columns:
                f[table][col].resize((rows,))
            return f"{table}: {rows} rows declared"
        col = rng.choice(("id", "wall", "step")) if table != "contacts" else "id1"
        if col in f[table] and f[table][col].shape[0] > 1:
            values = f[table][col][()]
            values[1] = values[0]
            f[table][col][...] = values
        return f"{table}/{col}: row 1 = row 0"


def mutate_cache(rng: random.Random, path: Path) -> str:
    """One change of the ingest cache ``path``, in place: raw damage, a column of a frame, a row listed twice,
    a frame's or the cache's attributes, a stored error, a frame removed, data outside the file."""
    import h5py

    kind = rng.choice(
        (
            "flip",
            "truncate",
            "column",
            "column",
            "column",
            "twice",
            "twice",
            "frame_attr",
            "frame_attr",
            "root_attr",
            "error",
            "drop_frame",
            "order",
            "foreign",
        )
    )
    if kind in ("flip", "truncate"):
        data, what = flip_bytes(rng, path.read_bytes()) if kind == "flip" else cut_bytes(rng, path.read_bytes())
        path.write_bytes(data)
        return what
    with h5py.File(path, "a") as f:
        names = sorted(f["frames"])
        name = rng.choice(names)
        g = f["frames"][name]
        table = rng.choice(("particles", "contacts"))
        if "error" in g.attrs and kind in ("column", "twice", "order", "foreign"):
            kind = "error"
        if kind == "column":
            group = g[table]
            return f"frame {name}: " + mutate_column(rng, group, rng.choice(sorted(group)))
        if kind == "twice":
            group = g[table]
            n = group[next(iter(group))].shape[0] if len(group) else 0
            if not n:
                return f"frame {name}: {table} has no rows"
            row = rng.randrange(n)
            for col in list(group):
                _rewrite(group, col, np.concatenate([group[col][()], group[col][row : row + 1]]))
            if table == "contacts" and "overlap_error" in g:
                _rewrite(
                    g, "overlap_error", np.concatenate([g["overlap_error"][()], g["overlap_error"][row : row + 1]])
                )
            return f"frame {name}: {table} row {row} listed twice"
        if kind == "frame_attr":
            attr = rng.choice(
                (
                    "step",
                    "time",
                    "box_lo",
                    "box_hi",
                    "box_periodic",
                    "box_tilt",
                    "source",
                    "notes",
                    "walls",
                    "overlap_source",
                )
            )
            if rng.random() < 0.2 and attr in g.attrs:
                del g.attrs[attr]
                return f"frame {name}: attribute {attr} removed"
            g.attrs[attr] = rng.choice(ODD_ATTRIBUTES)
            return f"frame {name}: attribute {attr} = {g.attrs[attr]!r}"
        if kind == "root_attr":
            attr = rng.choice(("steps", "scene", "scene", "sources", "describe", "version", "n_frames", "format"))
            if attr in ("scene", "describe", "sources"):
                return _mutate_json_attr(rng, f.attrs, attr)
            f.attrs[attr] = rng.choice(ODD_ATTRIBUTES + (np.array([-1, 5]), np.arange(len(names))[::-1] * 1000))
            return f"attribute {attr} = {f.attrs[attr]!r}"
        if kind == "error":
            g.attrs["error"] = rng.choice(
                (
                    "{",
                    "null",
                    json.dumps(
                        {
                            "class": rng.choice(
                                ("os", "InputFormatError", "DemsplitError", "KeyError", "Path", 5, "StoreError")
                            ),
                            "message": rng.choice(("x", 5, None)),
                            "file": rng.choice((None, 5, "f")),
                            "step": rng.choice((None, "x", 3)),
                            "line": rng.choice((None, 1.5, 2)),
                            "fix": None,
                        }
                    ),
                )
            )
            return f"frame {name}: error = {g.attrs['error'][:100]}"
        if kind == "drop_frame":
            del f["frames"][name]
            return f"frame {name} removed"
        if kind == "order":
            order = json.loads(g[table].attrs["order"])
            g[table].attrs["order"] = rng.choice(
                (
                    "[",
                    "null",
                    json.dumps(order + ["extra"]),
                    json.dumps(order[:-1]),
                    json.dumps(order + order[:1]),
                    "[1]",
                )
            )
            return f"frame {name}: {table} order = {g[table].attrs['order'][:80]}"
        group = g[table]
        col = rng.choice(sorted(group))
        how = rng.choice(FOREIGN_STORAGE)
        del group[col]
        foreign_storage(rng, how, group, col, path.with_name("secret.bin"))
        return f"frame {name}: {table}/{col}: {how}"


STORE_COMMANDS = (
    ("info",),
    ("report",),
    ("report",),
    ("export", "--csv"),
    ("export", "--csv"),
    ("export", "--dump"),
    ("export", "--dump"),
    ("export", "--vtk"),
    ("export", "--parquet"),
)
"""What is done with a damaged store (``report -o`` is left to the export family: a page takes seconds)."""


def store_case(rng: random.Random, base: Path, d: Path, out_dir: Path, index: int) -> Case:
    """A damaged result store given to info, report or export."""
    d.mkdir()
    store = d / "store.h5"
    shutil.copy(rng.choice((base / "results.h5", base / "results_packing.h5")), store)
    what = mutate_store(rng, store)
    command = list(rng.choice(STORE_COMMANDS))
    target = out_dir / {"--csv": "csv", "--dump": "p.dump", "--vtk": "vtk", "--parquet": "pq"}.get(command[-1], "")
    argv = [command[0], str(store), *command[1:], *([str(target)] if command[0] == "export" else []), "-q"]
    return Case(
        index, "store", f"{what}; {' '.join(command)}", argv, d, None, new_ok=[target] if command[0] == "export" else []
    )


def cache_case(rng: random.Random, base: Path, d: Path, out_dir: Path, index: int) -> Case:
    """A damaged ingest cache given to run or info."""
    d.mkdir()
    cache = d / "cache.h5"
    shutil.copy(rng.choice((base / "cache_packing.h5", base / "cache_yade.h5")), cache)
    what = mutate_cache(rng, cache)
    out = out_dir / "out.h5"
    if rng.random() < 0.15:
        return Case(index, "cache", f"{what}; info", ["info", str(cache), "-q"], d)
    return Case(index, "cache", f"{what}; run", ["run", str(cache), "-o", str(out), "-q"], d, out, new_ok=[out])


def _store_of_the_case(base: Path, d: Path) -> Path:
    """The packing run's store beside its files in ``d``, its provenance naming them (as a store made there)."""
    import h5py

    store = d / "results.h5"
    shutil.copy(base / "results_packing.h5", store)
    with h5py.File(store, "a") as f:
        f.attrs["provenance"] = f.attrs["provenance"].replace(str(base / "packing_all"), str(d))
    return store


def export_case(rng: random.Random, base: Path, d: Path, out_dir: Path, index: int) -> Case:
    """export (every format) and report -o into a folder or onto a file that is new, an earlier export, a
    folder of other files, a file of the run (by name, link or hard link), a crafted manifest, ..."""
    shutil.copytree(base / "packing_all", d)
    store = _store_of_the_case(base, d)
    fmt = rng.choice(EXPORT_FORMATS)
    overwrite = rng.random() < 0.3 and fmt != "report"  # a report that is written takes seconds
    victim = d / rng.choice(sorted(p.name for p in d.iterdir() if p.name != "results.h5"))
    expect, changes_ok = None, []
    if fmt in ("--csv", "--vtk", "--parquet"):
        target = out_dir / "export"
        kind = rng.choice(
            (
                "new",
                "empty",
                "earlier_same",
                "earlier_same",
                "earlier_other",
                "foreign",
                "hardlink_input",
                "symlink_input",
                "manifest",
                "file",
                "run_dir",
                "named_like_ours",
                "missing_parent",
            )
        )
        name = fmt[2:]
        ours = rng.choice(
            (
                "particles.csv",
                "particles.parquet",
                "particles.pvd",
                "provenance.json",
                "units.csv",
                "demsplit-export.json",
                f"particles_{2000:012d}.vtu",
            )
        )
        if kind == "empty":
            target.mkdir()
        elif kind in ("earlier_same", "earlier_other"):
            other = name if kind == "earlier_same" else rng.choice([f for f in ("csv", "vtk", "parquet") if f != name])
            shutil.copytree(base / "exports" / other, target)
        elif kind == "foreign":
            target.mkdir()
            shutil.copy(d / "floor.stl", target / "floor.stl")
        elif kind in ("hardlink_input", "symlink_input"):
            target.mkdir()
            (os.link if kind == "hardlink_input" else lambda a, b: os.symlink(a, b))(victim, target / ours)
        elif kind == "manifest":
            target.mkdir()
            listed = rng.choice((["../case/in.packing"], ["in.packing"], ["sub"], [".."], [ours], ["in.packing", ours]))
            if "in.packing" in listed:
                os.link(d / "in.packing", target / "in.packing")
            if "sub" in listed:
                (target / "sub").mkdir()
            if ours in listed:
                os.link(victim, target / ours)
            (target / "demsplit-export.json").write_text(
                json.dumps({"format": "demsplit-export", "kind": name, "files": listed})
            )
            kind = f"manifest listing {listed}"
        elif kind == "file":
            target = victim
        elif kind == "run_dir":
            target = d
        elif kind == "named_like_ours":
            target.mkdir()
            (target / ours).write_text("the user's own file\n")
        elif kind == "missing_parent":
            target = out_dir / "no" / "export"
        if kind == "run_dir":
            overwrite = False  # with --overwrite the export goes among the run's files, which it may
        if kind in ("new", "empty", "earlier_same"):
            expect = "ok"
        elif kind in ("earlier_other", "foreign", "named_like_ours"):
            expect = "ok" if overwrite else "error"
        elif kind in ("file", "run_dir", "missing_parent") or (kind.endswith("_input") and not overwrite):
            expect = "error"
        if (
            target.is_dir()
            and target != d
            and (overwrite or kind in ("earlier_same", "empty") or kind.startswith("manifest"))
        ):
            changes_ok = [p for p in target.rglob("*") if EXPORT_NAME.fullmatch(p.name) or kind.startswith("manifest")]
        argv = ["export", str(store), fmt, str(target)]
        new_ok = [target] if target not in (d, victim) else []
    else:
        kind = rng.choice(
            ("new", "earlier", "foreign", "input", "input", "symlink_input", "hardlink_input", "directory", "store")
        )
        target = out_dir / ("report.html" if fmt == "report" else "p.dump")
        if kind == "earlier" and fmt == "--dump":
            shutil.copy(base / "exports" / "p.dump", target)
        elif kind == "foreign":
            target.write_text("the user's notes\n")
        elif kind == "input":
            target = victim
        elif kind in ("symlink_input", "hardlink_input"):
            (os.link if kind == "hardlink_input" else lambda a, b: os.symlink(a, b))(victim, target)
        elif kind == "directory":
            target = out_dir
        elif kind == "store":
            target = store
        if fmt == "report" and kind in ("new", "earlier", "foreign"):
            kind = "input"  # a report that is written takes seconds: only the refusals
            target = victim
        expect = "ok" if kind in ("new", "earlier") or (kind == "foreign" and overwrite) else "error"
        if kind in ("earlier", "foreign") and expect == "ok":
            changes_ok = [target]
        argv = (
            ["report", str(store), "-o", str(target)]
            if fmt == "report"
            else ["export", str(store), "--dump", str(target)]
        )
        new_ok = [target] if kind == "new" else []
    argv += ["--overwrite"] * overwrite + ["-q"]
    return Case(
        index,
        "export",
        f"{fmt} {kind}{' --overwrite' if overwrite else ''}: {target}"[:300],
        argv,
        d,
        None,
        new_ok=new_ok,
        changes_ok=changes_ok,
        expect=expect,
    )


def _named_by(script: Path) -> list[Path]:
    """The existing files other than itself that ``script`` names (none when it cannot be read)."""
    from demsplit.errors import DemsplitError
    from demsplit.readers.liggghts_script import read_script

    try:
        files = read_script(script).named_files()
    except DemsplitError:
        return []
    return sorted({p for p in files if p.exists() and p.resolve() != script.resolve()})


def prepare_case(rng: random.Random, base: Path, d: Path, index: int) -> Case:
    """prepare (of the packing script, its dumps removed or not, sometimes damaged) onto a new name, its own
    earlier output, an edited one, a foreign file, a file the script names (by name or link), ..."""
    from demsplit.outputs import stamp_script

    shutil.copytree(base / "packing_all", d)
    script = d / "in.packing"
    text = script.read_text()
    what = []
    if rng.random() < 0.7:
        text = "".join(line for line in text.splitlines(True) if not line.startswith("dump"))
        what.append("dumps removed")
    if rng.random() < 0.3:
        (d / "extra.in").write_text("variable extra equal 1\n")
        text = "include extra.in\n" + text
        what.append("includes extra.in")
    script.write_text(text)
    if rng.random() < 0.2:
        data, how = mutate_script(rng, script.read_bytes())
        script.write_bytes(data)
        what.append(how)
    overwrite = rng.random() < 0.3
    kind = rng.choice(
        (
            "default",
            "new",
            "ours",
            "edited",
            "foreign",
            "input",
            "named",
            "named",
            "symlink_input",
            "hardlink_input",
            "directory",
            "missing_dir",
        )
    )
    named = _named_by(script) or [d / "floor.stl"]
    target = d / "in.packing.demsplit" if kind == "default" else d / "prepared.in"
    expect, changes_ok = None, []
    if kind == "ours":
        target.write_bytes(stamp_script(b"# an earlier prepared script\n"))
        changes_ok = [target]
    elif kind == "edited":
        target.write_bytes(stamp_script(b"# an earlier prepared script\n") + b"# edited\n")
    elif kind == "foreign":
        target.write_text("# the user's own script\n")
    elif kind == "input":
        target = script
    elif kind == "named":
        target = rng.choice(named)
    elif kind in ("symlink_input", "hardlink_input"):
        (os.link if kind == "hardlink_input" else lambda a, b: os.symlink(a, b))(rng.choice([script, *named]), target)
    elif kind == "directory":
        target = d
    elif kind == "missing_dir":
        target = d / "no" / "prepared.in"
    if kind in ("edited", "foreign"):
        expect = "error" if not overwrite else None
        changes_ok = [target] if overwrite else []
    elif kind in ("input", "named", "symlink_input", "hardlink_input", "directory", "missing_dir"):
        expect = "error"
    argv = ["prepare", str(script), *([] if kind == "default" else ["-o", str(target)])]
    argv += ["--overwrite"] * overwrite + ["-q"]
    parts = [target.with_name(f"{target.name}.part{k}") for k in range(2, 5)]
    return Case(
        index,
        "prepare",
        f"{', '.join(what) or 'as it is'}; {kind}{' --overwrite' if overwrite else ''}",
        argv,
        d,
        None,
        new_ok=[target, *parts] if kind in ("default", "new") else parts,
        changes_ok=changes_ok,
        expect=expect,
    )


# ------------------------------------------------------------------ the promise


def tree_state(directory: Path) -> dict[str, tuple]:
    """Every path below ``directory`` -> (kind, sha256 for files, target for links, rdev for devices)."""
    state = {}
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            p = Path(root) / name
            st = os.lstat(p)
            if stat.S_ISLNK(st.st_mode):
                state[str(p)] = ("link", os.readlink(p))
            elif stat.S_ISREG(st.st_mode):
                state[str(p)] = ("file", hashlib.sha256(p.read_bytes()).hexdigest(), st.st_ino)
            elif stat.S_ISDIR(st.st_mode):
                state[str(p)] = ("dir",)
            else:
                state[str(p)] = ("node", stat.S_IFMT(st.st_mode), st.st_rdev)
    return state


def store_problems(path: Path) -> list[str]:
    """What is wrong with the store at ``path``: a numeric value that is not finite in any table, a
    missing frame, JSON with NaN."""
    import h5py

    problems = []
    with h5py.File(path, "r") as h5:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "fc":
                values = obj[()]
                if not np.all(np.isfinite(values)):
                    problems.append(f"NONFINITE {name} ({int(np.count_nonzero(~np.isfinite(values)))} values)")

        h5.visititems(visit)
        for attr in ("provenance", "walls_meta"):
            try:
                json.loads(h5.attrs[attr], parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
            except (KeyError, ValueError) as exc:
                problems.append(f"BADJSON {attr}: {exc}")
        if len(h5["index/step"]) == 0:
            problems.append("EMPTY store written with exit 0")
    return problems


def check_case(case: Case) -> tuple[str, str]:
    """Run ``case`` through ``demsplit.cli.main`` in this process; return ``(outcome, detail)``. The outcome
    is ``ok``, ``error <DemsplitError class>`` or, when a promise is broken, a word in capitals."""
    from demsplit import cli
    from demsplit.errors import DemsplitError

    sandbox = case.directory.parent  # the case's files and the output directory: nothing but outputs changes
    before = tree_state(sandbox)
    cached = {c: cache_state(c) for c in case.caches}
    seen: dict = {}

    def recording(func):
        def wrapper(args):
            try:
                return func(args)
            except DemsplitError as exc:
                seen["class"] = type(exc).__name__
                raise
            except BaseException as exc:
                seen["class"] = type(exc).__name__
                seen["traceback"] = traceback.format_exc()
                raise

        return wrapper

    patched = {
        name: getattr(cli, name)
        for name in ("cmd_run", "cmd_report", "cmd_export", "cmd_convert", "cmd_prepare", "cmd_info")
    }
    out, err = io.StringIO(), io.StringIO()
    try:
        for name, func in patched.items():
            setattr(cli, name, recording(func))
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), warnings.catch_warnings():
            warnings.simplefilter("always")
            rc = cli.main(case.argv)
    finally:
        for name, func in patched.items():
            setattr(cli, name, func)
    err_text = err.getvalue()
    outcome, detail = ("ok", "") if rc == 0 else (f"error {seen.get('class', '?')}", err_text.strip())
    if rc == 2 and "no stored number is NaN or inf" in err_text:  # the store's last guard: the pipeline let it by
        return "NONFINITE caught by the store", err_text
    if rc == 2 and "earlier frames had" in err_text:  # the pipeline gave the frames of one run other columns
        return "INCONSISTENT frames caught by the store", err_text
    if rc not in (0, 2):
        return f"EXIT{rc} {seen.get('class', '?')}", seen.get("traceback", "") + err_text
    if case.expect == "error" and rc == 0:
        return "ACCEPTED a bad output", case.what
    if case.expect == "ok" and rc != 0:
        return "REFUSED a good output", f"{case.what}: {err_text}"
    if rc == 2 and (err_text.count("\n") != 1 or not err_text.startswith("demsplit: error: ")):
        return "MESSAGE not one line", err_text
    if rc == 2 and re.search(r"\bnp\.\w+\(", err_text):  # np.float64(0.0): a number printed by its repr
        return "MESSAGE numpy repr", err_text
    if rc == 0 and (err_text or out.getvalue()):
        return "MESSAGE output with -q", out.getvalue() + err_text
    after = tree_state(sandbox)
    allowed_new = [str(p) for p in case.new_ok]
    for path, state in before.items():
        if after.get(path) != state and path not in [str(p) for p in case.changes_ok]:
            if state[0] == "file" and after.get(path, ("?",))[0] == "file" and after[path][1] == state[1]:
                continue  # the same bytes (a new inode of the same content is fine, e.g. an atomic replace)
            return "MODIFIED input", f"{path}: {state[:2]} -> {after.get(path, ('gone',))[:2]}"
    for path in after:
        if path.endswith(".tmp") and path not in before:
            return "LEFTOVER", path
        if path not in before and not any(path == a or path.startswith(a + "/") for a in allowed_new):
            if rc == 2 and ".partial" in path and _resumable_work(path):
                continue
            return "LEFTOVER", path
    if (
        case.output is not None
        and rc == 0
        and case.output.is_file()
        and "report" not in case.argv[0]
        and case.argv[0] == "run"
    ):
        problems = store_problems(case.output)
        if problems:
            return problems[0].split(" ")[0], "; ".join(problems)
    for cache, earlier in cached.items():
        problems = cache_problems(cache, earlier)
        if problems:
            return "CACHE", "; ".join(problems)
    out_dir = case.output.parent if case.output is not None else None
    if out_dir is not None and out_dir.is_dir() and out_dir != case.directory and out_dir.name == "out":
        for p in out_dir.iterdir():
            if p.name.endswith(".tmp") or (p.name.endswith(".partial") and not _resumable_work(str(p))):
                return "LEFTOVER", str(p)
            if rc != 0 and p == case.output:
                return "LEFTOVER output of a failed run", str(p)
    return outcome, detail


def _resumable_work(path: str) -> bool:
    """Whether the ``.NAME.partial`` directory that ``path`` is in (or is) holds committed frames."""
    p = Path(path)
    while not p.name.endswith(".partial") and p != p.parent:
        p = p.parent
    return (p / "commit.npys").is_file() and (p / "store.h5").is_file()


# ------------------------------------------------------------------ running many: a worker child per batch


def _child(conn, base: Path, work: Path, seed: int, indices: list[int], families, full_fs) -> None:
    os.setpgid(0, 0)
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    for i in indices:
        conn.send(("start", i))
        try:
            case = build_case(base, work, seed, i, families, full_fs)
        except Exception:
            conn.send(("done", i, "?", "GENERATOR", traceback.format_exc()))
            continue
        t0 = time.monotonic()
        try:
            outcome, detail = check_case(case)
        except BaseException as exc:  # the check itself failed (e.g. the store unreadable)
            outcome, detail = f"CHECK {type(exc).__name__}", traceback.format_exc()
        if full_fs is not None:
            for p in full_fs.iterdir():  # the full file system holds no more than a resumable run after a case
                if kept(outcome) and not _resumable_work(str(p)):
                    outcome, detail = "LEFTOVER", str(p)
                _remove(p)
        conn.send(("done", i, case.family, outcome, f"{case.what}\n{detail}", time.monotonic() - t0))
    conn.send(("exit",))
    conn.close()


def warm_up(base: Path, work: Path) -> None:
    """Run each kind of input once in this process (numba compiles, modules import) so forked
    children start warm; and write the store the report/export cases read."""
    from demsplit.cli import main

    work.mkdir(parents=True, exist_ok=True)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for argv in (
            ["run", str(base / "packing_text" / "in.packing")],
            ["run", str(base / "packing_bin" / "in.packing"), "--atoms", str(base / "packing_bin" / "atoms.bin")],
            ["run", str(base / "packing_gz" / "in.packing")],
            *(["run", str(p)] for p in yade_bases(base, "")),
            *(
                [["run", str(base / "yade_states" / "facets-*"), "--state-cache", str(base / "yade_states" / "cache")]]
                if (base / "yade_states" / "done").exists()
                else []
            ),
        ):
            out = work / "warm.h5"
            if out.exists():
                out.unlink()
            rc = main([*argv, "-o", str(out), "-q"])
            if rc != 0:
                raise SystemExit(f"the unmutated base does not run: {argv}")
        if not (base / "results.h5").exists():  # the stores, caches and exports the later families start from
            main(["run", str(base / "yade" / "mindlin_box.npys"), "-o", str(base / "results.h5"), "-q"])
            main(["run", str(base / "packing_all" / "in.packing"), "-o", str(base / "results_packing.h5"), "-q"])
            main(["convert", str(base / "packing_text" / "in.packing"), "-o", str(base / "cache_packing.h5"), "-q"])
            main(["convert", str(base / "yade" / "mindlin_box.h5"), "-o", str(base / "cache_yade.h5"), "-q"])
            (base / "exports").mkdir(exist_ok=True)
            for fmt in ("csv", "vtk", "parquet"):
                main(["export", str(base / "results.h5"), f"--{fmt}", str(base / "exports" / fmt), "-q"])
            main(["export", str(base / "results.h5"), "--dump", str(base / "exports" / "p.dump"), "-q"])
        for path in ("results_packing.h5", "cache_packing.h5", "cache_yade.h5", "exports/csv", "exports/p.dump"):
            if not (base / path).exists():
                raise SystemExit(f"the base {path} was not written")
        for name in ("cache_packing.h5", "cache_yade.h5"):  # read once here: the children start warm
            main(["run", str(base / name), "-o", str(work / "warm.h5"), "-q", "--overwrite"])
        if (work / "warm.h5").exists():
            (work / "warm.h5").unlink()


@contextlib.contextmanager
def full_file_system(root: Path, enabled: bool):
    """A 64 KiB tmpfs (root only): the output cases' full disk. Yields its path, or None."""
    mount = root / "fullfs"
    mount.mkdir(exist_ok=True)
    ok = False
    if enabled and os.geteuid() == 0 and shutil.which("mount"):
        import subprocess

        ok = (
            subprocess.run(
                ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount)], capture_output=True
            ).returncode
            == 0
        )
    try:
        yield mount if ok else None
    finally:
        if ok:
            import subprocess

            subprocess.run(["umount", str(mount)], capture_output=True)


def kept(outcome: str) -> bool:
    """Whether ``outcome`` keeps the promise: exit 0 with a sound store, or exit 2 with one message."""
    return outcome == "ok" or outcome.startswith("error ")


def fuzz(
    seed: int,
    count: int | None,
    seconds: float | None,
    families=FAMILIES,
    root: Path | None = None,
    mount: bool = True,
    batch: int = BATCH,
    time_limit: float = TIME_LIMIT,
    progress: bool = True,
) -> dict:
    """Run inputs ``0 .. count-1`` of ``seed`` (or as many as fit in ``seconds``), a worker child per
    batch; return the summary (counts per family and outcome, every broken promise)."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    broken: list[dict] = []
    durations: list[float] = []
    t_start = time.monotonic()

    examples: dict[str, dict] = {}

    def record(i: int, family: str, outcome: str, detail: str) -> None:
        counts[family][outcome] += 1
        examples.setdefault(f"{family}: {outcome}", {"index": i, "detail": detail[:600]})
        if not kept(outcome):
            broken.append({"index": i, "family": family, "outcome": outcome, "detail": detail})
            log(f"\n[{i}] {family} {outcome}: {detail[:2000]}")
        total = sum(sum(c.values()) for c in counts.values())
        if progress and total % 1000 == 0:
            log(f"{total} inputs, {time.monotonic() - t_start:.0f} s, {len(broken)} broken")

    with contextlib.ExitStack() as stack:
        if root is None:
            shm = "/dev/shm" if Path("/dev/shm").is_dir() else None
            root = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="demsplit-fuzz-", dir=shm)))
        base = make_bases(root, families)
        work = root / "work"
        warm_up(base, work)
        full_fs = stack.enter_context(full_file_system(root, mount and "output_path" in families))
        running: list = []  # the worker, killed first when the fuzzer is interrupted (before the unmount)
        stack.callback(lambda: [_kill(p) for p in running])
        next_index, stop = 0, False
        while not stop and (count is None or next_index < count):
            end = next_index + batch if count is None else min(next_index + batch, count)
            parent, child = ctx.Pipe()
            proc = ctx.Process(
                target=_child, args=(child, base, work, seed, list(range(next_index, end)), families, full_fs)
            )
            proc.start()
            running[:] = [proc]
            child.close()
            current, started = None, time.monotonic()
            while True:
                msg = None
                if parent.poll(1.0):
                    try:
                        msg = parent.recv()
                    except EOFError:
                        msg = ("died",)
                if msg is None:
                    limit = (
                        TIME_LIMITS.get(family_of(seed, current, families), time_limit)
                        if current is not None
                        else time_limit
                    )
                    if current is not None and time.monotonic() - started > limit:
                        record(current, family_of(seed, current, families), "HANG", f"more than {limit} s")
                        next_index = current + 1
                        break
                    if proc.is_alive():
                        continue
                    msg = ("died",)
                if msg[0] == "start":
                    current, started = msg[1], time.monotonic()
                elif msg[0] == "done":
                    _, i, family, outcome, detail, *took = msg
                    durations += took
                    record(i, family, outcome, detail)
                    current, next_index = None, i + 1
                    if count is None and time.monotonic() - t_start > seconds:
                        stop = True
                        break
                elif msg[0] == "exit":
                    next_index = end
                    break
                else:  # the child died: a crash, or the memory limit
                    proc.join(5)
                    i = next_index if current is None else current
                    record(i, family_of(seed, i, families), f"CRASH exit {proc.exitcode}", "")
                    next_index = i + 1
                    break
            _kill(proc)
            parent.close()
    total = sum(sum(c.values()) for c in counts.values())
    return {
        "seed": seed,
        "inputs": total,
        "seconds": round(time.monotonic() - t_start, 1),
        "counts": {f: dict(c.most_common()) for f, c in sorted(counts.items())},
        "broken": broken,
        "median_seconds_per_input": float(np.median(durations)) if durations else None,
        "max_seconds_per_input": float(np.max(durations)) if durations else None,
        "peak_rss_mb_of_a_worker": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 1),
        "examples": examples,
    }


def _kill(proc) -> None:
    if proc.is_alive():
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            proc.kill()
    proc.join(10)


def print_summary(summary: dict) -> None:
    median, longest = summary["median_seconds_per_input"] or 0, summary["max_seconds_per_input"] or 0
    print(
        f"{summary['inputs']} inputs in {summary['seconds']:g} s (seed {summary['seed']}, median {median:.3f} s "
        f"per input, longest {longest:.2f} s; peak resident memory of a worker {summary['peak_rss_mb_of_a_worker']} "
        "MB)"
    )
    totals: collections.Counter = collections.Counter()
    for family, counts in summary["counts"].items():
        print(f"{family}: {sum(counts.values())}")
        for outcome, n in counts.items():
            print(f"  {n:6d}  {outcome}")
            totals[outcome] += n
    print("all families:")
    for outcome, n in totals.most_common():
        print(f"  {n:6d}  {outcome}")
    broken = summary["broken"]
    print(f"promises broken: {len(broken)}")
    for b in broken[:50]:
        print(f"\n[{b['index']}] {b['family']} {b['outcome']}: {b['detail'][:3000]}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--count", type=int, help="how many inputs (0 .. COUNT-1 of the seed)")
    p.add_argument("--seconds", type=float, help="fuzz this long instead (default 60 without --count)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument(
        "--families",
        default=",".join(FAMILIES),
        help="comma-separated subset of "
        + ", ".join(FAMILIES + NAMED_FAMILIES)
        + " (default: all but "
        + ", ".join(NAMED_FAMILIES)
        + ")",
    )
    p.add_argument("--only", type=int, help="run input ONLY of the seed in this process and show its traceback")
    p.add_argument("--json", help="write the summary here")
    p.add_argument("--no-mount", action="store_true", help="no full-file-system cases (they mount a tmpfs as root)")
    p.add_argument("--root", help="work directory (default: a temporary one in /dev/shm)")
    args = p.parse_args(argv)
    families = tuple(args.families.split(","))
    unknown = set(families) - set(FAMILIES + NAMED_FAMILIES)
    if unknown:
        p.error(f"unknown families {sorted(unknown)}")

    def stop(signum, frame):  # as Ctrl-C: the worker killed, the full file system unmounted, the work files removed
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    import demsplit.runtime.threads

    demsplit.runtime.threads.THREADS = 1  # one core: the fuzzer runs beside other work
    if args.only is not None:
        with tempfile.TemporaryDirectory(prefix="demsplit-fuzz-") as tmp:
            base = make_bases(Path(tmp), families)
            warm_up(base, Path(tmp) / "work")
            with full_file_system(Path(tmp), not args.no_mount and "output_path" in families) as full:
                case = build_case(base, Path(tmp) / "work", args.seed, args.only, families, full)
                print(f"[{args.only}] {case.family}: {case.what}\n  demsplit {' '.join(case.argv)}")
                outcome, detail = check_case(case)
                print(outcome, detail, sep="\n")
                return 0 if kept(outcome) else 1
    seconds = None if args.count is not None else 60.0 if args.seconds is None else args.seconds
    try:
        summary = fuzz(
            args.seed,
            args.count,
            seconds,
            families,
            None if args.root is None else Path(args.root),
            mount=not args.no_mount,
        )
    except KeyboardInterrupt:
        print("interrupted: no summary", file=sys.stderr)
        return 130
    print_summary(summary)
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1, default=str))
    return 1 if summary["broken"] else 0


if __name__ == "__main__":
    sys.exit(main())
