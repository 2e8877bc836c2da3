"""Ablation of evidence carving (``evidence``, beyond the paper) against the paper's carving.

Run from the repository root::

    .venv/bin/python benchmarks/evidence.py

For each sonar physics model (``specular``, the default, and ``amplitude``), world (office,
t-junction, doorway, their built-in tours) and seed, the Scout2 ring is simulated once and
mapped by every variant; the tables give means over seeds, per world and physics:

* *direct kept*: share of direct echoes (truth kind ``direct``) with a point in the global map
  (the map the method outputs by default);
* *removed* per spurious kind (crosstalk, floor, multipath) and all spurious together: share
  with no point in the global map;
* *median ratio*: median true error (distance to the nearest wall) of the method's points over
  the median of the centerline points of the *same readings*; *p90 ratio*: the map's 90th
  percentile over centerline's whole map's;
* *unprocessed*: mean share of the history not yet processed (Table I's measure);
* readings/s of the run (``process_readings``; noisy on these short logs).

Variants: ``carve`` (paper), ``carve β=30°`` (specular-aware), ``combined`` (paper, carving and
ATM); evidence carving with each part alone on top of the free-space evidence (``evidence
only``: graded evidence, split arcs kept, no ATM, no occlusion, no transmission, no confidence
filter; ``+occlusion``; ``+transmission``; ``+ATM``; ``+confidence``), ``evidence`` (all
together, the library defaults), the same with the confidence fitted before its ``repeated``
feature (issue 9's repeats: the previous default), with the same fit but ``repeated``'s weight
set to 0 (what the feature adds beyond the refit), with ``behind``'s weight 0 (the default
before that feature: only its weight was fitted), with every arc maturing with age alone
(``unwatched_prior`` False: the default before unwatched arcs kept the prior), with each point at
its run's middle (eq. 3.6) instead of at the median of its posterior (once its beam is cut), with
the placement before that posterior (the median of the localised support once cut, ATM's
median from one crossing), with the posterior placing the points of uncut beams too, and with
ATM's median from one crossing in the run (the default needs three), with split arcs dropped as
the paper drops them (issue 9's part 3 on its own), with finer profiles (K = 48 and 96 bins
per beam: how far the 24 bins are from exact), and the paper's carving with ε = 0 (the "carve"
row uses the library's 5 cm); and combined and evidence
with the occlusion map filter on their global maps (points 0.5 m or more behind a surface of
the finished map, on the line from their sensor, dropped: ``MapFilter(occlusion_depth=0.5)``).
``--variants`` picks rows, ``--per-seed`` adds each seed's direct kept and spurious removed;
``--variant P[:JSON]`` adds a row of evidence carving with P_carve ``P`` (and the confidence
model ``fit_confidence.py --save`` wrote).
``--no-echo`` adds a reading for every firing that heard nothing (range +inf, free space up to
the sensor's maximum range: what a ROS driver reports, REP 117) to each run; the echoes, and so
every kept and removed share, are those of the run without it.
A last table gives the roboND-sonar-8 log's line spread (the sharpness measure of
``lab/experiments/real_log.py``) and a throughput table times ``carve``, ``combined`` and
``evidence`` at history 250 on ``throughput.py``'s stream (after a warm-up, the three
interleaved, the best of 5 runs each: on a shared machine the fastest run is the one least
slowed by other processes).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from latency_openings import parse_variant, variant_method
from sonarcarve import MethodConfig, ReadingBatch, SonarMethod, make_method
from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter
from sonarcarve.lab.experiments.real_log import line_spread
from sonarcarve.lab.metrics import off_beam, segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods.evidence import ConfidenceModel, EvidenceMethod, EvidenceOptions
from sonarcarve.pipeline import ProcessResult, process_readings
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import NO_ECHO, EchoKind
from synthetic import corridor_stream

Factory = Callable[[MethodConfig], SonarMethod]


def _evidence(*, atm: bool = False, occlusion: bool = False, transmission: bool = False,
              confidence: bool = False) -> Factory:
    def make(config: MethodConfig) -> SonarMethod:
        c = config if confidence else replace(config, min_confidence=0.0)
        return EvidenceMethod(c.history_size, c.beam_width, c.range_tolerance,
                              c.min_transversal, c.range_resolution, c.evidence_bins,
                              c.carve_probability, c.min_confidence, c.stamp_error,
                              c.stamp_heading_error,
                              options=EvidenceOptions(atm=atm, occlusion=occlusion,
                                                      transmission=transmission))
    return make


def _all_with(confidence_model: ConfidenceModel | None = None, **options: Any) -> Factory:
    """Evidence carving with every part (the default), ``options`` the fields of its
    :class:`EvidenceOptions` and ``confidence_model`` on top of the config's values."""
    def make(c: MethodConfig) -> SonarMethod:
        return EvidenceMethod(c.history_size, c.beam_width, c.range_tolerance,
                              c.min_transversal, c.range_resolution, c.evidence_bins,
                              c.carve_probability, c.min_confidence, c.stamp_error,
                              c.stamp_heading_error, options=EvidenceOptions(**options),
                              confidence_model=confidence_model)
    return make


