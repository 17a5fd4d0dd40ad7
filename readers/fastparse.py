"""Compiled kernels of the text-dump reader (:mod:`demsplit.readers.lammps_dump`).

Two jobs, each one pass over bytes in memory, compiled by numba
(:func:`demsplit.runtime.jit.kernel`: cached, GIL released, so threads run them on
disjoint slices):

``scan_chunk``
    the index scan: count the newlines of a chunk and find the
    ``ITEM: TIMESTEP`` markers in it, with the newlines before each.
``parse_rows``
    the parse of whole rows: check each row's shape (``ncols`` fields, single
    spaces, optional trailing space, newline) and convert the requested
    columns, integers exactly to int64, reals to the float64 nearest the
    decimal (bit for bit Python's ``float(token)``).

Reals are converted by Clinger's fast path: a token
``[+-]digits[.digits][(e|E)[+-]digits]`` has the value m * 10**e with an
integer mantissa m (its significant digits) and a decimal exponent e. When
m <= 2**53 and |e| <= 22, both m and 10**|e| are exact doubles, so
``m * 10.0**e`` (e >= 0) or ``m / 10.0**-e`` (e < 0) is one IEEE operation on
exact operands, hence correctly rounded: the nearest double to the decimal.
LAMMPS's default ``%g`` (6 significant digits) takes it for magnitudes from
about 1e-17 to 1e22 (e is the printed exponent minus the digits after the
point: ``8.4781e-19`` is 84781e-23, outside). A decimal literal
outside the path (more digits, a larger exponent) is listed with its byte
range, for the caller to convert with Python's ``float`` (also correctly
rounded); any other token (``nan``, ``inf``, a letter, a real in an integer
column) is not converted: the kernel reports the row, and the caller parses
that block with its general (slower) parser, which also produces the located
error messages. So the fast path never decides what is an error, and never
produces a different number.

Speed. ``parse_rows`` steps over a run of two or more columns it does not read
with :func:`_skip_fields`, which flags and counts the separators of 64 bytes at a
time (:func:`demsplit.runtime.jit.bytes_below`, one vector compare; one branch per 64
bytes, not one per field), and over a single one with :func:`_field_end`. The
steps of one token (:func:`_real`, :func:`_integer`, :func:`_field_end`, ...)
are compiled into ``parse_rows`` (:func:`demsplit.runtime.jit.inlined`) rather than
called, and read the text through its address (:func:`demsplit.runtime.jit.byte_at`,
:func:`demsplit.runtime.jit.word_at`): a call's arguments, tuple result and, for an
array argument, reference counting cost as much as the step itself. A read
field's end is found (64 bytes a step) before the field is converted, so that
the next field's start does not wait for the conversion and the conversions of
a row overlap in the processor (docs/performance.md, "Standing decisions").
"""

from __future__ import annotations

import numpy as np
from demsplit.runtime.jit import address, byte_at, bytes_below, inlined, kernel, popcount, trailing_zeros, word_at

__all__ = ["scan_chunk", "count_newlines", "next_newline", "parse_rows", "OK", "SHAPE", "FALLBACK"]

MARKER = b"ITEM: TIMESTEP"
_MARKER = np.frombuffer(MARKER, dtype=np.uint8).copy()

# statuses of parse_rows
OK = 0  # every row well formed, every requested token converted
SHAPE = 1  # a row is not ncols single-space-separated fields (+ trailing space) and a newline
FALLBACK = 2  # rows well formed, but a requested token is outside the fast path: not all converted

_FAST, _SLOW, _NOT_DECIMAL = 0, 1, 2  # what _real found

_POW10 = np.array([10.0**k for k in range(23)])  # 1e0 .. 1e22, each an exact double
_MAX_EXACT = 1 << 53  # largest mantissa that is an exact double
_SEP = 32  # bytes <= 32 separate fields (LAMMPS writes ' ' and '\n')
_BLOCK = 64  # bytes per step of a mask (jit.bytes_below: one bit each)

