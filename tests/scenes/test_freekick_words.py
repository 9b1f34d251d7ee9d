"""The free-kick scene's words: the readout's verdict, goal-line crossing and keeper, and the goal-chance map's
summary, for kicks a review found misdescribed."""

from __future__ import annotations

import dataclasses
import itertools
import re

import numpy as np
import pytest

from kernels import ball
from scenes.freekick import FreeKickParams, FreeKickScene
from scenes.freekick import model as freekick_model
from scenes.freekick import scene as freekick_scene
from scenes.freekick.model import PRESETS, compute_kick, keeper_words, play_words
from scenes.freekick.odds import ODDS_MAP_ANGLES_DEG, ODDS_MAP_CAVEAT, ODDS_MAP_DISTANCES_M, odds_map_words


def _show(freekick: FreeKickScene, **changes: object) -> str:
    """The readout once the scene shows the default kick with ``changes``."""
    freekick.apply(dataclasses.replace(FreeKickParams(), **changes))  # type: ignore[arg-type]
    return freekick.result.content


def _keeper_line(readout: str) -> str:
    return next(line for line in readout.splitlines() if line.startswith("Keeper"))


def test_the_keeper_says_whose_right_he_dives_to(freekick: FreeKickScene) -> None:
    # Reported: "Keeper dives right" for a ball that crossed 4.64 m to the left, 26.75 m up. He faces the kicker:
    # he dived to the kicker's right, his own left, reading the ball as if it flew on straight; the words now say
    # whose side. He no longer dives at all for a ball that never comes at his goal, as that one.
    readout = _show(freekick, distance_m=40.0, speed_ms=40.0, elevation_deg=50.0)
    crossing = freekick.state.outcome.goal_point
    assert crossing is not None and crossing[1] > 4.0 and crossing[2] > 20.0
    assert freekick.state.played is not None and freekick.state.played.keeper_dive is None
    assert "never dives: the ball never comes at his goal" in _keeper_line(readout)
    readout = _show(freekick, azimuth_deg=-14.0)  # struck to the kicker's right, in off his fingertips
    dive = freekick.state.played.keeper_dive if freekick.state.played is not None else None
    assert dive is not None and dive.target[1] < 0.0
    assert "dives to his left (your right)" in _keeper_line(readout)
    # The other way round: he goes to his right, the kicker's left.
    assert "dives to his right (your left)" in _keeper_line(_show(freekick, azimuth_deg=-2.0))


def test_a_keeper_who_goes_straight_up_jumps(freekick: FreeKickScene) -> None:
    # Reported: a keeper going up for a ball read at him "dives up".
    line = _keeper_line(_show(freekick, azimuth_deg=-7.0))
    assert "jumps 0.67 s after the kick" in line and "dives" not in line


def test_how_near_the_keeper_came_is_said_only_when_he_came_near(freekick: FreeKickScene) -> None:
    # Reported: "gets within 24.04 m of the ball": a distance that large says nothing.
    far = _keeper_line(_show(freekick, distance_m=40.0, speed_ms=40.0, elevation_deg=50.0))
    assert " m of the ball" not in far and "beats him by" not in far
    assert "gets within" not in _keeper_line(_show(freekick, speed_ms=25.0, wall_jumps=True))
    near = _keeper_line(_show(freekick, azimuth_deg=-12.0, elevation_deg=20.0))  # off the bar, past his hands
    assert "gets within 0.20 m of the ball" in near
    assert "the ball beats him by 0.07 m" in _keeper_line(_show(freekick, azimuth_deg=-14.0))
    # Reported: the "Driven, off the post" preset said "gets within 2.00 m", 1.996 m rounded onto the cut-off.
    for preset in PRESETS:
        line = _keeper_line(_show(freekick, **dataclasses.asdict(preset.params)))
        assert "within 2.00 m" not in line and "by 2.00 m" not in line, (preset.label, line)


