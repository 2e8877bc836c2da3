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

import math
from dataclasses import dataclass
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry import ArcFate
from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.repeats import is_repeat
from sonarcarve.grids.cells import CellGrid, GridError
from sonarcarve.grids.elfes import MAX_CELLS, ROS_FADE_RANGE, OccupancyGrid
from sonarcarve.grids.range_sensor_layer import (
    FREE_SPACE,
    LETHAL_OBSTACLE,
    RangeSensorLayer,
)
from sonarcarve.history import SonarHistory
from sonarcarve.maps import CountingSink
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.base import Estimates, arc_point
from sonarcarve.methods.carving import CarvingMethod, CarvingModel
from sonarcarve.methods.combined import CombinedMethod
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE
from sonarcarve.readings import Reading, ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = [
    "DEFAULT_MAX_INCIDENCE",
    "DEFAULT_METHOD",
    "DEFAULT_SEE_THROUGH",
    "DEFAULT_SIDE_LOBES",
    "DEFAULT_SIDE_LOBE_RANGE",
    "DEFAULT_SPREAD_LENGTH",
    "FREE",
    "HEARD_BINS",
    "OCCUPIED",
    "UNKNOWN",
    "CarvedGrid",
    "CarvedGridParams",
    "OccupancyMap",
    "trinary",
]

#: Trinary cell values, as in ROS ``nav_msgs/OccupancyGrid``.
OCCUPIED = 100
FREE = 0
UNKNOWN = -1

Int8Grid = npt.NDArray[np.int8]

#: Length over which one echo counts as a whole hit, metres
#: (:attr:`CarvedGridParams.spread_length`).
#: Measured (``benchmarks/grids.py``, office, seeds 0-1, 0.05 and 0.10 m cells, fade 1.2 m, β 30°):
#: occupied precision / recall 0.81 / 0.84 at 0.05 m with 0.1, 0.72 / 0.95 with 0.2, 0.64 / 0.96
#: with 0.3; 0.2 is the shortest that keeps recall above the range sensor layer's at both
#: resolutions.
DEFAULT_SPREAD_LENGTH = 0.2
#: The method the grid runs by default (:class:`CarvedGrid`): carving and ATM on one history
#: (the paper's section 4), whose crossings narrow the interval a band is drawn over. Measured
#: against specular-aware carving alone (``benchmarks/grid_methods.py`` and the issue-10
#: benchmarks, office, seeds 0-2): occupied precision 0.720 -> 0.790 (0.05 m) and 0.825 ->
#: 0.901 (0.10 m) under the specular physics, 0.721 -> 0.775 and 0.853 -> 0.935 under the
#: amplitude physics, recall within ±0.005, phantoms -40 %; the Fig. 2 door 83/78 -> 92/86 %
#: passable (89/86 -> 97/94 % with no-echo readings); a crossing person forgotten in 0.2 s
#: instead of 5.2 s. Its price: more CPU per reading (ATM's crossings and medians), most
#: visible when the map is read every few readings (``benchmarks/grid_reads.py``: 2.0x / 3.9x
#: the range sensor layer's at 0.05 / 0.10 m, read every 5 readings, against 1.7x / 2.7x).
DEFAULT_METHOD = "combined"
#: Critical angle of the default method's specular-aware carving, radians (20°). Paper
#: carving (π/2) loses 45 % of the office's true echoes to glancing free space, and the grid's
#: recall with them (0.20 at 0.05 m against 0.53); with combined carving 20° kept recall where
#: 30° lost 0.004-0.023 of it (office 0.937 / 0.953 against 0.914 / 0.947 at 0.05 / 0.10 m).
DEFAULT_MAX_INCIDENCE = math.radians(20.0)

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
DEFAULT_SIDE_LOBES = 1.0
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
#: Sectors of bearing in which the carved grid records where each cell was heard from.
HEARD_BINS = 32
#: One bit a sector in each cell's word: more sectors than bits would shift out of it silently.
_HEARD_DTYPE = np.uint32
if not 0 < HEARD_BINS <= np.iinfo(_HEARD_DTYPE).bits:
    raise AssertionError(f"HEARD_BINS must lie in 1..{np.iinfo(_HEARD_DTYPE).bits}, "
                         f"got {HEARD_BINS}")
#: A beam within this many sectors of a bearing a cell was heard from would hear it again (one
#: more sector: half as likely). Measured: 2 changes the box's clearing time by nothing and
#: costs 0.003-0.004 of office recall. Tried and not kept: counting the opposite sectors too
#: (a beam from behind a surface meets the object's back first) clears the changing-scenes box
#: 3.0-3.6 s after the robot passes instead of 4.4 s (0.10 m, no-echo readings, seeds 0-2), but
#: clears true walls: office recall 0.944 -> 0.938 (0.05 m) and 0.955 -> 0.949 (0.10 m, the
#: layer's 0.947), with no-echo readings 0.893 -> 0.871 and 0.933 -> 0.911.
HEARD_NEAR = 1

_TWO_PI = 2.0 * math.pi
#: Cells believed occupied one beam's free space can hold back for :func:`_free_behind`; the
#: rest get the plain update.
_HELD = 512
_ALIVE = int(ArcFate.ALIVE)


def _logit(p: float) -> float:
    return math.log(p / (1.0 - p))


