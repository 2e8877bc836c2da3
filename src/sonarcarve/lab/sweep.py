"""Parameter sweeps: a grid of parameters × worlds × seeds × methods, one tidy table, resumable.

A :class:`SweepSpec` names the grid (from a small YAML file, :func:`load_sweep_spec`, or the
command line); :func:`run_sweep` simulates each distinct scenario once, runs every method at
every grid point on it (analysed as the sensitivity experiment's runs are:
:func:`~sonarcarve.lab.analyses.analyse_sweep`) on a :class:`~sonarcarve.runner.Runner`,
and writes into its folder:

* ``runs.jsonl``: one line per finished run, appended (one ``write`` of a whole line) as each
  run finishes; each line carries ``run_id``, a hash of everything the run's result depends
  on. Rerunning the sweep into the same folder skips the runs already there, so an interrupted
  sweep resumes where it stopped and a grown grid runs only its new points.
* ``runs.csv`` (and ``runs.parquet`` when pyarrow is installed): the tidy table, one row per
  run of this spec in plan order, every parameter and every measure as a column.
* ``sweep.png``: each measure against each parameter, one line per method (mean over the other
  parameters, worlds and seeds).

Parameters (:data:`PARAMETERS`): ``history``, ``range_tolerance`` (ε, m), ``min_transversal_deg``
(ψ), ``max_incidence_deg`` (β), ``beam_width_deg`` (φ, both the simulated sonar and the
methods), ``speed`` (m/s), ``range_noise`` (m), and any :class:`~sonarcarve.methods.MethodConfig`
field by its own name, in its own SI unit.
"""

from __future__ import annotations

import csv
import hashlib
import importlib
import io
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from itertools import product
from pathlib import Path
from typing import Any

from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.extras import require
from sonarcarve.io.atomic import atomic_path, atomic_text, make_output_dir
from sonarcarve.io.errors import load_yaml
from sonarcarve.lab.experiments.jobs import run_job
from sonarcarve.lab.plan import ALL_METHODS, Job
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import METHODS, MethodConfig
from sonarcarve.methods.carving import DEFAULT_RANGE_TOLERANCE
from sonarcarve.methods.config import check_degrees
from sonarcarve.runner import ProgressCallback, Ref, Runner, SerialRunner, Task
from sonarcarve.sim.motion import DEFAULT_SPEED
from sonarcarve.typing import JsonDict

__all__ = [
    "MEASURES",
    "PARAMETERS",
    "SweepError",
    "SweepResult",
    "SweepSpec",
    "load_sweep_spec",
    "parse_values",
    "plan_runs",
    "run_sweep",
]

#: Bumped when what a run computes changes, so that old lines are not taken as finished.
SWEEP_FORMAT = 1

#: What each run reports (:func:`~sonarcarve.lab.analyses.analyse_sweep`), then its size.
MEASURES = ("error_median", "error_p90", "unprocessed", "fully_carved", "refined_share",
            "error_median_refined", "error_median_fallback", "fallback_median_range")

#: Named parameters -> what they set (``config`` field with a unit conversion, or
#: the scenario); any other MethodConfig field is taken by its name, as is.
PARAMETERS: dict[str, str] = {
    "history": "arcs kept in the history (MethodConfig.history_size)",
    "range_tolerance": "ε, metres",
    "min_transversal_deg": "ψ, degrees (ATM)",
    "max_incidence_deg": "β, degrees (specular-aware carving; 90 = off)",
    "beam_width_deg": "φ, degrees (the simulated sonar and the methods)",
    "speed": "robot speed, m/s",
    "range_noise": "range noise σ of the simulated sonar, metres",
}

#: Short names people type, for the named parameters.
ALIASES = {"epsilon": "range_tolerance", "psi": "min_transversal_deg",
           "beta": "max_incidence_deg", "phi": "beam_width_deg", "noise": "range_noise",
           "history_size": "history"}

_RUNS = "runs.jsonl"
_TABLE = "runs.csv"
_PARQUET = "runs.parquet"
_FIGURE = "sweep.png"


