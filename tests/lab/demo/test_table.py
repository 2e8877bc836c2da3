""":mod:`sonarcarve.lab.demo.table`: the summaries."""

from __future__ import annotations

from sonarcarve.lab.demo import DEMO_METHODS, DemoResult, summary_markdown


def _table_rows(lines: list[str]) -> list[str]:
    return [line for line in lines if line.startswith("| ") and "---" not in line]


def test_summary_markdown_has_one_row_per_method_then_per_grid(doorway: DemoResult) -> None:
    text = summary_markdown(doorway)
    methods, grids = text.split("## Occupancy grids")
    rows = _table_rows(methods.splitlines())
    assert len(rows) == 1 + len(DEMO_METHODS)  # header + methods
    assert all(row.count("|") == rows[0].count("|") for row in rows)
    rows = _table_rows(grids.splitlines())
    assert [row.split("|")[1].strip() for row in rows] == [
        "grid", "carved grid", "ROS RangeSensorLayer (defaults)"]
    assert all(row.count("|") == 7 for row in rows)  # grid and five measures


def test_caption_states_what_each_carving_left_out(doorway: DemoResult) -> None:
    from sonarcarve.lab.demo.table import caption

    text = caption(doorway)
    for method, name in (("carve", "Carving"), ("evidence", "Evidence carving")):
        row = doorway.summary(method)
        assert (f"{name} left out {row.spurious_removed_pct:.0f}% of the spurious readings"
                in text)
        assert f"{row.true_lost_pct:.0f}% of the true ones." in text


def test_verdict_names_the_method_with_the_lowest_p90_error(doorway: DemoResult) -> None:
    from sonarcarve.lab.demo.table import caption, method_verdict

    shown = {row.label: f"{100.0 * row.p90_error_m:.1f}" for row in doorway.methods}
    best = sorted(shown, key=lambda label: float(shown[label]))[0]
    verdict = method_verdict(doorway)
    assert verdict.startswith(f"Sharpest map: {best}, 90% of its points within {shown[best]} cm")
    # Its own paragraph, between the table and the caption, not buried in the caption.
    table, rest = summary_markdown(doorway).split(f"\n\n**{verdict}**\n\n")
    assert table.splitlines()[-1].startswith("| ")
    assert rest.startswith(caption(doorway))
    assert verdict not in caption(doorway)


def test_verdict_names_the_best_paper_method_beside_one_beyond_the_paper(
        doorway: DemoResult) -> None:
    import dataclasses

    from sonarcarve.lab.demo.table import method_verdict

    rows = {row.method: row for row in doorway.methods}
    # Hand-made errors: evidence carving the sharpest, ATM the best of the paper's methods.
    p90 = {"centerline": 0.90, "atm": 0.20, "carve": 0.80, "combined": 0.35, "evidence": 0.10}
    made_up = dataclasses.replace(doorway, methods=tuple(
        dataclasses.replace(rows[m], p90_error_m=p90[m]) for m in p90))
    assert method_verdict(made_up) == (
        "Sharpest map: evidence carving (beyond the paper), 90% of its points within 10.0 cm "
        "of a true wall (centerline: 90.0 cm; the best of the paper's methods, ATM: 20.0 cm); "
        "figures 1-3 draw the paper's methods only, fig. 6 draws it beside carving.")
    without_carving = dataclasses.replace(made_up, methods=tuple(
        row for row in made_up.methods if row.method != "carve"))
    assert method_verdict(without_carving).endswith(
        "figures 1-3 draw the paper's methods only.")  # fig. 6 would have no carving panel
    only_paper = dataclasses.replace(made_up, methods=made_up.methods[:4])
    assert method_verdict(only_paper) == (
        "Sharpest map: ATM, 90% of its points within 20.0 cm of a true wall "
        "(centerline: 90.0 cm).")


def test_summaries_list_the_animation_when_it_is_written(doorway: DemoResult) -> None:
    import json

    from sonarcarve.lab.demo import summary_json

    def figures(text: str) -> list[str]:
        section = text.split("## Figures")[1].split("## Run")[0]
        return [line.split("]")[0][3:] for line in section.splitlines() if line.startswith("- [")]

    assert figures(summary_markdown(doorway, animation=True)) == [
        "fig1-global-maps.png", "fig2-global-maps-zoom.png", "fig3-error-vs-range.png",
        "fig4-door-local-maps.png", "approach.gif", "fig5-occupancy-grids.png",
        "fig6-kept-and-lost.png"]
    assert "approach.gif" not in figures(summary_markdown(doorway))
    assert json.loads(summary_json(doorway, animation=True))["figures"] == figures(
        summary_markdown(doorway, animation=True))


def test_door_note_only_when_no_door_tells_the_methods_apart(doorway: DemoResult) -> None:
    import dataclasses

    from sonarcarve.lab.demo import door_note

    # The doorway world's door: closed in centerline's local map, so fig. 4 shows the point.
    assert [door.passable["centerline"] for door in doorway.doors] == [False]
    assert door_note(doorway) == ""
    assert "Doors:" not in summary_markdown(doorway)
    # The same door open for every method, as on the office tour: say where to look instead.
    door = doorway.doors[0]
    all_open = dataclasses.replace(door, passable=dict.fromkeys(door.passable, True))
    office_like = dataclasses.replace(doorway, doors=(all_open, all_open))
    note = door_note(office_like)
    assert note.startswith("Doors: every door this tour approaches (2) looks passable 1.5 m")
    assert note.endswith("so fig. 4 and the animation show no method closing one.")
    assert note in summary_markdown(office_like)
    assert door_note(dataclasses.replace(doorway, doors=())) == ""
    # With the doorway scene run for fig. 4 (run_demo's door_scene): what each method left free
    # there, as measured at the scene's close-up door (centerline blocked, carving open).
    with_scene = dataclasses.replace(office_like, door_scene=doorway)
    note = door_note(with_scene)
    widths = doorway.doors[0].free_width
    assert "fig. 4 and approach.gif show the 'doorway' world's 0.85 m door instead" in note
    assert f"centerline {widths['centerline']:.2f} m free, blocked" in note
    assert f"carving {widths['carve']:.2f} m free;" in note
    assert note in summary_markdown(with_scene)
    import json

    from sonarcarve.lab.demo import summary_json

    record = json.loads(summary_json(with_scene))
    assert record["door_note"] == note
    assert record["door_figure"]["world"] == "doorway"
    assert record["door_figure"]["door_scene"] is True
    assert record["door_figure"]["passable"]["centerline"] is False
    assert json.loads(summary_json(doorway))["door_figure"]["door_scene"] is False


def test_caption_and_summary_give_the_occlusion_filters_shares(doorway: DemoResult) -> None:
    import dataclasses
    import json

    from sonarcarve.lab.demo import FilterSummary, summary_json
    from sonarcarve.lab.demo.table import caption

    made_up = dataclasses.replace(doorway, occlusion=FilterSummary("evidence", 0.5, 91.6, 4.4,
                                                                   123))
    assert caption(made_up).endswith(
        "With the occlusion filter on its final map (`sonarcarve process --method evidence "
        "--occlusion-depth 0.5`: points behind a wall of the map, as multipath echoes are), "
        "it left out 92% and 4%.")
    assert json.loads(summary_json(made_up))["occlusion_filter"] == {
        "method": "evidence", "depth_m": 0.5, "spurious_removed_pct": 91.6,
        "true_lost_pct": 4.4, "map_points": 123}
    without = dataclasses.replace(doorway, occlusion=None)
    assert "occlusion" not in caption(without)
    assert json.loads(summary_json(without))["occlusion_filter"] is None