@pytest.mark.parametrize(
    "changes",
    [{"speed_ms": 25.0, "wall_jumps": True}, {"speed_ms": 26.0, "elevation_deg": 13.0}],
    ids=["jumping wall", "standing wall"],
)
def test_a_ball_blocked_by_the_wall_has_no_goal_line_crossing(freekick: FreeKickScene, changes: dict) -> None:
    # Reported: with the ball blocked by the wall the readout said "At the goal line: y = −0.39 m, z = 1.59 m", the
    # free flight's crossing, for a ball that never got there.
    readout = _show(freekick, **changes)
    played = freekick.state.played
    assert played is not None and played.result == "wall", changes
    assert freekick.state.outcome.goal_point is not None  # the free flight, through the wall, crosses the line
    assert readout.startswith("**Blocked by the wall**")
    assert "At the goal line" not in readout


def test_a_ball_that_reaches_the_goal_line_says_where(freekick: FreeKickScene) -> None:
    readout = _show(freekick, azimuth_deg=-20.0)
    crossing = freekick.state.outcome.goal_point
    assert crossing is not None
    assert f"At the goal line: **y = {crossing[1]:+.2f} m, z = {crossing[2]:.2f} m**" in readout


def test_a_ball_wide_and_far_over_the_bar_reads_so(freekick: FreeKickScene) -> None:
    # Reported: "Wide of the post" for a ball crossing the goal line 26.75 m up. The kernel's verdict stays "wide"
    # (outside the posts it never says over); the headline says it was over the bar's height too.
    readout = _show(freekick, distance_m=40.0, speed_ms=40.0, elevation_deg=50.0)
    played, crossing = freekick.state.played, freekick.state.outcome.goal_point
    assert played is not None and played.result == "wide" and crossing is not None
    assert crossing[2] > 20.0
    assert readout.splitlines()[0].strip() == "**Wide and over the bar**"
    # A ball wide at a keeper's height is wide of the post.
    readout = _show(freekick, azimuth_deg=-20.0)
    crossing = freekick.state.outcome.goal_point
    assert crossing is not None and crossing[2] < ball.GOAL_HEIGHT_M
    assert readout.splitlines()[0].strip() == "**Wide of the post**"


def test_a_lob_that_lands_after_four_seconds_reads_where_it_lands(freekick: FreeKickScene) -> None:
    # Reported: "Lands after 4.00 s, 10.4 m short" for a ball still 19.25 m up: every flight stopped at 4 s. It
    # lands after 5.06 s (scipy's DOP853 on the same coefficients: 5.06 s), 7.3 m short of the line.
    readout = _show(
        freekick, distance_m=40.0, angle_deg=45.0, speed_ms=40.0, elevation_deg=50.0, azimuth_deg=-30.0, spin_rev_s=0.0
    )
    assert freekick.state.flight.ended == "ground"
    assert "Lands after **5.06 s**, 7.3 m short" in readout


@pytest.mark.parametrize("model", ["measured", "constant"])
@pytest.mark.parametrize("axis", ["back", "left", "top"])
def test_every_kick_the_controls_allow_lands_or_reaches_the_net_within_its_time(model: str, axis: str) -> None:
    # The longest flights: the fastest, steepest kick, from the nearest and farthest spots at the widest angles,
    # aimed either way, with no spin and the most of each kind. Each must end on the ground or 2 m into the net, not
    # at the time limit, where the readout would say it lands while it is still in the air.
    for distance, angle, azimuth, spin in itertools.product((12.0, 40.0), (-45.0, 45.0), (-30.0, 30.0), (0.0, 15.0)):
        params = FreeKickParams(
            distance_m=distance,
            angle_deg=angle,
            speed_ms=40.0,
            elevation_deg=50.0,
            azimuth_deg=azimuth,
            spin_rev_s=spin,
            spin_axis=axis,  # type: ignore[arg-type]
            model=model,  # type: ignore[arg-type]
        )
        state = compute_kick(params)
        assert state.flight.ended in ("ground", "x_stop"), (params, state.flight.ended)
        assert state.ghost.ended in ("ground", "x_stop"), (params, state.ghost.ended)