class SweepError(SonarcarveError):
    """A bad sweep: unknown parameter or method, empty grid, unreadable spec file."""


def _config_fields() -> tuple[str, ...]:
    return tuple(f.name for f in fields(MethodConfig))


def canonical_parameter(name: str) -> str:
    """``name`` as the table's column: aliases resolved, unknown names refused.

    Examples
    --------
    >>> canonical_parameter("psi")
    'min_transversal_deg'
    >>> canonical_parameter("range_resolution")
    'range_resolution'
    """
    key = ALIASES.get(name.strip(), name.strip())
    if key in PARAMETERS or key in _config_fields():
        return key
    known = sorted({*PARAMETERS, *ALIASES, *_config_fields()})
    msg = f"unknown sweep parameter {name!r}; choose from {', '.join(known)}"
    raise SweepError(msg)


@dataclass(frozen=True)
class SweepSpec:
    """A sweep: the grid, the worlds, seeds and methods, and the size of each run.

    Attributes
    ----------
    grid : tuple of (name, values)
        Each swept parameter (canonical name) and its values; the runs are their product.
    worlds : tuple of str
        Simulator worlds (any :func:`~sonarcarve.sim.world.load_world` spec with a tour).
    seeds : tuple of int
        Simulation seeds.
    methods : tuple of str
        Method names.
    length : float or None
        Metres of each world's tour to drive (None: all of it).
    sample_every : int
        Readings between two snapshots of the local map.
    """

    grid: tuple[tuple[str, tuple[float, ...]], ...] = ()
    worlds: tuple[str, ...] = ("office",)
    seeds: tuple[int, ...] = (0,)
    methods: tuple[str, ...] = ALL_METHODS
    length: float | None = 12.0
    sample_every: int = 32

    def __post_init__(self) -> None:
        names = [name for name, _ in self.grid]
        if len(set(names)) != len(names):
            msg = f"a sweep parameter is given twice: {', '.join(names)}"
            raise SweepError(msg)
        for name, values in self.grid:
            if canonical_parameter(name) != name:
                msg = f"sweep parameter {name!r}: use its name {canonical_parameter(name)!r}"
                raise SweepError(msg)
            if not values:
                msg = f"sweep parameter {name!r} has no values"
                raise SweepError(msg)
        for label, items in (("world", self.worlds), ("seed", self.seeds),
                             ("method", self.methods)):
            if not items:
                msg = f"a sweep needs at least one {label}"
                raise SweepError(msg)
        for method in self.methods:
            if method not in METHODS:
                msg = f"unknown method {method!r}; choose from {', '.join(METHODS)}"
                raise SweepError(msg)
        if self.length is not None and not (math.isfinite(self.length) and self.length > 0):
            msg = f"length must be > 0 metres (or none: the whole tour), got {self.length}"
            raise SweepError(msg)
        if self.sample_every < 1:
            msg = f"sample_every must be at least 1 reading, got {self.sample_every}"
            raise SweepError(msg)

    @property
    def parameters(self) -> tuple[str, ...]:
        """The swept parameters, in grid order."""
        return tuple(name for name, _ in self.grid)


def parse_values(text: str) -> tuple[float, ...]:
    """``"100,250,500"`` as numbers (whole numbers stay ints).

    Examples
    --------
    >>> parse_values("100, 250")
    (100, 250)
    >>> parse_values("0.01,0.05")
    (0.01, 0.05)
    """
    values: list[float] = []
    for part in text.split(","):
        item = part.strip()
        if not item:
            continue
        try:
            number = float(item)
        except ValueError:
            msg = f"sweep value {item!r} is not a number"
            raise SweepError(msg) from None
        values.append(int(number) if number.is_integer() and "." not in item
                      and "e" not in item.lower() else number)
    return tuple(values)


