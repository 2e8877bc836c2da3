"""The fuzz harness (fixtures): seeded byte mutation and one run of the real CLI, in-process.

Every case is a list of files (name -> bytes) written into a fresh folder, and a command line.
:func:`run_case` runs it through :func:`sonarcarve.cli.main` and checks the error promise:
exit code 0 or 2, no traceback, stderr either warnings only (exit 0) or exactly one
``sonarcarve: error:`` line (exit 2), and on failure the output that was already on disk
unchanged.
"""

from __future__ import annotations

import os
import random
from collections.abc import Callable
from pathlib import Path

import pytest

from sonarcarve.cli import main

Runner = Callable[[Path, dict[str, bytes], list[str], "str | None"], tuple[int, str]]
Mutator = Callable[[bytes, random.Random], bytes]

#: Cases per family in ``make test``; ``FUZZ_CASES=5000 make fuzz`` runs more.
CASES = int(os.environ.get("FUZZ_CASES", "0")) or None

#: Byte strings a mutation may splice in: the numbers, separators and YAML features that broke
#: parsers before.
TOKENS = [
    b"nan", b"inf", b"-inf", b"1e308", b"1.7e308", b"-1e300", b"1e-300", b"0", b"-1",
    b"99999999999999999999", b";", b"\t", b",", b"\n", b"\r\n", b"\x00", b"\xff\xfe",
    b"\xef\xbb\xbf",
    b'"', b"'", b"[", b"]", b"{", b"}", b"&a", b"*a", b"- ", b": ", b"#", b"~", b"null",
    b"true", b"1.0e-9", b"360", b"6000", b"P5", b"255",
]

OLD = b"old output\n"


def mutate(data: bytes, rng: random.Random, steps: int | None = None) -> bytes:
    """``data`` with 1-3 random edits (mostly one): flip, delete, duplicate, splice, truncate."""
    out = bytearray(data)
    for _ in range(steps or rng.choice([1, 1, 1, 2, 3])):
        kind = rng.randrange(7)
        at = rng.randrange(len(out) + 1)
        if kind == 0 and out:
            out[min(at, len(out) - 1)] ^= 1 << rng.randrange(8)
        elif kind == 1:
            del out[at:at + rng.randint(1, 16)]
        elif kind == 2:
            span = bytes(out[at:at + rng.randint(1, 64)])
            out[at:at] = span * rng.randint(1, 3)
        elif kind in (3, 4):
            out[at:at] = rng.choice(TOKENS)
        elif kind == 5:  # replace one number-like run by a token: keeps the syntax valid
            digits = [i for i, b in enumerate(out) if chr(b).isdigit()]
            if digits:
                i = rng.choice(digits)
                j = i
                while j < len(out) and chr(out[j]) in "0123456789.e-":
                    j += 1
                out[i:j] = rng.choice([*TOKENS[:12], b"1e5", b"100000.5", b"720", b"0.0001"])
        else:
            del out[at:]
    return bytes(out)


def run_case(folder: Path, files: dict[str, bytes], argv: list[str], out: str | None,
             capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """Write ``files``, run ``argv`` in ``folder``, check the promise; return (code, stderr)."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (folder / name).write_bytes(data)
    if out is not None:
        (folder / out).write_bytes(OLD)
    here = Path.cwd()
    os.chdir(folder)
    try:
        capsys.readouterr()
        code = main(argv)
        err = capsys.readouterr().err
    finally:
        os.chdir(here)
    lines = [line for line in err.splitlines() if line.strip()]
    context = f"argv={argv} files={ {k: v[:200] for k, v in files.items()} } stderr={err[:600]!r}"
    assert "Traceback" not in err, context
    assert code in (0, 2), context
    if code == 2:
        assert len(lines) == 1, context
        assert lines[0].startswith("sonarcarve: error: "), context
        assert len(lines[0]) <= 340, context
        if out is not None:
            assert (folder / out).read_bytes() == OLD, context
    else:
        assert all("warning" in line.lower() or not line.startswith("sonarcarve: error")
                   for line in lines), context
    if out is not None:  # no temporary left beside the output, whatever happened
        assert not [p for p in folder.iterdir() if p.name.startswith(f".{out}.")], context
    return code, err


@pytest.fixture
def run_cli(capsys: pytest.CaptureFixture[str]) -> Runner:
    """:func:`run_case` with pytest's captured output."""
    def run(folder: Path, files: dict[str, bytes], argv: list[str],
            out: str | None) -> tuple[int, str]:
        return run_case(folder, files, argv, out, capsys)
    return run


@pytest.fixture
def mutator() -> Mutator:
    """:func:`mutate`."""
    return mutate