# Word-at-a-time constants (8 bytes in a uint64, the first byte of the text the lowest)
_U = np.uint64
_EACH_21, _EACH_30, _EACH_06 = _U(0x2121212121212121), _U(0x3030303030303030), _U(0x0606060606060606)
_EACH_0F, _EACH_F0 = _U(0x0F0F0F0F0F0F0F0F), _U(0xF0F0F0F0F0F0F0F0)
_EACH_7F, _EACH_80 = _U(0x7F7F7F7F7F7F7F7F), _U(0x8080808080808080)
_EACH_5F, _EACH_60 = _U(0x5F5F5F5F5F5F5F5F), _U(0x6060606060606060)
_POW10_INT = np.array([10**k for k in range(20)], dtype=np.uint64)  # 10**0 .. 10**19, exact
_MAX_EXACT_U = _U(1 << 53)
_WORD_TOKEN = 24  # a real is read word-wise when this many bytes follow its start (else byte by byte)


@kernel
def count_newlines(a: np.ndarray, start: int, end: int) -> int:
    """Number of ``\\n`` bytes in ``a[start:end]``, 64 bytes a step (:func:`_bytes_equal`)."""
    base = address(a)
    n = 0
    p = start
    while p + _BLOCK <= end:
        n += np.int64(popcount(_bytes_equal(base, p, 10)))
        p += _BLOCK
    while p < end:
        n += a[p] == 10
        p += 1
    return n


@kernel
def scan_chunk(a: np.ndarray, limit: int, pos_out: np.ndarray, nl_out: np.ndarray) -> tuple[int, int]:
    """Newlines and ``ITEM: TIMESTEP`` markers of ``a[:limit]``.

    A marker is found when it starts before ``limit`` (it may extend past it,
    into the rest of ``a``). Its offset goes to ``pos_out[k]`` and the number
    of newlines before it (from ``a[0]``) to ``nl_out[k]``; both must hold one
    slot per ``len(MARKER)`` bytes of ``limit``. Returns (markers found,
    newlines in ``a[:limit]``). Counted in 64-byte steps
    (:func:`_bytes_equal`: a mask of the newlines and one of the ``I``, a letter
    no number contains); a step holding an ``I`` is then searched byte by byte.
    """
    base = address(a)
    m = _MARKER.size
    newlines = 0
    found = 0
    stop = limit - limit % _BLOCK
    for b in range(0, stop, _BLOCK):
        nl = np.int64(popcount(_bytes_equal(base, b, 10)))
        if _bytes_equal(base, b, 73) != 0:
            before = newlines
            for j in range(b, b + _BLOCK):
                if a[j] == 73 and _marker_at(a, j, m):
                    pos_out[found] = j
                    nl_out[found] = before
                    found += 1
                before += a[j] == 10
        newlines += nl
    for j in range(stop, limit):
        if a[j] == 73 and _marker_at(a, j, m):
            pos_out[found] = j
            nl_out[found] = newlines
            found += 1
        newlines += a[j] == 10
    return found, newlines


@inlined
def _bytes_equal(base: int, p: int, byte: int) -> np.uint64:
    """Bit j set where the byte at offset ``p + j`` (j < 64) is ``byte`` (0-254): the bytes below
    ``byte + 1`` but not below ``byte`` (two vector compares, :func:`demsplit.runtime.jit.bytes_below`)."""
    return bytes_below(base, p, byte + 1) ^ bytes_below(base, p, byte)


@kernel
def _marker_at(a: np.ndarray, j: int, m: int) -> bool:
    if j + m > a.size:
        return False
    for k in range(m):
        if a[j + k] != _MARKER[k]:
            return False
    return True