def load_sweep_spec(path: str | Path, **overrides: Any) -> SweepSpec:
    """Read a sweep from YAML; ``overrides`` (non-None) replace its fields.

    The file (every key optional)::

        grid:            # parameter: list of values (or "a,b,c")
          history: [100, 250, 500]
          epsilon: [0.0, 0.05]
        worlds: [office]
        seeds: [0, 1, 2]
        methods: [carve, combined]
        length: 12       # metres of the tour; null: all of it
        sample_every: 32
    """
    require("yaml", "cli", "sweep files")
    label = f"sweep file {path}"
    # The shared reader: "s.yaml: line 2, column 1: invalid YAML (...)", a missing or binary
    # file in one plain line, aliases limited (as robot and map_server YAML files).
    data = load_yaml(path, error_type=SweepError)
    data = {} if data is None else data
    if not isinstance(data, dict):
        msg = f"{label}: expected a mapping with grid, worlds, seeds, methods"
        raise SweepError(msg)
    unknown = set(data) - {"grid", "worlds", "seeds", "methods", "length", "sample_every"}
    if unknown:
        msg = f"{label}: unknown key(s) {', '.join(sorted(map(str, unknown)))}"
        raise SweepError(msg)
    grid_in = data.get("grid") or {}
    if not isinstance(grid_in, dict):
        msg = f"{label}: grid must map each parameter to a list of values"
        raise SweepError(msg)
    grid: dict[str, tuple[float, ...]] = {}
    for name, values in grid_in.items():
        items = values if isinstance(values, list) else [values]
        grid[canonical_parameter(str(name))] = parse_values(",".join(str(v) for v in items))
    fields_in: dict[str, Any] = {"grid": tuple(grid.items())}
    for key in ("worlds", "seeds", "methods"):
        if key in data:
            value = data[key]
            fields_in[key] = tuple(value if isinstance(value, list) else [value])
    if "seeds" in fields_in:
        fields_in["seeds"] = tuple(int(s) for s in fields_in["seeds"])
    if "worlds" in fields_in:
        fields_in["worlds"] = tuple(str(w) for w in fields_in["worlds"])
    for key in ("length", "sample_every"):
        if key in data:
            fields_in[key] = data[key]
    fields_in.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return SweepSpec(**fields_in)
    except (TypeError, ValueError) as err:
        msg = f"{label}: {' '.join(str(err).split())}"
        raise SweepError(msg) from None


@dataclass(frozen=True)
class PlannedRun:
    """One run of a sweep: where (world, seed), which method, which grid point."""

    run_id: str
    world: str
    seed: int
    method: str
    values: tuple[tuple[str, float], ...]
    job: Job

    def row(self, out: Mapping[str, Any]) -> JsonDict:
        """The table row: identity, parameters, measures, size and time."""
        row: JsonDict = {"run_id": self.run_id, "world": self.world, "seed": self.seed,
                         "method": self.method}
        row.update(dict(self.values))
        row.update({m: out.get(m) for m in MEASURES})
        row["readings"] = out.get("readings")
        row["seconds"] = out.get("seconds")
        return row


def _job(spec: SweepSpec, world: str, seed: int, method: str,
         values: Mapping[str, float]) -> Job:
    """The job of one run: parameters applied to the scenario and the method's config."""
    scenario = Scenario(world, seed, max_length=spec.length, speed=DEFAULT_SPEED)
    config = MethodConfig(range_tolerance=DEFAULT_RANGE_TOLERANCE)
    changes: dict[str, Any] = {}
    for name, value in values.items():
        if name == "history":
            changes["history_size"] = int(value)
        elif name == "min_transversal_deg":
            changes["min_transversal"] = math.radians(value)
        elif name == "max_incidence_deg":
            changes["max_incidence"] = (math.pi / 2 if value == 90 else math.radians(value))
        elif name == "beam_width_deg":
            scenario = replace(scenario, beam_width_deg=float(value))
            changes["beam_width"] = math.radians(value)
        elif name == "speed":
            scenario = replace(scenario, speed=float(value))
        elif name == "range_noise":
            scenario = replace(scenario, physics=(("range_noise", float(value)),))
        else:  # range_tolerance, or any MethodConfig field by its own name
            changes[name] = value
    for name in _DEGREE_PARAMETERS:
        if values.get(name) is not None:
            try:  # judged in degrees, as written in the sweep
                check_degrees(name.removesuffix("_deg"), values[name],
                              f"sweep point {dict(values)}: {name}")
            except ConfigError as err:
                raise SweepError(str(err)) from None
    try:
        config = replace(config, **changes)
    except (TypeError, ValueError) as err:
        msg = f"sweep point {dict(values)}: {' '.join(str(err).split())}"
        raise SweepError(msg) from None
    return Job(("sweep-run",), scenario, method, config, "sweep", spec.sample_every)


