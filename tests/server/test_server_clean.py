"""Recorded control specs (:mod:`server.clean`) live beside viser's handles, not on them: an explicit spec wins over
the handle's own, a handle made without one is read on first use, and a freed handle's spec is never another's."""

from __future__ import annotations

import viser

from server.clean import ControlSpec, control_spec, mark_costly, record_spec


class Plain:
    """Any object: what is not a viser input is a "display" control, which no browser may set."""


def test_an_explicit_spec_is_the_one_recorded_and_marking_costly_keeps_it() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        slider = server.gui.add_slider("Speed (km/h)", min=0.0, max=80.0, step=0.5, initial_value=40.0)
        declared = ControlSpec("number", lo=10.0, hi=60.0)
        assert record_spec(slider, declared) is declared
        slider.max = 1e9  # a later change of the handle's props is not what the scene declared
        assert control_spec(slider) == declared
        assert mark_costly(slider) is slider
        assert control_spec(slider) == ControlSpec("number", lo=10.0, hi=60.0, costly=True)
        unrecorded = server.gui.add_slider("Power (W)", min=0.0, max=500.0, step=1.0, initial_value=200)
        spec = control_spec(unrecorded)  # read from the handle as created
        assert (spec.kind, spec.lo, spec.hi, spec.costly) == ("number", 0.0, 500.0, False)
    finally:
        server.stop()


def test_a_freed_handles_spec_is_not_given_to_an_object_that_reuses_its_id() -> None:
    for _ in range(64):
        freed = Plain()
        record_spec(freed, ControlSpec("choice", options=("a",)))
        del freed  # freed at once (no cycle): a new object may reuse its id, and must not inherit its spec
        assert control_spec(Plain()) == ControlSpec("display")
