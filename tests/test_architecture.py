"""The two halves hold at run time: importing the product loads neither the lab, the simulator
nor matplotlib, and the core works with only numpy, scipy and numba installed.

(``lint-imports`` checks the same shape statically in ``make test``, from the contracts in
``pyproject.toml``; these tests check what actually gets imported.)
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

#: Packages of the optional extras (cli, plot, ros); the core must not need them.
EXTRAS = ("typer", "rich", "yaml", "matplotlib", "PIL", "rosbags", "click")


def _run(*parts: str) -> subprocess.CompletedProcess[str]:
    code = "\n".join(textwrap.dedent(part) for part in parts)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False)


def test_the_product_imports_no_lab_no_simulator_no_matplotlib() -> None:
    done = _run("""
        import sys
        import sonarcarve, sonarcarve.methods, sonarcarve.io, sonarcarve.grids
        import sonarcarve.filters, sonarcarve.polling, sonarcarve.pipeline, sonarcarve.plotting
        import sonarcarve.cli.process, sonarcarve.cli.convert
        print(sorted(m for m in sys.modules if m.startswith(
            ('sonarcarve.sim', 'sonarcarve.lab', 'sonarcarve.evaluation', 'matplotlib'))))
    """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


# A meta-path finder that makes the extras' packages look uninstalled.
_WITHOUT_EXTRAS = f"""
    import importlib.abc, sys
    class Uninstalled(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split('.')[0] in {EXTRAS!r}:
                raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
            return None
    sys.meta_path.insert(0, Uninstalled())
"""


def test_the_core_maps_a_log_without_the_extras(tmp_path: object) -> None:
    done = _run(_WITHOUT_EXTRAS, f"""
        import math
        from sonarcarve import MethodConfig, Reading, make_method, process_readings
        from sonarcarve import ReadingBatch, read_readings_csv, write_map_csv, write_readings_csv
        batch = ReadingBatch.from_readings(
            [Reading(0.1 * i, i % 2, 0.05 * i, 0.0, math.pi / 2, 1.0) for i in range(40)])
        write_readings_csv(batch, r'{tmp_path}/r.csv')
        batch = read_readings_csv(r'{tmp_path}/r.csv')
        for name in ("centerline", "carve", "atm", "combined"):
            result = process_readings(batch, make_method(name, MethodConfig(history_size=10)))
            write_map_csv(result.global_map, r'{tmp_path}/' + name + '.csv')
        print("OK", sorted(m for m in sys.modules if m.split('.')[0] in {EXTRAS!r}))
    """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "OK []"


def test_a_missing_extra_is_named_in_one_line() -> None:
    done = _run(_WITHOUT_EXTRAS, """
        from sonarcarve.errors import SonarcarveError
        from sonarcarve.io import read_rosbag
        try:
            read_rosbag("nowhere.bag")
        except SonarcarveError as err:
            print(err)
    """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ROS bags need rosbags: pip install 'sonarcarve[ros]'"


def test_the_command_without_its_extra_says_what_to_install() -> None:
    done = _run(_WITHOUT_EXTRAS, """
        from sonarcarve.cli import main
        sys.exit(main(["--version"]))
    """)
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "sonarcarve: error: the command line needs typer: pip install 'sonarcarve[cli]'")