def test_the_knuckleball_note_stands_only_while_the_spin_it_set_does(freekick: FreeKickScene) -> None:
    # Reported: tick Knuckleball, then set the spin to 15 rev/s, and the readout still said "Knuckleball: spin set
    # to 0 rev/s" above "S = r·ω/v = 0.415". The note now stands while the kick keeps the spin it set.
    note = "Knuckleball: spin set to 0 rev/s"
    freekick.controls["knuckle"].value = True
    assert freekick.params.spin_rev_s == 0.0 and note in freekick.result.content
    freekick.controls["speed_ms"].value = 27.0  # another control: the spin is still the one the tick set
    assert note in freekick.result.content
    freekick.controls["spin_rev_s"].value = 15.0
    readout = freekick.result.content
    assert note not in readout and "S = r·ω/v = 0.384" in readout  # 0.11 m · 2π · 15 / 27 m/s
    freekick.controls["spin_rev_s"].value = 0.0  # set by the user, not by the tick
    assert note not in freekick.result.content
    freekick.controls["knuckle"].value = False
    freekick.controls["knuckle"].value = True  # ticked again at zero spin: nothing to set, nothing to say
    assert note not in freekick.result.content
    freekick.controls["knuckle"].value = False
    freekick.controls["spin_rev_s"].value = 8.0
    freekick.controls["knuckle"].value = True
    assert note in freekick.result.content
    freekick.apply(FreeKickParams(knuckle=True, spin_rev_s=0.0))  # a preset or reset says nothing of the tick
    assert note not in freekick.result.content


def test_unticking_knuckleball_brings_back_the_spin_through_other_changes_but_not_past_the_users(
    freekick: FreeKickScene,
) -> None:
    freekick.controls["knuckle"].value = True
    freekick.controls["speed_ms"].value = 27.0  # another control: the spin is still the one the tick set
    freekick.controls["knuckle_seed"].value = 7
    assert freekick.params.spin_rev_s == 0.0
    freekick.controls["knuckle"].value = False
    assert freekick.params == FreeKickParams(speed_ms=27.0, knuckle_seed=7)
    assert freekick.controls["spin_rev_s"].value == 8.0
    freekick.controls["knuckle"].value = True
    assert "Untick it to get the 8 rev/s back" in freekick.result.content
    freekick.controls["spin_rev_s"].value = 0.0  # unchanged: still the tick's
    freekick.controls["spin_rev_s"].value = 3.0
    freekick.controls["spin_rev_s"].value = 0.0  # the user's zero now: nothing comes back
    assert "rev/s back" not in freekick.result.content
    freekick.controls["knuckle"].value = False
    assert freekick.params.spin_rev_s == 0.0 and freekick.controls["spin_rev_s"].value == 0.0
    freekick.controls["spin_rev_s"].value = 6.0
    freekick.controls["knuckle"].value = True
    freekick.apply(dataclasses.replace(freekick.params, view="above"))  # a change of view keeps the spin to restore
    freekick.controls["knuckle"].value = False
    assert freekick.params.spin_rev_s == 6.0
    freekick.controls["knuckle"].value = True
    freekick.apply(dataclasses.replace(FreeKickParams(), knuckle=True, spin_rev_s=0.0))  # a preset sets the spin
    assert "rev/s back" not in freekick.result.content
    freekick.controls["knuckle"].value = False
    assert freekick.params.spin_rev_s == 0.0


SHOWN_MARGINS = [(0.0, None), (0.001, None), (0.004, None), (0.006, "0.01"), (0.26, "0.26")]
"""Time margins (s) and how each reads at two decimals; None where that would be 0.00 s and words say it instead."""


