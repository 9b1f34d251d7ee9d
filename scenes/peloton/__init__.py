"""The peloton scene: a line of riders with their power split by cause, and a course mode riding a real route.

Split by concern: :mod:`~scenes.peloton.model` (parameters and the pure line model), :mod:`~scenes.peloton.projection`
(slots, the tilted course frame, label layout), :mod:`~scenes.peloton.meshes` (rider meshes),
:mod:`~scenes.peloton.scene` (:class:`PelotonScene`), :mod:`~scenes.peloton.course_model` (the course mode's
parameters, ride and drawn geometry) and :mod:`~scenes.peloton.course` (:class:`CourseMode`). The names callers use
are re-exported here.
"""

from __future__ import annotations

from scenes.peloton.course import CourseMode
from scenes.peloton.course_model import (
    SAMPLE_LABEL,
    CourseParams,
    CourseState,
    compute_course,
    format_duration,
)
from scenes.peloton.model import (
    MAX_GAP_M,
    MAX_GROUP,
    MAX_RIDERS,
    POSITIONS,
    LineState,
    PelotonParams,
    compute_line,
    group_cda,
)
from scenes.peloton.projection import LABEL_PX
from scenes.peloton.scene import BAR_METRES_PER_WATT, COMPONENT_COLOURS, PelotonScene

__all__ = [
    "BAR_METRES_PER_WATT",
    "COMPONENT_COLOURS",
    "LABEL_PX",
    "MAX_GAP_M",
    "MAX_GROUP",
    "MAX_RIDERS",
    "POSITIONS",
    "SAMPLE_LABEL",
    "CourseMode",
    "CourseParams",
    "CourseState",
    "LineState",
    "PelotonParams",
    "PelotonScene",
    "compute_course",
    "compute_line",
    "format_duration",
    "group_cda",
]
