"""Write the bundled sample route, kernels/routes/alpe_dhuez.gpx, from Alpe d'Huez's published climb profile.

python scripts/make_sample_route.py

The profile: 13.2 km from Le Bourg-d'Oisans (744 m) to the resort (1815 m), 1071 m up at 8.1 % on average, as the
climb guides publish it (Road Cycling UK's "five must-ride climbs of the Alps"; Epic Cols), with the section grades
they describe: about 10 % for the first 2.5 km to La Garde (near 1000 m), 8 % for the next kilometre, 10 % for one
more, 8–9 % to Huez (about 1400 m), then easing to under 6 % over the last two bends. Section grades are our
reading of those descriptions, chosen to meet the published start, summit and length exactly. The road's plan
shape (22 legs joined by 21 hairpins of 15 m radius, climbing east from 45.056° N, 6.030° E) is schematic, not the
real road's map.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from kernels.course import SAMPLE_ROUTE  # noqa: E402

SECTIONS_KM_GRADE = [(2.5, 0.102), (1.0, 0.080), (1.0, 0.100), (2.6, 0.085), (4.1, 0.075), (2.0, 0.054)]
START_ELEVATION_M = 744.0
START_LAT, START_LON = 45.0560, 6.0300
DESCRIPTION = (
    "Sample route rebuilt from Alpe d'Huez's published climb profile: 13.2 km, 744 m to 1815 m, 8.1 % average "
    "(Road Cycling UK; Epic Cols), section grades read from the guides' descriptions. The plan shape (21 hairpins) "
    "is schematic, not the real road."
)
"""The route's description in the GPX file."""
LEGS, HAIRPIN_RADIUS_M, STEP_M = 22, 15.0, 20.0


def plan(total_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(east, north, distance) every STEP_M metres along 22 straight legs alternating 20° and 160° joined by
    hairpins."""
    turn = math.radians(140.0)
    arc = HAIRPIN_RADIUS_M * turn
    leg = (total_m - (LEGS - 1) * arc) / LEGS
    s = np.arange(0.0, total_m + 1e-9, 1.0)
    heading = np.empty_like(s)
    period = leg + arc
    for i, si in enumerate(s):
        k, into = divmod(si, period)
        base = math.radians(20.0) if int(k) % 2 == 0 else math.radians(160.0)
        sign = 1.0 if int(k) % 2 == 0 else -1.0
        heading[i] = base if into <= leg else base + sign * (into - leg) / HAIRPIN_RADIUS_M
    east = np.concatenate(([0.0], np.cumsum(np.sin(heading[:-1]))))
    north = np.concatenate(([0.0], np.cumsum(np.cos(heading[:-1]))))
    keep = np.concatenate((np.arange(0, s.shape[0] - 1, int(STEP_M)), [s.shape[0] - 1]))
    return east[keep], north[keep], s[keep]


def main() -> None:
    total_m = 1000.0 * sum(km for km, _ in SECTIONS_KM_GRADE)
    east, north, s = plan(total_m)
    edges = np.concatenate(([0.0], np.cumsum([1000.0 * km for km, _ in SECTIONS_KM_GRADE])))
    rises = np.concatenate(([0.0], np.cumsum([1000.0 * km * g for km, g in SECTIONS_KM_GRADE])))
    elevation = START_ELEVATION_M + np.interp(s, edges, rises)
    lat = START_LAT + np.degrees(north / 6_371_008.8)
    lon = START_LON + np.degrees(east / (6_371_008.8 * math.cos(math.radians(START_LAT))))
    rows = "\n".join(
        f'      <trkpt lat="{a:.7f}" lon="{o:.7f}"><ele>{z:.1f}</ele></trkpt>'
        for a, o, z in zip(lat, lon, elevation, strict=True)
    )
    text = f"""<?xml version="1.0" encoding="UTF-8"?>
<gpx version="1.1" creator="viser-physics-scenes scripts/make_sample_route.py" xmlns="http://www.topografix.com/GPX/1/1">
  <metadata>
    <name>Alpe d'Huez (sample, from the published profile)</name>
    <desc>{DESCRIPTION}</desc>
  </metadata>
  <trk>
    <name>Alpe d'Huez (sample, from the published profile)</name>
    <trkseg>
{rows}
    </trkseg>
  </trk>
</gpx>
"""
    SAMPLE_ROUTE.parent.mkdir(parents=True, exist_ok=True)
    SAMPLE_ROUTE.write_text(text, encoding="utf-8")
    print(f"wrote {SAMPLE_ROUTE} ({len(text) / 1024:.0f} KiB, {s.shape[0]} points)")


if __name__ == "__main__":
    main()