@pytest.mark.parametrize(("margin_s", "shown"), SHOWN_MARGINS)
def test_a_save_with_no_margin_to_show_reads_just_reached(
    freekick: FreeKickScene, monkeypatch: pytest.MonkeyPatch, margin_s: float, shown: str | None
) -> None:
    # Reported after an aim: "Saved: the keeper reached it 0.00 s early". The default curler is saved; give its save
    # each margin, in the headline and the keeper's line alike.
    monkeypatch.setattr(freekick_scene, "save_margin_s", lambda _state: margin_s)
    monkeypatch.setattr(freekick_model, "save_margin_s", lambda _state: margin_s)
    readout = freekick.readout_markdown()
    assert "0.00 s" not in readout
    if shown is None:
        assert "**Saved: the keeper just reached it**" in readout
        assert ", just reaches it**" in readout
    else:
        assert f"**Saved: the keeper reached it {shown} s early**" in readout
        assert f", reaches it {shown} s early**" in readout


@pytest.mark.parametrize(("margin_s", "shown"), SHOWN_MARGINS[:-1] + [(0.2, "0.20")])
def test_a_ball_in_the_goal_as_it_passes_the_wall_reads_so(
    monkeypatch: pytest.MonkeyPatch, margin_s: float, shown: str | None
) -> None:
    # From 12 m at 30 m/s the ball is in the goal before the keeper can react. Moving the instant it passes the wall
    # gives its time from there into the goal each margin.
    state = compute_kick(FreeKickParams(distance_m=12.0, speed_ms=30.0, elevation_deg=8.0, azimuth_deg=-12.0))
    played = state.played
    assert played is not None and played.result == "goal" and played.keeper_dive is None
    assert not any(event.kind in ("post", "bar") for event in played.events)
    i = int(np.flatnonzero(played.position[:, 0] >= 0.0)[0])  # the goal line is x = 0
    x0, x1 = played.position[i - 1, 0], played.position[i, 0]
    line_s = float(played.t[i - 1] + (played.t[i] - played.t[i - 1]) * -x0 / (x1 - x0))
    passed_s = freekick_model.wall_passed_s(state, played)
    assert passed_s is not None
    assert f"in the goal {line_s - passed_s:.2f} s after it passes the wall" in keeper_words(state)
    monkeypatch.setattr(freekick_model, "wall_passed_s", lambda _state, _played: line_s - margin_s)
    words = keeper_words(state)
    assert "0.00 s" not in words
    if shown is None:
        assert words == "never dives: it is in the goal as it passes the wall, within his reaction time (0.25 s)"
    else:
        assert words == (
            f"never dives: it is in the goal {shown} s after it passes the wall, within his reaction time (0.25 s)"
        )


def test_keeper_words_never_give_a_far_distance() -> None:
    """Over spots and strikes, the words give how near he came only within a couple of metres."""
    for distance in (16.0, 25.0, 35.0):
        for azimuth in (-20.0, -9.0, 5.0, 15.0):
            p = FreeKickParams(distance_m=distance, azimuth_deg=azimuth)
            words = keeper_words(compute_kick(p))
            for part in ("gets within ", "beats him by "):
                if part in words:
                    metres = float(words.split(part)[1].split(" m")[0])
                    assert metres <= 2.0, (distance, azimuth, words)


# ------------------------------------------------------------------------------------------------ goal chance map
def test_a_map_where_no_spot_scores_names_no_best_spot(freekick: FreeKickScene) -> None:
    # Reported: with every tile 0 % the map still named "Best spot: 16 m, 40° right: goal 0 %".
    freekick.apply(dataclasses.replace(FreeKickParams(), speed_ms=5.0))  # short of the goal from every spot
    freekick.heat_button.value = True  # the click
    assert freekick.wait_idle(300.0)
    assert freekick.odds_map is not None and not freekick.odds_map.any()
    status = freekick.heat_status.content
    assert "No spot on the map scores" in status and "Best spot" not in status


