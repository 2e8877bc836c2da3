"""Figures of the simulated experiments (office, T junction, openings, sensitivity), drawn from
their results (plain dicts, as in ``results.json``) and artifacts (arrays).

matplotlib is imported inside each function with the Agg backend, so nothing here needs a
display or slows down importing the package. Each ``plot_*`` function draws on the axes it is
given (or a new figure) and returns the figure; the experiments
(:mod:`sonarcarve.lab.experiments`) save them. The appendix experiments draw their own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from sonarcarve.lab.drawing import METHOD_COLORS
from sonarcarve.maps import PointSource
from sonarcarve.plotting import new_figure, plot_sources, plot_walls
from sonarcarve.typing import JsonDict

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "SWEEP_LABELS",
    "plot_fig04",
    "plot_fig10",
    "plot_fig11",
    "plot_fig12",
    "plot_fig13",
    "plot_latency_accuracy",
    "plot_openings",
    "plot_sensitivity",
    "plot_true_error",
]


METHOD_ORDER = ("atm", "carving", "combined", "centerline", "evidence")


def _values(seq: Sequence[float | None]) -> npt.NDArray[np.float64]:
    return np.array([np.nan if v is None else v for v in seq], dtype=np.float64)


def _centers(edges: Sequence[float]) -> npt.NDArray[np.float64]:
    e = np.asarray(edges, dtype=np.float64)
    return np.asarray(0.5 * (e[1:] + e[:-1]))


def _binned_line(ax: Axes, entry: JsonDict, label: str, color: str, scale: float = 1.0,
                 style: str = "-o") -> None:
    """A per-range-bin line with its min-max band over seeds."""
    x = _centers(entry["edges"])
    y = _values(entry["value"]) * scale
    ax.plot(x, y, style, color=color, label=label, ms=3)
    if "min" in entry:
        ax.fill_between(x, _values(entry["min"]) * scale, _values(entry["max"]) * scale,
                        color=color, alpha=0.15, lw=0)


def _own_axes(ax: Axes | None, width: float = 7.0, height: float = 4.5) -> tuple[Figure, Axes]:
    if ax is not None:
        return ax.figure, ax  # type: ignore[return-value]
    fig, axes = new_figure(width=width, height=height)
    return fig, axes[0, 0]


#: Line styles of Fig. 10 that differ from ``-o``.
_FIG10_STYLE = {"combined": "--", "evidence": "-.^"}


def plot_fig10(fig10: JsonDict, ax: Axes | None = None) -> Figure:
    """Paper Fig. 10: percentage of history arcs unprocessed, by range (``fig10``: binned
    curves by method label)."""
    fig, ax = _own_axes(ax)
    for label in ("atm", "carving", "combined", "evidence"):
        if label in fig10:
            _binned_line(ax, fig10[label], label, METHOD_COLORS[label],
                         style=_FIG10_STYLE.get(label, "-o"))
    ax.set_xlabel("range of the reading (m)")
    ax.set_ylabel("unprocessed (% of history arcs)")
    ax.set_title("Fig. 10: unprocessed arcs by range (office tour; band: min-max over seeds)")
    ax.set_ylim(0, 100)
    ax.legend()
    ax.grid(alpha=0.3)
    return fig


def plot_fig11(f11: JsonDict, ax: Axes | None = None) -> Figure:
    """Paper Fig. 11: mean and median angular width of carved arcs, by range."""
    fig, ax = _own_axes(ax)
    _binned_line(ax, f11["carved_only"]["mean"], "carved arcs: mean", METHOD_COLORS["carving"])
    _binned_line(ax, f11["carved_only"]["median"], "carved arcs: median", "#17becf",
                 style="-s")
    _binned_line(ax, f11["all_surviving"]["mean"], "all surviving arcs: mean", "0.4",
                 style="--")
    ax.axhline(22.5, color="0.6", lw=0.8, ls=":", label="beam width φ (uncarved)")
    ax.set_xlabel("range of the reading (m)")
    ax.set_ylabel("final angular width θ_d (degrees)")
    ax.set_title("Fig. 11: angular width of carved arcs by range")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return fig


def plot_fig12(f12: JsonDict, ax: Axes | None = None) -> Figure:
    """Paper Fig. 12: mean maximum Euclidean error by range (eq. 5.3, 5.4)."""
    fig, ax = _own_axes(ax)
    _binned_line(ax, f12["carving"], "carving (measured, eq. 5.3)", METHOD_COLORS["carving"])
    _binned_line(ax, f12["centerline"], "centerline (E_m = φ/2)", METHOD_COLORS["centerline"])
    _binned_line(ax, f12["combined"], "combined (measured)", METHOD_COLORS["combined"],
                 style="--")
    if "evidence" in f12:
        _binned_line(ax, f12["evidence"], "evidence (measured)", METHOD_COLORS["evidence"],
                     style="-.^")
    ax.axhline(f12["atm_bound"], color=METHOD_COLORS["atm"], ls="-",
               label=f"ATM theoretical bound (eq. 5.4 × δ) = {f12['atm_bound']:.3f} m")
    ax.set_xlabel("range of the reading (m)")
    ax.set_ylabel("mean maximum error (m)")
    ax.set_title("Fig. 12: mean maximum Euclidean error by range")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return fig


def _walls(ax: Axes, segments: npt.ArrayLike) -> None:
    plot_walls(segments, ax, colors="0.75", linewidths=2.0)


def _robot(ax: Axes, xy: Sequence[float], radius: float = 0.205) -> None:
    from matplotlib.patches import Circle

    ax.add_patch(Circle((xy[0], xy[1]), radius, fill=False, color="k", lw=1.0, zorder=4))


def plot_fig04(tj: JsonDict, artifacts: JsonDict | None = None) -> Figure:
    """Paper Fig. 4: distance from the facing wall when each local map first shows it.

    Left: bars (mean over seeds, whiskers min-max) for all points and for refined points only;
    right: the local maps of ATM (refined points only, as in the paper), centerline, carving
    and evidence when the robot is about 4 m from the wall (seed 0).
    """
    snaps = (artifacts or {}).get("snapshots") or {}
    panels = [m for m in ("atm", "centerline", "carving", "evidence") if snaps.get(m)]
    fig, axes = new_figure(1, 1 + len(panels), width=4.2 + 3.0 * len(panels), height=5.0)
    ax = axes[0, 0]
    order = [m for m in METHOD_ORDER if m in tj["all"]]
    x = np.arange(len(order))
    for offset, kind, hatch in ((-0.2, "all", ""), (0.2, "refined", "//")):
        means = _values([tj[kind][m]["mean"] for m in order])
        lo = means - _values([tj[kind][m]["min"] for m in order])
        hi = _values([tj[kind][m]["max"] for m in order]) - means
        ax.bar(x + offset, np.nan_to_num(means), 0.4, yerr=np.nan_to_num([lo, hi]),
               color=[METHOD_COLORS[m] for m in order], hatch=hatch, alpha=0.85,
               edgecolor="k", label="any point" if kind == "all" else "refined points only")
        for xi, mean in zip(x + offset, means, strict=True):
            if not np.isfinite(mean):
                ax.text(xi, 0.1, "never", rotation=90, ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, order, rotation=30, ha="right")
    ax.set_ylabel("distance from the facing wall (m)")
    # Head room for the legend above the bars.
    tallest = np.nanmax(_values([tj["all"][m]["max"] for m in order]), initial=0.0)
    ax.set_ylim(0, 1.3 * tallest if np.isfinite(tallest) and tallest > 0 else None)
    ax.set_title(f"≥ {tj['points']} points within {tj['radius_m']:g} m of the wall")
    ax.legend(fontsize="small")
    for k, method in enumerate(panels, start=1):
        ax = axes[0, k]
        snap = dict(snaps[method])
        if method == "atm":
            keep = np.asarray(snap["source"]) == PointSource.ATM
            snap = {**snap, "xy": np.asarray(snap["xy"])[keep],
                    "source": np.asarray(snap["source"])[keep]}
        _walls(ax, snap["world"])
        plot_sources(snap["xy"], snap["source"], ax, 6.0)
        _robot(ax, snap["robot"])
        ax.set_aspect("equal")
        ax.set_xlim(-4.0, 4.0)
        ax.set_ylim(snap["robot"][1] - 3.0, snap["robot"][1] + snap["wall_distance"] + 1.0)
        title = "ATM (medians only)" if method == "atm" else method
        ax.set_title(f"{title}, {snap['wall_distance']:.1f} m from the wall", fontsize=9)
        ax.legend(fontsize=7, loc="lower right", markerscale=2)
    fig.suptitle("Fig. 4: T junction, when does the facing wall appear?")
    return fig


def plot_openings(op: JsonDict, artifacts: JsonDict | None = None) -> Figure:
    """Paper Fig. 2 and 9: share of runs whose local map shows the opening passable.

    Left: passable share by distance for each method (all opening runs); right: local maps at
    2 m of the example runs (seed 0): a doorway and the narrow hallway, per method.
    """
    snaps = (artifacts or {}).get("snapshots") or {}
    worlds = [w for w in ("doorway", "narrow-hallway") if snaps.get(w)]
    order = [m for m in METHOD_ORDER if m in op]
    methods = [m for m in ("centerline", "atm", "carving", "combined", "evidence") if m in op]
    rows = max(1, len(worlds))
    cols = 1 + (len(methods) if worlds else 0)
    fig, axes = new_figure(rows, cols, width=4.5 + 2.6 * (cols - 1), height=3.6 * rows)
    ax = axes[0, 0]
    distances = sorted(op[order[0]], key=float)
    x = np.arange(len(distances))
    bar = 0.8 / len(order)
    for k, m in enumerate(order):
        ax.bar(x + (k - 0.5 * (len(order) - 1)) * bar,
               [np.nan if op[m][d] is None else op[m][d] for d in distances], bar,
               color=METHOD_COLORS[m], label=m)
    ax.set_xticks(x, [f"{float(d):g} m" for d in distances])
    ax.set_xlabel("distance before the opening")
    ax.set_ylabel("runs with the opening passable (%)")
    ax.set_ylim(0, 130)
    ax.set_yticks(range(0, 101, 20))
    ax.legend(fontsize="small", loc="upper center", ncol=3, columnspacing=0.8,
              handlelength=1.2)
    ax.set_title("all opening runs")
    for r in range(1, rows):
        axes[r, 0].axis("off")
    for r, world in enumerate(worlds):
        for c, method in enumerate(methods, start=1):
            ax = axes[r, c]
            snap = snaps[world].get(method)
            if snap is None:
                ax.axis("off")
                continue
            _walls(ax, snap["world"])
            gap = np.asarray(snap["opening"])
            ax.plot(gap[:, 0], gap[:, 1], color="orange", lw=1.0, ls="--", zorder=2)
            plot_sources(snap["xy"], snap["source"], ax, 5.0)
            _robot(ax, snap["robot"])
            centre = gap.mean(axis=0)
            ax.set_xlim(centre[0] - 2.2, centre[0] + 2.2)
            ax.set_ylim(centre[1] - 3.2, centre[1] + 1.0)
            ax.set_aspect("equal")
            ax.set_title(f"{world}: {method}", fontsize=9)
            ax.tick_params(labelsize=7)
    fig.suptitle("Fig. 2 and 9: narrow openings (dashed: the gap; maps at 2 m before it)")
    return fig


def plot_fig13(threshold: float, artifacts: JsonDict | None = None) -> Figure | None:
    """Paper Fig. 13: final global maps of ATM (medians) and carving (max-error thresholded)."""
    maps = (artifacts or {}).get("fig13") or {}
    if not maps.get("atm") or not maps.get("carving"):
        return None
    # Show the part of the building the tour mapped (the walls' box is much larger).
    every = np.vstack([np.asarray(maps[m]["xy"]).reshape(-1, 2) for m in ("atm", "carving")])
    lo = np.percentile(every, 0.5, axis=0) - 2.0 if len(every) else np.zeros(2)
    hi = np.percentile(every, 99.5, axis=0) + 2.0 if len(every) else np.ones(2)
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-9)
    fig, axes = new_figure(1, 2, width=15.0, height=min(12.0, 1.0 + 7.5 * aspect))
    for ax, method in zip(axes[0], ("atm", "carving"), strict=True):
        data = maps[method]
        _walls(ax, data["world"])
        xy = np.asarray(data["xy"]).reshape(-1, 2)
        ax.scatter(xy[:, 0], xy[:, 1], s=1.2, c=METHOD_COLORS[method], linewidths=0, zorder=3)
        ax.set_aspect("equal")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        title = ("(a) ATM map: medians of transversal intersections" if method == "atm" else
                 f"(b) arc carving map: max error ≤ {threshold:.3f} m")
        ax.set_title(f"{title}\n(seed 0: {len(xy)} points)", fontsize=10)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    fig.suptitle("Fig. 13: final global maps, office tour seed 0 (grey: true walls)")
    return fig


def plot_true_error(by_range: JsonDict, ax: Axes | None = None) -> Figure:
    """True error of local-map points by range: median (solid) and 90th percentile (dashed)."""
    fig, ax = _own_axes(ax)
    for m in [m for m in METHOD_ORDER if m in by_range]:
        entry = by_range[m]
        _binned_line(ax, entry["median"], f"{m} median", METHOD_COLORS[m])
        _binned_line(ax, entry["p90"], f"{m} p90", METHOD_COLORS[m], style=":")
    ax.set_yscale("log")
    ax.set_xlabel("range of the reading (m)")
    ax.set_ylabel("distance of local-map points to the true walls (m)")
    ax.set_title("True error of local-map points by range (office tour)")
    ax.legend(fontsize="x-small", ncol=2)
    ax.grid(alpha=0.3, which="both")
    return fig


def plot_latency_accuracy(la: JsonDict) -> Figure:
    """Share of wall patches whose local-map points are right, against time and distance."""
    order = [m for m in METHOD_ORDER if m in la]
    tolerances = [k for k in la[order[0]] if k != "patches_seen"]
    fig, axes = new_figure(len(tolerances), 2, width=11.0, height=3.6 * len(tolerances))
    for r, tol in enumerate(tolerances):
        for c, (grid, key, unit) in enumerate(((la["grid_s"], "curve_s", "s"),
                                               (la["grid_m"], "curve_m", "m"))):
            ax = axes[r, c]
            for m in order:
                ax.plot(grid, la[m][tol][key], color=METHOD_COLORS[m], label=m)
            ax.set_xlabel(f"delay since the patch came into view ({unit})" if unit == "s"
                          else "distance travelled since the patch came into view (m)")
            ax.set_ylabel(f"patches within {float(tol) * 100:g} cm (%)")
            ax.set_ylim(0, 100)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize="small")
    fig.suptitle(f"Latency against accuracy: {la['patch_length_m']:g} m wall patches, "
                 "half of their local-map points within the tolerance")
    return fig


#: Each swept parameter of the sensitivity experiment in words, with its unit.
SWEEP_LABELS = {
    "history": "history length (arcs)",
    "range_tolerance": "range tolerance ε (m)",
    "beam_width_deg": "beam width φ (deg)",
    "min_transversal_deg": "minimum transversal angle ψ (deg)",
    "speed": "speed (m/s)",
    "range_noise": "range noise σ (m)",
}

#: Line style of each method in the sensitivity figure: carving thick and solid, combined
#: dashed on top of it, so that both show where their values coincide (fully carved share).
_SWEEP_STYLE: dict[str, dict[str, Any]] = {
    "carving": {"ls": "-", "marker": "s", "lw": 4.0, "ms": 8, "alpha": 0.5, "zorder": 2},
    "combined": {"ls": "--", "marker": "^", "lw": 1.5, "ms": 5, "zorder": 3},
    "atm": {"ls": "-", "marker": "o", "lw": 1.3, "ms": 4, "zorder": 2},
    "centerline": {"ls": ":", "marker": "D", "lw": 1.5, "ms": 3.5, "zorder": 2},
    "evidence": {"ls": "-.", "marker": "v", "lw": 1.5, "ms": 4, "zorder": 3},
}


def plot_sensitivity(sensitivity: JsonDict) -> Figure:
    """Each swept parameter against true error, unprocessed share and fully carved share.

    One row per parameter (x: its value, labelled by :data:`SWEEP_LABELS`), one column per
    measure; one legend for the whole figure.
    """
    sens = {k: v for k, v in sensitivity.items() if k != "scenario"}
    seed = sensitivity.get("scenario", {}).get("seed", 0)
    measures = (("error_median", "median true error (m)"),
                ("unprocessed", "unprocessed (% of history rows)"),
                ("fully_carved", "fully carved (% of arcs)"))
    fig, axes = new_figure(len(sens), len(measures), width=12.0, height=2.6 * len(sens) + 0.6)
    handles: dict[str, Any] = {}
    for r, (param, entry) in enumerate(sens.items()):
        x = np.asarray(entry["values"], dtype=np.float64)
        for c, (key, label) in enumerate(measures):
            ax = axes[r, c]
            for m in ("carving", "combined", "atm", "centerline", "evidence"):
                if m in entry:
                    (line,) = ax.plot(x, _values(entry[m][key]), color=METHOD_COLORS[m],
                                      label=m, **_SWEEP_STYLE[m])
                    handles.setdefault(m, line)
            if param == "history":
                ax.set_xscale("log")
                ax.set_xticks(x, [f"{v:g}" for v in x])
                ax.minorticks_off()
            else:
                ax.locator_params(axis="x", nbins=6)
            ax.set_xlabel(SWEEP_LABELS.get(param, f"{param} ({entry['unit']})"), fontsize=8)
            ax.set_ylabel(label, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
    order = [m for m in METHOD_ORDER if m in handles]
    fig.legend([handles[m] for m in order], order, loc="outside lower center",
               ncol=len(order), fontsize="small")
    fig.suptitle(f"Sensitivity (office tour, seed {seed} only; one parameter changed at a "
                 "time from the defaults)")
    return fig
