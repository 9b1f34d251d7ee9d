"""The scenes and their one registry (:mod:`server.switcher` shows one scene at a time on a viser server).

Add a scene by writing ``scenes/<name>.py`` with a :class:`~scenes._base.Scene` subclass and one line in
:data:`SCENES` (and its key in :data:`SceneName`, which the CLI offers).
"""

from __future__ import annotations

from typing import Literal

from scenes._base import Scene
from scenes.arm import ArmScene
from scenes.freekick import FreeKickScene
from scenes.peloton import PelotonScene
from scenes.sdf_gallery import SdfGalleryScene

SceneName = Literal["peloton", "arm", "sdf", "freekick"]
"""Keys of :data:`SCENES`, for the command line."""

SCENES: dict[str, type[Scene]] = {
    PelotonScene.key: PelotonScene,
    ArmScene.key: ArmScene,
    SdfGalleryScene.key: SdfGalleryScene,
    FreeKickScene.key: FreeKickScene,
}
"""Every scene that exists, in switcher order."""

__all__ = ["SCENES", "Scene", "SceneName"]
