"""Read a GPX file into a :class:`kernels.course.route.Course`, refusing a bad file in words a rider can act on.

:func:`load_gpx` takes a path, bytes or text (at most 20 MiB and 200 000 points), decodes it by its byte-order mark or
XML declaration (XML 1.0 §4.3.3), parses it with gpxpy, and refuses points off the map, pieces more than 2 km
apart, any stretch steeper than 50 % (:data:`MAX_GPX_GRADE`), which no road is, and a route shorter than
:data:`MIN_COURSE_M` (100 m), too short to ride or draw. The pieces are every track
segment and every route, joined in the order the file gives them: points arriving as tracks, as segments of one
track, as routes or as a mix of them make the same course, under the same rule. :data:`SAMPLE_ROUTE` is the
bundled Alpe d'Huez course in ``kernels/routes/``.
"""

from __future__ import annotations

import codecs
import dataclasses
import math
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import gpxpy
import gpxpy.gpx
import numpy as np
from numpy.typing import NDArray

from kernels import _checks
from kernels.course.route import (
    EARTH_RADIUS_M,
    MAX_ELEVATION_M,
    MAX_POINTS,
    MIN_ELEVATION_M,
    NOISE_WINDOW_PER_M,
    Course,
    course_from_points,
    elevation_noise_m,
    noise_smoothing_m,
    steepest_grade,
)

MAX_FILE_BYTES = 20 * 1024 * 1024
"""Largest GPX file :func:`load_gpx` reads (20 MiB)."""
SAMPLE_ROUTE = Path(__file__).parent.with_name("routes") / "alpe_dhuez.gpx"
"""The bundled sample: Alpe d'Huez rebuilt from its published profile (see the file's description)."""

_GPX_ROOT = re.compile(r"<(?:([A-Za-z_][\w.-]*):)?gpx[\s>/]")
_PROLOG = re.compile(r"(?:[\s\ufeff]+|<\?.*?\?>|<!--.*?-->|<!DOCTYPE(?:[^>\[]|\[.*?\])*>)*", re.DOTALL)
"""What XML allows before the root element: white space, processing instructions (``<?xml ...?>``), comments and a
document type, of any length."""