@inlined
def _digit_run(x: np.uint64) -> int:
    """How many of the word's bytes, from its first, are ASCII digits (0-8). A byte b is a digit when
    its high nibble is 3 and that of b + 6 too; a carry out of a byte (b >= 0xFA, not a digit) only
    disturbs the bytes after it."""
    m = ((x & _EACH_F0) ^ _EACH_30) | (((x + _EACH_06) & _EACH_F0) ^ _EACH_30)  # 0 for a digit byte
    nonzero = (((m & _EACH_7F) + _EACH_7F) | m) & _EACH_80  # exact: no carry between bytes
    if nonzero == 0:
        return 8
    return np.int64(trailing_zeros(nonzero) >> _U(3))


@inlined
def _digits_value(x: np.uint64, n: int) -> np.uint64:
    """Value of the first ``n`` (1-8) bytes of the word, ASCII digits, the first the most significant:
    the digits are moved to the top of the word (the bytes below read as leading zeros) and combined
    pairwise in three multiplications."""
    v = (x - _EACH_30) << _U(8 * (8 - n))
    v = ((v & _EACH_0F) * _U(2561)) >> _U(8)  # pairs of digits
    v = ((v & _U(0x00FF00FF00FF00FF)) * _U(6553601)) >> _U(16)  # groups of four
    return ((v & _U(0x0000FFFF0000FFFF)) * _U(42949672960001)) >> _U(32)  # all eight


@inlined
def _real(base: int, p: int, end: int) -> tuple[int, float, int]:
    """The decimal literal ``[+-]digits[.digits][(e|E)[+-]digits]`` at offset ``p``, as
    :func:`_real_bytewise` returns it, reading the digits 8 bytes at a time: the mantissa m (every
    digit; at most 19, which fit a uint64) is exact, and m has more than 18 significant digits
    exactly when m >= 10**18 > 2**53, so the fast-path test is the same. A literal with 8 or more
    integer digits, more than 19 digits or fewer than ``_WORD_TOKEN`` bytes before ``end`` is read
    by :func:`_real_bytewise`."""
    start = p
    sign = byte_at(base, p) if p < end else 0
    neg = sign == 45
    p += (sign == 45) | (sign == 43)  # no branch: a sign is as likely as none
    if p + _WORD_TOKEN > end:
        return _real_bytewise(base, start, end)
    x = word_at(base, p)
    n = _digit_run(x)
    if n == 8:
        return _real_bytewise(base, start, end)
    m = _digits_value(x, n) if n > 0 else _U(0)
    p += n
    total = n
    e10 = 0
    if byte_at(base, p) == 46:
        p += 1
        while True:
            x = word_at(base, p)
            k = _digit_run(x)
            if k > 0:
                if total + k > 19:
                    return _real_bytewise(base, start, end)
                m = m * _POW10_INT[k] + _digits_value(x, k)
                total += k
                e10 -= k
                p += k
            if k < 8:
                break
            if p + 8 > end:
                return _real_bytewise(base, start, end)
    if total == 0:
        return _NOT_DECIMAL, 0.0, p
    if p < end and (byte_at(base, p) | 32) == 101:  # e or E
        p, ok, ex = _exponent(base, p + 1, end)
        if not ok:
            return _NOT_DECIMAL, 0.0, p
        e10 += ex
    if m == 0:
        return _FAST, (-0.0 if neg else 0.0), p
    if m > _MAX_EXACT_U or e10 > 22 or e10 < -22:
        return _SLOW, 0.0, p
    v = float(m) * _POW10[e10] if e10 >= 0 else float(m) / _POW10[-e10]
    return _FAST, (-v if neg else v), p


