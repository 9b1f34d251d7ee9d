"""Bicycle power: aerodynamic, rolling and climbing terms, its inverse, drafting in a paceline and in formations, and
the air.

All quantities are SI: speed and wind in m/s, CdA in m², mass in kg, power in W, altitude in m. Grade is rise over
run (0.05 is 5 %), so the road angle is θ = atan(grade). Every function accepts numpy arrays and broadcasts them.

Model (the textbook one, with wind made sign-correct):

    P_aero  = ½·ρ·CdA·(v + w)·|v + w|·v        w = headwind (negative for a tailwind)
    P_roll  = Crr·m·g·cos θ·v
    P_climb = m·g·sin θ·v
    P_total = (P_aero + P_roll + P_climb) / η   η = drivetrain efficiency (when the sum is positive)
    ρ(h)    = 1.225·exp(−h / 8500)

The absolute value matters: a tailwind faster than the rider pushes instead of dragging. Assumptions: steady speed
(no kinetic-energy change), no wheel-bearing or wheel-rotation losses (Martin et al. 1998 add them; they are a few
watts), yaw-free CdA.

Drafting, two models:

* ``"textbook"``: every follower gets ``CdA·(1 − 0.27·exp(−gap/3.5))``, a simple exponential fade: 27.0 %, 6.5 % and
  1.6 % less drag at 0, 5 and 10 m, whatever the place in the line.
* ``"measured"``: position-dependent drag reductions fitted to published measurements::

      reduction(position k ≥ 2, gap g) = R_k · exp(−g / 9.7 m)
      R_2 = 0.40, R_3 = 0.48, R_k≥4 = 0.50           (close-gap plateau of a tight line)
      reduction(leader, gap g) = 0.03 · exp(−g / 1.5 m)   (only when someone follows)

  The close-gap plateaus follow the 4-rider team-pursuit line of Barry et al. 2015 and Fitton et al. 2018 (2nd
  42–45 %, 3rd 48–55 %, 4th 47–57 %) and Broker, Kyle & Burke 1999 (riders 3–4 need less than rider 2). The fade
  length 9.7 m is fitted to Swiss Side's CFD (36 % at 0.1 m, 13 % at 10 m behind one rider). The leader's gain
  follows Blocken et al. 2013 (0.8–2.6 %) and Swiss Side (~4 % at 0.1 m, gone by 5 m). Riders further back save
  more than the second, the leader saves a little, and every saving fades with the gap.

Formations (:func:`formation`, :func:`formation_drag`, :func:`formation_power`): riders laid out in two dimensions
(single file, a two-abreast paceline, a bunch, an echelon) and a wake model of each rider's drag from the offsets of
the riders around it, which is the line model above in single file and is fitted to Blocken et al. 2018's 121-rider
peloton (J. Wind Eng. Ind. Aerodyn. 179:319). Plain numpy over the (N, N) offsets: about 0.7 ms for 121 riders.

Modules: :mod:`~kernels.cycling.power_law` (the power law, its inverse, single-file drafting and the domains),
:mod:`~kernels.cycling.air` (the exponential atmosphere, moist air from a weather reading, the standard atmosphere),
:mod:`~kernels.cycling.martin` (Martin et al. 1998's full model), :mod:`~kernels.cycling.formations` (formations and
their wake model). Everything public is importable from here.
"""

from __future__ import annotations

from kernels.cycling.air import (
    AIR_DENSITY_ALTITUDE_M,
    ISA_ALTITUDE_M,
    ISA_LAPSE_RATE_K_PER_M,
    ISA_SEA_LEVEL_PRESSURE_HPA,
    ISA_SEA_LEVEL_TEMPERATURE_C,
    R_DRY_AIR,
    R_WATER_VAPOUR,
    RHO_SEA_LEVEL,
    SCALE_HEIGHT_M,
    air_density,
    air_density_weather,
    isa_pressure_hpa,
    isa_temperature_c,
    saturation_vapour_pressure_hpa,
)
from kernels.cycling.formations import (
    BIKE_LENGTH_M,
    BUNCH_FADE_M,
    BUNCH_OFFSET_M,
    BUNCH_PUSH,
    BUNCH_SHELTER,
    BUNCH_WIDTH,
    ECHELON_WIDTH,
    FORMATION_SHAPES,
    WAKE_WIDTH_M,
    FormationShape,
    apparent_yaw,
    formation,
    formation_drag,
    formation_power,
)
from kernels.cycling.martin import MARTIN_BEARING_W, MARTIN_DOMAIN, MartinPower, martin_power
from kernels.cycling.power_law import (
    DRAFT_MODELS,
    MAX_FORMATION_RIDERS,
    MODEL_DOMAIN,
    SPEED_FOR_POWER_DOMAIN,
    DraftModel,
    G,
    Power,
    draft_factor,
    drag_reduction,
    paceline,
    power,
    road_forces,
    speed_for_power,
    wheel_power_terms,
    wheel_power_terms_compiled,
)

__all__ = [
    "AIR_DENSITY_ALTITUDE_M",
    "BIKE_LENGTH_M",
    "BUNCH_FADE_M",
    "BUNCH_OFFSET_M",
    "BUNCH_PUSH",
    "BUNCH_SHELTER",
    "BUNCH_WIDTH",
    "DRAFT_MODELS",
    "ECHELON_WIDTH",
    "FORMATION_SHAPES",
    "ISA_ALTITUDE_M",
    "ISA_LAPSE_RATE_K_PER_M",
    "ISA_SEA_LEVEL_PRESSURE_HPA",
    "ISA_SEA_LEVEL_TEMPERATURE_C",
    "MARTIN_BEARING_W",
    "MARTIN_DOMAIN",
    "MAX_FORMATION_RIDERS",
    "MODEL_DOMAIN",
    "RHO_SEA_LEVEL",
    "R_DRY_AIR",
    "R_WATER_VAPOUR",
    "SCALE_HEIGHT_M",
    "SPEED_FOR_POWER_DOMAIN",
    "WAKE_WIDTH_M",
    "DraftModel",
    "FormationShape",
    "G",
    "MartinPower",
    "Power",
    "air_density",
    "air_density_weather",
    "apparent_yaw",
    "draft_factor",
    "drag_reduction",
    "formation",
    "formation_drag",
    "formation_power",
    "isa_pressure_hpa",
    "isa_temperature_c",
    "martin_power",
    "paceline",
    "power",
    "road_forces",
    "saturation_vapour_pressure_hpa",
    "speed_for_power",
    "wheel_power_terms",
    "wheel_power_terms_compiled",
]
