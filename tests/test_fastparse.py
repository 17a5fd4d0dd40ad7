"""Tests of the compiled parse of text dumps (demsplit.readers.fastparse) and of
its use by the reader (demsplit.readers.lammps_dump): bit-exact reals, the
fallback to the polars path, the same errors, threads."""

from __future__ import annotations

import gzip
import os
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import demsplit.readers.lammps_dump as ld
import numpy as np
import pytest
from demsplit.errors import InputFormatError, TruncatedFileError
from demsplit.readers import fastparse as fp
from demsplit.readers.lammps_dump import open_dump
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

REPO = Path(__file__).resolve().parent.parent
SAMPLES = REPO / "sample_dumps" / "liggghts"
FORMATS = ["%g", "%.6g", "%.10g", "%.15g", "%.16g", "%.17g", "%e", "repr"]


def bits(x: float) -> int:
    return struct.unpack("<q", struct.pack("<d", x))[0]


def fmt(x: float, f: str) -> str:
    return repr(x) if f == "repr" else f % x


def kernel_real(token: str) -> tuple[int, float | None, bool]:
    """parse_rows on a one-row text whose first column is ``token``, read as a real: (status, value
    written or None, listed as a slow token). Read twice, alone on its line (the last bytes of a block,
    read byte by byte) and followed by a long second column (read 8 bytes at a time); both must agree."""
    results = [_kernel_real(token, pad) for pad in ("", " " + "7" * 40)]
    assert results[0] == results[1] or (results[0][1] is not None and bits(results[0][1]) == bits(results[1][1])), (
        token,
        results,
    )
    return results[1]


def _kernel_real(token: str, pad: str) -> tuple[int, float | None, bool]:
    a = np.frombuffer((token + pad + "\n").encode(), dtype=np.uint8)
    ncols = 2 if pad else 1
    reals = np.full((1, 1), 12345.0)
    slow = np.empty((4, 4), dtype=np.int64)
    status, _, rows, n_slow = fp.parse_rows(
        a,
        0,
        a.size,
        ncols,
        False,
        np.array([1, 0][:ncols]),
        np.array([0, 0][:ncols]),
        reals,
        np.empty((0, 1), np.int64),
        0,
        1,
        slow,
    )
    assert rows == 1
    if n_slow:
        assert slow[0].tolist() == [0, 0, 0, len(token)]  # slot, row, the token's byte range
    written = status == fp.OK and not n_slow
    return status, (float(reals[0, 0]) if written else None), bool(n_slow)


# --------------------------------------------------------------------------- the kernel alone

doubles = (
    st.floats(allow_nan=False, allow_infinity=False)
    | st.floats(min_value=-1e-300, max_value=1e-300)
    | st.sampled_from(
        [
            0.0,
            -0.0,
            5e-324,
            2.2250738585072014e-308,
            1.7976931348623157e308,
            2.0**53,
            2.0**53 + 2,
            9007199254740993.0,
            1e22,
            1e23,
            1e-22,
            1e-23,
        ]
    )
)


@pytest.mark.slow
@settings(max_examples=400, deadline=None)
@given(x=doubles, f=st.sampled_from(FORMATS))
def test_kernel_real_is_pythons_float_or_not_converted(x, f):
    token = fmt(x, f)
    status, value, slow = kernel_real(token)
    assert status in (fp.OK, fp.FALLBACK)
    if value is not None:
        assert bits(value) == bits(float(token)), token
    else:  # outside the fast path: only for a literal with > 16 digits or |exponent| > 22
        assert slow and status == fp.OK
        mantissa, _, exp = token.lower().partition("e")
        digits = mantissa.lstrip("-+").replace(".", "").lstrip("0")
        frac = len(mantissa.partition(".")[2])
        assert len(digits) > 15 or abs(int(exp or 0) - frac) > 22 or int(digits) > 2**53, token


