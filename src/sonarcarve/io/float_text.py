"""Python's ``repr`` of floats and its ``float`` of decimal text, compiled, bit for bit.

``repr(float)`` (David Gay's shortest mode) gives the shortest decimal text that reads back to
the same float, and of those the nearest; the map CSV's contract is that exact text. Formatting
it costs about 0.2 µs a value in CPython, which bounded ``sonarcarve process`` at about
half a million map rows a second. This module computes the same digits with Ryu (Ulf Adams,
"Ryū: fast float-to-string conversion", PLDI 2018: the shortest, nearest digits from one
128-bit multiplication by a tabulated power of five) in a numba kernel, and lays them out as
``repr`` does: positional when the decimal point falls within ``-4 < decpt <= 16`` (``0.0001``,
``1234567890123456.0``), else ``d.ddde±XX`` (``1e-05``, ``1e+16``, ``5e-324``); ``-0.0``,
``inf``, ``-inf`` and ``nan`` as Python writes them. ``tests/io/test_float_text.py`` holds it
to ``repr`` on millions of floats of every exponent, subnormals and boundaries included.
:func:`parse_floats` reads the readings CSV's numbers the other way, exactly as ``float`` does
(or leaves a field undecided, for numpy's parser).

Measured rates, rows per CPU second (``nice .venv/bin/python benchmarks/process_speed.py --at
HEAD --baseline 1f0092d``, 1,000,000 rows, one core, load average 2.4-3.9; docs/RESULTS.md):
``write_map_csv`` about 1.9 million against 0.35-0.39 million with ``repr``;
``iter_readings_csv`` (parse and validate) 1.1-1.2 million against 0.71 million with numpy's
parser alone. Per value (1,000,000 normal and uniform doubles, best of 3): :func:`floats_text`
5.2 million a second against 2.0 million for ``repr``, :func:`parse_floats` 10.5 million
against 5.2 million for ``np.fromstring`` (load average 2.7).

This module imports numba: :mod:`sonarcarve.io.map_csv` imports it when it first writes rows,
so the command line starts without it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit

from sonarcarve.typing import FloatArray, Int8Array, IntArray

__all__ = ["floats_text", "map_rows_text", "parse_floats"]

_MASK64 = (1 << 64) - 1
#: Bits of the tabulated powers of five and of their inverses (Ryu's ``DOUBLE_POW5_BITCOUNT``
#: and ``DOUBLE_POW5_INV_BITCOUNT``).
_POW5_BITS = 125
#: Longest text of one float (``-1.2345678901234567e-308``) or int64, bytes.
_FIELD_BYTES = 25


def _power_tables() -> tuple[np.ndarray, np.ndarray]:
    """5^i scaled to 125 bits (i < 326), and 2^(len(5^i) - 1 + 125) / 5^i rounded up
    (i < 342), each as (low, high) 64-bit words, computed exactly with Python integers."""
    powers = np.zeros((326, 2), dtype=np.uint64)
    for i in range(326):
        value = 5**i
        shift = value.bit_length() - _POW5_BITS
        scaled = value >> shift if shift >= 0 else value << -shift
        powers[i] = (scaled & _MASK64, scaled >> 64)
    inverses = np.zeros((342, 2), dtype=np.uint64)
    for i in range(342):
        value = 5**i
        inverse = (1 << (value.bit_length() - 1 + _POW5_BITS)) // value + 1
        inverses[i] = (inverse & _MASK64, inverse >> 64)
    return powers, inverses


#: Ryu's tables: 5^i scaled to 125 bits, and its inverses (``_power_tables``).
_POWERS, _INVERSES = _power_tables()


def map_rows_text(reading_id: IntArray, t: FloatArray, sensor: IntArray, xy: FloatArray,
                  source: Int8Array, width: FloatArray, max_error: FloatArray,
                  confidence: FloatArray, labels: Sequence[str]) -> str:
    """Rows of the map CSV (``id,t,sensor,x,y,source,width,max_error,confidence``), each ending
    with ``\\n``: ints in decimal, floats as ``repr``, ``source`` as ``labels[code]``, a NaN
    confidence as an empty cell.

    Parameters
    ----------
    reading_id, sensor : ndarray of int64, shape (n,)
    t, width, max_error, confidence : ndarray of float64, shape (n,)
    xy : ndarray of float64, shape (n, 2)
    source : ndarray of int8, shape (n,)
        Codes, each a valid index of ``labels`` (the caller checks).
    labels : sequence of str
        ASCII labels by code.
    """
    n = len(t)
    table = np.zeros((len(labels), max(map(len, labels))), dtype=np.uint8)
    lengths = np.zeros(len(labels), dtype=np.int64)
    for code, label in enumerate(labels):
        table[code, : len(label)] = np.frombuffer(label.encode("ascii"), dtype=np.uint8)
        lengths[code] = len(label)
    out = np.empty(n * (8 * _FIELD_BYTES + table.shape[1] + 1), dtype=np.uint8)
    size = _rows(
        np.ascontiguousarray(reading_id, dtype=np.int64), _bits(t),
        np.ascontiguousarray(sensor, dtype=np.int64), _bits(xy[:, 0]), _bits(xy[:, 1]),
        np.ascontiguousarray(source, dtype=np.int64), _bits(width), _bits(max_error),
        _bits(confidence), table, lengths, _POWERS, _INVERSES, out,
    )
    return out[:size].tobytes().decode("ascii")


def floats_text(values: FloatArray) -> list[str]:
    """``[repr(v) for v in values]``, compiled (for tests and benchmarks of the kernel)."""
    out = np.empty(len(values) * (_FIELD_BYTES + 1), dtype=np.uint8)
    size = _floats_lines(_bits(values), _POWERS, _INVERSES, out)
    text = out[:size].tobytes().decode("ascii")
    return text.split("\n")[:-1] if text else []


def parse_floats(text: bytes, count: int, width: int = 0) -> FloatArray | None:
    """The ``count`` comma- or line-separated numbers of ``text``, exactly as ``float`` reads
    each; None if a field is not a plain decimal number (digits, one point, an exponent, a
    sign; or ``inf``), or is one this kernel does not decide (more than 19 significant digits,
    a 16-19 digit significand that is not the shortest text of its double, a subnormal or
    extreme exponent: rare), or if there are not ``count`` fields; with ``width`` > 0, also
    None if a line (``\n``-separated) has another number of fields than ``width`` (so that a
    reader need not count the fields of each line first).

    How: a significand of at most 15 digits times a power of ten of at most 22 is computed
    exactly in binary64 (Clinger's fast path: both factors exact, one rounding). Otherwise an
    approximation within two units in the last place is taken, and of it and its four nearest
    doubles, the one whose shortest text (:func:`_shortest`, Ryu) has the field's digits and
    exponent is the answer: a shortest text reads back to its own double, so that double is
    what ``float`` returns. Text written by ``repr`` (``write_readings_csv``, most loggers in
    Python) is always decided, subnormals aside.
    """
    values = np.empty(count, dtype=np.float64)
    scratch = np.empty(1, dtype=np.float64)
    found = _parse(np.frombuffer(text, dtype=np.uint8), values, width, scratch,
                   scratch.view(np.uint64), _POWERS_OF_TEN, _POWERS, _INVERSES)
    return values if found == count else None


#: 10^k as the nearest binary64, k = 0 .. 308 (exact up to 10^22).
_POWERS_OF_TEN = np.array([float(f"1e{k}") for k in range(309)])


def _bits(values: FloatArray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


# --------------------------------------------------------------------------------------------
# The kernel (every integer that meets a uint64 is a uint64 on purpose: numba turns a mix of
# uint64 and int64 into float64).
# --------------------------------------------------------------------------------------------

_U0 = np.uint64(0)
_U1 = np.uint64(1)
_U2 = np.uint64(2)
_U4 = np.uint64(4)
_U5 = np.uint64(5)
_U10 = np.uint64(10)
_U32 = np.uint64(32)
_U52 = np.uint64(52)
_U63 = np.uint64(63)
_U64 = np.uint64(64)
_U100 = np.uint64(100)
_LOW32 = np.uint64(0xFFFFFFFF)
_MANTISSA = np.uint64((1 << 52) - 1)
_HIDDEN = np.uint64(1 << 52)
_EXPONENT = np.uint64(0x7FF)


@njit(cache=True)
def _umul128(a: np.uint64, b: np.uint64) -> tuple[np.uint64, np.uint64]:
    """The 128-bit product a * b as (low, high) 64-bit words."""
    a_lo = a & _LOW32
    a_hi = a >> _U32
    b_lo = b & _LOW32
    b_hi = b >> _U32
    b00 = a_lo * b_lo
    b01 = a_lo * b_hi
    b10 = a_hi * b_lo
    b11 = a_hi * b_hi
    mid1 = b10 + (b00 >> _U32)
    mid2 = b01 + (mid1 & _LOW32)
    high = b11 + (mid1 >> _U32) + (mid2 >> _U32)
    low = (mid2 << _U32) | (b00 & _LOW32)
    return low, high


@njit(cache=True)
def _mul_shift(m: np.uint64, low: np.uint64, high: np.uint64, shift: int) -> np.uint64:
    """(m * (high * 2^64 + low)) >> shift, for 64 < shift < 128."""
    _, high0 = _umul128(m, low)
    low1, high1 = _umul128(m, high)
    total = high0 + low1
    if total < high0:
        high1 += _U1
    distance = np.uint64(shift - 64)
    return (high1 << (_U64 - distance)) | (total >> distance)


@njit(cache=True)
def _pow5_factor(value: np.uint64) -> int:
    count = 0
    while value % _U5 == _U0:
        value //= _U5
        count += 1
    return count


@njit(cache=True)
def _shortest(bits: np.uint64, powers: np.ndarray,
              inverses: np.ndarray) -> tuple[np.uint64, int]:
    """Ryu's digits of a finite nonzero double: (digits, exponent), value = digits * 10^exp,
    the shortest that reads back to it, the nearest of those, trailing zeros removed.

    Ryu's steps: the double and its two neighbours' midpoints as integers times a power of two
    (:func:`_unpack`); the three scaled to a power of ten (:func:`_decimal_above` for
    non-negative binary exponents, :func:`_decimal_below` for negative ones); then digits
    dropped while the interval still holds a shorter number, exactly where the bounds may
    end in zeros (:func:`_round_exact`), else fast (:func:`_round_common`). The steps are
    inlined into this kernel (``inline="always"``): called as functions they made
    :func:`floats_text` 1.0-1.4 % slower (1,000,000 doubles, seven interleaved runs).
    """
    m2, e2, mm_shift, accept_bounds = _unpack(bits)
    if e2 >= 0:
        vr, vp, vm, e10, vm_zeros, vr_zeros = _decimal_above(m2, e2, mm_shift, accept_bounds,
                                                             inverses)
    else:
        vr, vp, vm, e10, vm_zeros, vr_zeros = _decimal_below(m2, e2, mm_shift, accept_bounds,
                                                             powers)
    if vm_zeros or vr_zeros:
        digits, removed = _round_exact(vr, vp, vm, vm_zeros, vr_zeros, accept_bounds)
    else:
        digits, removed = _round_common(vr, vp, vm)
    exp10 = e10 + removed
    while digits % _U10 == _U0:
        digits //= _U10
        exp10 += 1
    return digits, exp10


@njit(cache=True, inline="always")
def _unpack(bits: np.uint64) -> tuple[np.uint64, int, np.uint64, bool]:
    """The double as m2 * 2^e2 (with two extra bits, so that the neighbours' midpoints are
    whole: 4 m2 ± 2), the lower neighbour's distance (1, or 0 at a power of two, where the
    gap below is half the gap above) and whether the bounds themselves read back (even m2)."""
    mantissa = bits & _MANTISSA
    exponent = int((bits >> _U52) & _EXPONENT)
    if exponent == 0:
        e2 = 1 - 1023 - 52 - 2
        m2 = mantissa
    else:
        e2 = exponent - 1023 - 52 - 2
        m2 = _HIDDEN | mantissa
    mm_shift = _U1 if (mantissa != _U0 or exponent <= 1) else _U0
    return m2, e2, mm_shift, (m2 & _U1) == _U0


@njit(cache=True, inline="always")
def _scaled_interval(mv: np.uint64, mm_shift: np.uint64, low: np.uint64, high: np.uint64,
                     shift: int) -> tuple[np.uint64, np.uint64, np.uint64]:
    """The value ``mv`` and its upper and lower bounds (``mv + 2``, ``mv - 1 - mm_shift``),
    each times the 128-bit factor ``(high, low)`` shifted right by ``shift``."""
    return (_mul_shift(mv, low, high, shift), _mul_shift(mv + _U2, low, high, shift),
            _mul_shift(mv - _U1 - mm_shift, low, high, shift))


@njit(cache=True, inline="always")
def _decimal_above(m2: np.uint64, e2: int, mm_shift: np.uint64, accept_bounds: bool,
                   inverses: np.ndarray) -> tuple[np.uint64, np.uint64, np.uint64, int, bool,
                                                  bool]:
    """For e2 >= 0: the value and its bounds times 10^-q (vr, vp, vm; e10 = q), and whether
    the lower bound and the value end in zeros that the scaling dropped."""
    mv = _U4 * m2
    q = ((e2 * 78913) >> 18) - (1 if e2 > 3 else 0)  # log10(2^e2), one less above 3
    k = _POW5_BITS + (((q * 1217359) >> 19) + 1) - 1
    shift = -e2 + q + k
    low, high = inverses[q, 0], inverses[q, 1]
    vr, vp, vm = _scaled_interval(mv, mm_shift, low, high, shift)
    vm_zeros = False
    vr_zeros = False
    if q <= 21:
        if mv % _U5 == _U0:
            vr_zeros = _pow5_factor(mv) >= q
        elif accept_bounds:
            vm_zeros = _pow5_factor(mv - _U1 - mm_shift) >= q
        elif _pow5_factor(mv + _U2) >= q:
            vp -= _U1
    return vr, vp, vm, q, vm_zeros, vr_zeros


@njit(cache=True, inline="always")
def _decimal_below(m2: np.uint64, e2: int, mm_shift: np.uint64, accept_bounds: bool,
                   powers: np.ndarray) -> tuple[np.uint64, np.uint64, np.uint64, int, bool,
                                                bool]:
    """For e2 < 0: as :func:`_decimal_above`, scaled by 5^-e2 and 10^-q (e10 = q + e2)."""
    mv = _U4 * m2
    q = ((-e2 * 732923) >> 20) - (1 if -e2 > 1 else 0)  # log10(5^-e2), one less above 1
    i = -e2 - q
    k = (((i * 1217359) >> 19) + 1) - _POW5_BITS
    shift = q - k
    low, high = powers[i, 0], powers[i, 1]
    vr, vp, vm = _scaled_interval(mv, mm_shift, low, high, shift)
    vm_zeros = False
    vr_zeros = False
    if q <= 1:
        vr_zeros = True
        if accept_bounds:
            vm_zeros = mm_shift == _U1
        else:
            vp -= _U1
    elif q < 63:
        vr_zeros = (mv & ((_U1 << np.uint64(q)) - _U1)) == _U0
    return vr, vp, vm, q + e2, vm_zeros, vr_zeros


@njit(cache=True, inline="always")
def _drop_digit(vr: np.uint64, vp: np.uint64, vm: np.uint64, vr_zeros: bool,
                last_removed: np.uint64) -> tuple[np.uint64, np.uint64, np.uint64, bool,
                                                  np.uint64]:
    """The value and its bounds with their last digit dropped, whether every digit dropped
    from the value before this one was 0, and the digit this drops."""
    return (vr // _U10, vp // _U10, vm // _U10, vr_zeros and last_removed == _U0,
            vr % _U10)


@njit(cache=True, inline="always")
def _round_exact(vr: np.uint64, vp: np.uint64, vm: np.uint64, vm_zeros: bool, vr_zeros: bool,
                 accept_bounds: bool) -> tuple[np.uint64, int]:
    """Digits dropped one at a time while the interval holds a shorter number, tracking
    whether what was dropped is all zeros (a bound that is itself shortest, an exact half
    rounded to even): the rare path. Returns the rounded digits and how many were dropped."""
    removed = 0
    last_removed = _U0
    while vp // _U10 > vm // _U10:
        vm_zeros = vm_zeros and vm % _U10 == _U0
        vr, vp, vm, vr_zeros, last_removed = _drop_digit(vr, vp, vm, vr_zeros, last_removed)
        removed += 1
    if vm_zeros:
        while vm % _U10 == _U0:
            vr, vp, vm, vr_zeros, last_removed = _drop_digit(vr, vp, vm, vr_zeros, last_removed)
            removed += 1
    if vr_zeros and last_removed == _U5 and vr % _U2 == _U0:
        last_removed = np.uint64(4)  # exactly halfway: round to even
    up = bool((vr == vm and (not accept_bounds or not vm_zeros)) or last_removed >= _U5)
    return vr + (_U1 if up else _U0), removed


@njit(cache=True, inline="always")
def _round_common(vr: np.uint64, vp: np.uint64, vm: np.uint64) -> tuple[np.uint64, int]:
    """Digits dropped while the interval holds a shorter number, two at a time first, the
    last dropped digit rounding: the common path, where no bound ends in zeros."""
    removed = 0
    up = False
    if vp // _U100 > vm // _U100:
        up = bool(vr % _U100 >= np.uint64(50))
        vr //= _U100
        vp //= _U100
        vm //= _U100
        removed += 2
    while vp // _U10 > vm // _U10:
        up = bool(vr % _U10 >= _U5)
        vr //= _U10
        vp //= _U10
        vm //= _U10
        removed += 1
    up = up or bool(vr == vm)
    return vr + (_U1 if up else _U0), removed


@njit(cache=True)
def _write_uint(value: np.uint64, out: np.ndarray, at: int) -> int:
    """Decimal digits of ``value`` at ``out[at:]``; the position after them."""
    count = 1
    rest = value // _U10
    while rest != _U0:
        count += 1
        rest //= _U10
    for k in range(count - 1, -1, -1):
        out[at + k] = 48 + int(value % _U10)
        value //= _U10
    return at + count


@njit(cache=True)
def _write_int(value: int, out: np.ndarray, at: int) -> int:
    if value < 0:
        out[at] = 45  # "-"
        return _write_uint(np.uint64(-value), out, at + 1)
    return _write_uint(np.uint64(value), out, at)


@njit(cache=True)
def _write_float(bits: np.uint64, powers: np.ndarray, inverses: np.ndarray, out: np.ndarray,
                 at: int) -> int:
    """``repr`` of the double with these bits at ``out[at:]``; the position after it."""
    exponent = (bits >> _U52) & _EXPONENT
    mantissa = bits & _MANTISSA
    negative = (bits >> _U63) != _U0
    if exponent == _EXPONENT:
        if mantissa != _U0:
            out[at] = 110  # "nan", whatever its sign
            out[at + 1] = 97
            out[at + 2] = 110
            return at + 3
        if negative:
            out[at] = 45
            at += 1
        out[at] = 105  # "inf"
        out[at + 1] = 110
        out[at + 2] = 102
        return at + 3
    if negative:
        out[at] = 45
        at += 1
    if exponent == _U0 and mantissa == _U0:
        out[at] = 48  # "0.0"
        out[at + 1] = 46
        out[at + 2] = 48
        return at + 3
    digits, exp10 = _shortest(bits, powers, inverses)
    start = at
    end = _write_uint(digits, out, at)
    count = end - start
    point = count + exp10  # the value is 0.DIGITS * 10^point
    if -4 < point <= 16:
        if point <= 0:  # 0.000DIGITS
            shift = 2 - point
            for k in range(count - 1, -1, -1):
                out[start + shift + k] = out[start + k]
            out[start] = 48
            out[start + 1] = 46
            for k in range(-point):
                out[start + 2 + k] = 48
            return start + shift + count
        if point < count:  # DI.GITS
            for k in range(count - 1, point - 1, -1):
                out[start + k + 1] = out[start + k]
            out[start + point] = 46
            return end + 1
        for k in range(point - count):  # DIGITS000.0
            out[end + k] = 48
        end += point - count
        out[end] = 46
        out[end + 1] = 48
        return end + 2
    if count > 1:  # D.IGITSe±XX
        for k in range(count - 1, 0, -1):
            out[start + k + 1] = out[start + k]
        out[start + 1] = 46
        end += 1
    out[end] = 101  # "e"
    power = point - 1
    out[end + 1] = 45 if power < 0 else 43
    power = -power if power < 0 else power
    if power < 10:
        out[end + 2] = 48
        out[end + 3] = 48 + power
        return end + 4
    return _write_uint(np.uint64(power), out, end + 2)


@njit(cache=True)
def _rows(reading_id: np.ndarray, t: np.ndarray, sensor: np.ndarray, x: np.ndarray,
          y: np.ndarray, source: np.ndarray, width: np.ndarray, max_error: np.ndarray,
          confidence: np.ndarray, labels: np.ndarray, lengths: np.ndarray, powers: np.ndarray,
          inverses: np.ndarray, out: np.ndarray) -> int:
    at = 0
    for k in range(t.shape[0]):
        at = _write_int(reading_id[k], out, at)
        out[at] = 44
        at = _write_float(t[k], powers, inverses, out, at + 1)
        out[at] = 44
        at = _write_int(sensor[k], out, at + 1)
        out[at] = 44
        at = _write_float(x[k], powers, inverses, out, at + 1)
        out[at] = 44
        at = _write_float(y[k], powers, inverses, out, at + 1)
        out[at] = 44
        at += 1
        code = source[k]
        for j in range(lengths[code]):
            out[at + j] = labels[code, j]
        at += lengths[code]
        out[at] = 44
        at = _write_float(width[k], powers, inverses, out, at + 1)
        out[at] = 44
        at = _write_float(max_error[k], powers, inverses, out, at + 1)
        out[at] = 44
        at += 1
        bits = confidence[k]
        if not (((bits >> _U52) & _EXPONENT) == _EXPONENT and (bits & _MANTISSA) != _U0):
            at = _write_float(bits, powers, inverses, out, at)
        out[at] = 10
        at += 1
    return at


@njit(cache=True)
def _floats_lines(values: np.ndarray, powers: np.ndarray, inverses: np.ndarray,
                  out: np.ndarray) -> int:
    at = 0
    for k in range(values.shape[0]):
        at = _write_float(values[k], powers, inverses, out, at)
        out[at] = 10
        at += 1
    return at


# --------------------------------------------------------------------------------------------
# Text to floats
# --------------------------------------------------------------------------------------------

_MAX_SIGNIFICAND_DIGITS = 19  # 10^19 < 2^64
#: Exponents (the number after ``e``) from this size on are left to ``float``. Leading zeros
#: of a fraction lower the decimal exponent by one each without limit, so only an exponent
#: read exactly gives the right sum: one capped at a bound instead read
#: ``"0." + "0" * 100_100 + "1e1000500"`` (``inf``) as 1e-51. Below the limit ``power`` stays
#: exact and far from int64's range.
_EXPONENT_LIMIT = 100_000


@njit(cache=True)
def _decimal(significand: np.uint64, exponent: int, digits: int, scratch: np.ndarray,
             scratch_bits: np.ndarray, tens: np.ndarray, powers: np.ndarray,
             inverses: np.ndarray) -> float:
    """significand * 10^exponent as ``float`` reads it (nonnegative); NaN if undecided."""
    if significand == _U0:
        return 0.0
    while significand % _U10 == _U0:  # the form _shortest gives: no trailing zeros
        significand //= _U10
        exponent += 1
        digits -= 1
    if digits <= 15 and -22 <= exponent <= 22:  # Clinger: exact operands, one rounding
        if exponent >= 0:
            return float(float(significand) * tens[exponent])
        return float(float(significand) / tens[-exponent])
    if exponent > 308 or exponent < -340:
        return np.nan  # overflow or underflow: left to float
    if exponent >= 0:
        scratch[0] = float(significand) * tens[exponent]
    elif exponent >= -308:
        scratch[0] = float(significand) / tens[-exponent]
    else:  # two roundings: still within two units in the last place
        scratch[0] = float(significand) / tens[308] / tens[-exponent - 308]
    center = scratch_bits[0]
    if (center >> _U52) & _EXPONENT == _EXPONENT or (center >> _U52) & _EXPONENT == _U0:
        return np.nan  # inf (overflow) or subnormal: left to float
    for step in range(5):  # 0, +1, -1, +2, -2 units in the last place
        offset = np.uint64((step + 1) // 2)
        candidate = center + offset if step % 2 == 1 else center - offset
        if (candidate >> _U52) & _EXPONENT == _EXPONENT or (candidate >> _U52) & _EXPONENT == _U0:
            continue
        shortest, power = _shortest(candidate, powers, inverses)
        if shortest == significand and power == exponent:
            scratch_bits[0] = candidate
            return float(scratch[0])
    return np.nan


@njit(cache=True)
def _parse(text: np.ndarray, values: np.ndarray, width: int, scratch: np.ndarray,
           scratch_bits: np.ndarray, tens: np.ndarray, powers: np.ndarray,
           inverses: np.ndarray) -> int:
    """Fields of ``text`` into ``values``; how many, or -1 at the first field not decided or
    (``width`` > 0) at the end of a line of another number of fields.

    The significand's digit loop stays here: moved into an inlined step returning its five
    numbers (or the whole field into one), it made :func:`parse_floats` 14 % (26 %) slower on
    600,000 ``repr`` fields; the exponent, rarer, is a step (:func:`_parse_power`)."""
    n = text.shape[0]
    at = 0
    count = 0
    line_fields = 0
    while at < n:
        if count == values.shape[0]:
            return -1
        negative = text[at] == 45
        if text[at] == 45 or text[at] == 43:
            at += 1
        if at < n and text[at] == 105:  # "inf"
            if at + 2 < n and text[at + 1] == 110 and text[at + 2] == 102:
                value = np.inf
                at += 3
            else:
                return -1
        else:
            significand = _U0
            digits = 0
            seen = 0
            exponent = 0
            point = False  # digits after "." scale the exponent down
            while at < n:
                if text[at] == 46 and not point:  # "."
                    point = True
                    at += 1
                    continue
                if not 48 <= text[at] <= 57:
                    break
                digit = np.uint64(text[at] - 48)
                seen += 1
                if digits > 0 or digit != _U0:  # leading zeros carry no digit
                    if digits == _MAX_SIGNIFICAND_DIGITS:
                        return -1
                    significand = significand * _U10 + digit
                    digits += 1
                if point:
                    exponent -= 1
                at += 1
            if seen == 0:
                return -1
            power, at = _parse_power(text, at)
            if power >= _EXPONENT_LIMIT:
                return -1
            exponent += power
            value = _decimal(significand, exponent, digits, scratch, scratch_bits, tens,
                             powers, inverses)
            if np.isnan(value):
                return -1
        values[count] = -value if negative else value
        count += 1
        line_fields += 1
        if at < n:
            if text[at] == 10:  # a line break ends the field and the line
                if width > 0 and line_fields != width:
                    return -1
                line_fields = 0
            elif text[at] != 44:  # "," ends a field
                return -1
            at += 1
            if at == n and text[at - 1] == 44:
                return -1  # a last, empty field
        elif width > 0 and line_fields != width:
            return -1  # the last line, without a final break
    return count


@njit(cache=True, inline="always")
def _parse_power(text: np.ndarray, at: int) -> tuple[int, int]:
    """The exponent ``e±ddd`` at ``text[at:]``, 0 where there is none, and the position after
    it; ``_EXPONENT_LIMIT`` where it is left to ``float`` (no digits, or too large)."""
    n = text.shape[0]
    if not (at < n and (text[at] == 101 or text[at] == 69)):  # "e", "E"
        return 0, at
    at += 1
    minus = at < n and text[at] == 45
    if at < n and (text[at] == 45 or text[at] == 43):
        at += 1
    power = 0
    power_digits = 0
    while at < n and 48 <= text[at] <= 57:
        power = power * 10 + (text[at] - 48)
        if power >= _EXPONENT_LIMIT:
            return _EXPONENT_LIMIT, at  # left to float: see _EXPONENT_LIMIT
        power_digits += 1
        at += 1
    if power_digits == 0:
        return _EXPONENT_LIMIT, at
    return (-power if minus else power), at
