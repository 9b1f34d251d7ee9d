"""Colour by power and its key, and the table of drag and power by row of a formation: what the flat road's group
and the course mode show alike. No viser handles."""

from __future__ import annotations

import numpy as np

from scenes._numbers import fixed

POWER_COLOURS = np.array([(40, 90, 220), (40, 180, 200), (90, 190, 80), (245, 200, 40), (225, 50, 40)], np.float64)
"""Rider colours by power, low to high: blue, teal, green, yellow, red."""
LEGEND_NAMES = ("blue", "teal", "green", "yellow", "red")
"""The colours' names: each swatch's tooltip."""
TABLE_ROWS = 14
"""A formation with more rows than this shows its first ten and its last three."""


def watts_text(value: float) -> str:
    """Whole watts, never "-0"."""
    return fixed(float(value), 0)


def coasting_words(brake_w: np.ndarray, cause: str, plural: bool = False) -> str:
    """A sentence for riders who coast (``brake_w``: (n,) watts each brakes off to hold the speed, 0 for those who
    pedal; ``cause``: what pushes them, "the slope", "the tailwind" or both, ``plural`` for both), or "" when no rider
    coasts."""
    braking = np.asarray(brake_w, np.float64)
    braking = braking[braking >= 0.5]
    if braking.size == 0:
        return ""
    low, high = watts_text(float(braking.min())), watts_text(float(braking.max()))
    amount = f"{low} W" if low == high else f"{low}–{high} W"
    if len(np.asarray(brake_w)) == 1:
        who, verb, they = "The rider", "coasts", "it brakes"
    else:
        one = braking.size == 1
        who, verb, they = riders_text(braking.size), "coasts" if one else "coast", "it brakes" if one else "they brake"
    give = "give" if plural else "gives"
    return f"{who} {verb} at 0 W: {cause} {give} more than this speed takes, and {they} off {amount} to hold it."


def power_range(watts: np.ndarray) -> tuple[float, float]:
    """(low, high) ends of the colour scale (W): the group's least and most power, at least 10 W apart, and never
    below 0 W where no rider is below it (a scale of pedal power that read "-4 W")."""
    low, high = float(np.min(watts)), float(np.max(watts))
    middle = 0.5 * (low + high)
    half = max(0.5 * (high - low), 5.0)
    if low >= 0.0 and middle - half < 0.0:
        return 0.0, 2.0 * half
    return middle - half, middle + half


def power_colours(watts: np.ndarray, low: float, high: float) -> np.ndarray:
    """(N, 3) uint8 colours of ``watts`` on :data:`POWER_COLOURS` from ``low`` to ``high`` W."""
    t = np.clip((np.asarray(watts, np.float64) - low) / (high - low), 0.0, 1.0) * (len(POWER_COLOURS) - 1)
    stops = np.arange(len(POWER_COLOURS), dtype=np.float64)
    channels = [np.interp(t, stops, POWER_COLOURS[:, c]) for c in range(3)]
    return np.round(np.stack(channels, axis=1)).astype(np.uint8)


def riders_text(n: int) -> str:
    """ "1 rider", "8 riders"."""
    return f"{n} rider" if n == 1 else f"{n} riders"


def legend_html(watts: np.ndarray, summary: str, title: str = "Rider colour = power (W)") -> str:
    """The colour scale of ``watts`` (:func:`power_range`) as five swatches, each over its watts on one line (its
    colour's name in a tooltip), under ``title``, then ``summary`` (plain text). Where every rider rides at the same
    power (a group of one), one swatch with that power: no scale to read."""
    values = np.asarray(watts, np.float64).reshape(-1)
    low, high = power_range(values)
    if float(values.max() - values.min()) < 0.5:
        ((r, g, b),) = power_colours(values[:1], low, high).astype(np.float64)
        every = " (every rider)" if len(values) > 1 else ""
        swatches = (
            '<div style="flex:1;min-width:0;white-space:nowrap">'
            f'<div style="height:14px;border-radius:2px;background:rgb({r:.0f},{g:.0f},{b:.0f})"></div>'
            f"{watts_text(values[0])} W{every}</div>"
        )
    else:
        swatches = "".join(
            f'<div title="{name}" style="flex:1;min-width:0;text-align:center;white-space:nowrap">'
            f'<div style="height:14px;border-radius:2px;background:rgb({r:.0f},{g:.0f},{b:.0f})"></div>'
            f"{watts_text(t)} W</div>"
            for name, t, (r, g, b) in zip(LEGEND_NAMES, np.linspace(low, high, 5), POWER_COLOURS, strict=True)
        )
    return (
        '<div style="font-size:13px;line-height:1.35;padding:2px 0 6px">'
        f"<b>{title}</b>"
        f'<div style="display:flex;gap:3px;margin:3px 0">{swatches}</div>{summary}</div>'
    )


def formation_table(positions: np.ndarray, drag: np.ndarray, columns: dict[str, np.ndarray], summary: str) -> str:
    """``summary``, then a markdown table of a formation by row (riders level with each other share a row), front to
    back: each row's number, its riders, their drag (%, of the same rider alone) and, per ``columns`` (header → (n,)
    watts), their watts (a range where they differ); a formation of more than :data:`TABLE_ROWS` rows shows its
    first ten and last three.

    Args:
        positions: (n, 2) where each rider rides (m ahead of the leader, m to its left), leader first.
        drag: (n,) each rider's drag as a fraction of the same rider alone.
        columns: header → (n,) watts of each rider.
        summary: markdown above the table.
    """
    x = np.round(np.asarray(positions, np.float64)[:, 0], 6)
    rows = [np.flatnonzero(x == value) for value in sorted(set(x.tolist()), reverse=True)]
    lines = [
        summary,
        "",
        "| Row | Riders | Drag (%) | " + " | ".join(columns) + " |",
        "|---|---|---|" + "---|" * len(columns),
    ]
    shown = rows if len(rows) <= TABLE_ROWS else [*rows[:10], None, *rows[-3:]]
    for index, members in enumerate(shown):
        if members is None:
            lines.append("| … | | |" + " |" * len(columns))
            continue
        number = index + 1 if index < 10 or len(rows) <= TABLE_ROWS else len(rows) - (len(shown) - index) + 1
        d = 100 * np.asarray(drag)[members]
        drag_text = f"{d.min():.0f}" if round(d.min()) == round(d.max()) else f"{d.min():.0f}–{d.max():.0f}"
        cells = []
        for values in columns.values():
            w = np.asarray(values)[members]
            low, high = watts_text(float(w.min())), watts_text(float(w.max()))
            cells.append(f"**{low}**" if low == high else f"**{low}–{high}**")
        lines.append(f"| {number} | {len(members)} | {drag_text} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