@settings(max_examples=300, deadline=None)
@given(
    m=st.integers(0, 2**53 + 64) | st.integers(0, 10**19),
    e=st.integers(-26, 26),
    point=st.integers(0, 20),
    neg=st.booleans(),
    e_char=st.sampled_from("eE"),
)
@pytest.mark.slow
def test_kernel_real_near_the_fast_path_bounds(m, e, point, neg, e_char):
    """Mantissas around 2**53 and exponents around +-22, with the decimal point
    anywhere: converted exactly as float() does, or listed as slow."""
    s = str(m)
    point = min(point, len(s))
    mantissa = s[: len(s) - point] + ("." + s[len(s) - point :] if point else "")
    token = ("-" if neg else "") + (mantissa if mantissa[0] != "." else "0" + mantissa) + f"{e_char}{e:+d}"
    status, value, slow = kernel_real(token)
    if value is None:
        assert slow
        assert m > 2**53 or abs(e - point) > 22
    else:
        assert bits(value) == bits(float(token)), token


def test_kernel_fast_path_covers_g_format():
    """Every %g token of moderate exponent takes the fast path (not merely 'is not wrong')."""
    rng = np.random.default_rng(1)
    x = rng.standard_normal(2000) * 10.0 ** rng.integers(-15, 15, 2000)
    for v in x.tolist() + [0.0, -0.0, 1.0, -1e-16]:
        token = "%g" % v
        _, value, _ = kernel_real(token)
        assert value is not None and bits(value) == bits(float(token)), token


@settings(max_examples=1500, deadline=None)
@given(
    token=st.text("0123456789.eE+-", min_size=1, max_size=30)
    | doubles.map(lambda x: "%.17g" % x)
    | st.sampled_from(
        [
            "12345678",
            "1234567.",
            "0.1234567890123456789",
            "00000000012345",
            "9007199254740993",
            "0.000000000000000000001234",
            "123456789012345678901234",
            "1." + "0" * 18,
        ]
    )
)
@pytest.mark.slow
def test_word_wise_real_equals_byte_wise(token):
    """The word-at-a-time reader of a real returns what the byte-by-byte one does, bit for bit (where the
    bytes are not a decimal literal, only that)."""
    a = np.frombuffer((token + " " + "x" * 30).encode(), dtype=np.uint8)
    base = a.ctypes.data  # the address the kernels read from (a stays alive meanwhile)
    words, byte = fp._real(base, 0, a.size), fp._real_bytewise(base, 0, a.size)
    assert words[0] == byte[0], token
    if byte[0] != 2:  # _NOT_DECIMAL: the offset says nothing
        assert words[2] == byte[2] and bits(words[1]) == bits(byte[1]), token


@pytest.mark.parametrize("token", ["nan", "-nan", "inf", "-inf", "abc", "1.5x", "1e", "-", ".", "1e+", "0x10", "1_0"])
def test_kernel_leaves_non_decimals_to_the_fallback(token):
    status, value, slow = kernel_real(token)
    assert status == fp.FALLBACK and value is None and not slow


@settings(max_examples=200, deadline=None)
@given(v=st.integers(-(2**63), 2**63 - 1))
@pytest.mark.parametrize("pad", ["", " " + "7" * 40])
def test_kernel_integers_exact_or_fallback(v, pad):
    a = np.frombuffer(f"{v}{pad}\n".encode(), dtype=np.uint8)
    ints = np.zeros((1, 1), np.int64)
    ncols = 2 if pad else 1
    status, *_ = fp.parse_rows(
        a,
        0,
        a.size,
        ncols,
        False,
        np.array([2, 0][:ncols]),
        np.array([0, 0][:ncols]),
        np.empty((0, 1)),
        ints,
        0,
        1,
        np.empty((1, 4), np.int64),
    )
    if len(str(abs(v))) <= 18:
        assert status == fp.OK and int(ints[0, 0]) == v
    else:
        assert status == fp.FALLBACK


