"""The carved grid's parameters, :class:`CarvedGridParams`, and the measured defaults.

The symbols are those of the sensor model (``docs/carved-grid.md``, "The sensor model"): ``p_hit``
and ``p_miss`` the band's and the free space's probabilities, ``L`` = ``spread_length``, ``d_f`` =
``fade_range``, ε = ``range_tolerance``; every rule added to the model has its own section there,
named in its parameter's description.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from sonarcarve.grids.cells import GridError, check_probability, check_real
from sonarcarve.grids.elfes import ROS_FADE_RANGE
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE, MAX_RANGE_TOLERANCE

__all__ = [
    "DEFAULT_FREE_THRESHOLD",
    "DEFAULT_FRESH_PERIODS",
    "DEFAULT_MARK_LENGTH",
    "DEFAULT_MAX_INCIDENCE",
    "DEFAULT_METHOD",
    "DEFAULT_SEE_THROUGH",
    "DEFAULT_SIDE_LOBES",
    "DEFAULT_SIDE_LOBE_RANGE",
    "DEFAULT_SPREAD_LENGTH",
    "MAX_SIDE_LOBES",
    "POSE_MARGIN_SIGMAS",
    "CarvedGridParams",
]

#: What the parameters' errors start with.
_LABEL = "carved grid"

#: Length over which one echo counts as a whole hit, metres
#: (:attr:`CarvedGridParams.spread_length`).
#: Measured (``benchmarks/grids.py``, office, seeds 0-1, 0.05 and 0.10 m cells, fade 1.2 m, β 30°):
#: occupied precision / recall 0.81 / 0.84 at 0.05 m with 0.1, 0.72 / 0.95 with 0.2, 0.64 / 0.96
#: with 0.3; 0.2 is the shortest that keeps recall above the range sensor layer's at both
#: resolutions.
DEFAULT_SPREAD_LENGTH = 0.2
#: The method the grid runs by default (:class:`~sonarcarve.grids.carved.CarvedGrid`): carving and
#: ATM on one history (the paper's section 4), whose crossings narrow the interval a band is drawn
#: over. Measured against specular-aware carving alone (``benchmarks/grid_methods.py`` and the
#: issue-10 benchmarks, office, seeds 0-2): occupied precision 0.720 -> 0.790 (0.05 m) and 0.825 ->
#: 0.901 (0.10 m) under the specular physics, 0.721 -> 0.775 and 0.853 -> 0.935 under the amplitude
#: physics, recall within ±0.005, phantoms -40 %; the Fig. 2 door 83/78 -> 92/86 % passable (89/86
#: -> 97/94 % with no-echo readings); a crossing person forgotten in 0.2 s instead of 5.2 s. Its
#: price: more CPU per reading (ATM's crossings and medians), most visible when the map is read
#: every few readings (``benchmarks/grid_reads.py``: 2.0x / 3.9x the range sensor layer's at 0.05 /
#: 0.10 m, read every 5 readings, against 1.7x / 2.7x).
DEFAULT_METHOD = "combined"
#: Critical angle of the default method's specular-aware carving, radians (20°). Paper
#: carving (π/2) loses 45 % of the office's true echoes to glancing free space, and the grid's
#: recall with them (0.20 at 0.05 m against 0.53); with combined carving 20° kept recall where
#: 30° lost 0.004-0.023 of it (office 0.937 / 0.953 against 0.914 / 0.947 at 0.05 / 0.10 m).
DEFAULT_MAX_INCIDENCE = math.radians(20.0)
#: How many ``pose_sigma`` before its echo's band a reading's free space ends
#: (:attr:`CarvedGridParams.pose_sigma`): two standard deviations of the believed pose's error
#: leave about 95 % of a true wall's cells, along the beam, out of a misplaced beam's free space.
POSE_MARGIN_SIGMAS = 2.0
#: How many of its sensor's firing periods a newest echo's mark lasts at most
#: (:attr:`CarvedGridParams.fresh_periods`): past one period the sensor has fired again; the
#: rest is room for the jitter of real firing times.
DEFAULT_FRESH_PERIODS = 1.1
#: Probability below which :meth:`~sonarcarve.grids.carved.CarvedGrid.trinary` calls a cell free
#: (:attr:`CarvedGridParams.free_threshold`): as much evidence to call a cell free as to call it
#: occupied (logit -0.62 against +0.62 for the occupied threshold 0.65, about one strong look),
#: symmetric about the prior as ROS's layer (0.2 / 0.8) and octomap (0.5) are. It was 0.196, ROS
#: map_saver's ``free_thresh``: the grey level of an *unknown* pixel in a map image, not an amount
#: of evidence; with it a cell needed about 3.5 on-axis misses, and the grid left much of the
#: floor near the robot's path unknown where ROS's layer marks it free (the numbers, before and
#: after, against the layer: ``benchmarks/grids.py --free-threshold 0.196`` and docs/RESULTS.md,
#: *Free space a planner can use*). The map_server YAML keeps 0.196, which reads the trinary
#: image back exactly (:data:`sonarcarve.io.map_server.FREE_THRESH`).
DEFAULT_FREE_THRESHOLD = 0.35
#: How much of its carved interval the newest echo's mark covers, metres
#: (:attr:`CarvedGridParams.mark_length`): 0, the point's own cell. The mark says where an
#: unexplained echo most likely came from (a pole dead ahead), and a planner inflates one cell
#: as it does any obstacle; a longer mark claims cells the echo's own arc does not single out.
#: It was ``spread_length`` (0.2 m) until 2026-12-04: on an uncarved arc of a jamb 9-11° off the
#: axis that stretch lay 0.14-0.16 m inside the Fig. 2 door and closed it in 17 of 288
#: approaches at 0.10 m (1 with 0; docs/RESULTS.md, *The narrow door of the paper*). The price:
#: the crossing person, first heard at a beam's edge, is marked at 1.2 s (the range sensor
#: layer's time) instead of 1.0 s, which the 0.2 m mark reached only by lying within the
#: measure's 0.25 m of the person while centred 0.51 m from it.
DEFAULT_MARK_LENGTH = 0.0
#: How far behind a surface a beam saw through it clears (:attr:`CarvedGridParams.see_through`),
#: metres: the depth of the obstacles a robot meets (a box, a person, a chair), not of a room.
DEFAULT_SEE_THROUGH = 0.5
#: How far past each edge of its beam an echo may have come from through a side lobe, in half
#: beam widths (:attr:`CarvedGridParams.side_lobes`): a circular piston's first side lobe lies
#: between its first and second nulls, at 1.8 times the first null's angle (Bessel zeros 3.83
#: and 7.02; 12.7° and 23.8° for the 600-series transducer, whose quoted 22.5° beam is about
#: its null-to-null width, 25.4°), so about one more half width each side. That holds for beams
#: quoted null to null, as this project's are; for a beam quoted at half power the first side
#: lobe lies 2.4-4.3 half widths off the axis (review rev10s): set ``side_lobes`` for the
#: transducer at hand.
#: 0, off by default (2026-12-02): with 1, an obstacle straight ahead in a corridor whose walls
#: are mapped went unmarked at some ranges (helper door10b's sweep), and the mark is the only
#: thing that makes such an obstacle occupied. A lobe cell now counts only if it was heard from
#: near the bearing of the ray to it (live arcs and final bands; docs/carved-grid.md, "Side
#: lobes"): that marks the obstacle at every range when the walls were heard by side sensors
#: (±90°), and opens the Fig. 2 door under the amplitude physics in 89 / 86 % of approaches (56 /
#: 53 % without side lobes), but not when sensors turned 22.5° also heard the walls at their
#: beam's edge (33.75°, one 11.25° sector from a lobe ray's 22.5°): helper lobe10s's sweep left
#: the obstacle unmarked at most ranges at 0.05 m. Still opt-in.
DEFAULT_SIDE_LOBES = 0.0
#: Echoes at this range or nearer, metres, may have come through a side lobe
#: (:attr:`CarvedGridParams.side_lobe_range`): two-way, the first side lobe is about 35 dB
#: below the axis, so only near reflectors are heard through it. Measured (amplitude physics,
#: office, seed 0, direct echoes whose true reflector lies outside the nominal beam): 12.9 %
#: below 1 m, 6.6 % at 1-2 m, 0.4 % at 2-3 m, 0.1 % at 3-5 m.
DEFAULT_SIDE_LOBE_RANGE = 2.0
#: The most half widths :attr:`CarvedGridParams.side_lobes` may reach past a beam's edge: a
#: piston's third null lies at 2.7 times its first (Bessel zero 10.17 against 3.83); past it the
#: lobes are 30 dB or more down one way, and a 22.5° beam widened by 3 half widths each side
#: still looks ahead of the sensor (±45°), never behind it.
MAX_SIDE_LOBES = 3.0


@dataclass(frozen=True)
class CarvedGridParams:
    """Parameters of the carved grid's sensor model (``docs/carved-grid.md``).

    Attributes
    ----------
    p_hit : float
        Probability a whole hit gives a cell (an arc carved down to one cell, confidence 1), in
        (0.5, 1); octomap's 0.7.
    p_miss : float
        Probability one reading's free space gives an on-axis cell, in (0, 0.5); octomap's 0.4.
    p_min, p_max : float
        Clamp of the final log-odds, ``p_min < 0.5 < p_max``; octomap's 0.12 and 0.97.
    occupied_threshold, free_threshold : float
        :meth:`~sonarcarve.grids.carved.CarvedGrid.trinary` calls a cell occupied above the first
        and free below the second (``0 < free < occupied < 1``); 0.65 (as the Elfes grid) and
        :data:`DEFAULT_FREE_THRESHOLD` (0.35; map_saver's 0.196 before). Compared in log-odds
        (``l > logit(occupied)``), which equals comparing
        :meth:`~sonarcarve.grids.carved.CarvedGrid.probabilities` with the threshold up to
        rounding: a cell within a few ulp of a threshold's logit may fall on the other side.
    range_tolerance : float
        ε, metres >= 0: the occupied band is ``r ± (h + ε)/2``, and the range slack of the
        repeat test (``repeat_weight``); carving's default 5 cm. The default method carves with
        the same ε (plus 2 ``pose_sigma``): a noisy sonar widens all three (``sonarcarve grid
        --range-tolerance``).
    spread : bool
        Spread each echo over its carved interval (``s`` in ``docs/carved-grid.md``); False gives
        every cell of the carved band a whole hit (Elfes' rule, on the carved interval).
    spread_length : float
        ``L``, metres >= 0: an arc carved to this length or shorter gives its cells a whole hit
        (the cell side where larger); :data:`DEFAULT_SPREAD_LENGTH`.
    fade_range : float
        ``d_f``, metres > 0, of the free-space fade; ``inf``: no fade. Default ROS's 1.2 m.
    surface_aware : bool
        Weigh the free space at cells believed occupied by the beam's audibility
        (``docs/carved-grid.md``, "Clearing what was heard"); False: the fade everywhere, the rule
        of the grid before issue 10's clearing work, equal to it up to rounding order (the fade is
        now applied as ``γ · (logit(p_miss) · f)``, before as ``(γ · f) · logit(p_miss)``).
    p_miss_heard : float
        Probability one on-axis beam that would have heard a cell's surface and passed it leaves
        the cell, in (0, 0.5); 0.2. Measured on the changing-scenes box with no-echo readings,
        seeds 0-2: 0.4 (octomap's miss) never clears it, 0.2 clears it 4.4 s after the robot
        passes at 0.10 m (4.4-6.2 s at 0.05 m), 0.12 gives 3.0-4.4 s.
    band_profile : float
        0 (default): every cell of the carved band gets the same value. ``k > 0``: a cell at
        ``u`` (-1..1) across the widened carved interval gets ``min(1, k (1 - u²))`` of it, the
        beam's angular profile laid over the interval. Measured (office, seeds 0-2): 1.0 raises
        precision (0.78/0.88 at 0.05/0.10 m) and the Fig. 2 door (81/78 % passable) but drops
        recall to the layer's (0.895 at 0.05 m); so off.
    fresh_arcs : bool
        Each sensor's newest echo, when no occupied cell on its carved band explains it, is a whole
        hit on the middle ``mark_length`` of its carved interval (by default the point's own
        cell, ``spread_length`` before 2026-12-04; its spread value on the rest)
        until that sensor fires again, or would have (``fresh_periods``) ("The newest echoes mark
        at once": a person stepping in front of the robot is marked after one reading). Where the
        map favours another part of the band and not the middle, the whole hit goes around the
        band's most likely cell instead ("Where
        the mark goes": the Fig. 2 door, echoes only, 92 -> 97 % / 86 -> 94 % passable at 0.05 /
        0.10 m). False: every live arc spread, the rule
        before.
    mark_length : float or None
        Metres >= 0 of the carved interval the newest echo's mark covers (``fresh_arcs``);
        :data:`DEFAULT_MARK_LENGTH` (0: the point's own cell, drawn, as every arc, half a cell
        wider each side); None: ``spread_length`` (at least the cell side), the default until
        2026-12-04 ("The mark's length"). 0 opens the Fig. 2 door in 108 of 108 approaches at
        0.05 and 0.10 m (105 / 101 with 0.2 m; 287 of 288 at both, 281 / 271) and lowers the
        changing scenes' phantom shares, but marks the crossing person at 1.2 s instead of 1.0
        (the range sensor layer's 1.2): its first echo comes from the beam's edge, and only the
        0.2 m mark reached it.
    fresh_seconds : float
        Seconds > 0 a newest echo stays fresh at most, counted back from the newest reading the
        grid has seen; 2.0. A log that drops silent firings (echoes only, or max-range readings
        filtered out) never shows the sensor "firing again", and without this bound a person
        heard once would stay marked until the arc left the history (20 s on a 16-sonar ring).
        2 s is three cycles of such a ring at 40 ms a sonar (0.64 s, the simulator's Scout2),
        so a sensor that keeps hearing an obstacle keeps it marked; set it to 2-3 ring periods
        of a slower ring.
    fresh_periods : float
        Number >= 1 (``inf``: off); :data:`DEFAULT_FRESH_PERIODS`. A newest echo stays fresh less
        than this many of its sensor's firing periods (the period as the log shows it,
        :class:`~sonarcarve.grids.carved.periods.FiringPeriods`): by then the sensor has fired
        again, and a log without that reading dropped a firing that heard nothing, so the mark
        ends as it would with the silent firing in the log ("Stale marks"). It acts only on a
        sensor whose gaps fit one fixed period; below 1 a sensor's own next echo could come
        after its mark ended, so it is refused. A log that drops readings whose value did not
        change (rather than firings that heard nothing) breaks its premise: use ``inf`` there.
    side_lobes : float
        Number in [0, :data:`MAX_SIDE_LOBES`]; :data:`DEFAULT_SIDE_LOBES` (0: the beam alone).
        How far past each edge of its beam, in half beam widths, a near echo may have come from
        through a side lobe, for the newest echo's mark ("Side lobes"): an occupied cell there,
        heard from near the bearing of the sensor's ray to it, explains the echo, and the mark
        goes to a likely one there when the map does not favour the arc's middle. 1 opens more
        doors under diffuse echoes but can leave an obstacle straight ahead in a mapped corridor
        unmarked (:data:`DEFAULT_SIDE_LOBES`).
    side_lobe_range : float
        Metres >= 0 (``inf``: every range); :data:`DEFAULT_SIDE_LOBE_RANGE` (2). Echoes farther
        than this are judged on their carved interval alone (the lobes are too weak to hear far
        reflectors; at every range the corridor walls beside a shut door 2.4-4.8 m ahead
        explained its echoes and it was never marked).
    repeat_weight : float
        In [0, 1]; 0. The factor of an arc's weight once a later echo of its sensor repeats it
        ("Repeated echoes count once": the sensor moved towards or away from
        one reflector and heard it again): 0 counts a run of repeats as its
        newest echo, 1 counts every echo (the rule before). Measured (seeds 0-2, Fig. 2 door
        at 1 m, echoes only, 0.05 / 0.10 m): 1 passable in 67 / 61 % of approaches, 0.25 in
        69 / 58 % (0.5 the same), 0 in 83 / 78 %; office precision / recall unchanged within
        0.003.
    see_through : float
        Metres >= 0 (``inf``: no limit; 0: off); :data:`DEFAULT_SEE_THROUGH`. A beam that
        passes a cell it would have heard (surface-aware audibility) and hears nothing there
        clears the believed-occupied cells behind that cell on its ray, up to this far behind
        it, as if it would have heard them too ("Seen through"). It acts only
        with ``surface_aware`` (without it no beam is known to have heard a cell, so nothing is
        seen through and the value is ignored).

    pose_sigma : float
        Metres >= 0 (finite); 0, the grid as before, bit for bit. The standard deviation of the
        readings' position error, as the user knows it from the localiser (its position σ;
        adding range times the heading σ was not measured, and a larger σ trades more
        precision): each reading's free space ends
        :data:`POSE_MARGIN_SIGMAS` times this before its band, and the default method's range
        tolerance ε grows by as much, so that a beam stamped a few centimetres off does not
        clear the true wall it was heard from. Measured (``benchmarks/pose_error.py
        --pose-sigma``, office, seeds 0-2, localisation noise 5 cm / 2°, σ = 0.05): a trade of
        precision for recall, 0.591 / 0.792 -> 0.558 / 0.834 at 0.05 m (phantoms 0.33 -> 0.44 %),
        0.806 / 0.917 -> 0.812 / 0.932 at 0.10 m; so 0 unless recall matters most.

    Raises
    ------
    GridError
        A value out of its range.
    """

    p_hit: float = 0.7
    p_miss: float = 0.4
    p_min: float = 0.12
    p_max: float = 0.97
    occupied_threshold: float = 0.65
    free_threshold: float = DEFAULT_FREE_THRESHOLD
    range_tolerance: float = DEFAULT_RANGE_TOLERANCE
    spread: bool = True
    spread_length: float = DEFAULT_SPREAD_LENGTH
    fade_range: float = ROS_FADE_RANGE
    surface_aware: bool = True
    p_miss_heard: float = 0.2
    band_profile: float = 0.0
    fresh_arcs: bool = True
    mark_length: float | None = DEFAULT_MARK_LENGTH
    fresh_seconds: float = 2.0
    fresh_periods: float = DEFAULT_FRESH_PERIODS
    see_through: float = DEFAULT_SEE_THROUGH
    repeat_weight: float = 0.0
    side_lobes: float = DEFAULT_SIDE_LOBES
    side_lobe_range: float = DEFAULT_SIDE_LOBE_RANGE
    pose_sigma: float = 0.0

    def __post_init__(self) -> None:
        def real(name: str, ok: Callable[[float], bool], rule: str) -> None:
            check_real(_LABEL, name, getattr(self, name), ok, rule)

        check_probability(_LABEL, "p_hit", self.p_hit, 0.5, 1.0)
        check_probability(_LABEL, "p_miss", self.p_miss, 0.0, 0.5)
        check_probability(_LABEL, "p_min", self.p_min, 0.0, 0.5)
        check_probability(_LABEL, "p_max", self.p_max, 0.5, 1.0)
        check_probability(_LABEL, "occupied_threshold", self.occupied_threshold, 0.0, 1.0)
        check_probability(_LABEL, "free_threshold", self.free_threshold, 0.0,
                          self.occupied_threshold)
        real("range_tolerance", lambda v: 0.0 <= v <= MAX_RANGE_TOLERANCE,
             f"a number in [0, {MAX_RANGE_TOLERANCE:g}] metres")
        real("spread_length", _finite_at_least_zero, "a finite number >= 0 metres")
        real("fade_range", lambda v: v > 0.0, "> 0 (inf: none) metres")
        check_probability(_LABEL, "p_miss_heard", self.p_miss_heard, 0.0, 0.5)
        for name in ("spread", "surface_aware", "fresh_arcs"):
            if not isinstance(getattr(self, name), bool):
                msg = f"carved grid: {name} must be True or False, got {getattr(self, name)!r}"
                raise GridError(msg)
        if self.mark_length is not None:
            real("mark_length", _finite_at_least_zero, "a finite number >= 0 metres, or None")
        real("see_through", lambda v: v >= 0.0, "a number >= 0 metres (inf: no limit)")
        real("fresh_seconds", lambda v: math.isfinite(v) and v > 0.0, "a finite number > 0")
        real("fresh_periods", lambda v: v >= 1.0, "a number >= 1 firing period (inf: off)")
        real("repeat_weight", lambda v: 0.0 <= v <= 1.0, "a number in [0, 1]")
        real("side_lobes", lambda v: 0.0 <= v <= MAX_SIDE_LOBES,
             f"a number in [0, {MAX_SIDE_LOBES:g}] half beam widths")
        real("side_lobe_range", lambda v: v >= 0.0, "a number >= 0 metres (inf: every range)")
        real("band_profile", _finite_at_least_zero, "a finite number >= 0")
        real("pose_sigma", _finite_at_least_zero, "a finite number >= 0 metres")
        carving_tolerance = self.range_tolerance + POSE_MARGIN_SIGMAS * self.pose_sigma
        if carving_tolerance > MAX_RANGE_TOLERANCE:  # the default method's ε would refuse it
            msg = (f"{_LABEL}: range_tolerance + {POSE_MARGIN_SIGMAS:g} pose_sigma (the ε it "
                   f"carves with) must be at most {MAX_RANGE_TOLERANCE:g} m, got "
                   f"{carving_tolerance:g}")
            raise GridError(msg)


def _finite_at_least_zero(value: float) -> bool:
    return math.isfinite(value) and value >= 0.0
