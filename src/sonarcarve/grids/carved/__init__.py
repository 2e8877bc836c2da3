"""The carved grid: an occupancy grid whose occupied band follows arc carving over time.

The paper (section 4) proposes that "a new distribution can be used for each reading, computed
from the carved results": this module is that distribution, written into a log-odds grid.

Each reading from origin ``o`` along ``θ`` with range ``r`` and beam width ``φ`` does two things:

- **free space**, final at once: every cell whose centre lies in the beam (``|α| <= φ/2`` off
  the axis) at a distance ``d < r - b`` gets ``l += γ(α) f(d) · logit(p_miss)``, with the
  angular profile ``γ(α) = 1 - (2α/φ)²`` of Elfes' cone (1 on the axis, 0 at the beam's edges),
  ROS ``range_sensor_layer``'s distance fade ``f(d) = (1 - tanh(2 (d - d_f))) / 2`` (``d_f`` =
  :attr:`CarvedGridParams.fade_range`, 1.2 m: on specular walls a long reading is often an
  echo that missed the wall, and its far free space is not to be trusted) and the band
  half-width ``b = (h + ε) / 2`` (cell side h, range tolerance ε) as in
  :class:`~sonarcarve.grids.elfes.OccupancyGrid`;
- **occupied band**, live while the reading's arc is in the carving method's history: the cells
  whose centre lies within ``b`` of the circle of radius r and whose bearing lies within the arc's
  *carved* interval ``[θ1', θ2']`` (widened by half a cell, ``h / 2r``, so that an interval
  carved narrower than a cell still marks the cell it points at) get

  ``l_k = c · s · logit(p_hit)``,  ``s = min(1, L / (r (θ2' - θ1')))``

  where ``s`` spreads the echo over the carved interval, ``L`` =
  :attr:`CarvedGridParams.spread_length` (0.2 m, at least the cell side): an uncarved 22.5° arc
  at 3 m (1.18 m long) gives each of its cells 0.17 of a hit, an arc carved down to 0.2 m or
  less a whole hit
  and ``c`` is the method's confidence in the point
  (:attr:`~sonarcarve.methods.Estimates.confidence`; 1 where the method does not model it,
  NaN). An arc carving removed (fully carved, split, or below the method's confidence)
  contributes nothing.

**A wall heard once stays unknown**, and that is what ROS's layer, which marks every echo's axis
point at once, gains under the amplitude physics (office recall 0.965 / 0.992 at 0.05 / 0.10 m
against the carved grid's 0.946 / 0.941; ``benchmarks/grids.py --physics amplitude``). Traced
(office, 0.10 m, seeds 0-2): 83-90 % of the missed wall cells hold 0.19-0.25 in log-odds (median),
from one or two echoes whose arcs stay long (seed 0: median 1.5 m carved length, 0.11 a cell each);
free space is not the cause (no fade, or no surface-aware rule: the same recall). Drawing every
carved band at a whole hit (``spread=False``) only ties the layer at 0.10 m (0.992, precision 0.816
against its 0.856), so no rule that draws the carved intervals can beat it there without losing
precision. Tried and not kept: an arc leaving the history that no occupied cell explains keeps its
point (a whole hit on its middle ``L``): amplitude recall 0.960 / 0.966, but under the specular
physics precision 0.790 -> 0.686 and phantoms 0.19 -> 0.35 % at 0.05 m (0.901 -> 0.784 and 0.16 ->
0.41 % at 0.10 m), because crosstalk and multipath echoes are lone echoes too (office, seed 0: 317
crosstalk and 324 multipath of 2,348 such arcs, their points within a cell of a wall in 7 % and 4 %
of cases, against 91 % for direct echoes). The amplitude model's office logs hold no crosstalk and
no multipath (0-1 of 12,850 readings), which is why marking every echo costs the layer little
there; a real ring has both.

**Repeated echoes count once** (:attr:`CarvedGridParams.repeat_weight`): the sum treats every echo
as independent evidence about the cells of its band, but a sensor driving towards (or away from)
one reflector hears it again and again, the range shrinking by the distance driven. Its circles are
then all (nearly) internally tangent, their bands lie within the range tolerance of each other over
a long stretch around the tangent point, and a reflector anywhere on that stretch would have given
every one of those ranges. Fig. 2's door showed what the sum does with them: a sensor driving at a
jamb 11° off its axis (its track 0.23 m from the jamb) draws circles that all pass through the jamb
*and* through the jamb's mirror image across its track, inside the doorway; no beam can carve them
there (every beam that reaches the mirror image passes the jamb first and hears it), and 7-11 arcs
of that one sensor summed to 1.8-2.7 in log-odds over the doorway, closing the door. The ranges
cannot tell the jamb from its mirror image (0.23 m off the track changes them by 1-2 cm over the
whole approach, below the range noise); only other sensors, from other places, can. So when an echo
*repeats* an earlier echo of its sensor still in the history
(:func:`~sonarcarve.geometry.repeats.is_repeat`: ``| |P2 - P1| - |r1 - r2| | <= ε``, the range
changed by the distance moved towards or away from the reflector within the range tolerance ε, and
the tangent point's bearing lies inside both beams; the origins more than 2ε apart, because nearer
than that any change of range fits within ε and a robot creeping along a wall would chain every echo
of a side sensor into one and lose the wall: review finding, a
16-sonar ring moving 2-4.5 cm a cycle lost all of a side wall with the earlier "stood still" case),
the earlier arc's weight is multiplied by ``repeat_weight``, live and when it leaves the history:
with the default 0 a run of repeats counts as its newest echo, whatever was heard between them.
Echoes of other sensors, and echoes of one sensor whose circles cross rather than touch (a side
sensor driving along a wall hears another point of the wall each time), still add up. It is decided
when the repeat is heard, from the two readings alone (a repeat heard after the earlier arc left
the history is none), so the map does not depend on batching; each echo is compared with the
earlier arcs of the history (a compiled loop over its slots; measured on the office log at 0.05 m:
0.4 µs a reading when the whole log is one batch, 2-3 µs a reading in 0.2 s batches, mostly the
call per batch, against 43-46 µs for the rest of ``add_many``). A standing obstacle heard only by
one sensor's repeats stays marked by that sensor's newest echo (a whole hit while nothing else
explains it, below). Measured (``benchmarks/grids.py``, seeds 0-2; before -> after): the Fig. 2
door passable at 1 m in 67 -> 83 % / 61 -> 78 % of approaches at 0.05 / 0.10 m, echoes only, 83 ->
89 % / 83 -> 86 % with no-echo readings (comparing an echo with its sensor's previous echo only: 72
% at 0.10 m, echoes only); amplitude physics 22 -> 31 % / 19 -> 31 %, and 53 / 50 % unchanged with
no-echo readings. What remains is the newest echo's point (below): every approach still closed at
0.05 and 0.10 m (specular physics) is open without it (without fresh arcs the door is passable in
all 36 approaches, both resolutions, both inputs). The price is the evidence the sum gave a wall
the robot drives at: office precision / recall 0.718 / 0.943 -> 0.720 / 0.941 (0.05 m) and 0.822 /
0.954 -> 0.825 / 0.952 (0.10 m); t-junction recall 0.987 -> 0.975 and 0.998 -> 0.989; doorway 0.844
-> 0.830 and 0.844 -> 0.824 (all above ROS's layer); in the changing scenes the same latencies and
about as many phantom cells, but fewer occupied cells while arcs are live (22 % fewer in the door
scene at 0.05 m, amplitude physics), so a larger phantom share. 0.25 keeps most of the pile-up
(door 69 / 58 %, echoes only).

**The newest echoes mark at once** (:attr:`CarvedGridParams.fresh_arcs`): spread over a
22.5° arc 3.5 m away, one echo gives its cells 0.12 in log-odds, and the changing scenes' person,
crossing 3.2-4.2 m ahead, is heard from each place by only a few firings before the beams of its
next places carve those arcs away (their sum peaked at 0.39 at its cells, below the 0.62 of
"occupied"): the grid never marked it, where ROS's layer, which marks the beam's middle at once,
takes 1.2 s. A robot must see an obstacle that steps in front of it now. So each sensor's
newest reading, while it is the newest (until that sensor fires again: the ring's current
view), also counts as carving's point estimate: the middle ``L``
(:attr:`~CarvedGridParams.spread_length`) of its carved interval is raised from the spread
value to a whole hit ``c · logit(p_hit)``, as if carved down to ``L`` around the method's
point. Only where nothing on the map explains the echo: if a cell of the arc's carved band is
occupied already (without the arc's own share), the echo may well come from it and the arc
keeps its spread value. Why these limits, measured on the changing scenes (0.10 m, no-echo
readings, seeds 0-2; phantom share person/door/box 11.8/9.1/10.3 % before): the whole carved
band at a whole hit for every newest echo marks the person in 0.8 s at 29.0/32.7/19.0 %, mostly
the flanks of long arcs early in a run when nothing is explained yet; only unexplained echoes,
25.0/23.1/15.4 %; the middle ``L`` of only unexplained echoes marks it in 1.0 s at
15.4/16.4/11.8 %. Counting as explained any cell more likely occupied than not (``l > 0``)
lowers the phantoms further but makes a person standing still flicker: its older spread arcs
"explain" each new echo while its cells are still unsure. Arcs leave the history at their
spread value: the mark is an overlay of the present, not evidence that accumulates. The points
are kept in an array of their own (4 bytes a cell), so that whether an echo is explained is
judged on the spread arcs alone (the fresh arcs' order does not matter) and a read redraws only
the points that changed: drawing them into ``live`` and back at every read doubled the cost of
a map read every 0.2 s. The price: more phantoms in changing scenes (above), and the Fig. 2
door, echoes only, passable in 67/61 % of approaches at 0.05/0.10 m instead of 72/67 % (an
uncarved echo's point can fall in the doorway).

**Where the mark goes**: the middle of the carved interval, the method's point, unless the map of
spread arcs (without the arc's own share) holds no cell more likely occupied than not (log-odds >
0) where that middle ``L`` would be drawn, and does hold one elsewhere on the band: then the ``L``
around the band's most likely cell, clipped to the interval. An uncarved echo says only that its
reflector is somewhere on the arc; where the map already favours one part of the arc and says
nothing for the middle, that part is the likelier reflector. Why, traced on the Fig. 2 door (echoes
only, combined carving, 0.10 m, seed 0, heading -35°): the blocking cells were the point of the
sensor aimed along the track, 1.83 m from the near jamb, which lies 11.1° off its axis (the beam's
edge): its arc was uncarved (the beams through the doorway heard nothing and an echoes-only log has
no such readings), its middle lay 0.24 m inside the doorway on cells the map knew nothing of
(log-odds 0), while its band's cells at the jamb held 0.54-0.57 (other sensors' spread echoes,
below "occupied"), so nothing "explained" the echo and the point went to the middle. Where the
middle is favoured too (a person standing still, heard again from one place: its cells hold the
older echoes' spread values) the point stays there, so a standing person does not flicker; where
the map knows nothing of the arc (a person stepping in front of the robot on open floor) it is the
middle as before. Measured (``benchmarks/grids.py``, seeds 0-2, 0.05 / 0.10 m): the Fig. 2 door
passable, echoes only, in 92 -> 97 % / 86 -> 94 % of approaches; under the amplitude physics 36 ->
33 % / 33 -> 39 % (mean free width 0.405 -> 0.403 / 0.372 -> 0.388 m); office, t-junction and
doorway precision and recall within 0.003 and phantoms within 0.008 percentage points under both
physics (the points touch only the final read's newest arcs); a map read every 5 readings 2.01x /
3.69x the layer's CPU against 1.84x / 3.35x (``benchmarks/grid_reads.py --every 5``, one run each,
load 2-5: the likeliest cell needs the bearing of every likely cell of the band, the occupied test
only of occupied ones); the changing scenes' latencies unchanged, phantom shares within 0.8 points
(fewer in the door scene). Without the guard on the middle (the most likely cell whenever one is
more likely occupied than not) a person heard again from one place was marked on the cell whose
free space happened to be weakest, not at its middle (the test of a person standing still: its
middle cell 0.44 instead of 1.05 after the second echo, not occupied). The remaining closed
approaches (0.10 m: heading 45°, offset 0.15 m, seeds 0 and 1) are the case the mark exists for:
the jamb, 9° off the sensor's axis, heard for the first time, with nothing else on the map near its
arc.

**Side lobes** (:attr:`CarvedGridParams.side_lobes`, :attr:`~CarvedGridParams.side_lobe_range`): a
real transducer is not a hard cone; a near reflector is also heard through the first side lobe,
outside the nominal beam (a circular piston's lies between its first and second nulls, at 1.0-1.9
times the main lobe's half width). For an echo at ``side_lobe_range`` (2 m) or nearer the newest
echo's mark therefore looks on the echo's circle over the beam widened by ``side_lobes`` (1) half
widths past each edge: an occupied cell there explains the echo as one inside the carved interval
does (no mark), and when the map favours no cell where the middle would be drawn and the likeliest
cell lies past the beam's edge, the whole hit goes around that cell, clipped to the lobe's stretch
of the circle (the arc draws no spread value there to raise). The arc's spread band is unchanged:
the lobes only decide whether the newest echo's point is drawn, and where. Why, traced on the Fig. 2
door under the amplitude physics (``sim/amplitude.py``; in its office logs 12.9 % of the direct
echoes nearer than 1 m come from outside the nominal beam, 6.6 % at 1-2 m, 0.4 % at 2-3 m, 0.1 % at
3-5 m): the door, echoes only, was passable at 1 m in 33 / 39 % of the 36 approaches (0.05 / 0.10 m;
89 / 86 % without fresh arcs). In 19 of the 22 closed at 0.10 m a newest echo's mark made blocking
cells occupied, and in 11 of those the echo had come through a side lobe: the near jamb 15-21° off
the axis of the sensor aimed through the door (0.7-1.2 m away; once 57°), the mark in the middle of
the doorway while the jamb was occupied or likely from other sensors' echoes. Measured
(``benchmarks/grids.py``, seeds 0-2, 0.05 / 0.10 m, before -> after): amplitude physics, echoes only
33 / 39 -> 83 / 78 %, with no-echo readings 58 / 56 -> 92 / 89 %; specular physics 97 / 94 -> 100 /
94 %, both inputs. ``side_lobes`` 0.5: 69 / 78 %; 2: 83 / 83 %; ``side_lobe_range`` 1 m: 44 / 44 %,
3 m or every range: 83 / 78 %, but at every range the changing scenes' shut door was never marked
(the corridor's walls, 12-24° off the axis at its range, explained its echoes) and the person at
0.8-1.4 s instead of 1.0; with 2 m every latency is that without side lobes (both physics, both
inputs, 0.05 and 0.10 m; phantom shares within 0.2 points). The price, where the map is read once at
the end of a log (only the last read's marks move): t-junction recall -0.001 to -0.006 (0.987 ->
0.982 at 0.10 m, specular, below ROS's layer's 0.984), office at most -0.001, doorway the same: a
robot ending near a corner hears the wall ahead, an occupied wall at the same range lies in a lobe
and explains the echo, and under the specular physics it came through the main lobe. Judging the
lobes only when nothing on the carved interval is even likely costs less (0.985) and gains less
(door 81 / 75 %, specular 97 / 94 %). CPU: once per log the same, a map read every 5 readings +1-6 %
(``benchmarks/grid_reads.py``, two rounds, old and new alternating). Tried and not kept: diluting a
near arc's spread value over its lobes too (as if spread over the widened arc): the door 81-100 %,
but office recall (specular, 0.05 m) 0.937 -> 0.850 for echoes nearer than 2 m, 0.657 nearer than
1.2 m (a wall 1 m beside a side sensor, heard once per pass, never reaches "occupied"); nearer than
0.8 m kept recall (0.937; t-junction -0.006 to -0.008) with the door at 81 / 86 %, but that bound is
half a corridor's width, not a property of sonar. A first version subtracted the arc's own spread
value from the lobe cells too, where the arc draws nothing (72 / 69 %). What still closes the door
under the amplitude physics (traced at 0.10 m, 8 approaches): in 4 the spread of very near echoes
(0.6-0.7 m) heard through a side lobe, whose uncarved 22.5° arc is so short (0.25 m) that one echo
alone (0.68 in log-odds) marks it, doorway included; in 3 the jamb at the main beam's edge (7-11°
off the axis, 1.2-1.4 m) with nothing on the map near its arc, the case the mark exists for; in 1 a
side-lobe echo at 0.71 m with nothing likely in its lobe.

Review (rev10s) fixes, kept: **first arrival**: a lobe that holds a cell more likely occupied than
not *nearer* than the echo cannot have produced it (a sonar reports the first echo it hears), so
that lobe is skipped. Without it mapped corridor walls crossing a near echo's circle 14-24° off the
axis "explained" an obstacle straight ahead: in a 1.2 m corridor a pole marked at 2.2 m left the map
at 1.9-1.6 m, 0.4 m from a wall it was never marked at 1.0-1.6 m (tests). Equally likely cells in
both lobes explain the echo (a symmetric scene got a lopsided map); ``side_lobes`` above
:data:`MAX_SIDE_LOBES` is refused (lobes reached behind the sensor); the lobe mark starts a cell
past the beam's edge (it added a whole hit to the arc's own band there). Their price, the door
under the amplitude physics: 83 / 78 -> 67 / 81 % (all but first arrival: 83 / 81 %; all but the
mark's start: 67 / 78 %), specular 100 /
94 -> 97 / 94 %; office and t-junction rows within 0.002 (``benchmarks/grids.py``, seeds 0-2, at
the fix against bac543c's rule). A safer map beats an open door. Left: a lobe cell that a wall
running along the beam puts at the lobe's outer edge still explains (the review's 0.4 m / 1.0 m
case); requiring that the lobe cell was heard from near this ray's bearing (``heard``) would
cover it. Tried instead of first arrival: the door back at 83 / 81 % and every side-lobe test
passed, but ``heard`` is written only when an arc leaves the history (about 20 s on the tours),
so walls heard since would again hide an obstacle ahead: not kept. As a condition on first
arrival's nearer cell: no change (67 / 81 %). Bearings recorded while arcs are live would make
the first safe.

**Clearing what was heard** (:attr:`CarvedGridParams.surface_aware`): the fade keeps a far
silent beam from erasing a wall it passed at a glancing angle, but it also keeps every far beam
from erasing an obstacle that has gone (the changing-scenes box stayed marked for good). So the
grid records, for every cell a final band marked, the bearings it was heard from
(:data:`HEARD_BINS` sectors of 11.25°, one bit each, 4 bytes a cell), since it was last freed
(free space brought its ``base`` from above 0 to 0 or below). A beam's free space at a
cell believed occupied (``base > 0``) is weighted by how likely that beam was to hear the
cell's surface, its *audibility* ``A`` (1 within one sector of a bearing the cell was heard
from, 1/2 at two, else 0: a smooth wall echoes only near normal incidence, so a beam from a
bearing the cell was heard from would have heard it again): ``l += γ(α) (A · logit(p_heard) +
(1 - A) f(d) · logit(p_miss))`` with ``p_heard`` = :attr:`CarvedGridParams.p_miss_heard` (0.2):
a beam that would have heard the surface and did not is strong evidence at any distance, a
glancing one keeps the faded weak update.

**Seen through** (:attr:`CarvedGridParams.see_through`): audibility is a property of a
surface, so it cannot clear the cells of an obstacle the returning robot only sees from the
other side. The changing-scenes box, heard on the way in from below (bearings 101-146°), kept
the cells of its near corner's arcs until the robot, on the way back, had driven 1.5-2 m past
it and its rear sensors looked at them from those bearings again (4.4 s after passing at
0.10 m, specular physics): the beams from above and abeam did pass through those cells, but
after passing through the box's other faces, which they would have heard (they were heard
from those bearings) and did not. A beam that passes a surface it would have heard and hears
nothing there has seen through where the obstacle stood: so a believed-occupied cell gets the
audibility of the most audible believed-occupied cell in front of it on the beam's ray (nearer
by a cell or more, the ray within half a cell diagonal of that cell's centre), when that cell is
at most ``see_through`` in front: the depth of an obstacle, not of a room. A glancing beam,
which would not have heard the face, clears nothing behind it either, so the walls a specular
sonar misses keep what stands behind them. Measured (``benchmarks/changing_scenes.py``, box,
seconds after the robot passes, seeds 0/1/2, no-echo readings): 0.10 m specular +4.4/+4.4/+4.4
before, +2.4/+0.6/-0.0 with 0.5 m; amplitude physics +3.0/+3.6/+3.6 before, +2.4/+2.4/+2.4;
0.05 m specular +6.2/+4.4/+4.4 before, +6.2/+1.2/+3.6 (seed 0's last cells are the box's
near corner itself, heard only from below: no beam from above passes anything to reach them).
Person and door: the same latencies and phantom shares. Swept 0.3, 0.5, 0.6, 1 and 5 m: 0.3 m
loses one snapshot on one seed, deeper gives the box nothing more and costs office recall
(echoes only, 0.05/0.10 m: 0.944/0.955 before, 0.943/0.954 with 0.5 m, 0.942/0.952 with 5 m;
with no-echo readings 0.893/0.933 before, 0.891/0.930 with 1 m; the opposite-sector rule of
:data:`HEARD_NEAR` cost up to 0.022); t-junction and doorway maps are the same.
The cells a beam can hold back for this are bounded (:data:`_HELD`, 512 a beam; the rest get
the plain update). Tried for the 0.05 m box and not kept, an occlusion test where the state is
deterministic: a final band skips a cell when a cell believed occupied (log-odds > 1.5) lies on the
ray from the sensor up to 0.5 m in front of it, beyond the band's width; the box still cleared
+5.55 s after passing on every seed (``benchmarks/box_trace.py``). The last cells (0.13-0.18 m
behind the wall the box stood against) get whole hits from arcs of the box's corner heard 2.0-2.4 m
away and carved to 0-6°, the cells within the band's width and half-cell widening of the arc's end;
when those arcs leave the history (21-23 s into the run) the wall between the sensor and them is
not on the map at all (log-odds -0.04 to -0.07 along the ray in front of them), so there is nothing
to occlude with.

A **no-echo** reading (``range`` = +inf, :attr:`~sonarcarve.readings.Reading.no_echo`) has
free space only: its beam's cells nearer than its ``max_range`` get the free-space update above
(same profile and fade), and it draws no band; the method carves the live arcs with it.

Following carving over time: the grid keeps two arrays, ``base`` (free space and the final
contributions of arcs that have left the history, clamped to ``[logit(p_min), logit(p_max)]``
after every update, octomap's way) and ``live`` (the sum of the current contributions of the
arcs still in the history, unclamped), and reads ``l = clamp(base + live)``. For each live arc it
remembers what it drew (origin, range, interval, value): when carving narrows the arc, the old
contribution is subtracted from ``live`` and the new one added, so the cells outside the new
interval lose exactly the log-odds they had gained and the cells inside gain (``s`` grows); when
the arc leaves the history its contribution is subtracted from ``live`` and added to ``base``,
final, in reading order (just before the free space of the reading that pushed it out), so the
map does not depend on how the readings were batched.

Memory: ``base`` (float32), ``live`` (float64), the fresh arcs' points (float32) and the heard
bearings (uint32), 20 bytes a cell, plus 25 numbers per storage slot (the history stores twice its
capacity; ``nbytes`` counts them) and the carving method's own state (bounded by its history; while
a batch is folded in, one more number per echo of the batch): bounded by the map size plus the
history, never by the length of the log (the method's global map, which does grow, is discarded
after each batch: the grid is the map).

``live`` is brought up to date lazily, when the map is read (:attr:`CarvedGrid.log_odds`,
:meth:`~CarvedGrid.probabilities`, :meth:`~CarvedGrid.trinary`, :meth:`~CarvedGrid.refresh`...),
not per reading; a read redraws only the arcs whose interval or value changed since the last
one (moving each in one pass), and with plain carving asks the method's estimates only for the
arcs whose carving state changed, so a robot can read its map at 5-10 Hz
(``benchmarks/grid_reads.py``). The map a read gives is the same bit for bit as redrawing
every arc would give; reads at other moments give the same map up to the rounding of the
additions and removals that the overlays sum (about 1e-15 in log-odds for the spread arcs'
float64 ``live``, 1e-7 for the float32 points).

The three grids of :mod:`sonarcarve.grids` share a small protocol (:class:`OccupancyMap`):
``resolution``, ``bounds``, ``extent``, ``shape``, ``cell_centers()`` and ``probabilities()``;
:func:`trinary` turns any of them into the ROS ``nav_msgs/OccupancyGrid`` convention (occupied
100, free 0, unknown -1) with that grid's own thresholds.
"""

from __future__ import annotations

from sonarcarve.grids.carved.classify import trinary
from sonarcarve.grids.carved.grid import CarvedGrid
from sonarcarve.grids.carved.heard import HEARD_BINS, HEARD_NEAR
from sonarcarve.grids.carved.params import (
    DEFAULT_MAX_INCIDENCE,
    DEFAULT_METHOD,
    DEFAULT_SEE_THROUGH,
    DEFAULT_SIDE_LOBE_RANGE,
    DEFAULT_SIDE_LOBES,
    DEFAULT_SPREAD_LENGTH,
    MAX_SIDE_LOBES,
    CarvedGridParams,
)
from sonarcarve.grids.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "DEFAULT_MAX_INCIDENCE",
    "DEFAULT_METHOD",
    "DEFAULT_SEE_THROUGH",
    "DEFAULT_SIDE_LOBES",
    "DEFAULT_SIDE_LOBE_RANGE",
    "DEFAULT_SPREAD_LENGTH",
    "FREE",
    "HEARD_BINS",
    "HEARD_NEAR",
    "MAX_SIDE_LOBES",
    "OCCUPIED",
    "UNKNOWN",
    "CarvedGrid",
    "CarvedGridParams",
    "OccupancyMap",
    "trinary",
]