def test_the_map_says_where_its_keeper_flatters_far_spots() -> None:
    # The keeper dives on his first read of the ball, as if it flew straight on, so 30–36 m out scores more than
    # 20 m out: the words beside the best spot say so wherever a keeper is in goal.
    chance = np.zeros((len(ODDS_MAP_DISTANCES_M), len(ODDS_MAP_ANGLES_DEG)))
    chance[-2, 8] = 0.9  # the best spot 35 m out
    with_keeper = odds_map_words(chance, FreeKickParams())
    assert with_keeper.startswith("Best spot: **35 m, on the centre line: goal 90 %**")
    assert ODDS_MAP_CAVEAT in with_keeper and "straight on" in ODDS_MAP_CAVEAT
    assert ODDS_MAP_CAVEAT not in odds_map_words(chance, FreeKickParams(keeper=False))


# Kind: lines of one readout about two different paths. A kick driven into the turf read "Height at the wall: never
# reaches the wall" and "Lands after 0.00 s" (its free flight) beside "GOAL" and a keeper line about the ball
# "after it passes the wall" (the ball played on, which bounced). The wall and landing lines now say which path,
# and a path that reaches the wall's plane is never said not to.
def _wall_crossing(state: object, played: ball.Trajectory) -> np.ndarray | None:
    """The played ball's centre where it first crosses the wall's plane toward the goal, by linear interpolation
    between its samples (the test's own reckoning)."""
    wall = state.wall  # type: ignore[attr-defined]
    normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
    side = (played.position[:, :2] - np.array(wall.centre_xy)) @ normal
    crossings = np.flatnonzero((side[:-1] < 0.0) & (side[1:] >= 0.0))
    if not crossings.size:
        return None
    i = int(crossings[0])
    return np.array([np.interp(0.0, side[i : i + 2], played.position[i : i + 2, k]) for k in range(3)])


def _beside(state: object, point: np.ndarray) -> str:
    """What the wall line adds for a ball whose centre at ``point`` passes clear of the wall's span (the test's own
    reckoning: along the wall, + to the kicker's left)."""
    wall = state.wall  # type: ignore[attr-defined]
    normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
    lateral = float((point[:2] - np.array(wall.centre_xy)) @ np.array([-normal[1], normal[0]]))
    clear = abs(lateral) - 0.5 * wall.width_m
    if clear <= ball.BALL_RADIUS_M:
        return ""
    return f", beside the wall, {clear:.2f} m {'left' if lateral > 0 else 'right'} of its end"


@pytest.mark.parametrize(
    ("distance_m", "angle_deg", "speed_ms", "elevation_deg"),
    [
        (12.0, 45.0, 40.0, -5.0),  # the report's kick: into the turf at once, then in
        (20.0, 0.0, 30.0, 2.0),
        (16.0, 0.0, 10.0, -5.0),
        (30.0, -30.0, 20.0, 0.0),
        (22.0, 0.0, 25.0, 17.0),  # over the wall in the air: the free flight's height
        (25.0, 10.0, 5.0, 30.0),  # a lob that lands short of the wall
        (20.0, 0.0, 30.0, 2.0),  # bounces, then into a defender's feet
        (20.0, 0.0, 6.0, 10.0),  # bounces and stops short of the wall
        (12.0, 0.0, 16.0, 15.0),  # into the wall in the air: its own line would land beyond
        (12.0, 0.0, 8.0, 15.0),  # bounces once, then into the wall
    ],
)
def test_the_wall_and_landing_lines_describe_the_path_they_name(
    freekick: FreeKickScene, distance_m: float, angle_deg: float, speed_ms: float, elevation_deg: float
) -> None:
    readout = _show(
        freekick, distance_m=distance_m, angle_deg=angle_deg, speed_ms=speed_ms, elevation_deg=elevation_deg
    )
    state = freekick.state
    played, free = state.played, state.outcome
    assert played is not None
    line = next(text for text in readout.splitlines() if text.startswith("Height at the wall"))
    bounced = any(e.kind == "ground" and (free.wall_time is None or e.t < free.wall_time) for e in played.events)
    if free.wall_point is not None and not bounced:
        point = free.wall_point
        # A ball whose centre passes over the wall's top but whose underside does not says so (the free flight
        # then reads "Blocked by the wall").
        below = state.wall.height_m - (point[2] - ball.BALL_RADIUS_M)
        clips = (
            f", its underside {max(below, 0.005):.2f} m below the wall's top" if 0 < below < ball.BALL_RADIUS_M else ""
        )
        assert line.startswith(f"Height at the wall: **{point[2]:.2f} m{clips}{_beside(state, point)}**")
    else:
        struck = [e for e in played.events if e.kind == "wall"]
        crossing = _wall_crossing(state, played)
        if struck:
            z = struck[0].position[2]
            assert line.startswith(f"Height at the wall: **{z:.2f} m, after bouncing, into a defender (pale line)**")
        elif crossing is None:
            assert "never reaches the wall" in line
        else:
            beside = _beside(state, crossing)
            assert line.startswith(f"Height at the wall: **{crossing[2]:.2f} m{beside}, after bouncing (pale line)**")
    if "never reaches the wall" in line:
        assert "passes the wall" not in readout
    landing = [text for text in readout.splitlines() if "short" in text and "after **" in text]
    if free.goal_point is None:
        (said,) = landing
        first, down = (played.events[0] if played.events else None), float(state.flight.t[-1])
        if said.startswith("First bounce"):
            assert first is not None and first.kind == "ground" and abs(first.t - down) < 1e-3
        elif said.startswith("In free flight it would land"):
            assert first is not None and first.kind != "ground" and first.t < down
        else:
            assert said.startswith("Lands after") and (first is None or first.t >= down)
    else:
        assert not landing