@pytest.mark.parametrize(
    "text, trailing, row",
    [
        ("1 2 3\n4 5 6\n", False, None),
        ("1 2 3 \n4 5 6 \n", True, None),
        ("1 2 3\n4 5\n", False, 1),  # short row
        ("1 2 3\n4 5 6 7\n", False, 1),  # long row
        ("1 2 3\n4  5 6\n", False, 1),  # empty field (double space)
        ("1 2 3\n 4 5 6\n", False, 1),  # leading space
        ("1 2 3\n4\t5 6\n", False, 1),  # tab
        ("1 2 3\r\n4 5 6\n", False, 0),  # CR
        ("1 2 3 \n4 5 6\n", True, 1),  # trailing space missing
        ("1 2 3\n4 5 6 \n", False, 1),  # unexpected trailing space
        ("1 2 3\n\n", False, 1),  # empty line
        ("1 2 3\n4 5 6", False, 1),  # no final newline
    ],
)
def test_kernel_shape_check(text, trailing, row):
    a = np.frombuffer(text.encode(), dtype=np.uint8)
    reals = np.zeros((3, 2))
    status, where, _, _ = fp.parse_rows(
        a,
        0,
        a.size,
        3,
        trailing,
        np.array([1, 0, 1]),
        np.array([0, 0, 1]),
        reals,
        np.empty((0, 2), np.int64),
        0,
        2,
        np.empty((1, 4), np.int64),
    )
    if row is None:
        assert status == fp.OK and reals[:2].tolist() == [[1, 4], [3, 6]]
    else:
        assert (status, where) == (fp.SHAPE, row)


def reference_shape(text: bytes, ncols: int, trailing: bool, max_rows: int) -> tuple[bool, int]:
    """(well formed, rows) or (False, first bad row) by the rule parse_rows documents, in plain Python."""
    rows = text.split(b"\n")
    for r, row in enumerate(rows[:-1]):
        if r >= max_rows:
            return False, r
        if trailing:
            if not row.endswith(b" "):
                return False, r
            row = row[:-1]
        fields = row.split(b" ")
        if len(fields) != ncols or any(not f or min(f) <= 32 for f in fields):
            return False, r
    if rows[-1]:  # no final newline
        return False, len(rows) - 1
    return True, len(rows) - 1


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(data=st.data(), ncols=st.integers(1, 40), trailing=st.booleans())
def test_kernel_shape_check_equals_the_rule(data, ncols, trailing):
    """Rows of digit tokens with now and then a damaged separator (two spaces, a tab, a CR, a newline,
    an empty field, a missing or extra field), any columns requested: parse_rows finds the first
    malformed row the plain rule finds, whether it steps over columns several at a time or not (runs of
    unread columns longer than 64 bytes are stepped over 64 bytes at a time, the rest 8 at a time)."""
    token = st.text("0123456789", min_size=1, max_size=12)
    sep = st.sampled_from([b" "] * 30 + [b"  ", b"\t", b"\r", b"\n", b""])
    lines = []
    for _ in range(data.draw(st.integers(1, 6))):
        n = ncols + data.draw(st.sampled_from([0] * 8 + [-1, 1]))
        fields = [data.draw(token).encode() for _ in range(max(n, 0))]
        line = b""
        for k, f in enumerate(fields):
            line += f + (data.draw(sep) if k < len(fields) - 1 else b"")
        lines.append(line + (b" " if trailing else b""))
    text = b"\n".join(lines) + data.draw(st.sampled_from([b"\n"] * 5 + [b""]))
    kind = np.array([data.draw(st.sampled_from([0, 0, 1, 2])) for _ in range(ncols)])
    slot = np.zeros(ncols, dtype=np.int64)
    a = np.frombuffer(text, dtype=np.uint8)
    rows = len(lines)
    status, where, n, _ = fp.parse_rows(
        a,
        0,
        a.size,
        ncols,
        trailing,
        kind,
        slot,
        np.zeros((1, rows)),
        np.zeros((1, rows), np.int64),
        0,
        rows,
        np.empty((4, 4), np.int64),
    )
    ok, expected = reference_shape(text, ncols, trailing, rows)
    if ok:
        assert status in (fp.OK, fp.FALLBACK) and n == expected, text
    else:
        assert (status, where) == (fp.SHAPE, expected), text