def load_gpx(
    source: str | os.PathLike[str] | bytes,
    *,
    name: str | None = None,
    file_name: str | None = None,
    smoothing_m: float = 50.0,
) -> Course:
    """Read a GPX file's track and route points into a :class:`Course`.

    Args:
        source: a path, the file's bytes, or the file's text (a string that starts with ``<``).
        name: course name (a str); default (None) the track's name, else the file name, else "GPX course".
        file_name: the file's name where ``source`` is its bytes or text (an upload's): the course's name when the
            file names no track (a path's own name is used without it).
        smoothing_m: elevation moving-average window (m, ≥ 0); 0, or a window shorter than
            :data:`~kernels.course.route.SMOOTHING_FLOOR_M` (1 cm), keeps the elevation as read. A file whose
            elevation jitters by σ from point to point is smoothed over :data:`NOISE_WINDOW_PER_M`·σ where that is
            longer (:func:`~kernels.course.route.noise_smoothing_m`).

    Returns:
        The course: every track segment and every route joined in the order the file gives them.

    Raises:
        ValueError: with a message a person can act on: the file is larger than 20 MiB, not GPX (or not text),
            has no track points, one point, points without elevation, unreadable (named by point and line),
            non-finite or out-of-range values, more
            than 200 000 points, a route shorter than :data:`MIN_COURSE_M` (100 m), a stretch steeper than
            :data:`MAX_GPX_GRADE` (50 %), or consecutive pieces (track segments or routes, in any mix) more than
            :data:`MAX_SEGMENT_GAP_M` (2 km) apart; the message names both pieces and the gap. Nothing else
            escapes for a bad file. A bad ``name`` or ``smoothing_m`` is refused naming it.

    The text is decoded by its byte-order mark, else the XML declaration's encoding (ISO-8859-1, UTF-16...),
    else as UTF-8; a namespace prefix on the GPX elements (``<g:gpx xmlns:g=...>``) is read too. Only positions and
    elevations are read: waypoints and other fields (:data:`_UNUSED`) cannot refuse a file.
    """
    for argument, value in (("name", name), ("file_name", file_name)):
        if value is not None and not isinstance(value, str):
            raise ValueError(f"{argument} must be a str or None, got {type(value).__name__}")
    _checks.non_negative("smoothing_m", smoothing_m)
    label = "the file"
    if isinstance(source, bytes):
        if len(source) > MAX_FILE_BYTES:
            raise ValueError(f"the file is {_mib(len(source))}; the limit is 20 MiB")
        data = source
    elif isinstance(source, os.PathLike) or (
        isinstance(source, str) and not source.lstrip("\ufeff \t\r\n").startswith("<")
    ):
        path = Path(source)
        label = path.name
        try:
            size = path.stat().st_size
            if size > MAX_FILE_BYTES:
                raise ValueError(f"{label} is {_mib(size)}; the limit is 20 MiB")
            data = path.read_bytes()  # a directory or an unreadable file: OSError, as a missing one
        except OSError as error:
            raise ValueError(f"cannot read {path}: {error.strerror}") from error
    elif isinstance(source, str):
        if len(source) > MAX_FILE_BYTES or len(source.encode("utf-8")) > MAX_FILE_BYTES:
            raise ValueError("the file is larger than the 20 MiB limit")
        data = source.encode("utf-8")
    else:
        raise ValueError(f"source must be a path, bytes or GPX text, got {type(source).__name__}")
    text = _decode(data, label)
    prolog = _PROLOG.match(text)
    root = _GPX_ROOT.match(text, prolog.end() if prolog else 0)
    if root is None:
        raise ValueError(f"{label} is not GPX: no <gpx> element at its start")
    # A "billion laughs", or an outside file (XXE): an entity the file declares and uses is never expanded.
    declared = re.findall(r"<!ENTITY\s+(?:%\s*)?([\w.:-]+)", prolog.group(0)) if prolog else []
    if any(f"&{entity};" in text or f"%{entity};" in text for entity in declared):
        raise ValueError(f"{label} uses XML entities (<!ENTITY>), which a GPX file does not need; they are not read")
    # Count before parsing (gpxpy would build every point first), whatever the namespace prefix.
    prefix = root.group(1)
    tags = ("<trkpt", "<rtept") + ((f"<{prefix}:trkpt", f"<{prefix}:rtept") if prefix else ())
    tagged = sum(text.count(tag) for tag in tags)
    if tagged > MAX_POINTS:
        raise ValueError(f"{label} has {tagged} points; the limit is {MAX_POINTS}")
    if prefix:  # <g:gpx xmlns:g=...>: gpxpy reads only unprefixed names, so drop the prefix
        text = text.replace(f"<{prefix}:", "<").replace(f"</{prefix}:", "</")
    text = _UNUSED.sub(_lines_kept, text)
    try:
        gpx = gpxpy.parse(text)
    except gpxpy.gpx.GPXException as error:
        unreadable = _unreadable_position(text)
        if unreadable is not None:
            raise ValueError(f"{label}: {unreadable}") from error
        raise ValueError(f"{label} is not a valid GPX file: {_gpx_error_words(str(error))}") from error
    except (ValueError, TypeError, AttributeError, IndexError) as error:
        raise ValueError(f"{label} is not a valid GPX file: {type(error).__name__}") from error

    pieces = _pieces(gpx, text)
    kinds = {piece.kind for piece in pieces}
    kind = " and ".join(sorted(kinds)) if kinds else "track"
    points = [p for piece in pieces for p in piece.points]
    if not points:
        raise ValueError(f"{label} has no track points")
    if len(points) > MAX_POINTS:
        raise ValueError(f"{label} has {len(points)} {kind} points; the limit is {MAX_POINTS}")
    if len(points) < 2:
        raise ValueError(f"{label} has only one {kind} point; a course needs two or more")
    missing = sum(p.elevation is None for p in points)
    if missing:
        raise ValueError(
            f"{label}: {missing} of {len(points)} {kind} points {'has' if missing == 1 else 'have'} no elevation "
            "(<ele>); export the file with elevation"
        )
    lat = np.array([p.latitude for p in points], dtype=np.float64)
    lon = np.array([p.longitude for p in points], dtype=np.float64)
    ele = np.array([p.elevation for p in points], dtype=np.float64)
    _check_values(label, kind, lat, lon, ele)
    _check_gaps(label, pieces)
    named = [*gpx.tracks, *gpx.routes]
    title = name or next((t.name for t in named if t.name), None) or gpx.name
    title = title or (label if label != "the file" else file_name or "GPX course")
    title = str(title)[:80]
    try:
        result = course_from_points(lat, lon, ele, name=title, smoothing_m=noise_smoothing_m(ele, smoothing_m))
    except ValueError as error:  # the builders name the course; a reader is told about the file
        message = str(error).removeprefix(f"{title}: ")
        raise ValueError(f"{label}: {message}") from error
    _check_grades(label, result)  # a cliff's words first: a vertical profile is short on the map too
    _check_length(label, kind, result)
    return result