@inlined
def _exponent(base: int, p: int, end: int) -> tuple[int, bool, int]:
    """The exponent ``[+-]digits`` after an ``e``/``E``, at offset ``p``: (offset after it, any digit,
    value), the value saturating beyond 100000 (past +-22 only a zero mantissa is fast anyway)."""
    sign = byte_at(base, p) if p < end else 0
    neg = sign == 45
    p += (sign == 45) | (sign == 43)  # no branch: a sign is as likely as none
    ex = 0
    digits = 0
    while p < end and 48 <= byte_at(base, p) <= 57:
        if ex < 100000:
            ex = ex * 10 + (byte_at(base, p) - 48)
        digits += 1
        p += 1
    return p, digits > 0, (-ex if neg else ex)


@kernel
def _real_bytewise(base: int, p: int, end: int) -> tuple[int, float, int]:
    """The decimal literal ``[+-]digits[.digits][(e|E)[+-]digits]`` at offset ``p``, byte by byte.

    Returns (status, value, q), ``q`` the offset after the literal's grammar:
    status ``_FAST`` with its value by Clinger's fast path (module docstring),
    ``_SLOW`` for a literal outside it (more than 18 significant digits,
    m > 2**53 or |e| > 22; value 0), ``_NOT_DECIMAL`` when the bytes at ``p``
    do not start such a literal (``q`` then says nothing).
    """
    sign = byte_at(base, p) if p < end else 0
    neg = sign == 45
    p += (sign == 45) | (sign == 43)  # no branch: a sign is as likely as none
    m = 0
    digits = 0  # significant digits (from the first nonzero one); m holds the first 18
    seen = False  # any mantissa digit at all
    e10 = 0
    point = False  # past the decimal point: each digit lowers the exponent
    while p < end:
        if 48 <= byte_at(base, p) <= 57:
            d = byte_at(base, p) - 48
            seen = True
            if digits > 0 or d != 0:
                digits += 1
                if digits <= 18:
                    m = m * 10 + d
            if point:
                e10 -= 1
        elif byte_at(base, p) == 46 and not point:
            point = True
        else:
            break
        p += 1
    if not seen:
        return _NOT_DECIMAL, 0.0, p
    if p < end and (byte_at(base, p) | 32) == 101:  # e or E
        p, ok, ex = _exponent(base, p + 1, end)
        if not ok:
            return _NOT_DECIMAL, 0.0, p
        e10 += ex
    if m == 0:
        return _FAST, (-0.0 if neg else 0.0), p
    if digits > 18 or m > _MAX_EXACT or e10 > 22 or e10 < -22:
        return _SLOW, 0.0, p
    v = float(m) * _POW10[e10] if e10 >= 0 else float(m) / _POW10[-e10]
    return _FAST, (-v if neg else v), p


@inlined
def _integer(base: int, p: int, end: int) -> tuple[bool, int, int]:
    """Value of the integer literal ``[-]digits`` (at most 18 digits) at
    offset ``p``: (converted, value, offset after its grammar)."""
    neg = False
    if p < end and byte_at(base, p) == 45:
        neg = True
        p += 1
    v = 0
    n = 0
    while p < end and 48 <= byte_at(base, p) <= 57:
        v = v * 10 + (byte_at(base, p) - 48)
        n += 1
        p += 1
    if n == 0 or n > 18:
        return False, 0, p
    return True, (-v if neg else v), p


@inlined
def _field_end(base: int, q: int, end: int) -> int:
    """Offset of the first separator (byte <= 32) at or after offset ``q``, or ``end``: the end of a
    field, read or not (a run of unread fields is stepped over by :func:`_skip_fields`). The 64 bytes
    from ``q`` in one step (:func:`demsplit.runtime.jit.bytes_below`: a field is found whole, however long its
    digits, without the conversion's result); past them, or within 64 bytes of ``end``, eight bytes at
    a time: (x - 0x21..21) & ~x & 0x80..80 flags each byte below 0x21 exactly up to the first one (a
    borrow starts only there), and the lowest flag is the first such byte; the last bytes one by one.
    ``parse_rows`` finds a read field's end this way before it converts the field, so the next field's
    start does not wait for the conversion, and the conversions of a row overlap in the processor."""
    if q + _BLOCK <= end:
        m = bytes_below(base, q, _SEP + 1)
        if m != 0:
            return q + np.int64(trailing_zeros(m))
        q += _BLOCK
    while q + 8 <= end:
        x = word_at(base, q)
        below = (x - _EACH_21) & ~x & _EACH_80
        if below != 0:
            return q + np.int64(trailing_zeros(below) >> _U(3))
        q += 8
    while q < end and byte_at(base, q) > _SEP:
        q += 1
    return q