@runtime_checkable
class OccupancyMap(Protocol):
    """What every grid of :mod:`sonarcarve.grids` offers: geometry and probabilities.

    Cell ``(i, j)`` (row i along y, column j along x) is the square of side ``resolution`` whose
    centre is ``(xmin + (j + 1/2) h, ymin + (i + 1/2) h)`` for ``(xmin, ymin)`` the first two
    numbers of ``bounds``.
    """

    @property
    def resolution(self) -> float:
        """Cell side, metres."""

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` as given, metres."""

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` covered by the cells, metres."""

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, columns)``."""

    def cell_centers(self) -> tuple[FloatArray, FloatArray]:
        """Centres of the columns and of the rows, metres."""

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, shape :attr:`shape`."""


def trinary(grid: OccupancyMap) -> Int8Grid:
    """Occupied (100), free (0) or unknown (-1) for every cell, shape ``grid.shape``.

    Each grid with its own rule: :class:`CarvedGrid` with its
    :attr:`CarvedGridParams.occupied_threshold` and ``free_threshold``, compared in log-odds
    (:meth:`CarvedGrid.trinary`: equal to comparing probabilities up to rounding within a few
    ulp of the thresholds);
    :class:`~sonarcarve.grids.RangeSensorLayer` as it writes its master costmap
    (:meth:`~sonarcarve.grids.RangeSensorLayer.costs`: lethal above ``mark_threshold``, free
    below ``clear_threshold``); :class:`~sonarcarve.grids.OccupancyGrid` (Elfes) occupied above
    its default threshold (0.65) and free below 0.196 (map_saver's ``free_thresh``); any other
    :class:`OccupancyMap` by probability with those two thresholds.

    Examples
    --------
    >>> g = CarvedGrid(0.1, (0.0, 0.0, 1.0, 1.0))
    >>> trinary(g)[0, :3].tolist()  # nothing seen yet
    [-1, -1, -1]
    """
    if isinstance(grid, CarvedGrid):
        return grid.trinary()
    if isinstance(grid, RangeSensorLayer):
        costs = grid.costs()
        out = np.full(costs.shape, UNKNOWN, dtype=np.int8)
        out[costs == LETHAL_OBSTACLE] = OCCUPIED
        out[costs == FREE_SPACE] = FREE
        return out
    if isinstance(grid, OccupancyGrid):
        return _classify(grid.probabilities(), CarvedGridParams.occupied_threshold,
                         CarvedGridParams.free_threshold)
    return _classify(np.asarray(grid.probabilities(), dtype=np.float64),
                     CarvedGridParams.occupied_threshold, CarvedGridParams.free_threshold)


def _classify(p: FloatArray, occupied: float, free: float) -> Int8Grid:
    """Occupied where the probability ``p`` is above ``occupied``, free below ``free``."""
    out = np.full(p.shape, UNKNOWN, dtype=np.int8)
    out[p > occupied] = OCCUPIED
    out[p < free] = FREE
    return out


def _check_probability(name: str, value: object, lo: float, hi: float) -> float:
    ok = (not isinstance(value, bool) and isinstance(value, int | float)
          and math.isfinite(value) and lo < value < hi)
    if not ok:
        msg = f"carved grid: {name} must lie in ({lo:g}, {hi:g}), got {value!r}"
        raise GridError(msg)
    return float(value)  # type: ignore[arg-type]


@dataclass(frozen=True)
class CarvedGridParams:
    """Parameters of the carved grid's sensor model (module docstring).

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
        :meth:`CarvedGrid.trinary` calls a cell occupied above the first and free below the
        second (``0 < free < occupied < 1``); 0.65 (as the Elfes grid) and 0.196 (ROS
        map_saver's ``free_thresh``). Compared in log-odds (``l > logit(occupied)``), which
        equals comparing :meth:`CarvedGrid.probabilities` with the threshold up to rounding:
        a cell within a few ulp of a threshold's logit may fall on the other side.
    range_tolerance : float
        ε, metres >= 0: the occupied band is ``r ± (h + ε)/2``; carving's default 5 cm.
    spread : bool
        Spread each echo over its carved interval (``s`` in the module docstring); False gives
        every cell of the carved band a whole hit (Elfes' rule, on the carved interval).
    spread_length : float
        ``L``, metres >= 0: an arc carved to this length or shorter gives its cells a whole hit
        (the cell side where larger); :data:`DEFAULT_SPREAD_LENGTH`.
    fade_range : float
        ``d_f``, metres > 0, of the free-space fade; ``inf``: no fade. Default ROS's 1.2 m.
    surface_aware : bool
        Weigh the free space at cells believed occupied by the beam's audibility (module
        docstring); False: the fade everywhere, the rule of the grid before issue 10's clearing
        work, equal to it up to rounding order (the fade is now applied as
        ``γ · (logit(p_miss) · f)``, before as ``(γ · f) · logit(p_miss)``).
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
        Each sensor's newest echo, when no occupied cell on its carved band explains it, is a
        whole hit on the middle ``spread_length`` of its carved interval (its spread value on
        the rest) until that sensor fires again (module docstring: a person stepping in front
        of the robot is marked after one reading). Where the map favours another part of the
        band and not the middle, the whole hit goes around the band's most likely cell instead
        (module docstring, "where the mark goes": the Fig. 2 door, echoes only, 92 -> 97 % /
        86 -> 94 % passable at 0.05 / 0.10 m). False: every live arc spread, the rule
        before.
    fresh_seconds : float
        Seconds > 0 a newest echo stays fresh at most, counted back from the newest reading the
        grid has seen; 2.0. A log that drops silent firings (echoes only, or max-range readings
        filtered out) never shows the sensor "firing again", and without this bound a person
        heard once would stay marked until the arc left the history (20 s on a 16-sonar ring).
        2 s is three cycles of such a ring at 40 ms a sonar (0.64 s, the simulator's Scout2),
        so a sensor that keeps hearing an obstacle keeps it marked; set it to 2-3 ring periods
        of a slower ring.
    side_lobes : float
        Number in [0, :data:`MAX_SIDE_LOBES`]; :data:`DEFAULT_SIDE_LOBES` (1). How far past
        each edge of its beam, in half beam widths, a near echo may have come from through a
        side lobe, for the newest echo's mark (module docstring, "side lobes"): an occupied
        cell there explains the echo, and the mark goes to a likely one there when the map does
        not favour the arc's middle. 0: the beam alone (the rule before).
    side_lobe_range : float
        Metres >= 0 (``inf``: every range); :data:`DEFAULT_SIDE_LOBE_RANGE` (2). Echoes farther
        than this are judged on their carved interval alone (the lobes are too weak to hear far
        reflectors; at every range the corridor walls beside a shut door 2.4-4.8 m ahead
        explained its echoes and it was never marked).
    repeat_weight : float
        In [0, 1]; 0. The factor of an arc's weight once a later echo of its sensor repeats it
        (module docstring, "Repeated echoes count once": the sensor moved towards or away from
        one reflector and heard it again): 0 counts a run of repeats as its
        newest echo, 1 counts every echo (the rule before). Measured (seeds 0-2, Fig. 2 door
        at 1 m, echoes only, 0.05 / 0.10 m): 1 passable in 67 / 61 % of approaches, 0.25 in
        69 / 58 % (0.5 the same), 0 in 83 / 78 %; office precision / recall unchanged within
        0.003.
    see_through : float
        Metres >= 0 (``inf``: no limit; 0: off); :data:`DEFAULT_SEE_THROUGH`. A beam that
        passes a cell it would have heard (surface-aware audibility) and hears nothing there
        clears the believed-occupied cells behind that cell on its ray, up to this far behind
        it, as if it would have heard them too (module docstring, "seen through"). It acts only
        with ``surface_aware`` (without it no beam is known to have heard a cell, so nothing is
        seen through and the value is ignored).

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
    free_threshold: float = 0.196
    range_tolerance: float = DEFAULT_RANGE_TOLERANCE
    spread: bool = True
    spread_length: float = DEFAULT_SPREAD_LENGTH
    fade_range: float = ROS_FADE_RANGE
    surface_aware: bool = True
    p_miss_heard: float = 0.2
    band_profile: float = 0.0
    fresh_arcs: bool = True
    fresh_seconds: float = 2.0
    see_through: float = DEFAULT_SEE_THROUGH
    repeat_weight: float = 0.0
    side_lobes: float = DEFAULT_SIDE_LOBES
    side_lobe_range: float = DEFAULT_SIDE_LOBE_RANGE

    def __post_init__(self) -> None:
        _check_probability("p_hit", self.p_hit, 0.5, 1.0)
        _check_probability("p_miss", self.p_miss, 0.0, 0.5)
        _check_probability("p_min", self.p_min, 0.0, 0.5)
        _check_probability("p_max", self.p_max, 0.5, 1.0)
        _check_probability("occupied_threshold", self.occupied_threshold, 0.0, 1.0)
        _check_probability("free_threshold", self.free_threshold, 0.0, self.occupied_threshold)
        tol = self.range_tolerance
        if isinstance(tol, bool) or not isinstance(tol, int | float) or not (
                math.isfinite(tol) and tol >= 0.0):
            msg = f"carved grid: range_tolerance must be a finite number >= 0 metres, got {tol!r}"
            raise GridError(msg)
        for name in ("spread_length", "fade_range"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                    value >= 0.0 if name == "spread_length" else value > 0.0) or (
                    name == "spread_length" and not math.isfinite(value)):
                rule = "a finite number >= 0" if name == "spread_length" else "> 0 (inf: none)"
                msg = f"carved grid: {name} must be {rule} metres, got {value!r}"
                raise GridError(msg)
        _check_probability("p_miss_heard", self.p_miss_heard, 0.0, 0.5)
        for name in ("spread", "surface_aware", "fresh_arcs"):
            if not isinstance(getattr(self, name), bool):
                msg = f"carved grid: {name} must be True or False, got {getattr(self, name)!r}"
                raise GridError(msg)
        st = self.see_through
        if isinstance(st, bool) or not isinstance(st, int | float) or not st >= 0.0:
            msg = (f"carved grid: see_through must be a number >= 0 metres (inf: no limit), "
                   f"got {st!r}")
            raise GridError(msg)
        fs = self.fresh_seconds
        if isinstance(fs, bool) or not isinstance(fs, int | float) or not (
                math.isfinite(fs) and fs > 0.0):
            msg = f"carved grid: fresh_seconds must be a finite number > 0, got {fs!r}"
            raise GridError(msg)
        rw = self.repeat_weight
        if isinstance(rw, bool) or not isinstance(rw, int | float) or not 0.0 <= rw <= 1.0:
            msg = f"carved grid: repeat_weight must be a number in [0, 1], got {rw!r}"
            raise GridError(msg)
        sl = self.side_lobes
        if isinstance(sl, bool) or not isinstance(sl, int | float) or not (
                0.0 <= sl <= MAX_SIDE_LOBES):
            msg = (f"carved grid: side_lobes must be a number in [0, {MAX_SIDE_LOBES:g}] half "
                   f"beam widths, got {sl!r}")
            raise GridError(msg)
        sr = self.side_lobe_range
        if isinstance(sr, bool) or not isinstance(sr, int | float) or not sr >= 0.0:
            msg = (f"carved grid: side_lobe_range must be a number >= 0 metres (inf: every "
                   f"range), got {sr!r}")
            raise GridError(msg)
        bp = self.band_profile
        if isinstance(bp, bool) or not isinstance(bp, int | float) or not (
                math.isfinite(bp) and bp >= 0.0):
            msg = f"carved grid: band_profile must be a finite number >= 0, got {bp!r}"
            raise GridError(msg)


# -- compiled kernels -----------------------------------------------------------------------------

class _Model(NamedTuple):
    """The grid's geometry and sensor model as the kernels use them (metres, log-odds), one
    argument instead of fourteen positional numbers that could be swapped unnoticed."""

    xmin: float
    ymin: float
    h: float
    band: float  # b, half-width of the occupied band
    l_hit: float
    l_miss: float
    l_heard: float  # logit(p_miss_heard)
    l_min: float
    l_max: float
    spread: float  # 1.0: spread each echo over its carved interval, 0.0: not
    unit: float  # max(spread_length, h)
    fade: float  # d_f, inf: no fade
    aware: bool
    profile: float  # band_profile
    l_occupied: float  # logit(occupied_threshold)
    through: float  # see_through, metres (0: off)
    lobes: float  # side_lobes: the explanation reaches this many half beam widths past an edge
    lobe_range: float  # side_lobe_range, metres: only echoes at this range or nearer


@compiled_inline
def _cell_range(lo: float, hi: float, origin: float, h: float, n: int) -> tuple[int, int]:
    """Indices ``k0..k1`` of the cells whose centres may lie in ``[lo, hi]`` (one cell of
    slack each side; the exact test is the caller's)."""
    k0 = max(0, math.floor((lo - origin) / h - 0.5) - 1)
    k1 = min(n - 1, math.ceil((hi - origin) / h - 0.5) + 1)
    return k0, k1


@compiled_inline
def _sector_box(x: float, y: float, t1: float, t2: float, r_in: float,
                r_out: float) -> tuple[float, float, float, float]:
    """Bounding box of the annular sector ``r_in <= d <= r_out``, bearings ``[t1, t2]``."""
    xlo = min(x + r_in * math.cos(t1), x + r_in * math.cos(t2),
              x + r_out * math.cos(t1), x + r_out * math.cos(t2))
    xhi = max(x + r_in * math.cos(t1), x + r_in * math.cos(t2),
              x + r_out * math.cos(t1), x + r_out * math.cos(t2))
    ylo = min(y + r_in * math.sin(t1), y + r_in * math.sin(t2),
              y + r_out * math.sin(t1), y + r_out * math.sin(t2))
    yhi = max(y + r_in * math.sin(t1), y + r_in * math.sin(t2),
              y + r_out * math.sin(t1), y + r_out * math.sin(t2))
    # The outer circle's extreme points at the cardinal bearings inside the interval.
    for k in range(4):
        a = 0.5 * math.pi * k
        a += _TWO_PI * math.ceil((t1 - a) / _TWO_PI)
        if a <= t2:
            if k == 0:
                xhi = x + r_out
            elif k == 1:
                yhi = y + r_out
            elif k == 2:
                xlo = x - r_out
            else:
                ylo = y - r_out
    return xlo, ylo, xhi, yhi


@compiled_inline
def _arc_value(r: float, lo: float, hi: float, weight: float, m: _Model,
               fresh: bool = False) -> float:
    """Log-odds one arc adds to each cell of its carved band: ``c · s · logit(p_hit)``; a
    ``fresh`` arc (the newest reading of its sensor, :attr:`CarvedGridParams.fresh_arcs`)
    ``c · logit(p_hit)``, unspread."""
    if not weight > 0.0:
        return 0.0
    s = 1.0
    if m.spread > 0.0 and not fresh:
        length = r * (hi - lo)
        if length > m.unit:
            s = m.unit / length
    return weight * s * m.l_hit


#: Margin of :func:`_surely_within`'s dot-product test: far above its rounding (about 1e-15)
#: and that of the bearing test it stands for, so the two never disagree outside it.
_EDGE = 1e-9
#: Log-odds above which a cell counts as more likely occupied than not where a fresh arc's
#: point is placed (:func:`_band_likeliest`): 0, up to the rounding of ``live``'s sums of
#: additions and removals (about 1e-15) and of float32 ``base``.
_LIKELY = 1e-6
#: Log-odds within which two cells are equally likely where a fresh arc's point is placed: far
#: above ``live``'s rounding (1e-15), which depends on when the map was read. Cells covered by
#: the same arcs are equal up to that rounding; a strict ``>`` let the rounding, and the scan
#: order, pick among them (review rev10: the mark moved with the read schedule and with the
#: grid's orientation), so equals go to the cell nearest the middle.
_TIE = 1e-9


@compiled_inline
def _bearing_off(dx: float, dy: float, mid: float) -> float:
    """Bearing of ``(dx, dy)`` minus ``mid``, wrapped into ``[-π, π)``."""
    off = math.atan2(dy, dx) - mid
    off -= _TWO_PI * math.floor((off + math.pi) / _TWO_PI)
    return off


@compiled_inline
def _within(dx: float, dy: float, d: float, mid: float, half: float, cos_mid: float,
            sin_mid: float, cos_half: float) -> bool:
    """``|_bearing_off(dx, dy, mid)| <= half``, the bearing test of :func:`_draw_arc`, with the
    arctangent only near the interval's edges: ``(dx, dy)`` (length ``d``) is within ``half``
    of the direction ``(cos_mid, sin_mid)`` when its cosine to it is above ``cos_half`` (-2
    when ``half >= π``: every bearing), and the cosine decides wherever it is more than
    :data:`_EDGE` from ``cos_half``: there both tests' rounding (1e-15) cannot change the
    answer, so the answer is the same bit for bit."""
    if d > 0.0:
        q = (dx * cos_mid + dy * sin_mid) / d - cos_half
        if q > _EDGE:
            return True
        if q < -_EDGE:
            return False
    return abs(_bearing_off(dx, dy, mid)) <= half


@compiled_inline
def _cos_half(half: float) -> float:
    """``cos(half)`` for :func:`_within`; -2 (every bearing) when ``half >= π``."""
    return math.cos(half) if half < math.pi else -2.0


@compiled_inline
def _ring_columns(dy: float, r_in: float, r_out: float, x: float, xmin: float, h: float,
                  nx: int, j0: int, j1: int) -> tuple[int, int, int, int]:
    """The columns ``a0..a1`` and ``b0..b1`` (disjoint, left then right; empty when the first
    index is larger) of the row ``dy`` (relative to the centre ``x``) whose cell centres may
    lie in the ring ``r_in <= d <= r_out``, within ``j0..j1``: one cell of slack each side, the
    exact test is the caller's."""
    rest = r_out * r_out - dy * dy
    if rest < 0.0:
        return 1, 0, 1, 0
    outer = math.sqrt(rest)
    inner = math.sqrt(max(0.0, r_in * r_in - dy * dy))
    a0, a1 = _cell_range(x - outer, x - inner, xmin, h, nx)
    b0, b1 = _cell_range(x + inner, x + outer, xmin, h, nx)
    a0, a1, b0, b1 = max(a0, j0), min(a1, j1), max(b0, j0), min(b1, j1)
    if b0 <= a1 + 1:  # the two stretches touch: one
        return min(a0, b0), max(a1, b1), 1, 0
    return a0, a1, b0, b1


@compiled_inline
def _draw_arc(grid: npt.NDArray[np.floating], clamp: bool, heard: npt.NDArray[np.uint32],
              m: _Model, x: float, y: float, r: float, lo: float, hi: float,
              value: float) -> None:
    """Add ``value`` to the cells of the arc's band (clamped into ``[l_min, l_max]`` if
    ``clamp``): centre within ``band`` of the circle, bearing within ``[lo, hi]`` widened by
    ``h / 2r``. A final (``clamp``) band with ``value > 0`` also records in ``heard`` the
    bearing each cell was heard from."""
    if value == 0.0:
        return
    xmin, ymin, h, band, profile = m.xmin, m.ymin, m.h, m.band, m.profile
    ny, nx = grid.shape
    widen = 0.5 * h / r
    t1 = lo - widen
    t2 = hi + widen
    mid = 0.5 * (t1 + t2)
    half = 0.5 * (t2 - t1)
    r_in = max(0.0, r - band)
    r_out = r + band
    xlo, ylo, xhi, yhi = _sector_box(x, y, t1, t2, r_in, r_out)
    j0, j1 = _cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = _cell_range(ylo, yhi, ymin, h, ny)
    # Only a plain live draw needs no bearing: it then takes the cheap bearing test.
    plain = not clamp and not profile > 0.0
    cos_mid, sin_mid, cos_half = math.cos(mid), math.sin(mid), _cos_half(half)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = _ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if plain:
                    if _within(dx, dy, d, mid, half, cos_mid, sin_mid, cos_half):
                        grid[i, j] += value
                    continue
                off = _bearing_off(dx, dy, mid)
                if abs(off) > half:
                    continue
                v = value
                if profile > 0.0:
                    u = off / half
                    v *= min(1.0, profile * (1.0 - u * u))
                if clamp:
                    grid[i, j] = min(m.l_max, max(m.l_min, grid[i, j] + v))
                    if v > 0.0:
                        heard[i, j] |= 1 << _heard_bin(mid + off)
                else:
                    grid[i, j] += v


@compiled_inline
def _heard_bin(bearing: float) -> int:
    """Bin of a ray's bearing (origin to cell) among :data:`HEARD_BINS` equal sectors."""
    k = math.floor((bearing + math.pi) / _TWO_PI * HEARD_BINS)
    return k % HEARD_BINS


@compiled_inline
def _audibility(heard: int, k: int) -> float:
    """How likely a ray in bin ``k`` was to hear the surface of a cell heard from the bins
    set in ``heard``: 1 within one bin (11.25°) of a bin it was heard from, 1/2 at two bins,
    else 0."""
    if heard == 0:
        return 0.0
    near = 0
    far = 0
    for o in range(-HEARD_NEAR - 1, HEARD_NEAR + 2):
        bit = 1 << ((k + o) % HEARD_BINS)
        if abs(o) > HEARD_NEAR:
            far |= bit
        else:
            near |= bit
    if heard & near:
        return 1.0
    if heard & far:
        return 0.5
    return 0.0


@compiled_inline
def _row_span(dy: float, reach: float, half: float, u1x: float, u1y: float, u2x: float,
              u2y: float) -> tuple[float, float]:
    """``(lo, hi)`` of ``dx`` on the line ``dy`` (relative to the apex) inside the sector of
    radius ``reach`` between the unit directions ``u1`` (clockwise edge) and ``u2``; empty
    when ``lo > hi``. The sector is the disk cut by two half-planes when ``half < π/2``."""
    rest = reach * reach - dy * dy
    if rest < 0.0:
        return 1.0, 0.0
    hi = math.sqrt(rest)
    lo = -hi
    if half >= 0.5 * math.pi:
        return lo, hi
    # Counter-clockwise of u1: u1x dy - u1y dx >= 0.
    if u1y > 0.0:
        hi = min(hi, u1x * dy / u1y)
    elif u1y < 0.0:
        lo = max(lo, u1x * dy / u1y)
    elif u1x * dy < 0.0:
        return 1.0, 0.0
    # Clockwise of u2: u2y dx - u2x dy >= 0.
    if u2y > 0.0:
        lo = max(lo, u2x * dy / u2y)
    elif u2y < 0.0:
        hi = min(hi, u2x * dy / u2y)
    elif u2x * dy > 0.0:
        return 1.0, 0.0
    return lo, hi


@compiled_inline
def _free_space(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: _Model,
                x: float, y: float, theta: float, r: float, half: float,
                held: FloatArray) -> None:
    """One reading's free space on the beam's cells nearer than ``r - band``, clamped into
    ``[l_min, l_max]``: ``γ(α) f(d) · logit(p_miss)`` (``f`` the fade) on cells not believed
    occupied (``base <= 0``), and where ``aware`` on the others
    ``γ(α) (A · logit(p_heard) + (1 - A) f(d) · logit(p_miss))``, ``A`` the cell's
    :func:`_audibility` from the beam's bearing (``aware`` False: the fade for all).

    A cell this brings from ``base > 0`` to ``base <= 0`` forgets the bearings it was heard
    from (module docstring)."""
    reach = r - m.band
    if reach <= 0.0:
        return
    xmin, ymin, h, l_miss, fade = m.xmin, m.ymin, m.h, m.l_miss, m.fade
    ny, nx = base.shape
    c, s, cos_half = math.cos(theta), math.sin(theta), math.cos(half)
    xlo, ylo, xhi, yhi = _sector_box(x, y, theta - half, theta + half, 0.0, reach)
    j0, j1 = _cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = _cell_range(ylo, yhi, ymin, h, ny)
    t1, t2 = theta - half, theta + half
    u1x, u1y, u2x, u2y = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
    n_held = 0
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        # Only the row's stretch inside the sector (plus a cell each side; the exact test is
        # per cell below): most of the bounding box of a slanted beam lies outside it.
        lo, hi = _row_span(dy, reach, half, u1x, u1y, u2x, u2y)
        if lo > hi:
            continue
        ja, jb = _cell_range(x + lo, x + hi, xmin, h, nx)
        for j in range(max(j0, ja), min(j1, jb) + 1):
            dx = xmin + (j + 0.5) * h - x
            d2 = dx * dx + dy * dy
            if d2 >= reach * reach:
                continue
            along = dx * c + dy * s
            if along < math.sqrt(d2) * cos_half:
                continue
            a = math.atan2(dy * c - dx * s, along)
            w = 1.0 - (a / half) ** 2
            cell = base[i, j]
            miss = l_miss
            if fade < math.inf:
                miss *= 0.5 * (1.0 - math.tanh(2.0 * (math.sqrt(d2) - fade)))
            if m.aware and cell > 0.0:
                audible = _audibility(int(heard[i, j]), _heard_bin(theta + a))
                if m.through > 0.0 and n_held < held.shape[0]:
                    held[n_held, 0] = i
                    held[n_held, 1] = j
                    held[n_held, 2] = math.sqrt(d2)
                    held[n_held, 3] = a
                    held[n_held, 4] = w
                    held[n_held, 5] = audible
                    held[n_held, 6] = miss
                    n_held += 1
                    continue
                miss = audible * m.l_heard + (1.0 - audible) * miss
            base[i, j] = min(m.l_max, max(m.l_min, cell + w * miss))
            # Freed: the surface it was heard from is believed gone, so are its bearings (else
            # a later, different surface here would be cleared at full strength from them).
            # Now, at the crossing, and not when a band next marks the cell: the bits are read
            # only while base > 0, which only a final band restores, so the bearings kept are
            # exactly those heard since the cell was freed; forgetting them at every free-space
            # update below 0 would drop the bands that raised the cell back, and forgetting at
            # the next band would keep only that band's. The stored (float32) value decides,
            # as it does when the bits are read.
            if cell > 0.0 and base[i, j] <= 0.0:
                heard[i, j] = 0
    if n_held:
        _free_behind(base, heard, m, held, n_held)


@compiled_inline
def _free_behind(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: _Model,
                 held: FloatArray, n: int) -> None:
    """The free space of the cells believed occupied that one beam passed (``held``: row,
    column, distance, bearing off the axis, profile, audibility, faded miss), each as audible
    as the most audible such cell in front of it on its ray (nearer by at least a cell and by
    at most ``through``, its ray within half a cell diagonal of that cell's centre): a surface
    the beam would have heard and did not is gone, and so is what stood behind it."""
    h = m.h
    for p in range(n):
        audible = held[p, 5]
        d = held[p, 2]
        for q in range(n):
            dq = held[q, 2]
            if (held[q, 5] > audible and dq <= d - h and d - dq <= m.through
                    and abs(held[p, 3] - held[q, 3]) * dq <= 0.7072 * h):
                audible = held[q, 5]
        i, j = int(held[p, 0]), int(held[p, 1])
        cell = base[i, j]
        miss = audible * m.l_heard + (1.0 - audible) * held[p, 6]
        base[i, j] = min(m.l_max, max(m.l_min, cell + held[p, 4] * miss))
        if cell > 0.0 and base[i, j] <= 0.0:
            heard[i, j] = 0


@compiled
def _fold_kernel(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: _Model,
                 x: FloatArray, y: FloatArray, theta: FloatArray, r: FloatArray,
                 half: FloatArray, seqs: npt.NDArray[np.int64], capacity: int,
                 finals: _Finals) -> None:
    """The final updates of a batch in reading order: before the free space of reading ``k``
    (arc sequence number ``seqs[k]``; for a no-echo reading, the newest arc before it), the
    final band of every arc it pushed out of the history (``finals.seq + capacity <= seq``)."""
    p = 0
    nf = finals.seq.shape[0]
    held = np.empty((_HELD if m.through > 0.0 else 0, 7), dtype=np.float64)
    for k in range(x.shape[0]):
        while p < nf and finals.seq[p] + capacity <= seqs[k]:
            _draw_final(base, heard, m, finals, p)
            p += 1
        _free_space(base, heard, m, x[k], y[k], theta[k], r[k], half[k], held)
    while p < nf:
        _draw_final(base, heard, m, finals, p)
        p += 1


@compiled_inline
def _draw_final(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: _Model,
                finals: _Finals, p: int) -> None:
    """Arc ``p`` of ``finals`` into ``base``, for good."""
    value = _arc_value(finals.r[p], finals.lo[p], finals.hi[p], finals.weight[p], m)
    _draw_arc(base, True, heard, m, finals.x[p], finals.y[p], finals.r[p], finals.lo[p],
              finals.hi[p], value)


@compiled
def _undraw_kernel(live: npt.NDArray[np.floating], drawn: FloatArray,
                   drawn_seq: npt.NDArray[np.int64], slots: SlotArray, seqs: npt.NDArray[np.int64],
                   heard: npt.NDArray[np.uint32], m: _Model) -> None:
    """Take the drawn contribution of arcs ``seqs`` (in ``slots``) out of ``live``."""
    for k in range(slots.shape[0]):
        slot = slots[k]
        if drawn_seq[slot] != seqs[k]:
            continue
        _undraw(live, heard, m, drawn, slot)
        drawn_seq[slot] = -1


@compiled
def _refresh_kernel(base: npt.NDArray[np.float32], live: FloatArray,
                    points: npt.NDArray[np.float32], drawn: FloatArray,
                    drawn_seq: npt.NDArray[np.int64], pdrawn: FloatArray,
                    pseq: npt.NDArray[np.int64], slots: SlotArray,
                    seqs: npt.NDArray[np.int64], x: FloatArray, y: FloatArray, r: FloatArray,
                    lo: FloatArray, hi: FloatArray, weight: FloatArray, fresh: BoolArray,
                    with_points: bool, heard: npt.NDArray[np.uint32], m: _Model,
                    theta1: FloatArray, theta2: FloatArray) -> int:
    """Bring ``live`` (and, ``with_points``, ``points``) up to date with the live arcs
    ``slots`` (arcs ``seqs``); ``x, y, r`` (the history's rows) and ``lo, hi, weight``
    (:func:`_intervals`) are indexed by slot, ``fresh`` by position. First every arc whose
    interval or value changed is redrawn into ``live``, then the points are judged on the whole
    updated spread map (:func:`_refresh_points`). Returns how many arcs and points changed."""
    changed = 0
    for k in range(slots.shape[0]):
        s = slots[k]
        value = _arc_value(r[s], lo[s], hi[s], weight[s], m)
        # _redraw's own test first: most arcs did not change, and the call costs more.
        if (drawn_seq[s] == seqs[k] and drawn[s, 3] == lo[s] and drawn[s, 4] == hi[s]
                and drawn[s, 5] == value):
            continue
        changed += _redraw(live, drawn, drawn_seq, s, seqs[k], x[s], y[s], r[s], lo[s],
                           hi[s], value, heard, m)
    if with_points:
        for k in range(slots.shape[0]):
            if not fresh[k] and pseq[slots[k]] < 0:  # no point, and none to draw
                continue
            changed += _refresh_points(base, live, points, drawn, pdrawn, pseq, slots[k],
                                       seqs[k], x, y, r, lo, hi, weight, fresh[k], heard, m,
                                       theta1[slots[k]], theta2[slots[k]])
    return changed


@compiled_inline
def _refresh_points(base: npt.NDArray[np.float32], live: FloatArray,
                    points: npt.NDArray[np.float32], drawn: FloatArray, pdrawn: FloatArray,
                    pseq: npt.NDArray[np.int64], slot: int, seq: int, x: FloatArray,
                    y: FloatArray, r: FloatArray, lo: FloatArray, hi: FloatArray,
                    weight: FloatArray, fresh: bool, heard: npt.NDArray[np.uint32],
                    m: _Model, theta1: float, theta2: float) -> int:
    """Draw the arc in ``slot`` into ``points`` as carving's point estimate if it is
    ``fresh`` (its sensor's newest reading) and the map of spread arcs (``base + live``,
    without the arc's own spread value) does not explain it (:func:`_band_likeliest`): the
    ``unit`` of its carved interval around the point's bearing (the middle, or the most likely
    cell of a band whose middle the map does not favour; clipped to the interval) raised from
    its spread value to a whole hit, or, where the likeliest cell lies in reach of a side lobe
    (``theta1, theta2``: the beam), a whole hit around it clipped to the lobe's stretch of the
    circle; else take its point out. The spread map does not hold the
    points, so the fresh arcs' order does not matter. Returns 1 if its point changed."""
    if fresh and weight[slot] > 0.0:
        explained, at, side = _band_likeliest(base, live, m, x[slot], y[slot], r[slot],
                                              lo[slot], hi[slot], drawn[slot, 5], theta1,
                                              theta2)
        whole = _arc_value(r[slot], lo[slot], hi[slot], weight[slot], m, True)
        if not explained and side != 0.0:
            # In a side lobe: a whole hit around ``at``, clipped to the lobe's stretch of the
            # circle beyond the arc's own band (it draws no spread value there to raise).
            half = 0.5 * m.unit / r[slot]
            axis = 0.5 * (theta1 + theta2)
            axis += _TWO_PI * math.floor((at - axis + math.pi) / _TWO_PI)
            edge = 0.5 * (theta2 - theta1)
            reach = (1.0 + m.lobes) * edge
            # Drawn widened by half a cell, as every arc: start a cell past the beam's edge so
            # the mark never adds to the arc's own band (that would be more than a whole hit).
            inner = edge + m.h / r[slot]
            z1, z2 = (axis + inner, axis + reach) if side > 0.0 else (axis - reach, axis - inner)
            return _redraw(points, pdrawn, pseq, slot, seq, x[slot], y[slot], r[slot],
                           max(z1, at - half), min(z2, at + half), whole, heard, m)
        if not explained:
            half = min(0.5 * (hi[slot] - lo[slot]), 0.5 * m.unit / r[slot])
            return _redraw(points, pdrawn, pseq, slot, seq, x[slot], y[slot], r[slot],
                           max(lo[slot], at - half), min(hi[slot], at + half),
                           whole - drawn[slot, 5], heard, m)
    if pseq[slot] >= 0:
        _undraw(points, heard, m, pdrawn, slot)
        pseq[slot] = -1
        return 1
    return 0


@compiled
def _stale_slots(slots: SlotArray, seqs: npt.NDArray[np.int64], lo: FloatArray,
                 hi: FloatArray, status: npt.NDArray[np.int8],
                 crossings: npt.NDArray[np.int32], seen: FloatArray,
                 seen_crossings: npt.NDArray[np.int32], seen_seq: npt.NDArray[np.int64],
                 out: SlotArray) -> int:
    """Positions ``k`` (into ``out``, returns how many) of the live arcs whose state differs
    from ``seen`` (``seen_seq``: the arc it was recorded for), recording the new state: the
    carving state ``lo, hi, status`` of :class:`~sonarcarve.methods.carving.CarvingModel` and,
    for combined carving, the number of ATM crossings the arc keeps (``crossings``, all zero
    for carving alone; indexed by slot). An arc whose state is as seen has the same estimate
    (ATM's point is the median of the arc's kept crossings, which only grow), so its interval
    need not be asked for again."""
    count = 0
    for k in range(slots.shape[0]):
        s = slots[k]
        if (seen_seq[s] != seqs[k] or seen[s, 0] != lo[s] or seen[s, 1] != hi[s]
                or seen[s, 2] != status[s] or seen_crossings[s] != crossings[s]):
            seen_seq[s] = seqs[k]
            seen[s, 0] = lo[s]
            seen[s, 1] = hi[s]
            seen[s, 2] = status[s]
            seen_crossings[s] = crossings[s]
            out[count] = k
            count += 1
    return count


@compiled  # its own function: inlined into the refresh loop, that loop ran 2x slower
def _redraw(live: npt.NDArray[np.floating], drawn: FloatArray,
            drawn_seq: npt.NDArray[np.int64], slot: int, seq: int, x: float, y: float,
            r: float, lo: float, hi: float, value: float, heard: npt.NDArray[np.uint32],
            m: _Model) -> int:
    """Make slot ``slot`` (arc ``seq``) hold ``value`` on ``[lo, hi]`` in ``live``; 1 if that
    changed anything. The same arc drawn before with another interval or value is moved in
    one pass (:func:`_move_arc`: the same additions, cell by cell, as taking it out and
    drawing it again)."""
    if (drawn_seq[slot] == seq and drawn[slot, 3] == lo and drawn[slot, 4] == hi
            and drawn[slot, 5] == value):
        return 0
    if (drawn_seq[slot] >= 0 and drawn[slot, 0] == x and drawn[slot, 1] == y
            and drawn[slot, 2] == r):
        _move_arc(live, heard, m, x, y, r, drawn[slot, 3], drawn[slot, 4], -drawn[slot, 5],
                  lo, hi, value)
    else:
        if drawn_seq[slot] >= 0:
            _undraw(live, heard, m, drawn, slot)
        _draw_arc(live, False, heard, m, x, y, r, lo, hi, value)
    drawn[slot, 0] = x
    drawn[slot, 1] = y
    drawn[slot, 2] = r
    drawn[slot, 3] = lo
    drawn[slot, 4] = hi
    drawn[slot, 5] = value
    drawn_seq[slot] = seq
    return 1


@compiled_inline
def _move_arc(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: _Model,
              x: float, y: float, r: float,
              lo0: float, hi0: float, value0: float, lo1: float, hi1: float,
              value1: float) -> None:
    """``_draw_arc(live, ..., lo0, hi0, value0)`` then ``_draw_arc(live, ..., lo1, hi1,
    value1)`` for one arc (same origin and radius), in one pass over the cells: each cell of
    the band gets the same two additions in the same order (so the same sum, bit for bit), and
    its distance and bearing are computed once instead of twice."""
    if value0 == 0.0 or value1 == 0.0:  # one of the two draws nothing
        _draw_arc(live, False, heard, m, x, y, r, lo0, hi0, value0)
        _draw_arc(live, False, heard, m, x, y, r, lo1, hi1, value1)
        return
    xmin, ymin, h, band, profile = m.xmin, m.ymin, m.h, m.band, m.profile
    ny, nx = live.shape
    widen = 0.5 * h / r
    r_in = max(0.0, r - band)
    r_out = r + band
    ta0, tb0 = lo0 - widen, hi0 + widen
    ta1, tb1 = lo1 - widen, hi1 + widen
    mid0, half0 = 0.5 * (ta0 + tb0), 0.5 * (tb0 - ta0)
    mid1, half1 = 0.5 * (ta1 + tb1), 0.5 * (tb1 - ta1)
    xlo0, ylo0, xhi0, yhi0 = _sector_box(x, y, ta0, tb0, r_in, r_out)
    xlo1, ylo1, xhi1, yhi1 = _sector_box(x, y, ta1, tb1, r_in, r_out)
    j0, j1 = _cell_range(min(xlo0, xlo1), max(xhi0, xhi1), xmin, h, nx)
    i0, i1 = _cell_range(min(ylo0, ylo1), max(yhi0, yhi1), ymin, h, ny)
    cm0, sm0, ch0 = math.cos(mid0), math.sin(mid0), _cos_half(half0)
    cm1, sm1, ch1 = math.cos(mid1), math.sin(mid1), _cos_half(half1)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = _ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if profile > 0.0:
                    off = _bearing_off(dx, dy, mid0)
                    if abs(off) <= half0:
                        u = off / half0
                        live[i, j] += value0 * min(1.0, profile * (1.0 - u * u))
                    off = _bearing_off(dx, dy, mid1)
                    if abs(off) <= half1:
                        u = off / half1
                        live[i, j] += value1 * min(1.0, profile * (1.0 - u * u))
                    continue
                if _within(dx, dy, d, mid0, half0, cm0, sm0, ch0):
                    live[i, j] += value0
                if _within(dx, dy, d, mid1, half1, cm1, sm1, ch1):
                    live[i, j] += value1


@compiled  # its own function: inlined, the refresh loop ran 4x slower (numba 0.68)
def _band_likeliest(base: npt.NDArray[np.float32], live: FloatArray, m: _Model, x: float,
                    y: float, r: float, lo: float, hi: float, own: float, theta1: float,
                    theta2: float) -> tuple[bool, float, float]:
    """``(explained, bearing, side)`` of a fresh arc: whether a cell of its band (as
    :func:`_draw_arc` draws it, without a profile) is occupied in the map of spread arcs without
    the arc's own share ``own``, ``clamp(base + live - own) > l_occupied``, and the bearing its
    point goes to: the middle of ``[lo, hi]``, unless that map holds no cell more likely
    occupied than not (above :data:`_LIKELY`) where the middle ``unit`` is drawn and does hold
    one elsewhere on the band: then the bearing of the band's most likely cell (of equals within
    :data:`_TIE`, the one nearest the middle). Near echoes (``r <= lobe_range``) also look past
    the beam's edges, ``lobes`` half widths, on the same circle: an occupied cell there explains
    the echo; when the middle is not favoured and a lobe's likeliest cell beats the band's,
    ``bearing`` is that cell's and ``side`` its lobe (+1 counter-clockwise of the axis, -1
    clockwise; 0: on the band). A lobe holding a likely cell nearer than the echo is skipped (it
    would have heard that first); equally likely cells in both lobes explain the echo (no side
    is favoured)."""
    xmin, ymin, h, band = m.xmin, m.ymin, m.h, m.band
    ny, nx = base.shape
    widen = 0.5 * h / r
    t1 = lo - widen
    t2 = hi + widen
    mid = 0.5 * (t1 + t2)
    half = 0.5 * (t2 - t1)
    # Where the point would be drawn: the middle unit, widened as _draw_arc widens it.
    reach = min(0.5 * (hi - lo), 0.5 * m.unit / r) + widen
    r_in, r_out = max(0.0, r - band), r + band
    # The side lobes' reach (CarvedGridParams.side_lobes): the beam [theta1, theta2], written
    # near the carved interval's middle, widened by ``lobes`` half widths past each edge.
    axis = 0.5 * (theta1 + theta2)
    axis += _TWO_PI * math.floor((mid - axis + math.pi) / _TWO_PI)
    e_half = 0.0
    if m.lobes > 0.0 and r <= m.lobe_range:
        e_half = 0.5 * (1.0 + m.lobes) * (theta2 - theta1) + widen
    s1, s2 = (min(t1, axis - e_half), max(t2, axis + e_half)) if e_half > 0.0 else (t1, t2)
    xlo, ylo, xhi, yhi = _sector_box(x, y, s1, s2, r_in, r_out)
    j0, j1 = _cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = _cell_range(ylo, yhi, ymin, h, ny)
    cos_mid, sin_mid, cos_half = math.cos(mid), math.sin(mid), _cos_half(half)
    cos_ax, sin_ax, cos_e = math.cos(axis), math.sin(axis), _cos_half(e_half)
    b_half = 0.5 * (theta2 - theta1) + widen
    cos_b = _cos_half(b_half)
    best = _LIKELY
    bearing = 0.5 * (lo + hi)  # the middle, unless a likelier cell is found
    middle_likely = False
    # Per lobe (cw: clockwise of the axis, ccw: counter-clockwise): the likeliest cell and its
    # bearing (none yet: farther than any bearing), and whether the lobe holds a likely cell
    # nearer than the echo, which it would have heard first. Scalars, not arrays: this runs for
    # every fresh arc at every read.
    best_cw, best_ccw = _LIKELY, _LIKELY
    at_cw = at_ccw = mid + 4.0 * math.pi
    blocked_cw = e_half > 0.0 and _lobe_nearer(base, live, m, x, y, r_in, axis, b_half,
                                                e_half, 0)
    blocked_ccw = e_half > 0.0 and _lobe_nearer(base, live, m, x, y, r_in, axis, b_half,
                                                 e_half, 1)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = _ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                # The cell's value first: most cells are not likely occupied, and need no
                # geometry. On the band it holds the arc's own share, which does not count;
                # in a side lobe's reach it does not hold it.
                spread = base[i, j] + live[i, j]
                value = min(m.l_max, max(m.l_min, spread - own))
                if not (value > _LIKELY or (e_half > 0.0 and spread > _LIKELY)):
                    continue
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if not _within(dx, dy, d, mid, half, cos_mid, sin_mid, cos_half):
                    # Outside the carved interval, in reach of a side lobe: the echo may have
                    # come from a surface there, heard through the lobe.
                    if (e_half > 0.0
                            and _within(dx, dy, d, axis, e_half, cos_ax, sin_ax, cos_e)
                            and not _within(dx, dy, d, axis, b_half, cos_ax, sin_ax, cos_b)):
                        ccw = _bearing_off(dx, dy, axis) > 0.0
                        if blocked_ccw if ccw else blocked_cw:
                            continue
                        value = min(m.l_max, max(m.l_min, spread))
                        if value > m.l_occupied:
                            return True, bearing, 0.0
                        off = _bearing_off(dx, dy, mid)
                        if ccw:
                            if _likelier(value, off, best_ccw, at_ccw - mid):
                                best_ccw, at_ccw = max(best_ccw, value), mid + off
                        elif _likelier(value, off, best_cw, at_cw - mid):
                            best_cw, at_cw = max(best_cw, value), mid + off
                    continue
                if not value > _LIKELY:
                    continue
                if value > m.l_occupied:
                    return True, bearing, 0.0
                off = _bearing_off(dx, dy, mid)
                if abs(off) <= reach:
                    middle_likely = True
                if _likelier(value, off, best, bearing - mid):
                    best = max(best, value)
                    bearing = mid + off
    if not middle_likely and max(best_cw, best_ccw) > best + _TIE:
        if abs(best_cw - best_ccw) <= _TIE:
            # Equally likely surfaces in both lobes: either may have answered, and picking one
            # would let rounding and the scan order draw a lopsided map of a symmetric scene.
            return True, bearing, 0.0
        return (False, at_ccw, 1.0) if best_ccw > best_cw else (False, at_cw, -1.0)
    return False, 0.5 * (lo + hi) if middle_likely else bearing, 0.0


@compiled_inline
def _likelier(value: float, off: float, best: float, best_off: float) -> bool:
    """Whether a cell of log-odds ``value``, ``off`` radians from the arc's middle, beats the
    likeliest so far (``best``, ``best_off`` from the middle): likelier by more than
    :data:`_TIE`, or as likely within it and nearer the middle."""
    return value > best + _TIE or (value >= best - _TIE and abs(off) < abs(best_off))


@compiled_inline
def _lobe_nearer(base: npt.NDArray[np.float32], live: FloatArray, m: _Model, x: float,
                 y: float, reach: float, axis: float, b_half: float, e_half: float,
                 side: int) -> bool:
    """Whether the side lobe ``side`` (1: counter-clockwise of ``axis``) holds a cell more
    likely occupied than not nearer than ``reach``: a sonar reports the first echo it hears, so
    a lobe that would have heard that cell did not hear the echo's surface farther out."""
    if reach <= 0.0:
        return False
    sign = 1.0 if side == 1 else -1.0
    c = axis + sign * 0.5 * (b_half + e_half)
    half = 0.5 * (e_half - b_half)
    t1, t2 = c - half, c + half
    xmin, ymin, h = m.xmin, m.ymin, m.h
    ny, nx = base.shape
    xlo, ylo, xhi, yhi = _sector_box(x, y, t1, t2, 0.0, reach)
    j0, j1 = _cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = _cell_range(ylo, yhi, ymin, h, ny)
    cc, sc, ch = math.cos(c), math.sin(c), _cos_half(half)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        for j in range(j0, j1 + 1):
            if not base[i, j] + live[i, j] > _LIKELY:
                continue
            dx = xmin + (j + 0.5) * h - x
            d = math.sqrt(dx * dx + dy * dy)
            if d < reach and _within(dx, dy, d, c, half, cc, sc, ch):
                return True
    return False


@compiled_inline
def _undraw(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: _Model,
            drawn: FloatArray, slot: int) -> None:
    """Take what slot ``slot`` drew (``drawn[slot]``: x, y, r, lo, hi, value) out of ``live``."""
    _draw_arc(live, False, heard, m, drawn[slot, 0], drawn[slot, 1], drawn[slot, 2],
              drawn[slot, 3], drawn[slot, 4], -drawn[slot, 5])


@compiled
def _trinary_kernel(base: npt.NDArray[np.float32], live: FloatArray,
                    points: npt.NDArray[np.float32], l_min: float, l_max: float,
                    l_occupied: float, l_free: float, out: Int8Grid) -> None:
    """Occupied (100) where ``clamp(base + (live + points)) > l_occupied``, free (0) below
    ``l_free``, else unknown (-1)."""
    ny, nx = base.shape
    for i in range(ny):
        for j in range(nx):
            lo = min(l_max, max(l_min, base[i, j] + (live[i, j] + points[i, j])))
            if lo > l_occupied:
                out[i, j] = OCCUPIED
            elif lo < l_free:
                out[i, j] = FREE
            else:
                out[i, j] = UNKNOWN


@compiled
def _repeat_kernel(chain: FloatArray, batch_chain: FloatArray,
                   seen_seq: npt.NDArray[np.int64], marked: SlotArray,
                   seqs: npt.NDArray[np.int64], first: int, no_echo: BoolArray,
                   sensor: npt.NDArray[np.int64], x: FloatArray, y: FloatArray, r: FloatArray,
                   theta: FloatArray, half: FloatArray, hsensor: npt.NDArray[np.int64],
                   hx: FloatArray, hy: FloatArray, hr: FloatArray, htheta: FloatArray,
                   hwidth: FloatArray, capacity: int, tol: float, factor: float) -> int:
    """For each echo ``k`` of a batch (arc ``seqs[k]``), give every earlier arc of the same
    sensor still in the history that the echo repeats
    (:func:`~sonarcarve.geometry.repeats.is_repeat`) the weight factor
    ``factor``: in ``batch_chain[p - first]`` if it is an arc of the batch (``first``: the
    batch's first arc), else in ``chain`` (by slot, rows ``hsensor..hwidth`` of the history),
    which then forgets it had seen that arc's state (``seen_seq`` -1) so that the next read
    recomputes its weight, and whose slot goes into ``marked`` (only arcs whose factor was 1, so
    that 1 undoes the marks; each at most once, so ``marked`` needs ``capacity`` places).
    Returns how many slots were marked."""
    size = chain.shape[0]
    rows = np.empty(x.shape[0], dtype=np.int64)  # the row of the batch's arc first + i
    count = 0
    for k in range(x.shape[0]):
        if not no_echo[k]:
            rows[count] = k
            count += 1
    n_marked = 0
    for k in range(x.shape[0]):
        if no_echo[k]:
            continue
        for p in range(max(0, seqs[k] - capacity + 1), seqs[k]):
            if p >= first:
                j = rows[p - first]
                if sensor[j] != sensor[k] or batch_chain[p - first] == factor:
                    continue
                x1, y1, r1, t1, h1 = x[j], y[j], r[j], theta[j], half[j]
            else:
                s = p % size
                if hsensor[s] != sensor[k] or chain[s] == factor:
                    continue
                x1, y1, r1, t1, h1 = hx[s], hy[s], hr[s], htheta[s], 0.5 * hwidth[s]
            if not is_repeat(x1, y1, r1, t1, h1, x[k], y[k], r[k], theta[k], half[k], tol):
                continue
            if p >= first:
                batch_chain[p - first] = factor
            else:
                chain[p % size] = factor
                seen_seq[p % size] = -1
                marked[n_marked] = p % size
                n_marked += 1
    return n_marked


class _Finals(NamedTuple):
    """Arcs that left the history in a batch, in order: where to draw their final band."""

    x: FloatArray
    y: FloatArray
    r: FloatArray
    lo: FloatArray
    hi: FloatArray
    weight: FloatArray
    seq: npt.NDArray[np.int64]


# -- the grid -------------------------------------------------------------------------------------

class CarvedGrid(CellGrid):
    """Log-odds occupancy grid whose occupied bands are the carved arcs (module docstring).

    Parameters
    ----------
    resolution : float
        Cell side h, metres (> 0).
    bounds : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)`` of the mapped rectangle, metres; the grid has
        ``ceil((xmax - xmin) / h)`` columns and ``ceil((ymax - ymin) / h)`` rows.
    method : SonarMethod, optional
        The carving method the grid runs, fresh (no readings yet); it becomes the grid's own.
        Default: combined carving and ATM with specular-aware carving at 20°,
        ``make_method(DEFAULT_METHOD, MethodConfig(max_incidence=DEFAULT_MAX_INCIDENCE))``
        (:data:`DEFAULT_METHOD`; specular-aware carving alone, the default before, is
        ``make_method("carve", MethodConfig(max_incidence=math.radians(30)))``, paper carving
        ``make_method("carve")``). Any method works: the band is drawn ``width`` wide around
        the point's bearing (:class:`~sonarcarve.methods.Estimates` ``xy``; for evidence
        carving, whose point is off its kept run's middle, a measured choice: :func:`_intervals`);
        its ``confidence``, where given, weighs the occupied band.
    params : CarvedGridParams, optional
        The sensor model (default: :class:`CarvedGridParams` defaults).

    Attributes
    ----------
    readings : int
        Readings folded in so far.

    Raises
    ------
    GridError
        A resolution or bounds that are not finite, not positive, or need more than
        :data:`~sonarcarve.grids.elfes.MAX_CELLS` cells; a method that has readings already.

    Examples
    --------
    >>> g = CarvedGrid(0.1, (0.0, 0.0, 2.0, 1.0))
    >>> g.add(Reading(t=0.0, sensor=0, x=0.05, y=0.55, theta=0.0, range=1.0))
    >>> p = g.probabilities()
    >>> float(p[5, 10].round(3)), float(p[5, 5].round(3))  # the arc's middle, free space
    (0.7, 0.406)
    >>> trinary(g)[5, [0, 5, 10, 15]].tolist()  # the newest echo, unexplained: marked now
    [-1, -1, 100, -1]
    >>> g.add(Reading(t=0.1, sensor=0, x=0.05, y=0.55, theta=math.pi, range=0.3))
    >>> float(g.probabilities()[5, 10].round(3))  # no longer the sensor's newest: spread
    0.606
    """

    def __init__(self, resolution: float, bounds: tuple[float, float, float, float],
                 method: SonarMethod | None = None, params: CarvedGridParams | None = None
                 ) -> None:
        super().__init__("carved grid", resolution, bounds, MAX_CELLS, "MAX_CELLS")
        (xmin, ymin, _, _), (ny, nx) = self._bounds, self._shape
        if method is None:
            method = make_method(DEFAULT_METHOD, MethodConfig(max_incidence=DEFAULT_MAX_INCIDENCE))
        elif method.readings:
            msg = (f"carved grid: the method must be fresh, it has {method.readings} readings "
                   f"already")
            raise GridError(msg)
        self._params = params if params is not None else CarvedGridParams()
        self._method = method
        p = self._params
        self._l_hit, self._l_miss = _logit(p.p_hit), _logit(p.p_miss)
        self._l_min, self._l_max = _logit(p.p_min), _logit(p.p_max)
        self._spread = 1.0 if p.spread else 0.0
        self._unit = max(p.spread_length, self._resolution)
        self._l_heard = _logit(p.p_miss_heard)
        self._model = _Model(xmin, ymin, self._resolution, self.band, self._l_hit,
                             self._l_miss, self._l_heard, self._l_min, self._l_max,
                             self._spread, self._unit, float(p.fade_range),
                             p.surface_aware, float(p.band_profile),
                             _logit(p.occupied_threshold), float(p.see_through),
                             float(p.side_lobes), float(p.side_lobe_range))
        self._base = np.zeros((ny, nx), dtype=np.float32)
        self._live = np.zeros((ny, nx), dtype=np.float64)
        # The points of the fresh arcs (CarvedGridParams.fresh_arcs), apart from ``live`` so
        # that whether an echo is explained is judged on the spread arcs alone.
        self._points = np.zeros((ny, nx), dtype=np.float32)
        # Per cell, the bearings (HEARD_BINS sectors, one bit each) it was heard from.
        self._heard = np.zeros((ny, nx), dtype=_HEARD_DTYPE)
        size = method.history.storage_size
        # Per slot, what was drawn into ``live``: x, y, r, lo, hi, value; and the arc's
        # sequence number (its position in the stream of arcs), -1 for nothing.
        self._drawn = np.zeros((size, 6), dtype=np.float64)
        self._drawn_seq = np.full(size, -1, dtype=np.int64)
        self._pdrawn = np.zeros((size, 6), dtype=np.float64)  # the same for the points
        self._pseq = np.full(size, -1, dtype=np.int64)
        # Per slot, the interval and weight (_intervals) of the live arc at the last read.
        self._lo = np.zeros(size)
        self._hi = np.zeros(size)
        self._weight = np.zeros(size)
        # Per slot, the factor of the arc's weight: repeat_weight if a later echo of its sensor
        # repeats it (geometry.repeats.is_repeat), else 1.
        self._chain = np.ones(size)
        # While a batch is folded in: its arcs' factors, by sequence number from _batch_first.
        self._batch_first = 0
        self._batch_chain = np.ones(0)
        # Plain carving or combined: per slot, the carving state (lo, hi, status) and the
        # number of ATM crossings those were computed from, and for which arc (-1: none); a
        # read asks only for the estimates of the arcs whose state changed since
        # (_stale_slots). Any other method is asked for every live arc.
        self._carving, self._atm = _known_models(method)
        self._seen = np.zeros((size, 3), dtype=np.float64)
        self._seen_crossings = np.zeros(size, dtype=np.int32)
        self._no_crossings = np.zeros(size, dtype=np.int32)  # carving alone keeps none
        self._seen_seq = np.full(size, -1, dtype=np.int64)
        self._changed = np.zeros(size, dtype=np.int64)
        self._pending: list[tuple[FloatArray, ...]] = []
        self._next_final = 0  # sequence number of the next arc to leave the history
        # Per sensor, the sequence number of its newest reading's arc (-1: it heard nothing).
        self._newest: dict[int, int] = {}
        self._latest_t = -math.inf  # time of the newest reading seen (fresh_seconds counts back)
        self._stale = False
        self.readings = 0
        method.add_commit_listener(self._on_commit)
        # A global map would grow with the log; the grid is the map, so only count the points.
        method.set_global_sink(CountingSink())

    def __repr__(self) -> str:
        ny, nx = self.shape
        return (f"CarvedGrid({self._resolution:g} m, {nx} x {ny} cells, "
                f"bounds={self._bounds}, {self.readings} readings)")

    @classmethod
    def around(cls, extent: tuple[float, float, float, float], resolution: float,
               margin: float = 0.5, method: SonarMethod | None = None,
               params: CarvedGridParams | None = None) -> CarvedGrid:
        """A grid over ``extent = (xmin, ymin, xmax, ymax)`` grown by ``margin`` metres on
        every side.

        Raises
        ------
        GridError
            A negative or non-finite margin; a flat extent and no margin.
        """
        if not (math.isfinite(margin) and margin >= 0.0):
            msg = f"carved grid: margin must be a finite number >= 0 metres, got {margin!r}"
            raise GridError(msg)
        xmin, ymin, xmax, ymax = extent
        return cls(resolution, (xmin - margin, ymin - margin, xmax + margin, ymax + margin),
                   method, params)

    # -- geometry ----------------------------------------------------------------------------

    @property
    def params(self) -> CarvedGridParams:
        """The sensor model."""
        return self._params

    @property
    def method(self) -> SonarMethod:
        """The carving method the grid runs (read it, do not feed it)."""
        return self._method

    @property
    def band(self) -> float:
        """Half-width b of the occupied band, metres: ``(h + ε) / 2``."""
        return 0.5 * (self._resolution + self._params.range_tolerance)

    @property
    def nbytes(self) -> int:
        """Memory of the grid's own state (the cell arrays and the per-slot record), bytes;
        the method's history and state come on top, fixed by its history size."""
        per_slot = (self._drawn, self._drawn_seq, self._pdrawn, self._pseq, self._lo, self._hi,
                    self._weight, self._chain, self._seen, self._seen_crossings,
                    self._no_crossings, self._seen_seq, self._changed)
        return int(self._base.nbytes + self._live.nbytes + self._points.nbytes
                   + self._heard.nbytes + sum(a.nbytes for a in per_slot))

    # -- updates -----------------------------------------------------------------------------

    def add(self, reading: Reading) -> None:
        """Fold one reading in (validated as by the method's ``add``)."""
        self.add_many(ReadingBatch.from_readings([reading]))

    def add_many(self, batch: ReadingBatch) -> None:
        """Fold every reading of ``batch`` in, in order.

        The method checks the whole batch first (:meth:`SonarMethod.add_many`): a bad batch
        raises :class:`~sonarcarve.readings.ReadingsError` and changes nothing.
        """
        n = len(batch)
        if not n:
            return
        method = self._method
        history = method.history
        first_seq = history.appended
        half = 0.5 * np.where(np.isnan(batch.beam_width), method.beam_width, batch.beam_width)
        r = batch.range
        no_echo = r == math.inf
        if no_echo.any():  # free up to max_range, and no arc of its own in the history
            echo = (~no_echo).astype(np.int64)
            seqs = first_seq + np.cumsum(echo) - 1
            r = np.where(no_echo, batch.max_range + self.band, r)
        else:
            seqs = first_seq + np.arange(n, dtype=np.int64)
        # Before the method runs: the arcs it retires during the batch are made final (their
        # weight read) as they retire, and an echo later in the batch may repeat them.
        newest = dict(self._newest)
        self._note_newest(batch.sensor, seqs, no_echo)
        marked = self._mark_repeats(batch, seqs, no_echo, half, first_seq)
        try:
            method.add_many(batch)
        except BaseException:  # a bad batch changes nothing
            self._newest = newest
            self._chain[marked] = 1.0
            self._batch_chain = np.ones(0)
            raise
        history.flush_retired()  # every arc that left the history is final now
        self._keep_batch_chain(history)
        finals = self._take_pending()
        self._latest_t = max(self._latest_t, float(batch.t.max()))
        _fold_kernel(self._base, self._heard, self._model, np.ascontiguousarray(batch.x),
                     np.ascontiguousarray(batch.y), np.ascontiguousarray(batch.theta),
                     np.ascontiguousarray(r), np.ascontiguousarray(half), seqs,
                     history.capacity, finals)
        self.readings += n
        self._stale = True

    def _note_newest(self, sensor: npt.NDArray[np.int64], seqs: npt.NDArray[np.int64],
                     no_echo: BoolArray) -> None:
        """Remember each sensor's newest reading: its arc's sequence number, or -1 when it
        heard nothing (its arc is then no sensor's newest)."""
        newest = self._newest
        # In order, the last reading of each sensor wins; a loop, because a robot's batches are
        # a few readings and np.unique costs more than the loop for them.
        for s, seq, silent in zip(sensor.tolist(), seqs.tolist(), no_echo.tolist(), strict=True):
            newest[s] = -1 if silent else seq

    def _mark_repeats(self, batch: ReadingBatch, seqs: npt.NDArray[np.int64],
                      no_echo: BoolArray, half: FloatArray, first_seq: int) -> SlotArray:
        """Give the arcs that the batch's echoes repeat
        (:func:`~sonarcarve.geometry.repeats.is_repeat`) the weight factor
        :attr:`CarvedGridParams.repeat_weight`: those of the history in ``_chain`` (by slot;
        the next read recomputes their weights), the batch's own in ``_batch_chain`` (by
        sequence number from ``first_seq``: a long batch reuses slots). Returns the slots of
        the history's arcs it marked (their factor was 1)."""
        history = self._method.history
        n_echo = int(np.count_nonzero(~no_echo))
        self._batch_first = first_seq
        self._batch_chain = np.ones(n_echo)
        if self._params.repeat_weight >= 1.0:
            return np.zeros(0, dtype=np.int64)
        marked = np.empty(history.capacity, dtype=np.int64)  # each live arc marked once at most
        count = _repeat_kernel(self._chain, self._batch_chain, self._seen_seq, marked, seqs,
                               first_seq, no_echo, np.ascontiguousarray(batch.sensor),
                               np.ascontiguousarray(batch.x), np.ascontiguousarray(batch.y),
                               np.ascontiguousarray(batch.range),
                               np.ascontiguousarray(batch.theta), np.ascontiguousarray(half),
                               history.sensor, history.x, history.y, history.r, history.theta,
                               history.beam_width, history.capacity,
                               self._params.range_tolerance, self._params.repeat_weight)
        return marked[:count]

    def _keep_batch_chain(self, history: SonarHistory) -> None:
        """The batch's arcs still in the history take their factors into their slots."""
        chain = self._batch_chain
        if len(chain):
            seqs = self._batch_first + np.arange(len(chain), dtype=np.int64)
            live = seqs >= history.appended - len(history)
            self._chain[seqs[live] % history.storage_size] = chain[live]
        self._batch_first = history.appended
        self._batch_chain = np.ones(0)

    def _chain_of(self, slots: SlotArray, seqs: npt.NDArray[np.int64]) -> FloatArray:
        """Weight factors of the arcs ``seqs`` (in ``slots``): the batch's own from
        ``_batch_chain``, older ones from ``_chain``."""
        own = seqs >= self._batch_first
        out = self._chain[slots]
        if own.any():
            out = np.where(own, self._batch_chain[np.where(own, seqs - self._batch_first, 0)],
                           out)
        return out

    def _on_commit(self, history: SonarHistory, slots: SlotArray, est: Estimates) -> None:
        """Arcs leaving the history: their live contribution out, their final one pending."""
        seqs = self._next_final + np.arange(len(slots), dtype=np.int64)
        self._next_final += len(slots)
        _undraw_kernel(self._live, self._drawn, self._drawn_seq, slots, seqs, self._heard,
                       self._model)
        _undraw_kernel(self._points, self._pdrawn, self._pseq, slots, seqs, self._heard,
                       self._model)
        x, y, r = history.x[slots], history.y[slots], history.r[slots]
        lo, hi, weight = _intervals(x, y, est)
        weight *= self._chain_of(slots, seqs)
        self._pending.append((x.copy(), y.copy(), r.copy(), lo, hi, weight,
                              seqs.astype(np.float64)))

    def _take_pending(self) -> _Finals:
        if self._pending:
            cols = [np.concatenate(c) for c in zip(*self._pending, strict=True)]
        else:
            cols = [np.zeros(0) for _ in range(7)]
        self._pending = []
        return _Finals(cols[0], cols[1], cols[2], cols[3], cols[4], cols[5],
                       cols[6].astype(np.int64))

    def _sync(self) -> None:
        """Bring ``live`` (and the points) up to date with the method's current carved
        intervals: only the arcs whose interval or value changed since the last read are
        redrawn, and with plain carving only those arcs' estimates are asked for."""
        if not self._stale:
            return
        history = self._method.history
        slots = np.ascontiguousarray(history.slots())
        if len(slots):
            seqs = history.appended - len(slots) + np.arange(len(slots), dtype=np.int64)
            self._update_intervals(history, slots, seqs)
            with_points = self._params.fresh_arcs
            fresh = self._fresh(slots, seqs) if with_points else np.zeros(len(slots), dtype=bool)
            _refresh_kernel(self._base, self._live, self._points, self._drawn,
                            self._drawn_seq, self._pdrawn, self._pseq, slots, seqs, history.x,
                            history.y, history.r, self._lo, self._hi, self._weight, fresh,
                            with_points, self._heard, self._model, history.theta1,
                            history.theta2)
        self._stale = False

    def _update_intervals(self, history: SonarHistory, slots: SlotArray,
                          seqs: npt.NDArray[np.int64]) -> None:
        """``_lo, _hi, _weight`` of the live ``slots`` (arcs ``seqs``) as :func:`_intervals`
        gives them from the method's estimates. With plain carving an estimate is a function
        of the arc's row and its model's ``lo, hi, status`` alone
        (:meth:`~sonarcarve.methods.carving.CarvingModel.estimates`), with combined carving of
        those and the arc's kept ATM crossings, so only the arcs whose state changed since the
        last read are computed: for carving alone from the model's state as its estimates
        would (:func:`_carving_intervals`), for combined by asking the method for them alone
        (row by row, the same numbers as asking for every arc). Measured for combined
        (``benchmarks/grid_reads.py``, office, a read every 5 readings): the grid's CPU per
        reading 4.32x -> 3.87x the range sensor layer's at 0.10 m, 1.98x -> 1.97x at 0.05 m."""
        carving = self._carving
        if carving is None:
            stale = slots
            lo, hi, weight = _intervals(history.x[slots], history.y[slots],
                                        self._method.estimates(slots))
        else:
            crossings = self._no_crossings if self._atm is None else self._atm.counts
            count = _stale_slots(slots, seqs, carving.lo, carving.hi, carving.status, crossings,
                                 self._seen, self._seen_crossings, self._seen_seq, self._changed)
            if not count:
                return
            stale = slots[self._changed[:count]]
            if self._atm is None:
                lo, hi, weight = _carving_intervals(history, carving, stale)
            else:
                lo, hi, weight = _intervals(history.x[stale], history.y[stale],
                                            self._method.estimates(stale))
        self._lo[stale] = lo
        self._hi[stale] = hi
        self._weight[stale] = weight * self._chain[stale]

    def _fresh(self, slots: SlotArray, seqs: npt.NDArray[np.int64]) -> BoolArray:
        """Which of the live arcs ``seqs`` (consecutive, in ``slots``) is its sensor's newest
        reading, heard at most ``fresh_seconds`` before the newest reading seen."""
        fresh = np.zeros(len(seqs), dtype=bool)
        at = np.fromiter(self._newest.values(), dtype=np.int64, count=len(self._newest))
        at -= seqs[0]
        at = at[(at >= 0) & (at < len(seqs))]
        young = self._method.history.t[slots[at]] >= self._latest_t - self._params.fresh_seconds
        fresh[at[young]] = True
        return fresh

    # -- reading the map ---------------------------------------------------------------------

    def refresh(self) -> None:
        """Bring the map up to date with the method's current carved intervals without
        reading it (every read does this first): what a costmap layer does when it is asked
        for its update, before the cells are read."""
        self._sync()

    @property
    def log_odds(self) -> FloatArray:
        """Each cell's log-odds of occupancy, ``clamp(base + live)``, shape :attr:`shape`
        (a new float64 array)."""
        self._sync()
        return np.asarray(np.clip(self._base + (self._live + self._points), self._l_min,
                                  self._l_max))

    @property
    def live_log_odds(self) -> FloatArray:
        """The live arcs' summed contribution (unclamped), shape :attr:`shape` (a copy)."""
        self._sync()
        return np.asarray(self._live + self._points)

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, shape :attr:`shape`: ``1 / (1 + exp(-l))``."""
        return np.asarray(1.0 / (1.0 + np.exp(-self.log_odds)))

    def trinary(self) -> Int8Grid:
        """:data:`OCCUPIED` (100) where the log-odds :attr:`log_odds` is above
        ``logit(`` :attr:`CarvedGridParams.occupied_threshold` ``)``, :data:`FREE` (0) below
        ``logit(free_threshold)``, else :data:`UNKNOWN` (-1).

        Compared in log-odds, one pass, no temporary grids. The logistic is monotone, so this
        is comparing :meth:`probabilities` with the thresholds, up to rounding: a cell whose
        log-odds lies within a few ulp of a threshold's logit may land in the other class.
        """
        self._sync()
        out = np.empty(self.shape, dtype=np.int8)
        _trinary_kernel(self._base, self._live, self._points, self._l_min, self._l_max,
                        _logit(self._params.occupied_threshold),
                        _logit(self._params.free_threshold), out)
        return out

    def occupied_mask(self, threshold: float | None = None) -> BoolArray:
        """Cells whose log-odds is above ``logit(threshold)`` (default
        :attr:`CarvedGridParams.occupied_threshold`), shape :attr:`shape`: the probability
        above ``threshold`` up to rounding, as :meth:`trinary`."""
        limit = self._params.occupied_threshold if threshold is None else _check_probability(
            "threshold", threshold, 0.0, 1.0)
        return np.asarray(self.log_odds > _logit(limit))

    def occupied_points(self, threshold: float | None = None) -> FloatArray:
        """Centres of the occupied cells (:meth:`occupied_mask`), shape (n, 2), row-major."""
        rows, cols = np.nonzero(self.occupied_mask(threshold))
        xs, ys = self.cell_centers()
        return np.column_stack((xs[cols], ys[rows])).astype(np.float64)


def _known_models(method: SonarMethod) -> tuple[CarvingModel | None, AtmModel | None]:
    """The carving model of a plain :class:`~sonarcarve.methods.carving.CarvingMethod`, or the
    carving and ATM models of a plain :class:`~sonarcarve.methods.combined.CombinedMethod` (no
    subclass: one that overrides its estimates must be asked), else ``(None, None)``."""
    models = method.models
    if type(method) is CarvingMethod and len(models) == 1 and type(models[0]) is CarvingModel:
        return models[0], None
    if (type(method) is CombinedMethod and len(models) == 2
            and type(models[0]) is CarvingModel and type(models[1]) is AtmModel):
        return models[0], models[1]
    return None, None


def _carving_intervals(history: SonarHistory, model: CarvingModel,
                       slots: SlotArray) -> tuple[FloatArray, ...]:
    """``_intervals(x, y, model.estimates(slots))`` for plain carving, with the same
    operations on the same numbers (so the same bits: the tests compare it with the method's
    estimates), without the fields of the estimates the grid does not read (half the cost)."""
    lo, hi = model.lo[slots], model.hi[slots]
    xy = arc_point(history, slots, 0.5 * (lo + hi))  # the point, as CarvingModel.estimates
    weight = np.where(model.status[slots] == _ALIVE, 1.0, 0.0)  # no confidence: 1 if alive
    return _interval_ends(np.arctan2(xy[:, 1] - history.y[slots], xy[:, 0] - history.x[slots]),
                          0.5 * (hi - lo), weight)


def _intervals(x: FloatArray, y: FloatArray, est: Estimates) -> tuple[FloatArray, ...]:
    """``(lo, hi, weight)`` of arcs from their estimates: the point's bearing ± width/2, and
    the confidence (1 where NaN or not modelled; 0 where the arc is not alive).

    Centred on the point even where the point is not the interval's middle (evidence
    carving's posterior point, off its kept run's middle), a choice measured, not an
    oversight (review rev9p found the band leaving the kept run in 95-98 % of cut evidence
    arcs): under evidence carving, office, seeds 0-2, specular,
    precision / recall / phantoms % at 0.10 m, a band centred on the point 0.864 / 0.947 /
    0.248, over the kept run 0.822 / 0.948 / 0.341, over their overlap 0.850 / 0.948 / 0.278
    (0.05 m: 0.736, 0.698, 0.712 precision; ``benchmarks/grid_methods.py --physics specular``
    on the three variants). The posterior point is where the echo most likely came from, so a
    band around it puts the arc's weight where the surface is.
    """
    weight = np.ones(len(x)) if est.confidence is None else np.where(
        np.isnan(est.confidence), 1.0, np.clip(est.confidence, 0.0, 1.0))
    return _interval_ends(np.arctan2(est.xy[:, 1] - y, est.xy[:, 0] - x), 0.5 * est.width,
                          np.where(est.alive, weight, 0.0))


def _interval_ends(bearing: FloatArray, half: FloatArray,
                   weight: FloatArray) -> tuple[FloatArray, ...]:
    """``(bearing - half, bearing + half, weight)``, all zero for an arc that adds nothing (no
    weight, or no point: NaN)."""
    dead = ~(weight > 0.0) | np.isnan(bearing) | np.isnan(half)
    bearing = np.where(dead, 0.0, bearing)
    half = np.where(dead, 0.0, half)
    weight = np.where(dead, 0.0, weight)
    return (np.ascontiguousarray(bearing - half), np.ascontiguousarray(bearing + half),
            np.ascontiguousarray(weight, dtype=np.float64))