MIN_COURSE_M = 100.0
"""Shortest route :func:`load_gpx` accepts, along the map (m): ten steps of the scene's 10 m Position slider, longer
than the 45 m of a group the scene frames (so its Start and Finish lines are never framed as one), and a ride of
some twenty seconds from rest. A shorter file (two points a centimetre apart) rode to "Finish 0:00"."""
MAX_GPX_GRADE = 0.5
"""Steepest grade :func:`load_gpx` accepts (50 %), over any stretch of :data:`GRADE_WINDOW_M` (or the whole route
if shorter), raw and smoothed. The steepest paved streets are about 35–37 % (Baldwin Street, Canton Avenue), so a
steeper stretch is a fault in the file (a GPS elevation jump, points logged in one place), not a road."""
GRADE_WINDOW_M = 25.0
"""Shortest stretch over which :data:`MAX_GPX_GRADE` is checked on the raw elevation (m): long enough that ±2 m GPS
noise between points a metre apart stays under 20 %, short enough that a real cliff cannot hide. A noisier file is
checked over a longer one (:func:`grade_window_m`)."""
MAX_SEGMENT_GAP_M = 2000.0
"""Largest jump :func:`load_gpx` accepts between the end of one piece (track segment or route) and the start of the
next (m)."""

_XML_ENCODING = re.compile(rb"""^<\?xml[^>]*?encoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def _decode(data: bytes, label: str) -> str:
    """The file's text: by its byte-order mark, else its XML declaration's encoding, else UTF-8 (XML 1.0 §4.3.3)."""
    for bom, codec in (
        (codecs.BOM_UTF32_LE, "utf-32"),
        (codecs.BOM_UTF32_BE, "utf-32"),
        (codecs.BOM_UTF8, "utf-8-sig"),
        (codecs.BOM_UTF16_LE, "utf-16"),
        (codecs.BOM_UTF16_BE, "utf-16"),
    ):
        if data.startswith(bom):
            encoding = codec
            break
    else:
        declared = _XML_ENCODING.match(data[:200])
        encoding = declared.group(1).decode("ascii") if declared else "utf-8"
        try:
            codecs.lookup(encoding)
        except LookupError as error:
            raise ValueError(f"{label} declares an unknown text encoding {_checks.shown(encoding)}") from error
    try:
        text = data.decode(encoding)
    except (UnicodeDecodeError, ValueError) as error:
        raise ValueError(f"{label} is not GPX: it is not text in {encoding.upper()}") from error
    # The text is decoded now: the declaration's encoding must not be applied a second time by the XML parser.
    return re.sub(r"""^(\ufeff?<\?xml[^>]*?)\s+encoding\s*=\s*["'][^"']*["']""", r"\1", text, count=1)


_UNUSED = re.compile(
    r"<wpt(?:\s[^<>]*?)?(?:/>|>.*?</wpt\s*>)"  # waypoints: places beside the course, not on it
    r"|<bounds(?:\s[^<>]*?)?(?:/>|>[^<]*</bounds\s*>)"
    r"|<(ageofdgpsdata|course|dgpsid|fix|geoidheight|hdop|magvar|number|pdop|sat|speed|time|vdop|year)"
    r"(?:\s[^<>]*?)?(?:/>|>[^<]*</\1\s*>)",
    re.DOTALL,
)
"""What :func:`load_gpx` does not read: waypoints, the bounds, and the typed fields of a point, track or file other
than its position and elevation (time, satellites, dilution, fix, speed...). gpxpy refuses a whole file for one of
these it cannot read (``<hdop>x</hdop>``), which says nothing of the ride, so they are dropped before it parses."""
_POINT = re.compile(r"<(trkpt|rtept)(?=[\s>/])([^<>]*)>(?:(?<=/>)|(.*?)</\1\s*>)", re.DOTALL)
_ATTRIBUTE = re.compile(r"""(?<![\w:.-])(lat|lon)\s*=\s*(["'])(.*?)\2""", re.DOTALL)
_ELEVATION = re.compile(r"<ele(?:\s[^<>]*)?>([^<]*)</ele\s*>")


def _lines_kept(match: re.Match[str]) -> str:
    """Nothing in place of what :data:`_UNUSED` drops, but its line breaks: later messages name lines of the file."""
    return "\n" * match.group(0).count("\n")


def _unreadable_position(text: str) -> str | None:
    """The first track or route point whose latitude, longitude or elevation gpxpy cannot read, named as a rider
    finds it ("track point 6's elevation (<ele>) is not a number (line 9)"), or None where none is found here.
    Points are counted from 1 in the file, each kind on its own."""
    counts = {"trkpt": 0, "rtept": 0}
    for point in _POINT.finditer(text):
        counts[point.group(1)] += 1
        named = f"{'track' if point.group(1) == 'trkpt' else 'route'} point {counts[point.group(1)]}"
        attributes = {a.group(1): a.group(3) for a in _ATTRIBUTE.finditer(point.group(2))}
        for key, word in (("lat", "latitude"), ("lon", "longitude")):
            if key not in attributes:
                return f"{named} has no {word} ({key}) (line {_line(text, point.start())})"
            if not _is_number(attributes[key]):
                return f"{named}'s {word} ({key}) is not a number (line {_line(text, point.start())})"
        for elevation in _ELEVATION.finditer(text, point.start(3) if point.group(3) else point.end(), point.end()):
            if elevation.group(1).strip() and not _is_number(elevation.group(1)):
                return f"{named}'s elevation (<ele>) is not a number (line {_line(text, elevation.start())})"
    return None


def _line(text: str, index: int) -> int:
    """The line of ``text`` that character ``index`` lies on, counted from 1."""
    return text.count("\n", 0, index) + 1


def _is_number(text: str) -> bool:
    """Whether gpxpy reads ``text`` as a number (it uses Python's ``float``)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _gpx_error_words(message: str) -> str:
    """gpxpy's complaint in a rider's words, without its Python text or the value it could not read ("could not
    convert string to float: 'nan(123)'" once reached the page)."""
    if message.startswith("Invalid value for"):  # "<ele>", "<time>", or "<None>" for an attribute (lat, lon)
        tag = re.match(r"Invalid value for <(\w+)>", message)
        where = {"ele": "an elevation (<ele>)", "time": "a time (<time>)"}.get(tag.group(1) if tag else "")
        return f"{where or 'a latitude or longitude'} is not a number"
    place = re.search(r"line (\d+), column (\d+)", message)
    at = f" at line {place.group(1)}, column {place.group(2)}" if place else ""
    return f"its XML is broken{at} (a tag left open or closed twice, or the file cut short)"


def _check_values(
    label: str, kind: str, lat: NDArray[np.float64], lon: NDArray[np.float64], ele: NDArray[np.float64]
) -> None:
    """Refuse a point that is not on the map, in words a rider reads (point numbers from 1, as in the file)."""
    for values, what, low, high, unit in (
        (lat, "latitude", -90.0, 90.0, "°"),
        (lon, "longitude", -180.0, 180.0, "°"),
        (ele, "elevation", MIN_ELEVATION_M, MAX_ELEVATION_M, " m"),
    ):
        bad = ~np.isfinite(values)
        if np.any(bad):
            first = int(np.argmax(bad))
            reading = "not a number" if np.isnan(values[first]) else "infinite"
            raise ValueError(
                f"{label}: {kind} point {first + 1}'s {what} is {reading}{_checks.and_more(int(bad.sum()))}"
            )
        out = (values < low) | (values > high)
        if np.any(out):
            first = int(np.argmax(out))
            value = float(values[first])
            shown = _as_given(value)
            span = f"±{_spaced(high)}{unit}" if low == -high else f"{_spaced(low)}{unit} to {_spaced(high)}{unit}"
            raise ValueError(f"{label}: {kind} point {first + 1} has {what} {shown}{unit}, outside {span}")


@dataclasses.dataclass(frozen=True)
class _Piece:
    """One run of points the file gives: a track segment or a route."""

    kind: Literal["track", "route"]
    name: str
    """How a reader finds it in the file: "track 2, segment 1", "route 1" (numbered from 1, empty ones included)."""
    points: Sequence[gpxpy.gpx.GPXTrackPoint | gpxpy.gpx.GPXRoutePoint]


# A <trk> or <rte> start tag (not <trkpt>, <trkseg>, <rtept>), outside comments and CDATA.
_PIECE_TAG = re.compile(r"<(trk|rte)[\s>/]")
_NOT_MARKUP = re.compile(r"<!--.*?-->|<!\[CDATA\[.*?\]\]>", re.DOTALL)


def _pieces(gpx: gpxpy.gpx.GPX, text: str) -> list[_Piece]:
    """The file's non-empty track segments and routes, in the order the file gives them.

    gpxpy keeps tracks and routes in two lists, so the order of ``<trk>`` and ``<rte>`` elements is read from the
    text; where that reading does not match what gpxpy found, GPX 1.1's schema order is used (routes, then tracks).
    """
    tracks = [
        [
            _Piece("track", f"track {i + 1}" + (f", segment {j + 1}" if len(track.segments) > 1 else ""), seg.points)
            for j, seg in enumerate(track.segments)
        ]
        for i, track in enumerate(gpx.tracks)
    ]
    routes = [[_Piece("route", f"route {i + 1}", route.points)] for i, route in enumerate(gpx.routes)]
    order = _PIECE_TAG.findall(_NOT_MARKUP.sub("", text))
    if order.count("trk") == len(tracks) and order.count("rte") == len(routes):
        queues = {"trk": iter(tracks), "rte": iter(routes)}
        elements = [next(queues[tag]) for tag in order]
    else:
        elements = [*routes, *tracks]
    return [piece for element in elements for piece in element if piece.points]


def _check_gaps(label: str, pieces: Sequence[_Piece]) -> None:
    """Refuse pieces that do not follow on, however they arrive: the route would jump across the map."""
    for i in range(1, len(pieces)):
        a, b = pieces[i - 1].points[-1], pieces[i].points[0]
        gap = _great_circle_m(a.latitude, a.longitude, b.latitude, b.longitude)
        if gap > MAX_SEGMENT_GAP_M:
            raise ValueError(
                f"{label}: segment {i + 1} starts {_beyond(gap / 1000, MAX_SEGMENT_GAP_M / 1000, 1)} km from where "
                f"segment {i} ends (segment {i} is "
                f"{pieces[i - 1].name}, segment {i + 1} is {pieces[i].name}; at most "
                f"{MAX_SEGMENT_GAP_M / 1000:.0f} km is joined); load the pieces as separate files"
            )


def _great_circle_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Haversine distance (m) between two points (°)."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    a = math.sin((p2 - p1) / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lon2 - lon1) / 2) ** 2
    return 2.0 * EARTH_RADIUS_M * math.asin(math.sqrt(min(max(a, 0.0), 1.0)))


def _spaced(number: float, digits: int = 0) -> str:
    """12 345.6 style: thousands apart by a space."""
    return f"{number:,.{digits}f}".replace(",", " ")


def _as_given(value: float) -> str:
    """A number read from the file as it was written (the shortest decimal that reads back as it), in the 12 345.6
    style: a longitude of 180.0002 is refused as 180.0002°, not as "180°" against ±180°."""
    if not math.isfinite(value) or abs(value) >= 1e15:
        return f"{value:.3g}"
    whole, _, fraction = np.format_float_positional(abs(value), trim="-").partition(".")
    sign = "-" if value < 0 else ""
    return sign + f"{int(whole):,}".replace(",", " ") + (f".{fraction}" if fraction else "")


def _beyond(value: float, bound: float, decimals: int = 0) -> str:
    """``value`` in the 12 345.6 style with at least ``decimals`` decimals and two significant digits, and as many
    more as it takes to read past ``bound`` on its side: 180.0002° outside ±180° is not "180°", nor a 2 000.4 m gap
    over a 2 km bound "2.0 km", nor 0.011 m "0 m"."""
    if not math.isfinite(value) or abs(value) >= 1e15:  # past any bound by orders of magnitude: no digits to add
        return f"{value:.3g}"
    if value != 0.0:
        decimals = max(decimals, 1 - math.floor(math.log10(abs(value))))
    for digits in range(decimals, 21):
        text = f"{value:.{digits}f}"
        if float(text) != bound and (float(text) > bound) == (value > bound):
            return _spaced(value, digits)
    return repr(value)


def _mib(size_bytes: int) -> str:
    return f"{_beyond(size_bytes / 2**20, MAX_FILE_BYTES / 2**20, 1)} MiB"


def _check_length(label: str, kind: str, route: Course) -> None:
    """Refuse a route too short to ride or draw (:data:`MIN_COURSE_M`)."""
    total = route.total_distance_m
    if total < MIN_COURSE_M:
        raise ValueError(
            f"{label}: the {kind} is {_beyond(total, MIN_COURSE_M)} m long from its first point to its last; "
            f"a course needs {MIN_COURSE_M:.0f} m or more"
        )


def grade_window_m(elevation_m: NDArray[np.float64]) -> float:
    """Stretch (m) over which :func:`load_gpx` checks the raw grade of a profile of (N,) elevations (m):
    :data:`GRADE_WINDOW_M`, or :data:`NOISE_WINDOW_PER_M` times its noise (:func:`elevation_noise_m`) where that is
    longer. Phone GPS without a barometer logs a few metres of noise from point to point: σ = 3 m at 4 m spacing
    read as 62 % over 25 m, and the file was refused as a cliff.

    The cost: on a noisy file, smoothed over the same window, a step loads while its smoothed grade stays under
    50 %, about half the window (a drop inside a climb a little more: at σ = 2 m, a 64 m window, drops of 30–37 m
    loaded, ridden at −49 %); a clean file, smoothed over 50 m, refuses a step from about 12 m at 1 m spacing and
    20 m at 10 m spacing.
    """
    return max(GRADE_WINDOW_M, NOISE_WINDOW_PER_M * elevation_noise_m(elevation_m))


def _check_grades(label: str, route: Course) -> None:
    """Refuse a profile steeper than any road (:data:`MAX_GPX_GRADE`), before smoothing can hide it."""
    window = grade_window_m(route.elevation_raw_m)
    grade, first = steepest_grade(route.distance_m, route.elevation_raw_m, window)
    smoothed = float(np.max(np.abs(route.grade)))
    if max(grade, smoothed) > MAX_GPX_GRADE:
        if smoothed > grade:
            first = int(np.argmax(np.abs(route.grade)))
        at = route.distance_m[first]
        raise ValueError(
            f"{label}: the elevation changes {_beyond(100 * max(grade, smoothed), 100 * MAX_GPX_GRADE)} % of the "
            "distance near "
            f"{at / 1000:.2f} km; no road is steeper than about 40 % (the limit is "
            f"{100 * MAX_GPX_GRADE:.0f} %), so the file's elevation or positions are wrong"
        )
