"""Atomic writes and output checks: a failure leaves every target as it was, in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import (
    atomic_path,
    atomic_paths,
    atomic_text,
    check_output_dir,
    check_output_file,
    make_output_dir,
    remove_stale,
)
from sonarcarve.io.errors import OutputError


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_missing_folder_is_an_error_not_created(tmp_path: Path) -> None:
    target = tmp_path / "typo" / "out.csv"
    with pytest.raises(OutputError) as caught, atomic_text(target) as handle:
        handle.write("x")
    assert str(caught.value) == f"cannot write {target}: directory {target.parent} does not exist"
    assert _names(tmp_path) == []


def test_output_error_is_a_one_line_sonarcarve_and_os_error(tmp_path: Path) -> None:
    with pytest.raises(OutputError) as caught, atomic_text(tmp_path):
        pass
    assert isinstance(caught.value, SonarcarveError)
    assert isinstance(caught.value, OSError)
    assert "is a directory" in str(caught.value)
    assert "\n" not in str(caught.value)


def test_an_os_error_while_writing_keeps_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "map.csv"
    target.write_text("old\n")

    def fail_halfway() -> None:
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise OSError(28, "No space left on device")

    with pytest.raises(OutputError, match="No space left on device") as caught:
        fail_halfway()
    assert str(target) in str(caught.value)
    assert target.read_text() == "old\n"
    assert _names(tmp_path) == ["map.csv"]


def test_other_exceptions_pass_through_and_clean_up(tmp_path: Path) -> None:
    target = tmp_path / "map.csv"
    with pytest.raises(KeyError), atomic_path(target):
        raise KeyError("x")
    assert _names(tmp_path) == []


def test_atomic_paths_replace_all_or_nothing(tmp_path: Path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "a.truth.json"
    a.write_text("old a\n")
    b.write_text("old b\n")

    def fail_in_the_second() -> None:
        with atomic_paths(b, a) as (tmp_b, tmp_a):
            tmp_b.write_text("new b\n")  # the first file is complete...
            with atomic_text(tmp_a) as handle:  # ...the second fails in its own atomic write
                handle.write("new a")
                raise OSError(5, "Input/output error")

    with pytest.raises(OutputError) as caught:
        fail_in_the_second()
    # The message names the target, not a temporary file.
    assert str(caught.value) == f"cannot write {a}: Input/output error"
    assert (a.read_text(), b.read_text()) == ("old a\n", "old b\n")
    assert _names(tmp_path) == ["a.csv", "a.truth.json"]

    with atomic_paths(b, a) as (tmp_b, tmp_a):
        tmp_b.write_text("new b\n")
        tmp_a.write_text("new a\n")
    assert (a.read_text(), b.read_text()) == ("new a\n", "new b\n")
    assert _names(tmp_path) == ["a.csv", "a.truth.json"]


def test_atomic_paths_checks_every_target_before_writing(tmp_path: Path) -> None:
    (tmp_path / "b").mkdir()
    entered = False
    with pytest.raises(OutputError, match="is a directory"), \
            atomic_paths(tmp_path / "a", tmp_path / "b"):
        entered = True
    assert not entered
    assert _names(tmp_path) == ["b"]


def test_check_output_file(tmp_path: Path) -> None:
    source = tmp_path / "in.csv"
    source.write_text("x\n")
    (tmp_path / "link.csv").symlink_to(source)
    assert check_output_file(tmp_path / "out.csv", inputs=[source]) == tmp_path / "out.csv"
    cases = {
        tmp_path / "in.csv": "is the input file",
        tmp_path / "link.csv": "is the input file",  # the same file, another name
        tmp_path: "is a directory",
        Path(): "empty, expected a file name",
        tmp_path / "none" / "out.csv": "does not exist",
        source / "out.csv": "is not a directory",
        Path("/proc/out.csv"): "cannot create a file in /proc",
        Path("/dev/null"): "not a regular file",
    }
    for path, problem in cases.items():
        with pytest.raises(OutputError, match=problem) as caught:
            check_output_file(path, inputs=[source], label=f"--out {path}")
        assert str(caught.value).startswith(f"--out {path}: ")
    assert _names(tmp_path) == ["in.csv", "link.csv"]  # the probes leave nothing behind


def test_check_and_make_output_dir(tmp_path: Path) -> None:
    nested = tmp_path / "a" / "b"
    assert check_output_dir(nested) == nested
    assert not (tmp_path / "a").exists()  # checked, not created
    assert check_output_dir(tmp_path) == tmp_path
    assert _names(tmp_path) == []
    (tmp_path / "file").write_text("x")
    for path, problem in ((tmp_path / "file", "exists and is not a directory"),
                          (tmp_path / "file" / "sub", "file exists and is not a directory"),
                          (Path("/proc/out"), "cannot create a folder in /proc"),
                          ("", "empty, expected a folder name")):
        with pytest.raises(OutputError, match=problem):
            check_output_dir(path, label="--out")
    assert make_output_dir(nested).is_dir()
    assert make_output_dir(nested).is_dir()  # already there: fine


@pytest.mark.parametrize("check", ["check", "write"])
def test_a_trailing_slash_a_dangling_link_or_a_name_too_long_change_nothing(
        tmp_path: Path, check: str) -> None:
    old = tmp_path / "old.csv"
    old.write_text("old\n")
    dangling = tmp_path / "dangling.csv"
    dangling.symlink_to("missing.csv")
    cases = {
        f"{old}/": "ends in '/', expected a file name",
        str(dangling): "is a symbolic link to missing.csv, which does not exist",
        str(tmp_path / ("x" * 300 + ".csv")): "File name too long",
    }
    for path, problem in cases.items():
        with pytest.raises(OutputError) as caught:
            _check_or_write(check, path)
        assert problem in str(caught.value)
        assert "\n" not in str(caught.value)
    assert old.read_text() == "old\n"
    assert dangling.is_symlink()
    assert _names(tmp_path) == ["dangling.csv", "old.csv"]


def _check_or_write(check: str, path: str) -> None:
    if check == "check":
        check_output_file(path)
        return
    with atomic_text(path) as handle:
        handle.write("new\n")


def test_a_link_to_a_file_is_followed_and_stays_a_link(tmp_path: Path) -> None:
    real = tmp_path / "real.csv"
    real.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to("real.csv")
    assert check_output_file(link) == real
    with atomic_text(link) as handle:
        handle.write("new\n")
    assert link.is_symlink()
    assert real.read_text() == "new\n"


def test_the_next_write_removes_temporaries_of_dead_writers_only(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    target = tmp_path / "out.csv"
    # A pid that has certainly exited: a child we waited for.
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    stale = tmp_path / f".out.csv.sc-{dead}-abcd1234.tmp"
    stale.write_text("half a file")
    live = tmp_path / f".out.csv.sc-{os.getppid()}-abcd1234.tmp"  # a running process
    live.write_text("being written")
    other = tmp_path / f".other.csv.sc-{dead}-abcd1234.tmp"  # another target's
    other.write_text("x")
    with atomic_text(target) as handle:
        handle.write("new\n")
    assert _names(tmp_path) == sorted([live.name, other.name, "out.csv"])


def test_a_long_target_name_gets_a_temporary_name_that_fits(tmp_path: Path) -> None:
    target = tmp_path / ("m" * 240 + ".csv")
    with atomic_text(target) as handle:
        handle.write("x\n")
    assert target.read_text() == "x\n"


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_a_written_file_has_the_usual_permissions(tmp_path: Path, umask: int,
                                                  mode: int) -> None:
    # As open() would make it (0o666 less the umask), not mkstemp's private 0o600: a map must
    # be readable by the ROS node of another user when the umask says so.
    import os

    old = os.umask(umask)
    try:
        with atomic_text(tmp_path / "map.csv") as handle:
            handle.write("x\n")
    finally:
        os.umask(old)
    assert (tmp_path / "map.csv").stat().st_mode & 0o777 == mode


def test_a_live_writer_of_this_process_keeps_its_temporary(tmp_path: Path) -> None:
    target = tmp_path / "map.csv"
    with atomic_path(target) as tmp:
        tmp.write_text("partial")
        assert remove_stale(target) == []  # another writer of the same file, same process
        assert tmp.exists()
    assert target.read_text() == "partial"


def test_atomic_paths_keep_each_target_s_suffix_on_its_temporary(tmp_path: Path) -> None:
    # Writers that choose a format by the file's ending (an image by .png) see the target's.
    with atomic_paths(tmp_path / "a.png", tmp_path / "b.yaml") as (png, yml):
        assert (png.suffix, yml.suffix) == (".png", ".yaml")
        png.write_bytes(b"1")
        yml.write_bytes(b"2")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "b.yaml"]
