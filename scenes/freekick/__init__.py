"""Free kick: a spinning ball's 3D flight over a wall, with its forces, a no-spin ghost, a ±10 % spin band and the
knuckleball.

- :mod:`~scenes.freekick.model`: the parameters (each one's control declared on it), presets and the pure functions
  from parameters to a kick state, the outcome map and the aim search (no viser).
- :mod:`~scenes.freekick.odds`: the strike's odds over a player's scatter and the goal-chance map over the pitch,
  with their colours and words (no viser).
- :mod:`~scenes.freekick.views`: where each view puts its camera.
- :mod:`~scenes.freekick.props`: goal, net, pitch markings, defender and arrow geometry, and the colours.
- :mod:`~scenes.freekick.scene`: :class:`FreeKickScene`, which draws it all on viser.

The package exports the scene and its parameters; everything else is imported from the module it lives in.
"""

from __future__ import annotations

from scenes.freekick.model import FreeKickParams
from scenes.freekick.scene import FreeKickScene

__all__ = ["FreeKickParams", "FreeKickScene"]
