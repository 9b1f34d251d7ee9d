"""GPX pieces joined into one course: tracks, segments of one track, routes, or a mix, all under one gap rule.

A file with no track and two routes (France and Sydney) used to load as one course over 16 800 km while the same
pieces as tracks were refused. Here random pieces, near or far apart, are written in every arrangement and each
must get the same verdict: joined into the same course, or refused with a message naming the two pieces and the
gap (the expected gap is computed in this file, independently of the loader).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Sequence

import pytest
from helpers.properties import examples
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from kernels import course

EXAMPLES = 150
Point = tuple[float, float]
Piece = list[Point]


def haversine_m(a: Point, b: Point) -> float:
    """Great-circle distance (m) on the IUGG mean sphere, written out here."""
    (lat1, lon1), (lat2, lon2) = a, b
    p1, p2 = math.radians(lat1), math.radians(lat2)
    h = math.sin((p2 - p1) / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lon2 - lon1) / 2) ** 2
    return 2.0 * 6_371_008.8 * math.asin(math.sqrt(min(1.0, h)))


def rows(piece: Piece, tag: str) -> str:
    return "".join(f'<{tag} lat="{lat!r}" lon="{lon!r}"><ele>100</ele></{tag}>' for lat, lon in piece)


def arrange(pieces: Sequence[Piece], layout: Sequence[str]) -> str:
    """A GPX file holding ``pieces`` in order; layout[i] says how piece i arrives: "trk" opens a track, "seg" adds
    a segment to the open track (a new track if none is open), "rte" is a route. "note" entries add a comment that
    looks like markup, and "empty" an empty track, which must change nothing."""
    parts: list[str] = []
    open_track = False
    pieces_left = iter(pieces)
    for how in layout:
        if how in ("note", "empty"):
            if open_track:
                parts.append("</trk>")
                open_track = False
            parts.append("<!-- <trk> <rte> -->" if how == "note" else "<trk><name>empty</name></trk>")
            continue
        piece = next(pieces_left)
        if how == "rte" or (how == "trk" and open_track):
            if open_track:
                parts.append("</trk>")
                open_track = False
        if how == "rte":
            parts.append(f"<rte>{rows(piece, 'rtept')}</rte>")
            continue
        if not open_track:
            parts.append("<trk>")
            open_track = True
        parts.append(f"<trkseg>{rows(piece, 'trkpt')}</trkseg>")
    if open_track:
        parts.append("</trk>")
    return f'<?xml version="1.0"?><gpx version="1.1" creator="test">{"".join(parts)}</gpx>'


def expected_verdict(pieces: Sequence[Piece]) -> tuple[int, float] | None:
    """(index from 1 of the first piece that starts more than 2 km from the previous one's end, that gap in m)."""
    for i in range(1, len(pieces)):
        gap = haversine_m(pieces[i - 1][-1], pieces[i][0])
        if gap > course.MAX_SEGMENT_GAP_M:
            return i + 1, gap
    return None


@st.composite
def piece_sets(draw: st.DrawFn) -> list[Piece]:
    """2–5 short straight pieces (10–14 points 11 m apart, heading north: each a course's 100 m or more); each starts
    near the previous one's end (within about 3 km, either side of the 2 km bound) or anywhere on Earth."""
    pieces: list[Piece] = []
    lat = draw(st.floats(-75.0, 75.0))
    lon = draw(st.floats(-170.0, 170.0))
    for k in range(draw(st.integers(2, 5))):
        if k > 0:
            if draw(st.booleans()):
                lat = max(-75.0, min(75.0, lat + draw(st.floats(-0.02, 0.02))))
                lon = max(-170.0, min(170.0, lon + draw(st.floats(-0.03, 0.03))))
            else:
                lat, lon = draw(st.floats(-75.0, 75.0)), draw(st.floats(-170.0, 170.0))
        n = draw(st.integers(10, 14))
        pieces.append([(lat + i * 1e-4, lon) for i in range(n)])
        lat = pieces[-1][-1][0]
    # Keep clear of the bound itself: a gap within 10 m of 2 km is a matter of rounding, not of rule.
    for i in range(1, len(pieces)):
        assume(abs(haversine_m(pieces[i - 1][-1], pieces[i][0]) - course.MAX_SEGMENT_GAP_M) > 10.0)
    return pieces


LAYOUTS = ("tracks", "segments", "routes", "mixed")


@settings(max_examples=examples(EXAMPLES), deadline=None)
@given(pieces=piece_sets(), mix=st.lists(st.sampled_from(["trk", "seg", "rte", "note", "empty"]), max_size=40))
def test_every_arrangement_of_the_pieces_gets_the_same_verdict(pieces: list[Piece], mix: list[str]) -> None:
    """Tracks, segments of one track, routes, or a random mix: the same course when the pieces follow on, the same
    refusal (which pieces, how far apart) when two consecutive ones are more than 2 km apart."""
    kept, used = [], 0
    for m in mix:  # one layout entry per piece, with comments and empty tracks wherever they fell
        if m in ("note", "empty"):
            kept.append(m)
        elif used < len(pieces):
            kept.append(m)
            used += 1
    kept += ["rte"] * (len(pieces) - used)
    layouts = {
        "tracks": ["trk"] * len(pieces),
        "segments": ["seg"] * len(pieces),
        "routes": ["rte"] * len(pieces),
        "mixed": kept,
    }
    verdict = expected_verdict(pieces)
    joined = [p for piece in pieces for p in piece]
    length = sum(haversine_m(a, b) for a, b in itertools.pairwise(joined))
    for layout in LAYOUTS:
        text = arrange(pieces, layouts[layout])
        if verdict is None:
            c = course.load_gpx(text)
            assert c.total_distance_m == pytest.approx(length, rel=1e-6, abs=1e-3), layout
            continue
        with pytest.raises(ValueError) as refused:
            course.load_gpx(text)
        message = str(refused.value)
        k, gap = verdict
        found = re.search(rf"segment {k} starts ([\d ]+\.\d+) km from where segment {k - 1} ends", message)
        assert found is not None, (layout, message)
        assert float(found.group(1).replace(" ", "")) == pytest.approx(gap / 1000.0, abs=0.051), (layout, message)
        assert f"segment {k - 1} is " in message and f"segment {k} is " in message, (layout, message)


def two_routes(second: Point) -> str:
    a = [(45.0 + i * 1e-3, 6.0) for i in range(3)]
    b = [(second[0] + i * 1e-3, second[1]) for i in range(3)]
    return arrange([a, b], ["rte", "rte"])


def test_routes_in_france_and_sydney_are_refused_not_joined() -> None:
    """The public case: no track, one route at 45° N 6° E and one at 33.8° S 151.2° E (loaded as 16 807 km)."""
    gap_km = haversine_m((45.002, 6.0), (-33.8, 151.2)) / 1000.0
    print(f"routes 45N 6E and 33.8S 151.2E: {gap_km:.1f} km apart")
    with pytest.raises(ValueError, match=r"segment 2 starts [\d ]+\.\d+ km from where segment 1 ends") as refused:
        course.load_gpx(two_routes((-33.8, 151.2)))
    message = str(refused.value)
    print(message)
    assert "segment 1 is route 1, segment 2 is route 2" in message
    number = re.search(r"starts ([\d ]+\.\d+) km", message)
    assert number is not None and float(number.group(1).replace(" ", "")) == pytest.approx(gap_km, abs=0.051)


def test_near_routes_and_a_track_after_a_route_are_joined_in_file_order() -> None:
    near = course.load_gpx(two_routes((45.003, 6.0)))
    assert near.total_distance_m == pytest.approx(haversine_m((45.0, 6.0), (45.005, 6.0)), rel=1e-9)
    # A track written before a route: the file's order, not "tracks first", decides how they join.
    a, b = [(45.0, 6.0), (45.001, 6.0)], [(45.002, 6.0), (45.003, 6.0)]
    track_then_route = arrange([a, b], ["trk", "rte"])
    assert course.load_gpx(track_then_route).total_distance_m == pytest.approx(
        haversine_m((45.0, 6.0), (45.003, 6.0)), rel=1e-9
    )
    route_then_track = arrange([b, a], ["rte", "trk"])  # b then a: 1 point back, 111 m, then on
    c = course.load_gpx(route_then_track)
    assert c.total_distance_m == pytest.approx(
        haversine_m(b[0], b[1]) + haversine_m(b[1], a[0]) + haversine_m(a[0], a[1]), rel=1e-9
    )


def test_a_far_route_after_a_track_is_refused_with_both_names() -> None:
    text = arrange([[(45.0, 6.0), (45.001, 6.0)], [(46.0, 6.0), (46.001, 6.0)]], ["trk", "rte"])
    with pytest.raises(ValueError, match=r"segment 1 is track 1, segment 2 is route 1"):
        course.load_gpx(text)
