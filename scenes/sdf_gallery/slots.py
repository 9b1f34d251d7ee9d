"""The gallery's four primitive slots in the GUI and the 3D view: each slot's folder of controls, built from the
declarations on :class:`~scenes.sdf_gallery.params.PrimitiveParams`, and its gizmo with a marker ball and a name.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import viser

from scenes._controls import Controls, build_controls, declared
from scenes.sdf_gallery.params import GIZMO_MARKER_RADIUS_M, PrimitiveParams, gizmo_label, gizmo_reach, gizmo_tips


def build_slot_controls(gui: Any, index: int, slot: PrimitiveParams) -> Controls[PrimitiveParams]:
    """The controls of primitive slot ``index`` (from 0) in its own closed folder, from PrimitiveParams'
    declarations, labelled with the slot's number ("P2 size b (m)"); the first slot has no "on" checkbox (it is
    always on) and its "combine" is greyed out (nothing comes before it)."""
    n = index + 1
    names = [name for name in declared(PrimitiveParams) if not (name == "enabled" and index == 0)]
    folder = str(declared(PrimitiveParams)["kind"].folder).format(slot=n)
    controls = build_controls(gui, slot, names, collapsed=(folder,), label_args={"slot": n})
    if index == 0:
        controls["op"].disabled = True
    return controls


def add_slot_gizmo(
    scene: Any, name: str, index: int, slot: PrimitiveParams, *, rings: bool = False
) -> tuple[viser.TransformControlsHandle, viser.IcosphereHandle, viser.LabelHandle]:
    """Add the gizmo of slot ``index`` (from 0) at node ``name``, with its marker ball and label; its rotation rings
    only when ``rings``."""
    reach = gizmo_reach(slot)
    marker_at, label_at = gizmo_tips(reach)
    gizmo = scene.add_transform_controls(
        name,
        scale=reach,
        line_width=2.0,
        disable_sliders=True,  # the plane handles of four gizmos cluttered the middle
        disable_rotations=not rings,  # so did twelve rotation rings: shown on request ("Rotation rings on the gizmos")
        # Drawn over the mesh: a gizmo sits at its primitive's centre, inside the surface. Each is sized to its own
        # primitive (its arrows just poke out of it), so the four do not pile up in the middle.
        depth_test=False,
        position=slot.position,
        wxyz=slot.wxyz,
        visible=slot.enabled,
    )
    # A ball in the primitive's colour at the tip of its local z arrow, and its name: which gizmo moves which
    # primitive, at a glance.
    marker = scene.add_icosphere(
        f"{gizmo.name}/marker",
        radius=GIZMO_MARKER_RADIUS_M,
        color=slot.color,
        subdivisions=2,
        position=marker_at,
        cast_shadow=False,
        receive_shadow=False,
    )
    label = scene.add_label(f"{gizmo.name}/label", gizmo_label(index, slot), position=label_at)
    return gizmo, marker, label


def update_gizmo_looks(
    gizmo: viser.TransformControlsHandle,
    marker: viser.IcosphereHandle,
    label: viser.LabelHandle,
    index: int,
    slot: PrimitiveParams,
) -> None:
    """Make a slot's gizmo size, marker colour and label follow its primitive's kind, size and colour (each
    written only when it changed)."""
    reach = gizmo_reach(slot)
    if abs(gizmo.scale - reach) > 1e-6:
        gizmo.scale = reach
        marker.position, label.position = gizmo_tips(reach)
    if tuple(int(c) for c in marker.color) != slot.color:
        marker.color = slot.color
    text = gizmo_label(index, slot)
    if label.text != text:
        label.text = text


def read_wxyz(gizmo: Any, last_good: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """A gizmo's orientation, normalised; ``last_good`` (put back on the gizmo) if it is not a usable quaternion."""
    try:
        q = np.asarray(gizmo.wxyz, dtype=np.float64).reshape(4)
    except (TypeError, ValueError):
        q = np.full(4, np.nan)
    norm = float(np.linalg.norm(q)) if np.all(np.isfinite(q)) else 0.0
    if norm < 1e-6:
        gizmo.wxyz = last_good
        return last_good
    q = q / norm
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
