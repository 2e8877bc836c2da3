"""How long ``import sonarcarve`` and ``sonarcarve --version`` take, warm (issue 8: < 0.5 s).

Each is run in a fresh interpreter ``REPEAT`` times after one warm-up (which fills the bytecode
cache); the median is reported, with a bare ``python -c pass`` measured in the same run as the
baseline interpreter start. Run: ``.venv/bin/python benchmarks/import_time.py``.
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPEAT = 9


def _median_seconds(command: list[str]) -> float:
    subprocess.run(command, check=True, capture_output=True)  # warm-up
    times = []
    for _ in range(REPEAT):
        tic = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - tic)
    return statistics.median(times)


def main() -> None:
    cli = shutil.which("sonarcarve") or str(Path(sys.executable).with_name("sonarcarve"))
    cases = {
        "python -c pass (interpreter start)": [sys.executable, "-c", "pass"],
        "import sonarcarve": [sys.executable, "-c", "import sonarcarve"],
        "import sonarcarve, sonarcarve.methods, sonarcarve.io": [
            sys.executable, "-c", "import sonarcarve, sonarcarve.methods, sonarcarve.io"],
        "sonarcarve --version": [cli, "--version"],
        "sonarcarve --help": [cli, "--help"],
    }
    print(f"| command | median of {REPEAT} runs, s |")
    print("|---|---:|")
    for label, command in cases.items():
        print(f"| `{label}` | {_median_seconds(command):.3f} |")


if __name__ == "__main__":
    main()
