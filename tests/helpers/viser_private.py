"""Every access to viser 1.1.1's private state, in one place (viser is pinned exactly for this reason).

Tests use these to prove that a scene leaves nothing behind: viser has no public list of node names or GUI elements.
"""

from __future__ import annotations

import viser


def node_names(server: viser.ViserServer) -> set[str]:
    """Names of every scene node the server currently holds."""
    return set(server.scene._handle_from_node_name)


def gui_uuids(server: viser.ViserServer) -> set[str]:
    """UUIDs of every GUI element (inputs and containers) reachable from the server's root panel."""
    gui = server.gui
    found: set[str] = set()
    stack = [gui._resolve_container_handle("root")]
    while stack:
        container = stack.pop()
        for uuid, child in list(getattr(container, "_children", {}).items()):
            found.add(uuid)
            stack.append(child)
    found.update(gui._gui_input_handle_from_uuid)
    found.update(gui._container_handle_from_uuid.keys() - {"root"})
    return found


def gui_uuid(handle: object) -> str:
    """The uuid a browser uses to address ``handle`` in GuiUpdateMessage."""
    return handle._impl.uuid  # type: ignore[attr-defined]


def gui_inputs(api: viser.GuiApi) -> dict[str, object]:
    """Every GUI input handle of ``api`` (the server's or a client's GUI), by uuid."""
    return dict(api._gui_input_handle_from_uuid)


def gizmos(api: viser.SceneApi) -> dict[str, viser.TransformControlsHandle]:
    """Every transform-controls handle of ``api`` (the server's or a client's scene), by node name."""
    return dict(api._handle_from_transform_controls_name)


def store_value(handle: object, value: object) -> None:
    """Store ``value`` on GUI ``handle`` as viser does on a browser's update, before it runs the callbacks (none
    run here)."""
    handle._impl.value = value  # type: ignore[attr-defined]


def control_state(handle: object) -> dict[str, object]:
    """What a browser must not be able to change about a control: its props, callbacks and liveness."""
    impl = handle._impl  # type: ignore[attr-defined]
    return {"props": repr(impl.props), "callbacks": len(impl.update_cb), "removed": impl.removed}


def dropdowns(server: viser.ViserServer) -> dict[str, tuple[str, ...]]:
    """Every dropdown the server holds: its label and its options."""
    handles = server.gui._gui_input_handle_from_uuid.values()
    return {handle.label: tuple(handle.options) for handle in handles if isinstance(handle, viser.GuiDropdownHandle)}