@inlined
def _skip_fields(base: int, p: int, end: int, n: int) -> int:
    """Offset after the ``n`` fields starting at offset ``p`` (just after a separator, or at a row's start) and
    the single space after each, stepped over 64 bytes at a time, then 8: per step, the separators (bytes
    <= 32) are flagged and counted, and in the step holding the n-th the lower ones are cleared to find it.
    Checked as the field-by-field loop checks: no separator but spaces (a newline before the n-th means a
    short row) and no two in a row (an empty field). Returns -1 for a row of the wrong shape, -2 when the
    n-th space is not found 8 bytes or more before ``end`` (the caller then goes field by field).

    64 bytes: :func:`~demsplit.runtime.jit.bytes_below` gives one bit per byte, bit j for byte p + j. 8 bytes
    (the last ones before ``end``): one flag per byte, its bit 7 (with b7 = b & 0x7F, b7 + 0x5F reaches
    0x80 exactly when b7 >= 0x21; a byte with its high bit set is no separator). The two loops are the
    same steps on the two layouts of flags, written out twice on purpose: one loop over both (the 8-byte
    flags gathered into a bit per byte) or none for the last bytes (-2 within 64 bytes of ``end``) made
    the kernel slower."""
    before = _U(1)  # a separator just before the step: one at its first byte ends an empty field
    left = n
    while p + _BLOCK <= end:
        sep = bytes_below(base, p, _SEP + 1)
        other = bytes_below(base, p, _SEP)  # bytes < 32: a separator but not a space
        k = np.int64(popcount(sep))
        if k >= left:
            m = _nth_lowest(sep, left)
            upto = m ^ (m - _U(1))  # the bytes up to the n-th separator
            sep &= upto
            if (other & upto) != 0 or (sep & ((sep << _U(1)) | before)) != 0:
                return -1
            return p + np.int64(trailing_zeros(m)) + 1
        if other != 0 or (sep & ((sep << _U(1)) | before)) != 0:
            return -1
        before = sep >> _U(63)
        left -= k
        p += _BLOCK
    before <<= _U(7)  # the same flag, as the 8-byte steps place it: bit 7 of byte 0
    while p + 8 <= end:
        x = word_at(base, p)
        low = x & _EACH_7F
        sep = ~((low + _EACH_5F) | x) & _EACH_80
        other = ~((low + _EACH_60) | x) & _EACH_80  # bytes < 32: a separator but not a space
        k = np.int64(popcount(sep))
        if k >= left:
            m = _nth_lowest(sep, left)
            upto = m ^ (m - _U(1))  # the bytes up to the n-th separator
            sep &= upto
            if (other & upto) != 0 or (sep & ((sep << _U(8)) | before)) != 0:
                return -1
            return p + np.int64(trailing_zeros(m) >> _U(3)) + 1
        if other != 0 or (sep & ((sep << _U(8)) | before)) != 0:
            return -1
        before = sep >> _U(56)
        left -= k
        p += 8
    return -2


@inlined
def _nth_lowest(bits: np.uint64, n: int) -> np.uint64:
    """The ``n``-th lowest set bit of ``bits`` (1-based; ``bits`` has at least ``n``) alone."""
    for _ in range(n - 1):
        bits &= bits - _U(1)
    return bits & ~(bits - _U(1))