@pytest.mark.parametrize("damage", [b"  ", b"\t", b"\n", b" \x00", b"\x1f"])
def test_long_runs_of_unread_columns_are_checked_everywhere(damage):
    """A row of 40 unread columns (about 300 bytes, stepped over 64 bytes at a time) with one separator
    damaged, or one value empty, at each of its places in turn: refused at that row, wherever the damage
    falls in a step."""
    fields = [str(10 ** (k % 9) + k).encode() for k in range(40)]
    good = b" ".join(fields) + b"\n"
    kind, slot = np.zeros(40, np.int64), np.zeros(40, np.int64)
    kind[0] = kind[-1] = slot[-1] = 1  # the first and last read: the run between starts after a space
    for k in range(39):
        bad = b" ".join(fields[: k + 1]) + damage + b" ".join(fields[k + 1 :]) + b"\n"
        if damage == b"  ":  # an empty field in place of a value: the row still has 40 fields
            bad = b" ".join(fields[: k + 1]) + damage + b" ".join(fields[k + 2 :]) + b"\n"
        a = np.frombuffer(good + bad + good, dtype=np.uint8)
        status, where, _, _ = fp.parse_rows(
            a,
            0,
            a.size,
            40,
            False,
            kind,
            slot,
            np.zeros((2, 3)),
            np.zeros((1, 3), np.int64),
            0,
            3,
            np.empty((1, 4), np.int64),
        )
        assert (status, where) == (fp.SHAPE, 1), (k, damage)
    a = np.frombuffer(good * 3, dtype=np.uint8)
    reals = np.zeros((2, 3))
    status, _, rows, _ = fp.parse_rows(
        a, 0, a.size, 40, False, kind, slot, reals, np.zeros((1, 3), np.int64), 0, 3, np.empty((1, 4), np.int64)
    )
    assert (status, rows, reals.tolist()) == (fp.OK, 3, [[float(fields[0])] * 3, [float(fields[-1])] * 3])


def test_fields_longer_than_a_step():
    """A field of 70 bytes (more than one 64-byte step to its end), read and not read: its end is found, and
    a read one is listed as outside the fast path with its exact byte range."""
    long = b"1" * 70
    text = b"7 " + long + b" 8\n" + b"9 " + long + b" 10\n"
    a = np.frombuffer(text, dtype=np.uint8)
    for kind in ([1, 0, 1], [1, 1, 1]):
        reals, slow = np.zeros((3, 2)), np.zeros((4, 4), np.int64)
        status, _, rows, n_slow = fp.parse_rows(
            a, 0, a.size, 3, False, np.array(kind), np.array([0, 1, 2]), reals, np.zeros((3, 2), np.int64), 0, 2, slow
        )
        assert (status, rows) == (fp.OK, 2)
        assert reals[0].tolist() == [7, 9] and reals[2].tolist() == [8, 10]
        assert slow[:n_slow].tolist() == ([[1, 0, 2, 72], [1, 1, 77, 147]] if kind[1] else [])


def test_bytes_below_flags_each_byte():
    """demsplit.runtime.jit.bytes_below against numpy, on every byte value and at unaligned offsets."""
    from demsplit.runtime.jit import address, bytes_below, kernel

    @kernel
    def below(a, i, bound):
        return bytes_below(address(a), i, bound)

    a = np.concatenate([np.arange(256, dtype=np.uint8), np.random.default_rng(5).integers(0, 256, 300, np.uint8)])
    for i in (0, 1, 63, 200, a.size - 64):
        for bound in (0, 1, 32, 33, 128, 255):
            bits = (a[i : i + 64] < bound).astype(np.uint64) << np.arange(64, dtype=np.uint64)
            assert int(below(a, i, bound)) == int(np.bitwise_or.reduce(bits)), (i, bound)


