"""The numba cache key covers every kernel source, subpackages included."""

from __future__ import annotations

from pathlib import Path

from sonarcarve.geometry._compiled import KERNEL_FOLDERS, _sources_stamp


def _package(root: Path) -> Path:
    """A fake package tree: one module per kernel folder and one in a subpackage."""
    for folder in KERNEL_FOLDERS:
        (root / folder).mkdir(parents=True)
        (root / folder / "kernel.py").write_text("x = 1\n")
    (root / "grids" / "carved").mkdir()
    (root / "grids" / "carved" / "band.py").write_text("y = 2\n")
    return root


def test_an_edit_in_a_subpackage_changes_the_stamp(tmp_path: Path) -> None:
    package = _package(tmp_path)
    before = _sources_stamp(package)
    (package / "grids" / "carved" / "band.py").write_text("y = 3\n")
    assert _sources_stamp(package) != before


def test_a_moved_file_changes_the_stamp(tmp_path: Path) -> None:
    """The same bytes under another path are another module (another cache entry)."""
    package = _package(tmp_path)
    before = _sources_stamp(package)
    (package / "grids" / "carved" / "band.py").rename(package / "grids" / "band.py")
    assert _sources_stamp(package) != before


def test_files_outside_the_kernel_folders_do_not_count(tmp_path: Path) -> None:
    package = _package(tmp_path)
    before = _sources_stamp(package)
    (package / "cli").mkdir()
    (package / "cli" / "main.py").write_text("z = 1\n")
    assert _sources_stamp(package) == before


def test_the_installed_package_stamp_covers_its_kernel_packages() -> None:
    """Every subpackage holding kernels is inside a kernel folder, so rglob reaches it."""
    package = Path(__file__).resolve().parents[2] / "src" / "sonarcarve"
    nested = [p for f in KERNEL_FOLDERS for p in (package / f).rglob("*.py")
              if p.parent != package / f]
    assert any(p.parent.name == "carved" for p in nested)
    assert any(p.parent.name == "evidence" for p in nested)
