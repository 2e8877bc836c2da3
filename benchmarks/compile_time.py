"""Where `sonarcarve warm`'s minutes go: compile seconds per step and per kernel, tree by tree.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/compile_time.py                      # this checkout
    nice .venv/bin/python benchmarks/compile_time.py --trees 2dd8a0c WORKTREE --together

Each tree's ``src`` (``WORKTREE``: this checkout's; otherwise a commit, exported with ``git
archive``) runs every step of :func:`sonarcarve.warm.warm_steps` in a child process with an empty
numba cache of its own, and numba's compile events (which fire only for a real compile, never
for a cache load) time every kernel. A kernel's *own* seconds exclude the kernels compiled while
it was being compiled (its callees), so the column adds up to the whole. ``--together`` runs the
trees at the same time, one core each, so a busy machine slows both alike (compiling is
single-threaded); without it they run one after the other.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from commits import child_env, export_src

WORKTREE = "WORKTREE"
ROOT = Path(__file__).resolve().parent.parent

# Run in each child: warm every step with a listener on numba's compile events; print JSON.
CHILD = r"""
import json, sys, time
from numba.core import event
import sonarcarve.warm as warm

stack, own, steps = [], {}, []

def name_of(ev):
    f = ev.data["dispatcher"].py_func
    return f"{f.__module__.removeprefix('sonarcarve.')}.{f.__qualname__}"

class Timer(event.Listener):
    def on_start(self, ev):
        stack.append([name_of(ev), time.perf_counter(), 0.0])

    def on_end(self, ev):
        name, start, inner = stack.pop()
        took = time.perf_counter() - start
        own[name] = own.get(name, 0.0) + took - inner
        if stack:
            stack[-1][2] += took

event.register("numba:compile", Timer())
wanted = sys.argv[1:]
for what, step in warm.warm_steps():
    if wanted and not any(word in what for word in wanted):
        continue
    tic = time.perf_counter()
    step()
    steps.append([what, time.perf_counter() - tic])
print(json.dumps({"steps": steps, "own": own}))
"""


def start(tree: str, scratch: Path, steps: list[str] | None = None) -> subprocess.Popen[str]:
    """A child compiling ``tree``'s warm steps (those whose name holds one of ``steps``; all by
    default) into an empty numba cache under ``scratch``."""
    src = ROOT / "src" if tree == WORKTREE else export_src(tree, scratch / tree)
    env = child_env(src, scratch / f"numba-{tree}")
    return subprocess.Popen([sys.executable, "-c", CHILD, *(steps or [])], env=env, text=True,
                            stdout=subprocess.PIPE)


def finish(tree: str, child: subprocess.Popen[str]) -> dict[str, Any]:
    """The child's result: ``steps`` (name, wall seconds) and ``own`` (kernel: own seconds)."""
    out, _ = child.communicate()
    if child.returncode != 0:
        raise SystemExit(f"compile_time.py: the child for {tree} failed")
    result: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    return result


def _print(tree: str, result: dict[str, Any], top: int) -> None:
    steps: list[tuple[str, float]] = result["steps"]
    own: dict[str, float] = result["own"]
    total = sum(seconds for _, seconds in steps)
    print(f"\n{tree}: warm steps, wall seconds (total {total:.1f} s, {len(own)} kernels)\n")
    print("| step | seconds |\n|---|---:|")
    for what, seconds in steps:
        print(f"| {what} | {seconds:.1f} |")
    print(f"\n{tree}: the {top} kernels with the most compile seconds of their own\n")
    print("| kernel | own seconds |\n|---|---:|")
    for name, seconds in sorted(own.items(), key=lambda kv: -kv[1])[:top]:
        print(f"| {name} | {seconds:.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trees", nargs="+", default=[WORKTREE],
                        help=f"commits or {WORKTREE} (this checkout), each with an empty cache")
    parser.add_argument("--together", action="store_true",
                        help="run the trees at the same time (one core each) instead of in turn")
    parser.add_argument("--steps", nargs="+", default=None,
                        help="only the warm steps whose name holds one of these words")
    parser.add_argument("--top", type=int, default=12, help="kernels listed per tree")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="compile-time-") as folder:
        scratch = Path(folder)
        results = {}
        if args.together:
            children = {tree: start(tree, scratch, args.steps) for tree in args.trees}
            results = {tree: finish(tree, child) for tree, child in children.items()}
        else:
            for tree in args.trees:
                results[tree] = finish(tree, start(tree, scratch, args.steps))
    for tree in args.trees:
        _print(tree, results[tree], args.top)


if __name__ == "__main__":
    main()
