"""Everything that adapts viser to this app, apart from the scenes: the gate on browser messages, sessions per tab,
the scene switcher, the process's callback turns, and the one module that reaches into viser's internals.

- :mod:`server.decode`: a browser frame into a viser message, and the checks on its fields;
- :mod:`server.clean`: each control's recorded spec, and cleaning a browser's value against it;
- :mod:`server.budget`: the per-tab costly-input budget and the uploads-in-flight bookkeeping;
- :mod:`server.refusals`: the rate-limited log of what the gate refuses;
- :mod:`server.gate`: the gate in front of a server's dispatch (:func:`server.gate.install_gate`);
- :mod:`server.sessions`: a session per browser tab (or one shared), its GUI facade and camera hub;
- :mod:`server.switcher`: the dropdown that shows one scene at a time on a session;
- :mod:`server.turns`: the process-wide turn every scene callback takes;
- :mod:`server.memory`: handing a closed session's memory back to the system;
- :mod:`server.viser_compat`: the only module touching viser's private state.

Importing the package installs the one change to viser's Python side, a faster property cast
(:func:`server.viser_compat.patch_property_cast`): the scenes import the package, so it is in place before any scene
writes a property.
"""

from __future__ import annotations

from server import viser_compat

viser_compat.patch_property_cast()
