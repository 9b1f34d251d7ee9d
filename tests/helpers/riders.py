"""Hypothesis strategies for the rider quantities the cycling tests draw, in the kernel's SI units: the same
plausible ranges everywhere a test asks for "any rider"."""

from __future__ import annotations

from hypothesis import strategies as st

cda_m2 = st.floats(0.1, 0.8)
"""Drag area of a rider on a bike, from a small time-trial tuck to an upright touring rider in a coat (m²)."""
mass_kg = st.floats(40.0, 150.0)
"""Mass of rider and bike (kg)."""
crr = st.floats(0.0, 0.02)
"""Rolling-resistance coefficient, from none to a soft gravel road."""