@kernel
def parse_rows(
    a: np.ndarray,
    start: int,
    end: int,
    ncols: int,
    trailing: bool,
    kind: np.ndarray,
    slot: np.ndarray,
    reals: np.ndarray,
    ints: np.ndarray,
    row0: int,
    max_rows: int,
    slow: np.ndarray,
) -> tuple[int, int, int, int]:
    """Check and convert the whole rows in ``a[start:end]`` (ending with ``\\n``).

    Column ``c`` of a row is written, when ``kind[c]`` is 1, as float64 to
    ``reals[slot[c], row0 + r]``, when 2, as int64 to ``ints[slot[c], row0 + r]``;
    0 = not requested (only its shape is checked). At most ``max_rows`` rows
    are expected. A real that is a decimal literal outside the fast path is
    not written but listed in ``slow`` (one row per token: slot, row, start
    and end offset in ``a``), for the caller to convert; when ``slow`` is full,
    that token counts as outside the fast path.

    Returns (status, row, rows, n_slow): ``OK`` with the number of rows;
    ``SHAPE`` with the row (0-based in this slice) that is not ``ncols``
    non-empty fields separated by single spaces, then one space when
    ``trailing``, then a newline (any other byte <= 32 is a bad separator),
    or that exceeds ``max_rows``; ``FALLBACK`` with the first row holding a
    requested token that is neither converted nor listed (conversion stops
    there; the shape check goes on to the end, so the rows are well formed).
    """
    base = address(a)
    p = start
    r = 0
    n_slow = 0
    convert = True
    first_fallback = -1
    skip = np.zeros(ncols, np.int64)  # columns not requested from c on, before the last column
    for c in range(ncols - 2, -1, -1):
        skip[c] = skip[c + 1] + 1 if kind[c] == 0 else 0
    while p < end:
        if r >= max_rows:
            return SHAPE, r, r, n_slow
        c = 0
        while c < ncols:
            n_skip = skip[c] if convert else ncols - 1 - c
            if n_skip > 1:
                q = _skip_fields(base, p, end, n_skip)
                if q == -1:
                    return SHAPE, r, r, n_slow
                if q >= 0:
                    p = q
                    c += n_skip
                    continue
            k = kind[c] if convert else 0
            q = _field_end(base, p, end)  # first: the next field's start does not wait for the conversion
            if k == 1:
                found, v, t = _real(base, p, end)
                if t != q:  # the literal is not the whole field
                    found = _NOT_DECIMAL
                if found == _FAST:
                    reals[slot[c], row0 + r] = v
                elif found == _SLOW and n_slow < slow.shape[0]:
                    slow[n_slow, 0] = slot[c]
                    slow[n_slow, 1] = row0 + r
                    slow[n_slow, 2] = p
                    slow[n_slow, 3] = q
                    n_slow += 1
                else:
                    convert = False
                    first_fallback = r
            elif k == 2:
                ok, iv, t = _integer(base, p, end)
                if ok and t == q:
                    ints[slot[c], row0 + r] = iv
                else:
                    convert = False
                    first_fallback = r
            if q == p or q == end:  # empty field, or no newline at the end
                return SHAPE, r, r, n_slow
            if c < ncols - 1:
                if a[q] != 32:
                    return SHAPE, r, r, n_slow
                p = q + 1
            elif trailing:
                if a[q] != 32 or q + 1 == end or a[q + 1] != 10:
                    return SHAPE, r, r, n_slow
                p = q + 2
            else:
                if a[q] != 10:
                    return SHAPE, r, r, n_slow
                p = q + 1
            c += 1
        r += 1
    if first_fallback >= 0:
        return FALLBACK, first_fallback, r, n_slow
    return OK, r, r, n_slow


@kernel
def next_newline(a: np.ndarray, p: int) -> int:
    """Offset after the first ``\\n`` at or after ``a[p]`` (``a.size`` if none)."""
    while p < a.size:
        if a[p] == 10:
            return p + 1
        p += 1
    return a.size