#: The sweep parameters given in degrees (``min_transversal_deg`` sets ``min_transversal``).
_DEGREE_PARAMETERS = ("min_transversal_deg", "max_incidence_deg", "beam_width_deg")


def _run_id(spec: SweepSpec, world: str, seed: int, method: str, job: Job) -> str:
    """A hash of everything a run's result depends on (not of how the grid is written)."""
    identity = {"format": SWEEP_FORMAT, "world": world, "seed": seed, "method": method,
                "scenario": repr(job.scenario), "config": repr(job.config),
                "sample_every": spec.sample_every}
    text = json.dumps(identity, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def plan_runs(spec: SweepSpec) -> list[PlannedRun]:
    """Every run of ``spec``, in table order (worlds, seeds, grid points, methods)."""
    names = spec.parameters
    runs = []
    for world, seed in product(spec.worlds, spec.seeds):
        for point in product(*(values for _, values in spec.grid)):
            values = tuple(zip(names, point, strict=True))
            for method in spec.methods:
                job = _job(spec, world, seed, method, dict(values))
                runs.append(PlannedRun(_run_id(spec, world, seed, method, job), world, seed,
                                       method, values, job))
    return runs


@dataclass(frozen=True)
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    rows : list of dict
        The table: one row per run of the spec, in plan order.
    ran : int
        Runs made now.
    skipped : int
        Runs found finished in the folder and not run again.
    simulations : int
        Simulations made now.
    files : list of Path
        What was written.
    """

    rows: list[JsonDict]
    ran: int
    skipped: int
    simulations: int
    files: list[Path]


def read_finished(folder: Path) -> dict[str, JsonDict]:
    """The finished runs in ``folder/runs.jsonl`` by run id (a torn last line is ignored)."""
    path = folder / _RUNS
    if not path.exists():
        return {}
    done: dict[str, JsonDict] = {}
    with path.open(encoding="utf-8") as handle:
        for line in handle:
            if not line.endswith("\n"):
                break  # a line cut short by a crash: that run is not finished
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(row, dict) and "run_id" in row:
                done.setdefault(str(row["run_id"]), row)
    return done


def _append(folder: Path, row: JsonDict) -> None:
    """Append one finished run as one line, in one ``write`` (O_APPEND), then sync it."""
    path = folder / _RUNS
    data = (json.dumps(row, allow_nan=False) + "\n").encode()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        if os.fstat(fd).st_size and not _ends_with_newline(path):
            data = b"\n" + data  # seal a torn line left by a crash, so this one stands alone
        os.write(fd, data)
        os.fsync(fd)
    finally:
        os.close(fd)


def _ends_with_newline(path: Path) -> bool:
    with path.open("rb") as handle:
        handle.seek(-1, os.SEEK_END)
        return handle.read(1) == b"\n"


def _strict(value: Any) -> Any:
    """NaN and infinities as None (strict JSON)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def run_sweep(
    spec: SweepSpec,
    out_dir: str | Path,
    *,
    runner: Runner | None = None,
    on_progress: ProgressCallback | None = None,
    figure: bool = True,
) -> SweepResult:
    """Run the runs of ``spec`` not yet in ``out_dir`` and write the table (and figure).

    Parameters
    ----------
    spec : SweepSpec
        The sweep.
    out_dir : path
        Its folder (created): ``runs.jsonl``, ``runs.csv``, ``runs.parquet`` (with pyarrow)
        and ``sweep.png``.
    runner : Runner, optional
        Where the runs go (default: this process); the table does not depend on it, except
        for the ``seconds`` column.
    on_progress : callable, optional
        ``on_progress(stage, done, total)``, stages ``"simulating"`` and ``"mapping"``.
    figure : bool
        Draw ``sweep.png`` (needs matplotlib).
    """
    runs = plan_runs(spec)  # first: a bad point is refused before any folder is made
    folder = make_output_dir(out_dir, label=f"--out {out_dir}")
    finished = read_finished(folder)
    todo = [run for run in runs if run.run_id not in finished]
    scenarios = list(dict.fromkeys(run.job.scenario for run in todo))
    index = {scenario: i for i, scenario in enumerate(scenarios)}
    tasks = [Task(run_simulation, (scenario,), "simulating", gather=False)
             for scenario in scenarios]
    tasks += [Task(run_job, (run.job, Ref(index[run.job.scenario])), "mapping")
              for run in todo]
    own = runner if runner is not None else SerialRunner()
    for i, out in own.run(tasks, on_progress=on_progress):
        run = todo[i - len(scenarios)]
        if run.run_id in finished:
            continue  # never twice, whatever the runner delivers
        row = {k: _strict(v) for k, v in run.row(out).items()}
        _append(folder, row)
        finished[run.run_id] = row
    rows = [finished[run.run_id] for run in runs]
    files = _write_table(folder, spec, rows)
    if figure:
        files.append(_write_figure(folder, spec, rows))
    return SweepResult(rows, len(todo), len(runs) - len(todo), len(scenarios), files)


def _columns(spec: SweepSpec) -> list[str]:
    return ["run_id", "world", "seed", "method", *spec.parameters, *MEASURES, "readings",
            "seconds"]


def _write_table(folder: Path, spec: SweepSpec, rows: Sequence[JsonDict]) -> list[Path]:
    columns = _columns(spec)
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow(["" if row.get(c) is None else
                         (repr(row[c]) if isinstance(row[c], float) else row[c])
                         for c in columns])
    path = folder / _TABLE
    with atomic_text(path) as handle:
        handle.write(text.getvalue())
    files = [path]
    try:
        pa = importlib.import_module("pyarrow")
        pq = importlib.import_module("pyarrow.parquet")
    except ImportError:
        return files  # Parquet only where pyarrow happens to be installed
    table = pa.table({c: [row.get(c) for row in rows] for c in columns})
    with atomic_path(folder / _PARQUET) as tmp:
        pq.write_table(table, tmp)
    files.append(folder / _PARQUET)
    return files


def _mean_by(rows: Sequence[JsonDict], param: str, method: str,
             measure: str) -> tuple[list[float], list[float]]:
    """Mean of ``measure`` per value of ``param`` for ``method`` (None values left out)."""
    groups: dict[float, list[float]] = {}
    for row in rows:
        if row["method"] == method and row.get(measure) is not None:
            groups.setdefault(float(row[param]), []).append(float(row[measure]))
    xs = sorted(groups)
    return xs, [sum(groups[x]) / len(groups[x]) for x in xs]


def _write_figure(folder: Path, spec: SweepSpec, rows: Sequence[JsonDict]) -> Path:
    """Each measure (rows of panels) against each parameter (columns), a line per method."""
    from sonarcarve.lab.drawing import save_pngs

    figure_module = require("matplotlib.figure", "plot", "sweep figures")
    params = list(spec.parameters) or ["seed"]
    measures = ("error_median", "error_p90", "unprocessed", "fully_carved", "refined_share")
    fig = figure_module.Figure(figsize=(3.2 * len(params) + 1, 2.2 * len(measures) + 0.5))
    axes = fig.subplots(len(measures), len(params), squeeze=False)
    for col, param in enumerate(params):
        for r, measure in enumerate(measures):
            ax = axes[r][col]
            for method in spec.methods:
                xs, ys = _mean_by(rows, param, method, measure)
                if xs:
                    ax.plot(xs, ys, marker="o", label=method)
            if r == len(measures) - 1:
                ax.set_xlabel(param)
            if col == 0:
                ax.set_ylabel(measure)
            ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize="small")
    fig.tight_layout()
    return save_pngs({_FIGURE: fig}, folder)[0]
