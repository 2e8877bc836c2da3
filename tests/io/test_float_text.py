"""The compiled ``repr`` of floats (Ryu) against Python's ``repr``, value by value."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.io.float_text import floats_text, parse_floats


def _assert_repr(values: np.ndarray) -> None:
    values = np.concatenate([values, -values])
    expected = [repr(v) for v in values.tolist()]
    got = floats_text(values)
    assert len(got) == len(expected)
    wrong = [(e, g) for e, g in zip(expected, got, strict=True) if e != g]
    assert not wrong, wrong[:10]


def _seeds(count: int) -> list[object]:
    """Seeds ``0 .. count-1``: 0 in ``make test``, the others (the same checks on other random
    values, a second each) marked slow, for ``make experiments``."""
    return [0, *(pytest.param(seed, marks=pytest.mark.slow) for seed in range(1, count))]


def test_the_forms_python_writes() -> None:
    values = np.array([0.0, 1.0, 0.1, 0.3, 100.0, 123.456, 1e15, 1e16, 1234567890123456.0,
                       9999999999999998.0, 1e-4, 1e-5, 0.00012345, 2.5e-7, 1.5e300, 1e22,
                       5e-324, 1.7976931348623157e308, 2.0**53 + 2, math.pi, math.inf])
    assert floats_text(values[:12]) == [
        "0.0", "1.0", "0.1", "0.3", "100.0", "123.456", "1000000000000000.0", "1e+16",
        "1234567890123456.0", "9999999999999998.0", "0.0001", "1e-05"]
    assert floats_text(np.array([-0.0, math.nan, -math.nan, -math.inf])) == [
        "-0.0", "nan", "nan", "-inf"]
    _assert_repr(values)


@pytest.mark.parametrize("seed", _seeds(3))
def test_random_bit_patterns(seed: int) -> None:
    bits = np.random.default_rng(seed).integers(0, 2**64, 200_000, dtype=np.uint64)
    _assert_repr(bits.view(np.float64))


def test_subnormals() -> None:
    rng = np.random.default_rng(7)
    _assert_repr(rng.integers(1, 2**52, 100_000, dtype=np.uint64).view(np.float64))
    _assert_repr(np.arange(1, 2000, dtype=np.uint64).view(np.float64))  # the smallest


def test_powers_of_two_and_ten_and_their_neighbours() -> None:
    powers = np.concatenate([np.ldexp(1.0, np.arange(-1074, 1024)),
                             np.array([float(f"1e{k}") for k in range(-323, 309)])])
    _assert_repr(np.concatenate([powers, np.nextafter(powers, math.inf),
                                 np.nextafter(powers, 0.0)]))


@pytest.mark.parametrize("seed", _seeds(2))
def test_values_written_in_decimal(seed: int) -> None:
    """Doubles nearest to short and long decimal texts (where ties between candidates and
    trailing zeros are likeliest), and everyday magnitudes."""
    rng = np.random.default_rng(10 + seed)
    digits = rng.integers(1, 10**17, 50_000)
    exponents = rng.integers(-340, 300, 50_000)
    short = rng.integers(1, 10**6, 50_000)
    near = rng.integers(-30, 30, 50_000)
    decimal = [float(f"{m}e{e}") for m, e in zip(digits.tolist(), exponents.tolist(), strict=True)]
    decimal += [float(f"{m}e{e}") for m, e in zip(short.tolist(), near.tolist(), strict=True)]
    _assert_repr(np.array(decimal))
    _assert_repr(np.concatenate([rng.normal(size=50_000), rng.uniform(-10, 10, 50_000),
                                 rng.lognormal(0, 100, 50_000),
                                 rng.integers(-2**60, 2**60, 50_000).astype(np.float64)]))


def _decimal_texts(rng: np.random.Generator, n: int) -> list[str]:
    """Numbers as logs write them: reprs of everyday and extreme doubles, short decimals,
    fixed and exponent forms with up to 25 digits, signs, leading and trailing zeros."""
    values = np.concatenate([rng.normal(size=n), rng.uniform(-1e4, 1e4, n),
                             rng.lognormal(0, 60, n),
                             rng.integers(1, 2**64, n, dtype=np.uint64).view(np.float64)])
    values = values[np.isfinite(values)]
    texts = [repr(v) for v in values.tolist()]
    texts += [f"{v:.{p}f}" for v, p in zip(rng.normal(scale=100, size=n).tolist(),
                                           rng.integers(0, 25, n).tolist(), strict=True)]
    texts += [f"{v:+.{p}e}" for v, p in zip(rng.lognormal(0, 40, n).tolist(),
                                            rng.integers(0, 25, n).tolist(), strict=True)]
    texts += [f"{m}e{e}" for m, e in zip(rng.integers(1, 10**17, n).tolist(),
                                         rng.integers(-330, 320, n).tolist(), strict=True)]
    texts += ["0", "-0", "+0.000", "007", ".5", "5.", "-.5e-3", "1E5", "1e+05", "100",
              "1.2500", "inf", "-inf", "+inf", "1e22", "1e23", "9007199254740993",
              "0.30000000000000004", "0.10000000000000001", "4.9e-324", "1e400", "1e-400",
              "2.2250738585072014e-308", "2.2250738585072011e-308"]
    rng.shuffle(texts)
    return texts


@pytest.mark.parametrize("seed", _seeds(3))
def test_parse_floats_is_float_or_undecided(seed: int) -> None:
    """Each group of fields is read bit for bit as ``float`` reads it, or left undecided
    (None) as a whole; repr's texts and short decimals are always decided."""
    rng = np.random.default_rng(20 + seed)
    texts = _decimal_texts(rng, 20_000)
    decided = 0
    for text in texts:
        values = parse_floats(text.encode(), 1)
        if values is not None:
            assert values.tobytes() == np.array([float(text)]).tobytes(), text
            decided += 1
    assert decided > len(texts) // 2
    for start in range(0, len(texts), 8):  # groups: separators, and undecided as a whole
        group = texts[start : start + 8]
        line = ",".join(group[:4]) + "\n" + ",".join(group[4:]) + "\n"
        values = parse_floats(line.encode(), len(group))
        if values is not None:
            assert values.tobytes() == np.array([float(t) for t in group]).tobytes(), group
    scales = 10.0 ** rng.integers(-300, 300, 5000)  # no subnormals
    reprs = [repr(v) for v in rng.normal(scale=scales).tolist()]
    values = parse_floats(",".join(reprs).encode(), len(reprs))
    assert values is not None
    assert values.tolist() == [float(t) for t in reprs]