@pytest.mark.slow
def test_scan_chunk_finds_markers_and_newlines():
    text = b"x\nITEM: TIMESTEP\n1\n" + b"1 2\n" * 50 + b"ITEM: TIMESTEP\n2\nITEM: TIMESTE" + b"I\n" * 30
    a = np.frombuffer(text, dtype=np.uint8)
    pos, nl = np.empty(a.size, np.int64), np.empty(a.size, np.int64)
    for limit in (a.size, a.size - 40, 5, 100):
        found, newlines = fp.scan_chunk(a, limit, pos, nl)
        expect = [p for p in (2, text.index(b"ITEM: TIMESTEP\n2")) if p < limit]
        assert pos[:found].tolist() == expect
        assert nl[:found].tolist() == [text[:p].count(b"\n") for p in expect]
        assert newlines == text[:limit].count(b"\n")
    for start, end in ((0, a.size), (3, a.size - 1), (70, 140), (64, 128), (5, 6), (9, 9)):
        assert fp.count_newlines(a, start, end) == text[start:end].count(b"\n")


def index_of(path: Path) -> tuple:
    return ld._scan(open_dump(path)._stream())


@pytest.mark.parametrize("compressed", [False, True], ids=["mapped", "gzip-buffer"])
@pytest.mark.parametrize("chunk", [1, 7, 333, 4096])
def test_index_scan_is_the_same_for_any_window(tmp_path, monkeypatch, compressed, chunk):
    """Windows of any size (headers cut between windows, a window smaller than a
    header, markers right at a limit) give the index of one window holding it all,
    for the memory-mapped plain file and for the buffered compressed stream."""
    frames = [
        local_dump([f"{k} {k * 0.5:g}" for k in range(n)], 2, step=s) for s, n in ((0, 3), (10, 0), (20, 11), (30, 1))
    ]
    text = ("".join(frames) + "ITEM: TIMESTEP\n40\nITEM: NUMB").encode()  # a cut header at the end
    path = tmp_path / ("d.txt.gz" if compressed else "d.txt")
    path.write_bytes(gzip.compress(text) if compressed else text)
    markers = [k for k in range(len(text)) if text.startswith(b"ITEM: TIMESTEP", k)]
    whole = index_of(path)
    assert whole[0] == markers and whole[3:6] == (len(text), text.count(b"\n"), text[-1:])
    assert whole[2] == [text[:m].count(b"\n") for m in markers]
    assert whole[1] == [text[m:n] for m, n in zip(markers, markers[1:] + [len(text)])]
    monkeypatch.setattr(ld, "CHUNK", chunk)
    monkeypatch.setattr(ld, "CHECKPOINT", max(1, chunk // 3))
    monkeypatch.setattr(ld, "HEADER_MAX", 200)  # holds each header (at most 155 bytes here)
    windowed = index_of(path)
    assert windowed[:6] == whole[:6]
    checkpoints = windowed[6].tolist()  # (offset, newlines before it), at most CHECKPOINT bytes apart
    offsets = [o for o, _ in checkpoints] + [len(text)]
    assert offsets[0] == 0 and all(0 < b - a <= max(1, chunk // 3) for a, b in zip(offsets, offsets[1:]))
    assert all(n == text[:o].count(b"\n") for o, n in checkpoints)


# --------------------------------------------------------------------------- the reader


def local_dump(rows: list[str], ncols: int, step: int = 1) -> str:
    names = " ".join(f"c{k}" for k in range(1, ncols + 1))
    return (
        f"ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ENTRIES\n{len(rows)}\nITEM: BOX BOUNDS ff ff ff\n"
        f"0 1\n0 1\n0 1\nITEM: ENTRIES {names} \n" + "".join(r + " \n" for r in rows)
    )


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(xs=st.lists(doubles, min_size=1, max_size=60), f=st.sampled_from(FORMATS), first=st.integers(0, 10**6))
@pytest.mark.slow
def test_reader_equals_pythons_float_per_token(xs, f, first):
    """Fast path + float() for slow tokens + polars fallback: always float(token)."""
    tokens = [fmt(x, f) for x in xs]
    rows = [f"{first + k} {t} {t}" for k, t in enumerate(tokens)]
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "d.txt"
        p.write_text(local_dump(rows, 3))
        if not all(np.isfinite([float(t) for t in tokens])):  # printed rounded up to inf: refused
            with pytest.raises(InputFormatError, match="finite"):
                open_dump(p).frame(0)
            return
        frame = open_dump(p).frame(0)
    for name in ("c2", "c3"):
        got = frame.columns[name]
        if got.dtype == np.int64:  # every token an integer literal ('0', '%g' of 12345)
            assert got.tolist() == [int(t) for t in tokens]
        else:
            assert [bits(v) for v in got.tolist()] == [bits(float(t)) for t in tokens]
    assert frame.columns["c1"].tolist() == [first + k for k in range(len(xs))]


def force_polars(monkeypatch):
    """Make every block (compressed dumps) and slice (plain files) go through the polars path
    (after the kernel's shape check)."""
    fast, fast_slice = ld._parse_fast, ld._parse_slice

    def slow_path(*args):
        n, _ = fast(*args)
        return n, False

    def slow_slice(*args):
        status, *rest = fast_slice(*args)
        return (ld.SLICE_FALLBACK if status == ld.SLICE_OK else status, *rest)

    monkeypatch.setattr(ld, "_parse_fast", slow_path)
    monkeypatch.setattr(ld, "_parse_slice", slow_slice)


def read_all(path: Path, columns=None) -> tuple[list, object]:
    d = open_dump(path)
    return [(f.step, {k: v.copy() for k, v in f.columns.items()}, f.digits) for f in d.frames(columns)], d


def assert_same_frames(a: list, b: list) -> None:
    assert len(a) == len(b)
    for (sa, ca, da), (sb, cb, db) in zip(a, b):
        assert sa == sb and da == db and list(ca) == list(cb)
        for k in ca:
            assert ca[k].dtype == cb[k].dtype, k
            assert np.array_equal(ca[k].view(np.int64), cb[k].view(np.int64)), k  # bit for bit


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("gen")
    subprocess.run(
        [
            sys.executable,
            str(REPO / "benchmarks" / "generate.py"),
            str(d),
            "--particles",
            "2000",
            "--contacts",
            "4000",
            "--frames",
            "2",
        ],
        check=True,
        capture_output=True,
    )
    return d


def sample_files() -> list[Path]:
    return sorted(p for p in SAMPLES.glob("*/*.txt*"))


@pytest.mark.slow
@pytest.mark.parametrize("path", sample_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_fast_path_equals_polars_path_on_samples(path, monkeypatch):
    fast, d = read_all(path)
    if ".gz" not in path.suffixes:  # %g dumps (the .gz are full precision): every block compiled
        assert d.fast_blocks > 0 and d.fallback_blocks == 0
    force_polars(monkeypatch)
    slow, d2 = read_all(path)
    assert d2.fallback_blocks == d2.fast_blocks + d2.fallback_blocks > 0
    assert_same_frames(fast, slow)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["atoms.txt", "pairs.txt"])
def test_fast_path_equals_polars_path_on_generated_run(generated, name, monkeypatch):
    fast, d = read_all(generated / name)
    assert d.fast_blocks >= 2 and d.fallback_blocks == 0  # a slice or more per frame
    force_polars(monkeypatch)
    slow, _ = read_all(generated / name)
    assert_same_frames(fast, slow)


def g17_dump(n: int) -> str:
    rng = np.random.default_rng(3)
    x = rng.standard_normal((n, 3))
    return local_dump([f"{k + 1} " + " ".join("%.17g" % v for v in row) for k, row in enumerate(x)], 4)


def test_full_precision_dump_falls_back_and_reads_exactly(tmp_path):
    n = 3000  # 9000 tokens of 17 digits: more than a slice lists, so the block falls back to polars
    p = tmp_path / "g17.txt"
    text = g17_dump(n)
    p.write_text(text)
    d = open_dump(p)
    f = d.frame(0)
    assert d.fallback_blocks == 1 and d.fast_blocks == 0
    rows = [ln.split() for ln in text.splitlines()[9:]]
    for c in (1, 2, 3):
        assert [bits(v) for v in f.columns[f"c{c + 1}"].tolist()] == [bits(float(r[c])) for r in rows]


def test_a_few_slow_tokens_are_converted_by_float(tmp_path):
    rows = [f"{k} {0.001 * k:g} 1e-30" if k % 100 == 7 else f"{k} {0.001 * k:g} 2.5" for k in range(1000)]
    p = tmp_path / "d.txt"
    p.write_text(local_dump(rows, 3))
    d = open_dump(p)
    f = d.frame(0)
    assert d.fast_blocks == 1 and d.fallback_blocks == 0
    assert f.columns["c3"].tolist() == [1e-30 if k % 100 == 7 else 2.5 for k in range(1000)]


def test_nan_falls_back_and_is_reported(tmp_path):
    rows = [f"{k} 0.5 0.25" for k in range(50)]
    rows[31] = "31 0.5 nan"
    text = local_dump(rows, 3)
    d = open_dump(ld_write(tmp_path, text))
    with pytest.raises(InputFormatError, match="expected a finite number") as err:
        d.frame(0)
    assert d.fallback_blocks == 1
    assert err.value.line == 10 + 31


def ld_write(tmp_path: Path, text: str, name: str = "d.txt") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


# --------------------------------------------------------------------------- errors, blocks, threads


@pytest.mark.parametrize(
    "bad, expect",
    [
        ("7 0.5", "row 8 has 2 values, expected 3"),
        ("7 0.5 0.25 1", "row 8 has 4 values, expected 3"),
        ("7 0.5  0.25", "row 8 has two spaces in a row before value 3"),  # an empty field
        ("7 0.5 abc", "column 3 ('c3') of row 8 is 'abc'; expected a number"),
    ],
)
@pytest.mark.parametrize("block", [None, 64])
def test_errors_name_the_line(tmp_path, monkeypatch, bad, expect, block):
    if block:  # the bad row in a later block (slice) than the first
        monkeypatch.setattr(ld, "BLOCK", block)
        monkeypatch.setattr(ld, "CHECKPOINT", block)
    rows = [f"{k} 0.5 0.25" for k in range(20)]
    rows[7] = bad
    text = local_dump(rows, 3)
    with pytest.raises(InputFormatError) as err:
        open_dump(ld_write(tmp_path, text)).frame(0)
    assert not isinstance(err.value, TruncatedFileError)
    assert expect in str(err.value) and err.value.line == 10 + 7 and err.value.step == 1


def test_missing_final_newline(tmp_path):
    text = local_dump([f"{k} 0.5 0.25" for k in range(5)], 3)[:-1]
    with pytest.raises(TruncatedFileError, match="middle of a row") as err:
        open_dump(ld_write(tmp_path, text)).frame(0)
    assert err.value.line == 10 + 4


def test_integer_column_turning_real_in_a_later_block(tmp_path, monkeypatch):
    monkeypatch.setattr(ld, "DIGITS_SAMPLE", 64)
    monkeypatch.setattr(ld, "BLOCK", 100)
    monkeypatch.setattr(ld, "CHECKPOINT", 100)
    rows = [f"{k} {k * 0.5:g}" for k in range(40)]
    rows[20] = "2.5e+06 10"
    f = open_dump(ld_write(tmp_path, local_dump(rows, 2))).frame(0)
    assert f.columns["c1"].dtype == np.float64
    assert f.columns["c1"].tolist() == [2.5e6 if k == 20 else float(k) for k in range(40)]
    assert f.columns["c2"].tolist() == [10.0 if k == 20 else k * 0.5 for k in range(40)]


@pytest.mark.slow
@pytest.mark.parametrize("block", [60, 1000, 1 << 24])  # rows longer than a block, several blocks, one
def test_threaded_parse_equals_serial(generated, monkeypatch, block):
    path = generated / "pairs.txt"
    monkeypatch.setattr(ld, "BLOCK", block)
    monkeypatch.setattr(ld, "CHECKPOINT", min(block, 1 << 20))
    monkeypatch.setattr(ld, "_SLICE_MIN", 1)
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", 1)  # slices per block
    serial, _ = read_all(path)
    monkeypatch.setattr(threads, "THREADS", 5)  # slices per block
    threaded, _ = read_all(path)
    assert_same_frames(serial, threaded)


@pytest.mark.slow
@pytest.mark.parametrize("margin", [200, 1 << 16])
def test_slices_equal_blocks(generated, monkeypatch, margin):
    """A plain file read in slices cut at the index's checkpoints (each read and parsed by one
    thread) equals the same file read as a compressed stream, block by block; rows longer than a
    slice's margin (ROW_MAX bytes past its end) make the frame take the block path."""
    plain = generated / "pairs.txt"
    packed = generated / "pairs.txt.gz"
    packed.write_bytes(gzip.compress(plain.read_bytes()))
    monkeypatch.setattr(ld, "CHECKPOINT", 64)
    monkeypatch.setattr(ld, "BLOCK", 64)
    monkeypatch.setattr(ld, "ROW_MAX", margin)
    from demsplit.runtime import threads

    monkeypatch.setattr(threads, "THREADS", 3)
    block_reads = []
    by_blocks = ld.TextDump._parse_blocks
    monkeypatch.setattr(
        ld.TextDump, "_parse_blocks", lambda self, e, *a: block_reads.append(self.path) or by_blocks(self, e, *a)
    )
    sliced, _ = read_all(plain)
    blocks, _ = read_all(packed)
    assert_same_frames(sliced, blocks)
    row = len(plain.read_text().splitlines()[-1]) + 1
    assert block_reads.count(str(plain)) == (0 if margin > row else 2)  # each frame, when rows do not fit
    assert block_reads.count(str(packed)) == 2


def test_compressed_dump_uses_the_fast_path(tmp_path):
    text = local_dump([f"{k} {k * 0.25:g} {k * 1e-3:g}" for k in range(300)], 3)
    p = tmp_path / "d.txt.gz"
    with gzip.open(p, "wt") as f:
        f.write(text)
    d = open_dump(p)
    f = d.frame(0)
    assert d.fast_blocks == 1 and d.fallback_blocks == 0
    assert f.columns["c3"].tolist() == [float(f"{k * 1e-3:g}") for k in range(300)]


@pytest.mark.slow
def test_kernels_load_from_the_cache():
    """A fresh process loads the compiled kernels instead of compiling them
    (the first one may have had to compile them)."""
    code = (
        "import numpy as np\n"
        "from demsplit.readers import fastparse as fp\n"
        "a = np.frombuffer(b'1 2.5\\n', dtype=np.uint8)\n"
        "fp.parse_rows(a, 0, a.size, 2, False, np.array([2, 1]), np.array([0, 0]), np.zeros((1, 1)),\n"
        "              np.zeros((1, 1), np.int64), 0, 1, np.empty((1, 4), np.int64))\n"
        "fp.scan_chunk(a, a.size, np.empty(2, np.int64), np.empty(2, np.int64))\n"
        "fp.count_newlines(a, 0, a.size); fp.next_newline(a, 0)\n"
        "k = (fp.parse_rows, fp.scan_chunk, fp.count_newlines, fp.next_newline)\n"
        "print(sum(sum(f.stats.cache_misses.values()) for f in k), "
        "sum(sum(f.stats.cache_hits.values()) for f in k))\n"
    )
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, env=env)
    misses, hits = map(int, out.stdout.split())
    assert misses == 0 and hits == 4


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_forked_process_parses_with_its_own_threads(monkeypatch):
    """The parse threads of a process that forks are not in the child: it starts its own."""
    monkeypatch.setattr(ld, "_SLICE_MIN", 1)
    path = SAMPLES / "packing" / "pairs.txt"
    parent = open_dump(path).frame(0).columns["c_cpgl[38]"].copy()  # the parent's pool now exists
    pid = os.fork()
    if pid == 0:  # child: exit 0 when it reads the same, within 20 s
        import signal

        signal.alarm(20)
        os._exit(0 if np.array_equal(open_dump(path).frame(0).columns["c_cpgl[38]"], parent) else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