#: The default confidence before the ``repeated`` feature (fitted at 7bc4ab6 by
#: ``benchmarks/fit_confidence.py`` on the same runs): the comparison row of issue 9's repeats.
WITHOUT_REPEATS = ConfidenceModel(
    intercept=-3.645, support=0.277, viewpoints=0.942, crossings=0.668, free=-0.368,
    looked=0.290, split=-0.555, occluded=-0.471, unheard=-0.013, range=-0.063, width=0.549,
    others=3.386, through=0.285, repeated=0.0, behind=0.0, fresh=2.453, maturity_time=2.0,
    alone=0.0, looks_per_support=math.inf)  # fitted before alone and the normalisation


VARIANTS: dict[str, Factory] = {
    "carve (paper)": lambda c: make_method("carve", c),
    # The paper's carving with the paper's ε = 0 (the row above uses the library's 5 cm).
    "carve (paper, ε = 0)": lambda c: make_method("carve", replace(c, range_tolerance=0.0)),
    "carve β=30°": lambda c: make_method("carve", replace(c, max_incidence=math.radians(30.0))),
    "combined (paper)": lambda c: make_method("combined", c),
    "evidence only": _evidence(),
    "+occlusion": _evidence(occlusion=True),
    "+transmission": _evidence(transmission=True),
    "+ATM": _evidence(atm=True),
    "+confidence": _evidence(confidence=True),
    "evidence (all)": lambda c: make_method("evidence", c),
    "all, without repeats (fit before them)": _all_with(confidence_model=WITHOUT_REPEATS),
    "all, repeats' weight 0 (same fit)":
        _all_with(confidence_model=replace(ConfidenceModel(), repeated=0.0)),
    "all, behind's weight 0 (before behind)":
        _all_with(confidence_model=replace(ConfidenceModel(), behind=0.0)),
    "all, every arc matures (before watch)":
        _all_with(confidence_model=replace(ConfidenceModel(), unwatched_prior=False)),
    "all, point at the run's middle": _all_with(located_placement=False),
    "all, placement before the posterior (located median once cut, ATM from 1 crossing)":
        _all_with(posterior_placement=False, min_atm_crossings=1),
    "all, posterior on uncut beams too": _all_with(uncut_posterior=True),
    "all, posterior, ATM from 1 crossing": _all_with(min_atm_crossings=1),
    # Part 3 of issue 9 on its own: without it a split arc is dropped, as in the paper.
    "all, split arcs dropped (the paper's rule)": _all_with(keep_split=False),
    "evidence (all), K = 48 bins": lambda c: make_method("evidence", replace(c, evidence_bins=48)),
    "evidence (all), K = 96 bins": lambda c: make_method("evidence", replace(c, evidence_bins=96)),
}
#: Rows of a variant above whose global map then goes through the occlusion map filter
#: (``MapFilter(occlusion_depth=0.5)``: points behind a surface of the finished map dropped).
OCCLUDED = {"combined (paper), occluded points dropped": "combined (paper)",
            "evidence (all), occluded points dropped": "evidence (all)"}
VARIANTS.update({name: VARIANTS[base] for name, base in OCCLUDED.items()})


def _map_filter(name: str) -> MapFilter | None:
    """The occlusion filter for the rows of :data:`OCCLUDED`, None for the others."""
    return MapFilter(occlusion_depth=OCCLUSION_DEPTH) if name in OCCLUDED else None
KINDS = (EchoKind.CROSSTALK, EchoKind.FLOOR, EchoKind.MULTIPATH)
COLUMNS = ("direct_kept", "crosstalk", "floor", "multipath", "spurious", "median_ratio",
           "p90_ratio", "unprocessed", "readings_per_s")


