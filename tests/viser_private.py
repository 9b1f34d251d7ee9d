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