# Kind: a height at the wall with no word of where along it. Topspin at 14° read "Height at the wall: 1.14 m (wall
# top 1.80 m)" beside GOAL, as if through the wall: the ball passed 1.45 m right of the wall's centre, beside its
# end at 1.0 m (an outside tester).
@pytest.mark.parametrize(
    ("changes", "side"),
    [
        ({"spin_axis": "top", "elevation_deg": 14.0}, "right"),  # the tester's kick
        ({"spin_axis": "right", "azimuth_deg": -14.0, "elevation_deg": 12.0}, "right"),
        ({"spin_axis": "left", "azimuth_deg": 8.0, "elevation_deg": 12.0}, "left"),
        ({}, None),  # the default curler goes over
        ({"elevation_deg": 10.0}, None),  # into the wall
    ],
)
def test_a_ball_that_passes_beside_the_wall_says_so_and_which_side(
    freekick: FreeKickScene, changes: dict, side: str | None
) -> None:
    readout = _show(freekick, **changes)
    line = next(text for text in readout.splitlines() if text.startswith("Height at the wall"))
    state = freekick.state
    point = state.outcome.wall_point
    assert point is not None
    wall = state.wall
    normal = np.array(wall.normal_xy) / np.hypot(*wall.normal_xy)
    lateral = float((point[:2] - np.array(wall.centre_xy)) @ np.array([-normal[1], normal[0]]))  # + to the left
    clear = abs(lateral) - 0.5 * wall.width_m
    if side is None:
        assert clear <= ball.BALL_RADIUS_M and "beside" not in line
        assert line.startswith(f"Height at the wall: **{point[2]:.2f} m**")
    else:
        assert clear > ball.BALL_RADIUS_M and (lateral > 0) == (side == "left")
        assert line.startswith(
            f"Height at the wall: **{point[2]:.2f} m, beside the wall, {clear:.2f} m {side} of its end**"
        )


