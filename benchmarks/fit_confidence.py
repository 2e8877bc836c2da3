"""Fit evidence carving's confidence by logistic regression on the simulator's truth.

Run from the repository root::

    .venv/bin/python benchmarks/fit_confidence.py
    nice .venv/bin/python benchmarks/fit_confidence.py --worlds office random:4 random:5 --seeds 2
    nice .venv/bin/python benchmarks/fit_confidence.py --only behind
    nice .venv/bin/python benchmarks/fit_confidence.py --only alone --check

Training data: the runs of every ``--worlds`` world under every ``--physics`` physics (default:
ONE world and physics, the office tour under the specular physics, seeds 0-2; the arcs of
several runs are pooled, each arc one sample, and the direct share behind ``fresh`` is the
pool's). Each arc that leaves the history with a surviving piece is one sample: its features at that
moment (:meth:`~sonarcarve.methods.evidence.EvidenceMethod.features`, the order of
:data:`~sonarcarve.methods.evidence.CONFIDENCE_FEATURES`) and its label, 1 for a direct echo and
0 for a spurious one (crosstalk, floor, multipath). The weights minimise the mean log-loss plus
a small ridge (``--ridge``) by Newton's method (numpy only). The maturity time (how long the
logit takes to move from ``fresh`` to the fitted one, :class:`ConfidenceModel`) is then chosen on
the same runs: every ``--snapshot-every`` readings, every arc in the history with a surviving
piece is a sample of the local map (its features and age then); the time on ``--maturity-grid``
with the smallest mean log-loss over those samples is printed (each time scored with the
``unheard`` feature rebuilt for it). The weights themselves are fitted at the library's default
maturity time (it picks the mature arcs at commit and sets their ``unheard``; an arc no distinct
reading looked at squarely but that something supported never matures,
``ConfidenceModel.unwatched_prior``, so it is left out too: its confidence is the prior whatever
the weights; 0.2 % of the office's arcs, about a fifth of a Pioneer front ring's): a time chosen
here that differs from the default is a fixed point only once the default is changed and the
script run again. A ``min_confidence`` is then
chosen by one rule on the same training data: the largest threshold, on a 0.05 grid, that keeps
at least ``--keep`` (90 %) of *all* direct echoes (fully carved ones count as lost); shares are
printed for it and for 0.5 (the library default: the decision of a calibrated probability).

``--only NAME ...`` fits only those features' weights (:func:`fit_only`): the intercept, the
other weights, ``fresh`` and the maturity time stay the library default's. A new feature that
is 0 wherever the live map reads it (``behind``: judged only when the arc leaves the history)
then leaves that map as it was, bit for bit. ``alone`` (no other sensor's beam held the arc)
was fitted the same way, the library's other weights held: it is 1 for a few arcs of the
training ring, whose 22.5° beams just meet, and says where ``others`` could not have
confirmed an arc.

``--carve-probability P`` fits the confidence of evidence carving run with that P_carve (its
features change with it: ``free`` and ``looked`` are in units of the threshold, and what
survives changes). ``--without NAME ...`` leaves features out of the full fit (weight 0):
``behind``, which the live map never sees, is then fitted alone by ``--only behind --base
FILE``, the other weights held at FILE's, as the library's was (at P_carve 0.8 the two steps
give the library's weights to the third decimal). ``--save FILE`` writes the fitted model's
fields as JSON (``latency_openings.py --variant``, ``evidence.py --variant`` and ``heldout.py
--variant`` read it).

Printed: the weights as ``ConfidenceModel`` keyword arguments, the threshold, and a reliability
table (predicted confidence against the observed share of direct echoes, per decile of
confidence) on the training data and on each held-out world and physics (``--check``).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from sonarcarve import MethodConfig
from sonarcarve.geometry.fate import UNCHANGED
from sonarcarve.history import SonarHistory
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods.base import Estimates
from sonarcarve.methods.evidence import (
    CONFIDENCE_FEATURES,
    ConfidenceModel,
    EvidenceMethod,
    EvidenceModel,
)
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.typing import SlotArray


@dataclass(frozen=True)
class Samples:
    """Committed arcs with a surviving piece: features (n, F), labels (n,), and per run the
    number of direct echoes (kept or not)."""

    features: np.ndarray
    maturity: np.ndarray
    direct: np.ndarray
    kind: np.ndarray
    total_direct: int
    total_by_kind: dict[int, int]
    local: LocalSamples | None = None


@dataclass(frozen=True)
class LocalSamples:
    """Arcs of the local map at regular snapshots: features (n, F), whether the arc was never
    supported, age (s), labels (n,) and whether a distinct reading had looked squarely at it
    (an unwatched arc keeps the prior: ``ConfidenceModel.unwatched_prior``).

    The ``unheard`` column of ``features`` is ``unsupported * maturity(age)`` with the maturity
    time of the run that collected them; :meth:`features_at` rebuilds it for another time.
    """

    features: np.ndarray
    unsupported: np.ndarray
    age: np.ndarray
    direct: np.ndarray
    watched: np.ndarray

    def maturity_at(self, model: ConfidenceModel) -> np.ndarray:
        """The maturity ``model`` (its maturity time) gives these arcs."""
        return model.maturity(self.age, self.watched | self.unsupported)

    def features_at(self, model: ConfidenceModel) -> np.ndarray:
        """The features as ``model`` (its maturity time) would have computed them."""
        features = self.features.copy()
        features[:, CONFIDENCE_FEATURES.index("unheard")] = (
            self.unsupported * self.maturity_at(model))
        return features


def collect(world: str, physics: str, seeds: range,
            model: ConfidenceModel | None = None, snapshot_every: int = 0,
            carve_probability: float | None = None) -> Samples:
    """Simulate ``world`` under ``physics`` for ``seeds`` and record the committed arcs (and,
    with ``snapshot_every``, the local map's arcs every that many readings); evidence carving
    with the library's configuration, or ``carve_probability`` for P_carve."""
    local: list[tuple[np.ndarray, ...]] = []
    rows: list[np.ndarray] = []
    maturities: list[np.ndarray] = []
    kinds: list[np.ndarray] = []
    total_direct = 0
    total_by_kind: dict[int, int] = {}
    overrides = () if physics == "specular" else (("echo_model", physics),)
    config = MethodConfig(min_confidence=0.0)
    if carve_probability is not None:
        config = replace(config, carve_probability=carve_probability)
    for seed in seeds:
        sim = run_simulation(Scenario(world, seed, physics=overrides))  # type: ignore[arg-type]
        method = EvidenceMethod(
            config.history_size, config.beam_width, config.range_tolerance,
            config.min_transversal, config.range_resolution, config.evidence_bins,
            config.carve_probability, 0.0, config.stamp_error, config.stamp_heading_error,
            confidence_model=model)
        kind = sim.truth.kind

        def listener(history: SonarHistory, slots: SlotArray, est: Estimates,
                     method: EvidenceMethod = method, kind: np.ndarray = kind) -> None:
            has = est.fate == UNCHANGED
            if has.any():
                arcs = method.models[0]
                assert isinstance(arcs, EvidenceModel)
                raw = arcs.raw(slots[has])  # once, for both (it is not cheap)
                rows.append(method.features(slots[has], raw))
                maturities.append(method.maturity(slots[has], raw))
                kinds.append(kind[history.reading_id[slots[has]]])

        method.add_commit_listener(listener)
        if snapshot_every > 0:
            local += _snapshots(method, sim.readings, kind, snapshot_every)
        else:
            method.add_many(sim.readings)
        method.finish()
        total_direct += int(np.count_nonzero(kind == EchoKind.DIRECT))
        for k in np.unique(kind):
            count = int(np.count_nonzero(kind == k))
            total_by_kind[int(k)] = total_by_kind.get(int(k), 0) + count
    all_kinds = np.concatenate(kinds)
    direct = (all_kinds == EchoKind.DIRECT).astype(float)
    snapshots = None
    if local:
        features, unsupported, age, labels, watched = (np.concatenate(part)
                                                       for part in zip(*local, strict=True))
        snapshots = LocalSamples(features, unsupported, age, labels, watched)
    return Samples(np.vstack(rows), np.concatenate(maturities), direct, all_kinds, total_direct,
                   total_by_kind, snapshots)


def pooled(parts: list[Samples]) -> Samples:
    """The arcs of several :func:`collect` runs as one training set."""
    if len(parts) == 1:
        return parts[0]
    by_kind: dict[int, int] = {}
    for part in parts:
        for k, count in part.total_by_kind.items():
            by_kind[k] = by_kind.get(k, 0) + count
    return Samples(np.vstack([p.features for p in parts]),
                   np.concatenate([p.maturity for p in parts]),
                   np.concatenate([p.direct for p in parts]),
                   np.concatenate([p.kind for p in parts]),
                   sum(p.total_direct for p in parts), by_kind, _pooled_local(parts))


def _pooled_local(parts: list[Samples]) -> LocalSamples | None:
    """The local-map samples of every part, or None when a part has none."""
    local = [p.local for p in parts if p.local is not None]
    if len(local) < len(parts):
        return None
    return LocalSamples(np.vstack([loc.features for loc in local]),
                        np.concatenate([loc.unsupported for loc in local]),
                        np.concatenate([loc.age for loc in local]),
                        np.concatenate([loc.direct for loc in local]),
                        np.concatenate([loc.watched for loc in local]))


def _snapshots(method: EvidenceMethod, readings: ReadingBatch, kind: np.ndarray,
               every: int) -> list[tuple[np.ndarray, ...]]:
    """Add ``readings`` in blocks of ``every``; after each, the features, whether it was never
    supported, age (seconds), label (direct echo) and whether it was watched, of every arc in
    the history with a surviving piece."""
    out = []
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    for stop in range(every, len(readings) + every, every):
        block = readings[stop - every : min(stop, len(readings))]
        method.add_many(block)
        slots = method.history.slots()
        slots = slots[model.raw(slots)[0]]
        raw = model.raw(slots)
        support = raw[4]  # as EvidenceMethod.features reads it for ``unheard``
        now = float(block.t[-1])
        out.append((method.features(slots, raw), support <= 0.0, now - method.history.t[slots],
                    (kind[method.history.reading_id[slots]] == EchoKind.DIRECT).astype(float),
                    model.watched[slots].copy()))
    return out


def fit_maturity(model: ConfidenceModel, local: LocalSamples,
                 grid: tuple[float, ...]) -> tuple[float, list[float]]:
    """The maturity time on ``grid`` whose confidence has the smallest mean log-loss over the
    local map's arcs, and the log-loss of each time on the grid.

    Each time is scored with the model it names: its maturity moves the logit and also the
    ``unheard`` feature (never supported, times the maturity), rebuilt per time
    (:meth:`LocalSamples.features_at`). The weights of ``model`` stay those fitted at commit.
    """
    losses = []
    for t in grid:
        timed = replace(model, maturity_time=t)
        losses.append(_log_loss(timed.confidence(local.features_at(timed),
                                                 local.maturity_at(timed)), local.direct))
    return grid[int(np.argmin(losses))], losses


def _log_loss(confidence: np.ndarray, direct: np.ndarray) -> float:
    return float(-np.mean(direct * np.log(np.clip(confidence, 1e-12, 1.0))
                          + (1 - direct) * np.log(np.clip(1 - confidence, 1e-12, 1.0))))


def _newton(a: np.ndarray, labels: np.ndarray, penalty: np.ndarray, offset: np.ndarray | float,
            steps: int) -> np.ndarray:
    """Weights ``w`` minimising the mean log-loss of ``offset + a @ w`` plus
    ``sum(penalty/2 w²)`` (Newton's method, from 0)."""
    w = np.zeros(a.shape[1])
    for _ in range(steps):
        p = 1.0 / (1.0 + np.exp(-(offset + a @ w)))
        grad = a.T @ (p - labels) / len(a) + penalty * w
        hess = (a * (p * (1.0 - p))[:, None]).T @ a / len(a) + np.diag(penalty) + 1e-9 * np.eye(
            a.shape[1])
        step = np.linalg.solve(hess, grad)
        w -= step
        if np.max(np.abs(step)) < 1e-10:
            break
    return w


def fit(features: np.ndarray, labels: np.ndarray, ridge: float,
        steps: int = 50) -> tuple[float, np.ndarray]:
    """Intercept and weights minimising mean log-loss + ``ridge/2 |w|²`` (Newton's method)."""
    a = np.column_stack([np.ones(len(features)), features])
    penalty = np.full(a.shape[1], ridge)
    penalty[0] = 0.0  # the intercept is not shrunk
    w = _newton(a, labels, penalty, 0.0, steps)
    return float(w[0]), w[1:]


def fit_only(features: np.ndarray, labels: np.ndarray, names: tuple[str, ...],
             base: ConfidenceModel, ridge: float, steps: int = 50) -> ConfidenceModel:
    """``base`` with only the weights of ``names`` refitted: mean log-loss +
    ``ridge/2 |w|²`` over those weights (Newton's method), the logit of every sample offset by
    ``base``'s intercept and its other weights' terms, which are held."""
    columns = [CONFIDENCE_FEATURES.index(name) for name in names]
    held = base.weights()
    held[columns] = 0.0
    offset = base.intercept + features @ held
    w = _newton(features[:, columns], labels, np.full(len(columns), ridge), offset, steps)
    return replace(base, **{name: float(v) for name, v in zip(names, w, strict=True)})


def threshold_keeping(confidence: np.ndarray, samples: Samples, keep: float) -> float:
    """Largest threshold on a 0.05 grid keeping ≥ ``keep`` of all direct echoes."""
    best = 0.0
    for t in np.arange(0.0, 1.0, 0.05):
        kept = np.count_nonzero((confidence >= t) & (samples.direct == 1.0))
        if kept >= keep * samples.total_direct:
            best = float(round(t, 2))
    return best


def report(title: str, samples: Samples, model: ConfidenceModel,
           thresholds: tuple[float, ...]) -> None:
    """Reliability table and the kept/removed shares at each of ``thresholds``."""
    conf = model.confidence(samples.features, samples.maturity)
    young = np.count_nonzero(samples.maturity < 1.0)
    print(f"\n{title}: {len(conf)} arcs with a piece at commit ({young} not mature)\n")
    print("| confidence | arcs | mean confidence | direct share |")
    print("|---|---:|---:|---:|")
    edges = np.linspace(0.0, 1.0, 11)
    for lo, hi in itertools.pairwise(edges):
        sel = (conf >= lo) & ((conf < hi) | (hi == 1.0))
        if sel.any():
            print(f"| {lo:.1f}-{hi:.1f} | {np.count_nonzero(sel)} | {conf[sel].mean():.2f} | "
                  f"{samples.direct[sel].mean():.2f} |")
    print(f"\nlog-loss {_log_loss(conf, samples.direct):.3f}")
    for threshold in thresholds:
        kept = conf >= threshold
        direct_kept = np.count_nonzero(kept & (samples.direct == 1.0)) / samples.total_direct
        parts = [f"direct kept {100 * direct_kept:.1f} %"]
        for k in (EchoKind.CROSSTALK, EchoKind.FLOOR, EchoKind.MULTIPATH):
            total = samples.total_by_kind.get(int(k), 0)
            if total:
                removed = 1.0 - np.count_nonzero(kept & (samples.kind == k)) / total
                parts.append(f"{k.label} removed {100 * removed:.1f} % (of {total})")
        print(f"- min_confidence {threshold:.2f}: {'; '.join(parts)}")


def _positive_int(text: str) -> int:
    """An argparse type: an integer ≥ 1 (argparse turns the error into a usage message)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        msg = f"must be an integer of at least 1, not {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def fit_model(train: Samples, ridge: float,
              maturity_grid: tuple[float, ...]) -> tuple[ConfidenceModel, list[float]]:
    """Weights fitted on the mature arcs at commit, ``fresh`` from the direct share, then the
    maturity time on ``maturity_grid`` (:func:`fit_maturity`); and the grid's log-losses."""
    mature = train.maturity >= 1.0
    intercept, weights = fit(train.features[mature], train.direct[mature], ridge)
    share = float(train.direct.mean())
    fresh = float(np.log(share / (1.0 - share)))
    model = ConfidenceModel.from_weights(intercept, weights, fresh)
    assert train.local is not None  # snapshot_every >= 1 (_positive_int)
    maturity_time, losses = fit_maturity(model, train.local, maturity_grid)
    return replace(model, maturity_time=maturity_time), losses


def print_model(model: ConfidenceModel) -> None:
    """``model`` as ``ConfidenceModel`` keyword arguments (paste-able)."""
    print("ConfidenceModel(")
    print(f"    intercept={model.intercept:.3f},")
    print(f"    fresh={model.fresh:.3f},")
    print(f"    maturity_time={model.maturity_time:g},")
    for name, w in zip(CONFIDENCE_FEATURES, model.weights(), strict=True):
        print(f"    {name}={w:.3f},")
    print(")")


def main(argv: list[str] | None = None) -> int:
    """Fit on the training worlds and physics, print the weights, check on the others."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", "--world", nargs="+", default=["office"],
                        help="training worlds (every one under every --physics)")
    parser.add_argument("--physics", nargs="+", default=["specular"],
                        help="training physics: specular, or an echo_model such as amplitude")
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1")
    parser.add_argument("--ridge", type=float, default=1e-3)
    parser.add_argument("--keep", type=float, default=0.90)
    parser.add_argument("--snapshot-every", type=_positive_int, default=20,
                        help="readings between local-map samples for the maturity time")
    parser.add_argument("--maturity-grid", type=float, nargs="+",
                        default=[0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0],
                        help="maturity times tried, seconds")
    parser.add_argument("--only", nargs="+", choices=CONFIDENCE_FEATURES, metavar="FEATURE",
                        help="fit only these features' weights, the rest held at the "
                             "library default's (fit_only)")
    parser.add_argument("--check", nargs="*", default=[
        "t-junction/specular", "doorway/specular", "office/amplitude", "t-junction/amplitude",
        "doorway/amplitude"], help="held-out world/physics pairs")
    parser.add_argument("--carve-probability", type=float, default=None,
                        help="P_carve of the runs (default: the library's)")
    parser.add_argument("--without", nargs="+", default=[], choices=CONFIDENCE_FEATURES,
                        metavar="FEATURE",
                        help="full fit with these features left out (weight 0), e.g. behind, "
                             "to fit it alone afterwards with --only and --base")
    parser.add_argument("--base", metavar="JSON",
                        help="with --only: the model whose other weights are held (default: "
                             "the library's)")
    parser.add_argument("--save", metavar="JSON",
                        help="also write the fitted model's fields to this file")
    args = parser.parse_args(argv)
    train = pooled([collect(world, physics, range(args.seeds),
                            snapshot_every=args.snapshot_every,
                            carve_probability=args.carve_probability)
                    for physics in args.physics for world in args.worlds])
    if args.only:
        mature = train.maturity >= 1.0
        base = (ConfidenceModel() if args.base is None else ConfidenceModel(
            **json.loads(Path(args.base).read_text(encoding="utf-8"))))
        model = fit_only(train.features[mature], train.direct[mature], tuple(args.only),
                         base, args.ridge)
        assert train.local is not None  # snapshot_every >= 1 (_positive_int)
        _, losses = fit_maturity(model, train.local, tuple(args.maturity_grid))
    else:
        if args.without:
            train.features[:, [CONFIDENCE_FEATURES.index(n) for n in args.without]] = 0.0
            assert train.local is not None
            train.local.features[:, [CONFIDENCE_FEATURES.index(n) for n in args.without]] = 0.0
        model, losses = fit_model(train, args.ridge, tuple(args.maturity_grid))
    threshold = threshold_keeping(model.confidence(train.features, train.maturity), train,
                                  args.keep)
    worlds, physics = ", ".join(args.worlds), ", ".join(args.physics)
    print(f"fitted on {worlds}, {physics} physics, seeds 0-{args.seeds - 1}: "
          f"{len(train.direct)} arcs ({int(train.direct.sum())} direct)\n")
    print_model(model)
    if args.save:
        Path(args.save).write_text(json.dumps(dataclasses.asdict(model), indent=1),
                                   encoding="utf-8")
    assert train.local is not None  # every part was collected with snapshots
    print(f"local-map log-loss by maturity time ({len(train.local.direct)} samples): "
          + ", ".join(f"{t:g} s {loss:.4f}" for t, loss in
                      zip(args.maturity_grid, losses, strict=True)))
    print(f"min_confidence (largest keeping ≥ {100 * args.keep:.0f} % of direct): {threshold:.2f}")
    thresholds = (0.5, threshold)
    report(f"train: {'+'.join(args.worlds)}/{'+'.join(args.physics)}", train, model, thresholds)
    for pair in args.check:
        world, check_physics = pair.split("/")
        report(f"held out: {world}/{check_physics}",
               collect(world, check_physics, range(args.seeds),
                       carve_probability=args.carve_probability), model, thresholds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
