"""The peloton scene: a line of riders with their power split by cause, and a course mode riding a real route.

Split by concern: :mod:`~scenes.peloton.model` (parameters and the pure line model), :mod:`~scenes.peloton.projection`
(slots, the tilted course frame, label layout), :mod:`~scenes.peloton.meshes` (rider meshes),
:mod:`~scenes.peloton.scene` (:class:`PelotonScene`), :mod:`~scenes.peloton.course_model` (the course mode's
parameters, ride and drawn geometry) and :mod:`~scenes.peloton.course` (:class:`CourseMode`).

The package exports the scene and its parameters; everything else is imported from the module it lives in.
"""

from __future__ import annotations

from scenes.peloton.model import PelotonParams
from scenes.peloton.scene import PelotonScene

__all__ = ["PelotonParams", "PelotonScene"]