# Kind: one contact said twice. A ball between two defenders touches both at one instant, and read "hits a defender
# at 0.3 m, hits a defender at 0.3 m".
def test_contacts_that_read_alike_are_said_once() -> None:
    params = dataclasses.replace(
        FreeKickParams(), distance_m=22.0, speed_ms=20.0, elevation_deg=8.0, azimuth_deg=0.0, spin_rev_s=0.0
    )
    played = compute_kick(params).played
    assert played is not None and [e.kind for e in played.events[:2]] == ["wall", "wall"]
    assert played.events[0].t == played.events[1].t
    assert play_words(played).startswith("Hits two defenders at 0.3 m, bounces")
    # The same contact again later, and a third time: counted, not repeated.
    post = ball.Event(1.0, "post", (0.0, 3.6, 1.5))
    again = dataclasses.replace(played, events=(post, dataclasses.replace(post, t=1.2)))
    assert play_words(again).startswith("Hits the left post at 1.5 m twice, ")
    thrice = dataclasses.replace(
        played, events=(post, dataclasses.replace(post, t=1.2), dataclasses.replace(post, t=1.4))
    )
    assert play_words(thrice).startswith("Hits the left post at 1.5 m 3×, ")
    alternating = dataclasses.replace(played, events=(post, ball.Event(1.1, "ground", (0.0, 3.0, 0.11)), post))
    assert play_words(alternating).startswith("Hits the left post at 1.5 m, bounces, hits the left post at 1.5 m, ")


# Kind: one quantity measured along two different axes. At a 45° spot the readout said "up to 0.11 m off the
# spinless path: swerves 0.19 m right at 30 m": the "up to" took world y for sideways, the swerves the direction of
# the kick. Both now measure square to the launch heading, so no swerve or rise named exceeds the "up to".
@pytest.mark.parametrize(
    ("angle_deg", "azimuth_deg", "seed"),
    [(45.0, 0.0, 7), (0.0, 0.0, 7), (-30.0, 0.0, 3), (30.0, 6.0, 11), (-45.0, -8.0, 0), (15.0, 3.0, 5)],
)
def test_the_knuckle_wobble_bounds_every_swerve_it_names(
    freekick: FreeKickScene, angle_deg: float, azimuth_deg: float, seed: int
) -> None:
    readout = _show(
        freekick, knuckle=True, spin_rev_s=0.0, knuckle_seed=seed, angle_deg=angle_deg, azimuth_deg=azimuth_deg
    )
    line = next(line for line in readout.splitlines() if line.startswith("Knuckle wobble"))
    up_to = float(re.search(r"up to \*\*([0-9.]+) m", line).group(1))  # type: ignore[union-attr]
    named = [float(m) for m in re.findall(r"([0-9.]+) m (?:left|right|higher|lower)", line)]
    assert named and max(named) <= up_to
    # Against the flights themselves: the kick's offset from its ghost at equal times, square to the launch.
    state = freekick.state
    assert state.played is not None
    end = min(state.flight.t[-1], state.ghost.t[-1], *(e.t for e in state.played.events[:1]))
    times = np.linspace(0.0, end, 2000)
    diff = np.stack([np.interp(times, state.flight.t, state.flight.position[:, k]) for k in range(3)], axis=1)
    diff -= np.stack([np.interp(times, state.ghost.t, state.ghost.position[:, k]) for k in range(3)], axis=1)
    launch = state.ghost.velocity[0, :2] / np.linalg.norm(state.ghost.velocity[0, :2])
    across = np.hypot(diff[:, :2] @ np.array([-launch[1], launch[0]]), diff[:, 2])
    assert freekick_model.knuckle_wobble_m(freekick.params, state) == pytest.approx(across.max(), abs=2e-3)