def _measure(sim: Simulation, make: Factory, config: MethodConfig,
             centerline_err: np.ndarray, centerline_p90: float,
             map_filter: MapFilter | None = None) -> dict[str, float]:
    result = process_readings(sim.readings, make(config), map_filter=map_filter)
    return map_row(sim, result, centerline_err, centerline_p90)


def map_row(sim: Simulation, result: ProcessResult, centerline_err: np.ndarray,
            centerline_p90: float, told: ReadingBatch | None = None) -> dict[str, float]:
    """The columns of :data:`COLUMNS` for one method's run on ``sim`` (``centerline_err``:
    centerline's error per reading, NaN where it kept no point; ``centerline_p90``: its map's
    90th percentile), and three more that split the direct echoes by where their reflector
    lies against the beam the method was told (``told``'s beam widths, the simulation's
    readings by default; :func:`~sonarcarve.lab.metrics.off_beam`): ``off_beam`` (share of
    direct echoes from outside it), ``in_beam_kept`` and ``off_beam_removed``."""
    gmap = result.global_map
    kind = sim.truth.kind
    kept = np.zeros(len(kind), dtype=bool)
    kept[gmap.reading_id] = True
    err = segment_distance(gmap.xy, sim.world.segments)[0]
    direct = kind == EchoKind.DIRECT
    readings = sim.readings if told is None else told
    outside = direct & off_beam(np.column_stack([readings.x, readings.y]), readings.theta,
                                readings.beam_width, sim.truth.reflection)
    row = {"direct_kept": 100.0 * float(np.mean(kept[direct])),
           "off_beam": 100.0 * float(np.mean(outside[direct])),
           "in_beam_kept": 100.0 * float(np.mean(kept[direct & ~outside])),
           "off_beam_removed": 100.0 * float(np.mean(~kept[outside])) if outside.any()
           else math.nan}
    for k in KINDS:
        sel = kind == k
        row[k.label] = 100.0 * float(np.mean(~kept[sel])) if sel.any() else math.nan
    # A no-echo reading (``--no-echo``) is neither kind: it never makes a point.
    spurious = (kind != EchoKind.DIRECT) & (kind != NO_ECHO)
    row["spurious"] = 100.0 * float(np.mean(~kept[spurious]))
    same = float(np.median(centerline_err[gmap.reading_id]))
    row["median_ratio"] = float(np.median(err)) / same
    row["p90_ratio"] = float(np.percentile(err, 90.0)) / centerline_p90
    row["unprocessed"] = 100.0 * result.mean_unprocessed_share
    row["readings_per_s"] = result.readings_per_second
    return row


def _pct(value: float) -> str:
    """A share with one decimal, "–" where the world has no such echo."""
    return "–" if math.isnan(value) else f"{value:.1f}"


