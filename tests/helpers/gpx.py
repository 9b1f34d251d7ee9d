"""GPX files written for the tests: good ones from points, a hill, and bad ones with the message each must get."""

from __future__ import annotations

import math
from collections.abc import Sequence


def gpx_text(points: Sequence[tuple[float, float, float | None]], *, kind: str = "trk") -> str:
    def row(lat: float, lon: float, ele: float | None) -> str:
        tag = "trkpt" if kind == "trk" else "rtept"
        inner = "" if ele is None else f"<ele>{ele}</ele>"
        return f'<{tag} lat="{lat}" lon="{lon}">{inner}</{tag}>'

    body = "".join(row(*p) for p in points)
    if kind == "trk":
        body = f"<trk><name>t</name><trkseg>{body}</trkseg></trk>"
    else:
        body = f"<rte>{body}</rte>"
    return f'<?xml version="1.0"?><gpx version="1.1" creator="test">{body}</gpx>'


def line_points(n: int, step_deg: float = 1e-4) -> list[tuple[float, float, float | None]]:
    return [(45.0 + i * step_deg, 6.0, 100.0 + i) for i in range(n)]


def hill_gpx(name: str = "Test hill", n: int = 300) -> bytes:
    points = [(45.0 + i * 1e-4, 6.0 + i * 5e-5, 200.0 + 40.0 * math.sin(i / 40.0)) for i in range(n)]
    return gpx_text(points).replace("<name>t</name>", f"<name>{name}</name>").encode()


BAD_FILES = {
    "plain text": ("hello, I am not a GPX file", "not (a )?GPX"),
    "html": ("<html><body>hi</body></html>", "is not GPX"),
    "broken xml": ('<?xml version="1.0"?><gpx><trk><trkseg><trkpt lat="1"', "its XML is broken at line 1, column 39"),
    "kml": ('<?xml version="1.0"?><kml><Document/></kml>', "is not GPX"),
    "no track points": ('<?xml version="1.0"?><gpx version="1.1"><wpt lat="1" lon="2"/></gpx>', "no track points"),
    "empty segment": (gpx_text([]), "no track points"),
    "one point": (gpx_text(line_points(1)), "only one"),
    "one place": (gpx_text([(45.0, 6.0, 10.0)] * 5), "one place"),
    "no elevation": (gpx_text([(45.0 + i * 1e-4, 6.0, None) for i in range(5)]), "no elevation"),
    "some elevation missing": (gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, None), (45.002, 6.0, 3.0)]), "1 of 3"),
    "nan latitude": (gpx_text([(45.0, 6.0, 1.0), (float("nan"), 6.0, 2.0)]), "point 2's latitude is not a number"),
    "inf elevation": (gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, float("inf"))]), "point 2's elevation is infinite"),
    "latitude out of range": (gpx_text([(45.0, 6.0, 1.0), (95.0, 6.0, 2.0)]), "latitude"),
    # gpxpy's refusals named no point ("a latitude or longitude is not a number"), and a missing latitude read as
    # broken XML: each now names the point and its line.
    "bad number": (
        gpx_text([(45.0, 6.0, 1.0)]).replace('lat="45.0"', 'lat="abc"'),
        r"^the file: track point 1's latitude \(lat\) is not a number \(line 1\)$",
    ),
    "no longitude": (
        gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, 2.0)], kind="rte").replace('lat="45.001" lon="6.0"', 'lat="45.001"'),
        r"^the file: route point 2 has no longitude \(lon\) \(line 1\)$",
    ),
    # An outside tester: gpxpy's "could not convert string to float: 'nan(123)'" reached the page.
    "unreadable elevation": (
        gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, 2.0)]).replace("<ele>2.0</ele>", "<ele>nan(123)</ele>"),
        r"^the file: track point 2's elevation \(<ele>\) is not a number \(line 1\)$",
    ),
    # An outside tester: a "billion laughs" file read as an elevation that is not a number, an outside entity (XXE)
    # as broken XML. Neither is expanded; both are refused for what they are.
    "entities": (
        gpx_text(line_points(3))
        .replace('<?xml version="1.0"?>', '<?xml version="1.0"?><!DOCTYPE g [<!ENTITY a "1"><!ENTITY b "&a;&a;">]>')
        .replace("<ele>101</ele>", "<ele>&b;</ele>"),
        r"^the file uses XML entities \(<!ENTITY>\), which a GPX file does not need; they are not read$",
    ),
    "outside entity": (
        gpx_text(line_points(3))
        .replace('<?xml version="1.0"?>', '<?xml version="1.0"?><!DOCTYPE g [<!ENTITY x SYSTEM "file:///etc/passwd">]>')
        .replace("<name>t</name>", "<name>&x;</name>"),
        r"^the file uses XML entities",
    ),
    "elevation absurd": (gpx_text([(45.0, 6.0, 1.0), (45.001, 6.0, 1e7)]), "elevation"),
    "too short": (gpx_text([(45.0, 6.0, 10.0), (45.0000001, 6.0, 10.0)]), "100 m or more"),
}