# Kind: the free flight's verdict read without the goal's frame. "In free flight through the goal plane: Over the
# bar" stood beside "z = 2.43 m" (the bar's underside is 2.44 m), and "Wide of the post" beside "y = −3.64 m" (its
# inside edge is 3.66 m): the free flight has no frame and calls a ball not wholly inside wide or over. A crossing
# that overlaps a post or the bar meets it, as the pitch's verdict says.
@pytest.mark.parametrize(
    ("changes", "headline"),
    [
        ({"distance_m": 12.0, "angle_deg": 45.0}, "Hits the bar"),
        ({"knuckle": True, "spin_rev_s": 0.0, "knuckle_seed": 7}, "Hits the post"),
    ],
)
def test_a_free_flight_into_the_frame_is_not_called_wide_or_over(
    freekick: FreeKickScene, changes: dict[str, object], headline: str
) -> None:
    readout = _show(freekick, **changes)
    assert readout.splitlines()[0].strip() == f"**{headline}**"
    assert "In free flight through the goal plane" not in readout


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_free_flight_clear_over_the_bar_between_the_posts_reads_over(freekick: FreeKickScene, side: float) -> None:
    # A re-test: "Hits the bar / In free flight through the goal plane: Wide and over the bar" beside y = −3.57 m,
    # z = 2.67 m: the centre 9 cm inside the post's line and clear over the bar. The kernel's free flight calls it
    # wide (not wholly inside the posts); with the frame in the goal plane it is over.
    azimuth = {1.0: 15.5, -1.0: -14.5}[side]
    readout = _show(
        freekick,
        distance_m=12.0,
        angle_deg=45.0 * side,
        speed_ms=35.0,
        elevation_deg=17.0,
        azimuth_deg=azimuth,
        knuckle=True,
        spin_rev_s=0.0,
        knuckle_seed=7,
    )
    crossing = freekick.state.outcome.goal_point
    assert crossing is not None and abs(crossing[1]) < 0.5 * ball.GOAL_WIDTH_M and crossing[2] > 2.6
    line = next(line for line in readout.splitlines() if line.startswith("In free flight through"))
    assert line.strip() == "In free flight through the goal plane: Over the bar"


def test_the_free_flights_words_agree_with_the_crossing_they_stand_beside(freekick: FreeKickScene) -> None:
    post_axis, bar_axis = 0.5 * ball.GOAL_WIDTH_M + 0.06, ball.GOAL_HEIGHT_M + 0.06
    reach = ball.BALL_RADIUS_M + 0.06
    said = set()
    for azimuth, elevation in itertools.product(np.linspace(-16.0, 4.0, 21), (12.0, 17.0, 19.0)):
        readout = _show(freekick, keeper=False, azimuth_deg=float(azimuth), elevation_deg=elevation)
        crossing = freekick.state.outcome.goal_point
        line = next((line for line in readout.splitlines() if line.startswith("In free flight through")), None)
        if line is None or crossing is None:
            continue
        y, z = abs(crossing[1]), crossing[2]
        words = line.split(": ", 1)[1].strip()
        said.add(words)
        if words.startswith("Wide"):
            assert y - post_axis >= reach, (azimuth, elevation, crossing)
        elif words == "Over the bar":
            assert z - bar_axis >= reach and y < post_axis, (azimuth, elevation, crossing)
        elif words == "GOAL":
            assert y <= post_axis - reach and z <= bar_axis - reach, (azimuth, elevation, crossing)
    assert said  # the sweep crosses posts and bar: the pitch and the free flight differ somewhere


def test_a_ball_whose_underside_clips_the_wall_says_so_beside_the_free_flights_block(freekick: FreeKickScene) -> None:
    # An outside tester: the default kick at 22 m/s read "GOAL", "In free flight through the goal plane: Blocked by
    # the wall" and "Height at the wall: 1.89 m (wall top 1.80 m)": the centre passes over, the ball does not.
    readout = _show(freekick, speed_ms=22.0)
    assert "In free flight through the goal plane: Blocked by the wall" in readout
    assert "Height at the wall: **1.89 m, its underside 0.02 m below the wall's top** (wall top 1.80 m)" in readout


@pytest.mark.parametrize("spin", ["back", "top"])
def test_a_kick_with_no_sideways_movement_reads_zero_not_minus_zero(freekick: FreeKickScene, spin: str) -> None:
    # An outside tester: 40 m/s with backspin read "Sideways against the no-spin kick: -0.00 m".
    readout = _show(freekick, speed_ms=40.0, spin_axis=spin)
    line = next(text for text in readout.splitlines() if text.startswith("Sideways against"))
    assert "**0.00 m**" in line, line