#: Single fields that are no plain decimal number, or that this parser leaves to ``float``.
BAD_FIELDS = ["e5", "1e", "1e+", "--1", "+-1", "1..2", "1.2.3", ".", "-", "+", "in", "infinity",
              "inff", "nan", "NaN", "1" * 20, "0." + "1" * 20, "1_0", "1 ", " 1", "1;2",
              "1 2", "0x10", "1e5.5", "1e--5"]


@pytest.mark.parametrize("text", BAD_FIELDS)
def test_parse_floats_refuses_a_field_it_does_not_read_exactly(text: str) -> None:
    """Alone, and between good fields, with the right field count: the parser itself must
    refuse the text (a miscount would refuse anything)."""
    assert parse_floats(text.encode(), 1) is None
    assert parse_floats(f"1,{text},3".encode(), 3) is None
    assert parse_floats(f"1\n{text}\n3\n".encode(), 3) is None
    assert parse_floats(b"1,2,3", 3) is not None  # the same shape, good fields: read


@pytest.mark.parametrize(("text", "count"), [(",", 2), ("1,", 2), (",1", 2), ("1,,2", 3),
                                             ("1\n\n2", 3), ("1\n,2", 3), ("1,\n2", 3)])
def test_parse_floats_refuses_empty_fields(text: str, count: int) -> None:
    assert parse_floats(text.encode(), count) is None


@pytest.mark.parametrize(("text", "count"), [("", 1), ("1", 2), ("1,2", 3), ("1,2,3", 2),
                                             ("1\n2\n", 3), ("1\n2\n", 1)])
def test_parse_floats_refuses_another_field_count(text: str, count: int) -> None:
    assert parse_floats(text.encode(), count) is None


_ZEROS = "0" * 100_100


@pytest.mark.parametrize("text", [
    f"0.{_ZEROS}1e1000500", f"-0.{_ZEROS}1e+1000500", f"0.{_ZEROS}1E1000500",  # inf, -inf
    f"0.{_ZEROS}1e100050", f"0.{_ZEROS}9e100100",  # 1e-51, 9e-2: finite, exponent > limit
    f"0.{_ZEROS}1e-1000500", f"{_ZEROS}1e-1000500", f"-{_ZEROS}1.5e1000500",  # 0.0, -inf
    f"1e{_ZEROS}5", f"-1e-{_ZEROS}5", f"0.{_ZEROS[:99_990]}1e99995",  # 1e5, -1e-5, 1e4
    f"0e{_ZEROS}1000500", "1e99999", "1e-99999", "1e100000", "1e-100000",
])
def test_parse_floats_with_huge_exponents_is_float_or_undecided(text: str) -> None:
    """Exponents of many digits, offset by many leading zeros: an exponent capped instead of
    read exactly gave 1e-51 for the first text, whose value is inf."""
    values = parse_floats(text.encode(), 1)
    if values is not None:
        assert values.tobytes() == np.array([float(text)]).tobytes(), text[:20]


def test_exponents_from_the_limit_on_are_left_to_float() -> None:
    """Of the texts above: the bug's text is left undecided, shorter exponents are read."""
    assert parse_floats(f"0.{_ZEROS}1e1000500".encode(), 1) is None
    decided = parse_floats(f"1e{_ZEROS}5,0.{_ZEROS[:99_990]}1e99995".encode(), 2)
    assert decided is not None  # exponents below the limit, leading zeros or not: read
    assert decided.tolist() == [1e5, 1e4]


@pytest.mark.parametrize(("text", "count"), [("1,2\n3\n", 3), ("1,2\n3,4,5\n", 5), ("1\n2,3", 3),
                                             ("1,2\n3", 3), ("1,2,3,4", 4)])
def test_parse_floats_with_a_width_refuses_a_line_of_another_width(text: str,
                                                                   count: int) -> None:
    # The right count of fields, in lines of the wrong widths (the last without its break).
    assert parse_floats(text.encode(), count) is not None  # without a width: read
    assert parse_floats(text.encode(), count, width=2) is None


@pytest.mark.parametrize("text", ["1,2\n3,4\n", "1,2\n3,4", "1,2\n"])
def test_parse_floats_with_a_width_reads_lines_of_that_width(text: str) -> None:
    values = parse_floats(text.encode(), text.count(",") * 2, width=2)
    assert values is not None
    assert values.tolist() == [float(v) for v in text.replace("\n", ",").split(",") if v]