def _table(title: str, rows: dict[str, list[dict[str, float]]]) -> None:
    print(f"\n{title}\n")
    print("| variant | direct kept (%) | crosstalk removed (%) | floor removed (%) | "
          "multipath removed (%) | spurious removed (%) | median / centerline's | "
          "p90 / centerline's | unprocessed (%) | readings/s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, runs in rows.items():
        m = {c: float(np.nanmean([r[c] for r in runs])) for c in COLUMNS}
        print(f"| {name} | {m['direct_kept']:.1f} | {_pct(m['crosstalk'])} | "
              f"{_pct(m['floor'])} | {_pct(m['multipath'])} | {m['spurious']:.1f} | "
              f"{m['median_ratio']:.2f} | "
              f"{m['p90_ratio']:.2f} | {m['unprocessed']:.1f} | {m['readings_per_s']:,.0f} |")


def _per_seed(rows: dict[str, list[dict[str, float]]]) -> None:
    """Direct kept and spurious removed per seed (how thin a mean's margin is)."""
    print("\n| variant | direct kept per seed (%) | spurious removed per seed (%) |")
    print("|---|---|---|")
    for name, runs in rows.items():
        kept = " / ".join(f"{run['direct_kept']:.1f}" for run in runs)
        removed = " / ".join(_pct(run["spurious"]) for run in runs)
        print(f"| {name} | {kept} | {removed} |")


def _robond(config: MethodConfig, variants: dict[str, Factory]) -> None:
    from sonarcarve.io.roboND import read_robond

    batch = read_robond().batch
    cfg = replace(config, range_resolution=0.01)
    print("\nroboND-sonar-8 log (real, no truth): line spread (25 cm, 5 points), as in "
          "RESULTS\n")
    print("| variant | points | line spread median (cm) | p90 (cm) | isolated (%) |")
    print("|---|---:|---:|---:|---:|")
    for name, make in variants.items():
        gmap = process_readings(batch, make(cfg), map_filter=_map_filter(name)).global_map
        spread = line_spread(gmap.xy, 0.25, 5).spread
        ok = np.isfinite(spread)
        print(f"| {name} | {len(gmap)} | {100 * np.median(spread[ok]):.1f} | "
              f"{100 * np.percentile(spread[ok], 90):.1f} | {100 * np.mean(~ok):.0f} |")


def _throughput(history: int = 250, repeats: int = 5) -> None:
    batch = corridor_stream(20_000, noise=0.01, spurious_share=0.05, seed=0).batch

    def run(name: str, readings: ReadingBatch) -> float:
        method = make_method(name, MethodConfig(history_size=history))
        tic = time.perf_counter()
        method.add_many(readings)
        method.finish()
        return time.perf_counter() - tic

    print(f"\nthroughput: history {history}, ring corridor, {len(batch):,} readings, best "
          f"of {repeats} interleaved runs\n")
    print("| method | readings/s |")
    print("|---|---:|")
    names = ("carve", "combined", "evidence")
    for name in names:
        run(name, batch[:2000])
    times: dict[str, list[float]] = {name: [] for name in names}
    for _ in range(repeats):
        for name in names:
            times[name].append(run(name, batch))
    rates = {name: len(batch) / min(times[name]) for name in names}
    for name in names:
        print(f"| {name} | {rates[name]:,.0f} |")
    print(f"\nevidence / carve: {rates['evidence'] / rates['carve']:.2f}")


def _with_no_echo(sim: Simulation) -> Simulation:
    """The same run with a no-echo reading for every firing that heard nothing (its echoes,
    and so every echo's truth, are those of ``sim``)."""
    return simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics, sim.odometry,
                    scene=sim.scene, no_echo=True)


def main(argv: list[str] | None = None) -> int:
    """Simulate, measure and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=["office", "t-junction", "doorway"])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"])
    parser.add_argument("--skip-robond", action="store_true")
    parser.add_argument("--skip-throughput", action="store_true")
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), metavar="VARIANT",
                        help="only these rows (default: all; names as in the tables)")
    parser.add_argument("--no-echo", action="store_true",
                        help="simulate with no-echo readings too (a firing that heard nothing, "
                             "range +inf: free space up to max range, as ROS drivers report "
                             "it); the echoes are those of the default run")
    parser.add_argument("--per-seed", action="store_true",
                        help="also print direct kept and spurious removed per seed")
    parser.add_argument("--variant", nargs="+", default=[], type=parse_variant,
                        metavar="P[:JSON]",
                        help="add rows: evidence with P_carve P (and the confidence model of "
                             "JSON, as fit_confidence.py --save writes it)")
    args = parser.parse_args(argv)
    variants = {name: VARIANTS[name] for name in (args.variants or VARIANTS)}
    for variant in args.variant:
        variants[variant[0]] = (lambda c, v=variant: variant_method(c, v))
    config = MethodConfig()
    for physics in args.physics:
        overrides = () if physics == "specular" else (("echo_model", physics),)
        for world in args.worlds:
            rows: dict[str, list[dict[str, float]]] = {name: [] for name in variants}
            for seed in range(args.seeds):
                sim = run_simulation(Scenario(world, seed, physics=overrides))  # type: ignore[arg-type]
                if args.no_echo:
                    sim = _with_no_echo(sim)
                center = process_readings(sim.readings, make_method("centerline", config))
                c_err = np.full(len(sim.readings), np.nan)
                c_err[center.global_map.reading_id] = segment_distance(
                    center.global_map.xy, sim.world.segments)[0]
                c_p90 = float(np.nanpercentile(c_err, 90.0))
                for name, make in variants.items():
                    rows[name].append(_measure(sim, make, config, c_err, c_p90,
                                               _map_filter(name)))
            silent = ", with no-echo readings" if args.no_echo else ""
            _table(f"{world}, physics {physics}{silent}: {args.seeds} seeds, mean over seeds",
                   rows)
            if args.per_seed:
                _per_seed(rows)
    if not args.skip_robond:
        _robond(config, variants)
    if not args.skip_throughput:
        _throughput()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
