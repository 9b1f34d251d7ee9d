"""Kick a ball: :func:`simulate` one flight, :func:`simulate_batch` many, judge them against the wall and the goal.

Python around the compiled cores of :mod:`kernels.ball.core`: it validates (``ValueError`` naming the argument),
packs arrays and returns frozen dataclasses: :class:`Trajectory` ((N,) times, (N, 3) positions, velocities and forces
in m, m/s and N), :class:`BatchTrajectory` ((K, T) and (K, T, 3)), :class:`Outcome` and :class:`BatchOutcome`.
:func:`warm_up` compiles (or loads) every core. Frame, units, model and sources: :mod:`kernels.ball`.
"""

from __future__ import annotations

import dataclasses
import decimal
import functools
import math
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
from kernels._rows import run_rows
from kernels.ball import core, play
from kernels.ball.config import (
    BALL_RADIUS_M,
    DT,
    GROUND,
    MAX_STEPS,
    MEASURED,
    N_STEPS,
    RADIUS,
    RK4,
    T_MAX,
    FlightConfig,
    Q,
    check_launches,
    checked_seed,
    checked_vector,
    fast_floats,
    flight_config,
    kick_rows,
    launch_rows,
)
from kernels.ball.core import ENDINGS, RESULTS, Ending, Result
from kernels.ball.laws import bounce, coefficients
from kernels.ball.pitch import Keeper, Panel, Pitch, free_kick_panels, keeper_slots, panel_rows, pitch_vector
from kernels.warming import Entry

# The compiled cores called from here: plain Python while the app's first start compiles them (kernels.warming).
fly_and_judge_rows = Entry(core.fly_and_judge_rows)
fly_rows = Entry(core.fly_rows)
judge = Entry(core.judge)
judge_rows = Entry(core.judge_rows)
pad = Entry(core.pad)
simulate_one = Entry(core.simulate_one)
stable_step = Entry(core.stable_step)
play_rows = Entry(play.play_rows)
keeper_path_core = Entry(play.keeper_path)

EVENT_KINDS: tuple[str, ...] = ("ground", "post", "bar", "wall", "keeper", "net")
"""Kinds of :class:`Event`, in the compiled flight's code order."""

RESERVE_BYTES = 2**31
"""Largest time-major reservation :func:`simulate_batch` makes before it counts the samples first (bytes)."""
MAX_KICKS = 1_000_000
"""Most kicks one batch call flies (:func:`simulate_batch`, :func:`simulate_outcomes`), as many as the odds' strikes."""
MAX_BATCH_BYTES = 2**32
"""Most memory a batch's trajectories may take (bytes): :func:`simulate_batch` refuses more, naming ``positions``."""


@dataclasses.dataclass(frozen=True)
class Event:
    """A contact on the pitch."""

    t: float
    """Time since the kick (s)."""
    kind: str
    """``"ground"``, ``"post"``, ``"bar"``, ``"wall"`` (a player), ``"keeper"`` or ``"net"``."""
    position: tuple[float, float, float]
    """Ball centre at the contact (m)."""


@dataclasses.dataclass(frozen=True)
class KeeperDive:
    """When the keeper set off and where he went (a flight on a pitch with a keeper)."""

    t: float
    """Start of the dive (s since the kick)."""
    target: tuple[float, float, float]
    """Where he read the ball would cross the goal line (m)."""


def _events(rows: NDArray[np.float64], count: int) -> tuple[Event, ...]:
    return tuple(
        Event(float(row[0]), EVENT_KINDS[int(row[1])], (float(row[2]), float(row[3]), float(row[4])))
        for row in rows[:count]
    )


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """One flight sampled every ``dt``; the last sample is the interpolated end (ground contact or ``x_stop``)."""

    t: NDArray[np.float64]
    """(N,) time since the kick (s)."""
    position: NDArray[np.float64]
    """(N, 3) ball centre (m)."""
    velocity: NDArray[np.float64]
    """(N, 3) ball velocity (m/s)."""
    drag: NDArray[np.float64]
    """(N, 3) drag force (N)."""
    magnus: NDArray[np.float64]
    """(N, 3) Magnus force (N)."""
    gravity: NDArray[np.float64]
    """(N, 3) weight (N)."""
    knuckle: NDArray[np.float64]
    """(N, 3) knuckleball side force (N); zero unless ``knuckle_seed`` was set and the spin is near zero."""
    ended: Ending
    """Why the flight stopped: it touched the ground (no pitch), passed ``x_stop``, or reached ``t_max``; on a
    pitch also ``"stopped"`` (at rest on the turf), ``"net"``, ``"out"`` (left the pitch), ``"saved"`` or
    ``"contacts"`` (its 64th contact, :data:`kernels.ball.play.MAX_EVENTS`: a surface that returns nearly all the
    ball's energy)."""
    events: tuple[Event, ...] = ()
    """On a pitch: the contacts in order (ground, post, bar, wall, keeper, net); empty without one."""
    spin: NDArray[np.float64] | None = None
    """On a pitch: (N, 3) the angular velocity at each sample (rad/s), changed by each contact; None without one."""
    result: Result | None = None
    """On a pitch: the verdict (as :class:`Outcome`'s, with ``"post"``, ``"bar"`` and ``"saved"``); None without."""
    keeper_dive: KeeperDive | None = None
    """On a pitch with a keeper: his dive, or None if he never set off."""


@dataclasses.dataclass(frozen=True)
class BatchTrajectory:
    """Many flights integrated together, padded after each one's end with its final state."""

    t: NDArray[np.float64]
    """(K, T) time of each sample (s); kick k's samples are ``[:n_samples[k]]``."""
    position: NDArray[np.float64]
    """(K, T, 3) ball centre (m)."""
    velocity: NDArray[np.float64]
    """(K, T, 3) ball velocity (m/s)."""
    n_samples: NDArray[np.int64]
    """(K,) samples that belong to each flight; the last is its interpolated end."""
    ended: NDArray[np.str_]
    """(K,) ``"ground"``, ``"x_stop"`` or ``"t_max"`` (on a pitch also ``"stopped"``, ``"net"``, ``"out"``,
    ``"saved"``, ``"contacts"``)."""
    events: tuple[tuple[Event, ...], ...] | None = None
    """On a pitch: each kick's contacts in order; None without one."""
    result: NDArray[np.str_] | None = None
    """On a pitch: (K,) each kick's verdict; None without one."""


@dataclasses.dataclass(frozen=True)
class Outcome:
    """What a kick did, and where it crossed the wall's and the goal's planes."""

    result: Result
    """``"goal"``, ``"wall"`` (hit it), ``"over"`` the bar, ``"wide"`` of a post, or ``"short"`` (landed first)."""
    wall_point: NDArray[np.float64] | None
    """(3,) ball centre where it crossed the wall's plane (m), None if it never got there."""
    goal_point: NDArray[np.float64] | None
    """(3,) ball centre where it crossed the goal's plane (m), None if it never got there."""
    wall_time: float | None
    """Time of the wall crossing (s)."""
    goal_time: float | None
    """Time of the goal crossing (s)."""


@dataclasses.dataclass(frozen=True)
class BatchOutcome:
    """:class:`Outcome` for each kick of a batch; crossings are NaN where there was none."""

    result: NDArray[np.str_]
    """(K,) one of the five results."""
    wall_point: NDArray[np.float64]
    """(K, 3) crossing of the wall's plane (m)."""
    goal_point: NDArray[np.float64]
    """(K, 3) crossing of the goal's plane (m)."""

    def counts(self) -> dict[str, int]:
        """How many kicks ended each way: every one of the eight results, zeros included."""
        return {name: int(np.count_nonzero(self.result == name)) for name in RESULTS}


def _round_down(value: float) -> float:
    """``value`` cut (not rounded) to three significant digits, so a printed limit is one a caller can use."""
    if not 0.0 < value < math.inf:
        return value
    exact = decimal.Decimal(value)  # the float's exact decimal expansion: no division to round up, no underflow
    cut = exact.quantize(decimal.Decimal(1).scaleb(exact.adjusted() - 2), rounding=decimal.ROUND_DOWN)
    return float(cut)  # the float nearest the cut, so printed with three digits it reads as the cut


def _refuse_overflow(
    endings: NDArray[np.int64],
    config: NDArray[np.float64],
    launches: NDArray[np.float64],
    pitches: NDArray[np.float64] | None = None,
    pitch_of: NDArray[np.int64] | None = None,
    strikes: bool = False,
) -> None:
    """Raise where a kick's step was beyond the method's stability limit (ending 4, not flown), where its ball
    started inside a body of the pitch (ending 9, not flown), or where a flight overflowed to inf or NaN (ending 3: a
    step too long for its drag that the limit does not bound, or absurd input).
    ``launches`` are the (K, 13) launch rows, for the limit the message names; on a pitch, where a bounce can turn
    the spin into speed, kick k flew on ``pitches[pitch_of[k]]`` ((P, N_PITCH) rows). ``strikes``: the kicks are
    strikes scattered about one intended kick, so a refusal names its ``speed_ms`` and ``spin_rads``."""
    refused = np.flatnonzero(endings == 4)
    if refused.size:
        first = int(refused[0])
        spin_inertia = 0.0 if pitches is None or pitch_of is None else _spin_inertia_bound(pitches[pitch_of[first]])
        limit, fastest = stable_step(launches[first], config, spin_inertia)
        single = len(endings) == 1
        velocity, spin = ("velocity", "spin") if single or strikes else (f"velocities[{first}]", f"spins[{first}]")
        launched = f"launched at |{velocity}| = {math.hypot(*launches[first, 3:6].tolist()):.3g} m/s"
        subjects = ["speed_ms" if strikes else velocity]
        rate = math.hypot(*launches[first, 6:9].tolist())
        if spin_inertia > 0.0 and rate > 0.0:
            launched += f" and spinning at |{spin}| = {rate:.3g} rad/s, whose energy a bounce can turn into speed"
            subjects.append("spin_rads" if strikes else spin)
        at_most = (
            f"at most {_round_down(limit):.3g} s for {'rk4' if config[RK4] else 'euler'}, the method's stability "
            f"limit with the drag at {fastest:.3g} m/s (the fastest this ball can fly, {launched}; see kernels.ball)"
        )
        which = "" if single else f" of {'strikes' if strikes else 'kicks'} {refused[:5].tolist()}"
        shortest = config[T_MAX] / MAX_STEPS
        if limit >= shortest:
            remedy = "use a smaller " + ", ".join(["dt", *subjects[:-1]]) + f" or {subjects[-1]}"
        else:  # no dt the flight takes is that short: a shorter t_max allows one
            remedy = (
                f"t_max = {config[T_MAX]:g} s takes no step under t_max/{MAX_STEPS} = {shortest:g} s, so use a "
                f"smaller {' or '.join(subjects)}, a t_max of at most {_round_down(limit * MAX_STEPS):.3g} s"
            )
        raise ValueError(
            f"dt = {config[DT]:g} s is too long for this drag{which}: {at_most}: a longer "
            f"step overshoots the drag, reversing or amplifying the velocity; {remedy}, or a smaller air_density or "
            "a larger mass_kg"
        )
    inside = np.flatnonzero(endings == 9)
    if inside.size:
        which = "the ball" if len(endings) == 1 else f"the ball of kicks {inside[:5].tolist()}"
        raise ValueError(
            f"position: {which} starts inside a post, the bar, a player of the wall or the keeper (at "
            f"{launches[int(inside[0]), :3].tolist()} m); it would leave the body with no contact: start it outside"
        )
    bad = np.flatnonzero(endings == 3)
    if bad.size and config[Q] == 0.0:
        # No air: nothing to overshoot, and the spin is bounded (refuse_fast_spin). Either the square of the launch
        # speed overflows (over ~1.34e154 m/s), which no t_max mends, or the flight outruns the floats in a t_max
        # that a vacuum allows (its RK4 is exact at any step).
        first = int(bad[0])
        speed = math.hypot(*launches[first, 3:6].tolist())
        if speed * speed == math.inf:
            subject = "speed_ms" if strikes else "velocity" if len(endings) == 1 else f"velocities[{first}]"
            raise ValueError(
                f"{subject}: a launch at {speed:.3g} m/s is beyond floating-point numbers (its square overflows); "
                "launch it slower"
            )
        which = "the flight" if len(endings) == 1 else f"the flights of kicks {bad[:5].tolist()}"
        raise ValueError(
            f"t_max = {config[T_MAX]:g} s is too long for {which}: with no air (air_density 0) nothing slows the "
            "ball, and it leaves the range of floating-point numbers; use a shorter t_max"
        )
    if bad.size:
        which = "the flight" if len(endings) == 1 else f"kicks {bad[:5].tolist()}"
        raise ValueError(
            f"dt = {config[DT]:g} s is too long for {which}: each step overshoots the drag, so the ball gains "
            "energy until it overflows; use a smaller dt (or a smaller air_density or a larger mass_kg)"
        )


def simulate(
    position: ArrayLike,
    velocity: ArrayLike,
    spin: ArrayLike,
    config: FlightConfig | None = None,
    *,
    knuckle_seed: int | None = None,
    pitch: Pitch | None = None,
    **options: Any,
) -> Trajectory:
    """Integrate one kick until the ball's centre reaches ``ground_m``, passes ``x_stop``, or ``t_max`` runs out.

    Args:
        position: (3,) launch position of the ball's centre (m).
        velocity: (3,) launch velocity (m/s).
        spin: (3,) angular velocity (rad/s); +z curls a ball kicked along +x to the left (+y), +y is topspin.
        config: the ball, air, integrator and end of the flight (:class:`FlightConfig`, validated once); default
            ``FlightConfig()``.
        knuckle_seed: turn on the knuckleball side force (near-zero spin only), drawn from this seed.
        pitch: a :class:`Pitch`: the flight goes on after it lands (bounces, rolls, strikes the posts, the bar, the
            wall's players and the keeper) until it stops, enters the net, leaves the pitch, is saved, passes
            ``x_stop`` or reaches ``t_max``; its contacts are ``events`` and its verdict ``result`` (see
            :mod:`kernels.ball.play`). None (the default): it ends where it first touches the ground.
        **options: instead of ``config``, any of :class:`FlightConfig`'s fields as keywords (``dt=1e-2,
            method="rk4"``); the config built from them is cached, so repeating the same options costs no
            validation.

    Returns:
        :class:`Trajectory`, sampled every ``dt`` plus the interpolated end (on a pitch, plus each contact).

    Raises:
        ValueError: naming the argument, for non-finite, boolean or wrongly shaped input, an invalid
            :class:`FlightConfig` field, a position below ``ground_m``, a spin beyond the measured model's range
            (see :mod:`kernels.ball`); naming dt and its limit when dt is beyond the method's stability limit for
            this kick's drag (a step that would reverse or amplify the velocity; see :mod:`kernels.ball`), and
            the t_max that allows so short a step where ``t_max``'s :data:`~kernels.ball.config.MAX_STEPS` steps do
            not; or when the steps still overshoot and the ball gains energy without bound.
        TypeError: an unknown keyword.
    """
    flight = flight_config(config, options)
    settings = flight.settings
    p0, v0, w0 = fast_floats(position), fast_floats(velocity), fast_floats(spin)
    if p0 is None or v0 is None or w0 is None or knuckle_seed is not None:
        launch = launch_rows(
            checked_vector("position", position, 3)[None],
            checked_vector("velocity", velocity, 3)[None],
            checked_vector("spin", spin, 3)[None],
            [checked_seed("knuckle_seed", knuckle_seed)],
        )
        check_launches(launch, settings, batch=False)
        launch = launch[0]
    else:  # three plain vectors and no knuckle: the launch row at once
        launch = np.array(p0 + v0 + w0 + _NO_KNUCKLE)
        if settings[MEASURED] or p0[2] < settings[GROUND]:
            check_launches(launch[None], settings, batch=False)
    if pitch is not None:
        return _simulate_on_pitch(launch, settings, pitch)
    rows = int(settings[N_STEPS]) + 1
    t, state, forces = np.empty(rows), np.empty((rows, 6)), np.empty((rows, 12))
    n, ending = simulate_one(launch, settings, t, state, forces)
    if ending >= 3:
        _refuse_overflow(np.array([ending]), settings, launch[None])
    return _trajectory(t, state, forces, n, ending)


def _trajectory(
    t: NDArray[np.float64], state: NDArray[np.float64], forces: NDArray[np.float64], n: int, ending: int
) -> Trajectory:
    """The first ``n`` samples of a flight's buffers: times (T,), states (T, 6) and forces (T, 12: drag, Magnus,
    gravity, knuckle), ended by ``ending``'s code."""
    state, forces = state[:n], forces[:n]
    return Trajectory(
        t=t[:n],
        position=state[:, :3],
        velocity=state[:, 3:],
        drag=forces[:, 0:3],
        magnus=forces[:, 3:6],
        gravity=forces[:, 6:9],
        knuckle=forces[:, 9:12],
        ended=_ending(ending),
    )


def _ending(code: int) -> Ending:
    name = ENDINGS[code]
    assert name not in ("diverged", "refused")
    return name  # type: ignore[return-value]


def _keeper_dive(info: NDArray[np.float64]) -> KeeperDive | None:
    if math.isnan(info[play.I_DIVE]):
        return None
    target = info[play.I_TARGET : play.I_TARGET + 3]
    return KeeperDive(float(info[play.I_DIVE]), (float(target[0]), float(target[1]), float(target[2])))


@dataclasses.dataclass(frozen=True)
class KeeperPath:
    """The keeper at given times as a flight on a pitch moves him (:class:`Keeper`): a stick of radius
    ``keeper.body_radius_m`` from his soles to his fingertips through his centre of mass."""

    t: NDArray[np.float64]
    """(T,) times since the kick (s)."""
    com: NDArray[np.float64]
    """(T, 3) centre of mass (m)."""
    up: NDArray[np.float64]
    """(T, 3) unit direction from the soles toward the fingertips."""
    capsule: NDArray[np.float64]
    """(T, 2, 3) the segment the ball is tested against (m): the stick's ends pulled in by the body's radius and kept
    a radius above the turf; a ball whose centre comes within its radius plus the body's of it touches him."""


def keeper_path(
    keeper: Keeper, position_xy: ArrayLike, dive: KeeperDive | None, times: ArrayLike, *, turf_m: float = 0.0
) -> KeeperPath:
    """Where ``keeper``, standing at ``position_xy`` (m) on turf at height ``turf_m``, is at each of ``times`` (s since
    the kick), after ``dive`` (a flight's :attr:`Trajectory.keeper_dive`; None: he stands). The flight's own compiled
    keeper, so a picture drawn from it is the body the ball met. ``ValueError`` naming a non-finite argument."""
    _checks.instance("keeper", keeper, Keeper)
    spot = checked_vector("position_xy", position_xy, 2)
    t = np.ascontiguousarray(_checks.finite_array("times", times).reshape(-1))
    vector = np.zeros(play.N_PITCH)
    vector[play.TURF] = _checks.finite_number("turf_m", turf_m)
    keeper_slots(vector, keeper, (float(spot[0]), float(spot[1])))
    if dive is None:
        dive_t, target = math.inf, np.zeros(3)
    else:
        _checks.instance("dive", dive, KeeperDive)
        dive_t = _checks.finite_number("dive.t", dive.t)
        target = checked_vector("dive.target", dive.target, 3)
    vector.setflags(write=False)  # read-only, as the flight hands it on: one compiled keeper for both
    out = np.empty((len(t), 12))
    keeper_path_core(vector, dive_t, target, t, out)
    return KeeperPath(t, out[:, 0:3], out[:, 3:6], out[:, 6:12].reshape(-1, 2, 3))


@functools.lru_cache(maxsize=64)
def _cached_pitch_vector(pitch: Pitch, spot: tuple[float, float], ground: float, radius: float) -> NDArray[np.float64]:
    vector = pitch_vector(pitch, spot, ground, radius)
    vector.setflags(write=False)
    return vector


def _plain(value: object) -> bool:
    """Whether every number in ``value`` (a pitch: dataclasses and tuples of numbers) is a plain ``float`` or
    ``int``. Only then may a cache keyed on equality stand in for the checks: ``True == 1.0`` and
    ``Decimal(1) == 1.0``, with equal hashes, where the checks refuse a bool or a Decimal."""
    stack = [value]
    while stack:
        item = stack.pop()
        kind = type(item)
        if kind is float or kind is int or item is None:
            continue
        if kind is tuple:
            stack.extend(item)  # type: ignore[arg-type]
        elif hasattr(item, "__dataclass_fields__"):
            stack.extend(vars(item).values())
        else:
            return False
    return True


def _pitch_vector(pitch: Pitch, spot: NDArray[np.float64], ground: float, radius: float) -> NDArray[np.float64]:
    """:func:`pitch_vector`, cached for a pitch flown again from the same spot (the checks cost more than a kick),
    where its numbers are plain (:func:`_plain`)."""
    _checks.instance("pitch", pitch, Pitch)
    if not _plain(pitch):
        vector = pitch_vector(pitch, spot, ground, radius)
        vector.setflags(write=False)
        return vector
    try:
        return _cached_pitch_vector(pitch, (float(spot[0]), float(spot[1])), ground, radius)
    except TypeError:  # a field that cannot be hashed (an array where a tuple belongs): checked uncached
        vector = pitch_vector(pitch, spot, ground, radius)
        vector.setflags(write=False)  # the one array type the compiled flight is built for
        return vector


def _simulate_on_pitch(launch: NDArray[np.float64], settings: NDArray[np.float64], pitch: Pitch) -> Trajectory:
    vector = _placed_pitch(launch[None], settings, pitch)
    _refuse_unplayable(launch[None], vector[None], _FIRST, settings)
    rows = int(settings[N_STEPS]) + 1 + play.EXTRA_ROWS
    # A batch of one: the long compiled flight on a pitch has one entry, compiled once, not one for each use.
    t, (state, spin, forces) = np.empty((1, rows)), (np.empty((1, rows, width)) for width in (6, 3, 12))
    events, info = np.empty((1, play.MAX_EVENTS, 5)), np.empty((1, play.N_INFO))
    n_samples, endings = np.empty(1, dtype=np.int64), np.empty(1, dtype=np.int64)
    kick = (launch[None], settings, vector[None], _FIRST, t, state, spin, forces, events, info, n_samples, endings)
    play_rows(0, 1, *kick)
    n, ending, t, state, spin, forces = int(n_samples[0]), int(endings[0]), t[0], state[0], spin[0], forces[0]
    events, info = events[0], info[0]
    if ending in (3, 4, 9):
        _refuse_overflow(np.array([ending]), settings, launch[None], vector[None], _FIRST)
    return dataclasses.replace(
        _trajectory(t, state, forces, n, ending),
        events=_events(events, int(info[play.I_EVENTS])),
        spin=spin[:n],
        result=RESULTS[int(info[play.I_RESULT])],
        keeper_dive=_keeper_dive(info),
    )


_NO_KNUCKLE = [0.0, 0.0, 0.0, 0.0]
"""Knuckle angles θ φ₁ φ₂ and flag of a launch row without the knuckle force."""


def simulate_batch(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    config: FlightConfig | None = None,
    *,
    knuckle_seeds: Sequence[int | None] | None = None,
    pitch: Pitch | None = None,
    **options: Any,
) -> BatchTrajectory:
    """Integrate K kicks, in parallel over the kicks; each flight is :func:`simulate`'s, bit for bit.

    Memory is K·T·7 floats (T the longest flight's samples): 10 000 kicks of 1.9 s at RK4 10 ms take ~110 MB, at
    Euler 1 ms ten times that; use ``x_stop`` and a coarser ``dt`` for large sweeps, or :func:`simulate_outcomes`
    when only the verdicts matter. Forces are not stored; run :func:`simulate` on a kick of interest for them.

    Args:
        positions: (K, 3) launch positions (m).
        velocities: (K, 3) launch velocities (m/s).
        spins: (K, 3) angular velocities (rad/s).
        knuckle_seeds: None, or K seeds (each None or an int) as :func:`simulate`'s ``knuckle_seed``.
        pitch: as for :func:`simulate`, shared by every kick (a keeper without a position is placed for the first
            kick's spot); each flight is then :func:`simulate`'s on that pitch, and ``events`` and ``result`` are
            filled.
        config, options: as for :func:`simulate`, shared by every kick.

    Returns:
        :class:`BatchTrajectory`.
    """
    settings, launches = _checked_batch(positions, velocities, spins, knuckle_seeds, config, options)
    if pitch is not None:
        return _batch_on_pitch(launches, settings, pitch)
    k = len(launches)
    rows = int(settings[N_STEPS]) + 1
    n_samples, endings = np.ones(k, dtype=np.int64), np.full(k, 2, dtype=np.int64)
    # Time-major (T, K) storage with room for the longest flight t_max allows: rows past this batch's longest
    # flight are never touched, so they never become memory. Where even that reservation is too large, count
    # the samples first.
    if rows * k * 56 > RESERVE_BYTES:
        run_rows(fly_rows, k, launches, settings, np.empty((0, k)), np.empty((0, k, 6)), n_samples, endings)
        rows = int(n_samples.max())
        _refuse_too_large(k, rows)
    t, state = np.empty((rows, k)), np.empty((rows, k, 6))
    run_rows(fly_rows, k, launches, settings, t, state, n_samples, endings)
    width = int(n_samples.max()) if k else 1
    t, state = t[:width], state[:width]
    pad(t, state, n_samples)
    _refuse_overflow(endings, settings, launches)
    state = state.transpose(1, 0, 2)  # (K, T, 6) view, no copy
    return BatchTrajectory(
        t=t.T,
        position=state[:, :, :3],
        velocity=state[:, :, 3:],
        n_samples=n_samples,
        ended=np.array(ENDINGS, dtype="<U6")[endings],
    )


_FIRST = np.zeros(1, dtype=np.int64)
MAX_PITCH_LENGTH_M = 120.0
"""How far from the goal line a kick on a pitch may start (m; Law 1: a touchline is 90–120 m long)."""


def _spin_inertia_bound(pitch: NDArray[np.float64]) -> float:
    """:func:`kernels.ball.play.spin_inertia_bound` of one (N_PITCH,) pitch row, in the same operations."""
    slots = (play.TURF_SURFACE, play.FRAME_SURFACE, play.BODY_SURFACE)
    return max(0.0, *(float(pitch[slot + 4]) * float(pitch[slot + 3]) ** 2 for slot in slots))


MAX_PITCH_DT_S = 0.05
"""The longest step a flight on a pitch takes (s): contacts are found once a step, with the keeper where he is at its
middle, so a coarser step can decide the verdict (the default kick, a goal at dt ≤ 0.1 s, was saved at 0.3 s)."""


def _refuse_unplayable(
    launches: NDArray[np.float64],
    pitches: NDArray[np.float64],
    which: NDArray[np.int64],
    settings: NDArray[np.float64],
    strikes: bool = False,
) -> None:
    """``ValueError`` naming ``dt`` where it is over :data:`MAX_PITCH_DT_S`, or the first kick that starts off its
    pitch: behind the goal line (it would fly in through the back of the net), more than
    :data:`MAX_PITCH_LENGTH_M` in front of it, or beyond a touchline."""
    if settings[DT] > MAX_PITCH_DT_S:
        raise ValueError(
            f"dt must be at most {MAX_PITCH_DT_S:g} s on a pitch (contacts are found once a step), got "
            f"{_checks.shown(float(settings[DT]))}"
        )
    rows = pitches[which]
    dx, dy = launches[:, 0] - rows[:, play.GX], launches[:, 1] - rows[:, play.GY]
    depth = dx * rows[:, play.GNX] + dy * rows[:, play.GNY]  # + behind the goal line
    across = -dx * rows[:, play.GNY] + dy * rows[:, play.GNX]
    off = np.flatnonzero((depth > 0.0) | (depth < -MAX_PITCH_LENGTH_M) | (np.abs(across) > rows[:, play.HALF_WIDTH]))
    if off.size:
        k = int(off[0])
        which_kick = f"positions[{k}]" if len(launches) > 1 and not strikes else "position"
        where = f"{abs(depth[k]):.4g} m {'behind' if depth[k] > 0.0 else 'in front of'}"
        raise ValueError(
            f"{which_kick} must be on the pitch, in front of the goal line (at most {MAX_PITCH_LENGTH_M:g} m) and "
            f"between the touchlines; {launches[k, :3].tolist()} m is {where} the line and {across[k]:.4g} m across "
            f"(the touchlines are ±{rows[k, play.HALF_WIDTH]:g} m)"
        )


def _refuse_too_large(k: int, rows: int, per_sample: int = 56) -> None:
    """``ValueError`` where K flights of ``rows`` samples each, ``per_sample`` bytes a sample (t, position and
    velocity: 7 float64), would take more than :data:`MAX_BATCH_BYTES`."""
    size = k * rows * per_sample
    if size > MAX_BATCH_BYTES:
        raise ValueError(
            f"positions: {k:,} flights of up to {rows:,} samples would take {size / 2**30:.1f} GiB, more than "
            f"{MAX_BATCH_BYTES / 2**30:g} GiB: give fewer kicks, a coarser dt, an x_stop or a shorter t_max, or "
            f"use simulate_outcomes() where only the verdicts matter"
        )


def _checked_batch(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    knuckle_seeds: Sequence[int | None] | None,
    config: FlightConfig | None,
    options: dict[str, Any],
    strikes: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A batch's (14,) settings and its (K, 13) launch rows, checked (``ValueError`` naming the argument; for
    ``strikes``, see :func:`~kernels.ball.config.check_launches`)."""
    settings = flight_config(config, options).settings
    launches = kick_rows(positions, velocities, spins, knuckle_seeds)
    if len(launches) > MAX_KICKS:
        raise ValueError(f"positions must hold at most {MAX_KICKS:,} kicks in one call, got {len(launches):,}")
    check_launches(launches, settings, batch=True, strikes=strikes)
    return settings, launches


def _play_batch(
    launches: NDArray[np.float64],
    settings: NDArray[np.float64],
    pitches: NDArray[np.float64],
    which: NDArray[np.int64],
    keep: bool,
    strikes: bool = False,
) -> tuple[Any, ...]:
    """Every kick on its pitch (``pitches[which[k]]``, read-only (P, N_PITCH) rows), in parallel: (t, state, spin,
    events, info, n_samples, endings); flights kept only when ``keep`` (else zero-length rows, and each flight ends
    once its verdict cannot change)."""
    k = len(launches)
    _refuse_unplayable(launches, pitches, which, settings, strikes)
    rows = int(settings[N_STEPS]) + 1 + play.EXTRA_ROWS if keep else 0
    t, state, spin = np.empty((k, rows)), np.empty((k, rows, 6)), np.empty((k, rows, 3))
    events, info = np.empty((k, play.MAX_EVENTS, 5)), np.empty((k, play.N_INFO))
    n_samples, endings = np.ones(k, dtype=np.int64), np.full(k, 2, dtype=np.int64)
    forces = np.empty((k, 0, 12))  # a batch keeps no forces
    run_rows(play_rows, k, launches, settings, pitches, which, t, state, spin, forces, events, info, n_samples, endings)
    _refuse_overflow(endings, settings, launches, pitches, which, strikes)
    return t, state, spin, events, info, n_samples, endings


def _one_pitch(
    launches: NDArray[np.float64], settings: NDArray[np.float64], pitch: Pitch, strikes: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """(1, N_PITCH) read-only rows of ``pitch`` (a keeper placed for the first kick's spot) and every kick's index."""
    return _placed_pitch(launches, settings, pitch, strikes)[None], np.zeros(len(launches), dtype=np.int64)


def _placed_pitch(
    launches: NDArray[np.float64], settings: NDArray[np.float64], pitch: Pitch, strikes: bool = False
) -> NDArray[np.float64]:
    """``pitch``'s vector with its keeper placed from the first kick's spot; a spot off the pitch (behind the goal,
    where the keeper's placement would be refused first, naming his fields) is refused naming the kick's position."""
    ground, radius = float(settings[GROUND]), float(settings[RADIUS])
    spot = launches[0, :2] if len(launches) else np.zeros(2)
    try:
        return _pitch_vector(pitch, spot, ground, radius)
    except ValueError:  # the keeper's placement, or another field: is it the kick's spot that is wrong?
        if isinstance(pitch, Pitch) and pitch.keeper is not None and pitch.keeper.position_xy is None and len(launches):
            bare = _pitch_vector(dataclasses.replace(pitch, keeper=None), spot, ground, radius)
            _refuse_unplayable(launches, bare[None], np.zeros(len(launches), dtype=np.int64), settings, strikes)
        raise


def pitch_outcomes(
    launches: NDArray[np.float64],
    settings: NDArray[np.float64],
    pitches: NDArray[np.float64],
    which: NDArray[np.int64],
    strikes: bool = False,
) -> NDArray[np.int64]:
    """Result codes (:data:`RESULTS` order) of K checked launch rows (``kick_rows``) each on its own pitch row
    (``pitch_vector`` rows stacked, ``which[k]`` the row of kick k), in one parallel call: what a map over many spots
    wants. Trusts its arguments (the callers in this package check them); ``strikes`` as for the refusal of
    :func:`pitch_strike_outcomes`."""
    stacked = np.array(pitches, dtype=np.float64, order="C")
    stacked.setflags(write=False)
    *_, info, _, _ = _play_batch(launches, settings, stacked, np.asarray(which, dtype=np.int64), False, strikes)
    return info[:, play.I_RESULT].astype(np.int64)


def pitch_strike_outcomes(
    positions: ArrayLike, velocities: ArrayLike, spins: ArrayLike, pitch: Pitch, options: dict[str, Any]
) -> BatchOutcome:
    """:func:`simulate_outcomes` on ``pitch`` for strikes scattered about one intended kick: a step too long for
    them is refused naming that kick's ``speed_ms`` and ``spin_rads``, the arguments its caller was given."""
    options = dict(options)
    config = options.pop("config", None)  # as simulate_outcomes takes it
    settings, launches = _checked_batch(positions, velocities, spins, None, config, options, strikes=True)
    return _pitch_outcome(launches, settings, pitch, strikes=True)


def _pitch_outcome(
    launches: NDArray[np.float64], settings: NDArray[np.float64], pitch: Pitch, strikes: bool
) -> BatchOutcome:
    *_, info, _, _ = _play_batch(launches, settings, *_one_pitch(launches, settings, pitch, strikes), False, strikes)
    return BatchOutcome(
        result=np.array(RESULTS, dtype="<U5")[info[:, play.I_RESULT].astype(np.int64)],
        wall_point=info[:, play.I_WALL + 1 : play.I_WALL + 4].copy(),
        goal_point=info[:, play.I_GOAL + 1 : play.I_GOAL + 4].copy(),
    )


def _batch_on_pitch(launches: NDArray[np.float64], settings: NDArray[np.float64], pitch: Pitch) -> BatchTrajectory:
    _refuse_too_large(len(launches), int(settings[N_STEPS]) + 1 + play.EXTRA_ROWS, per_sample=80)  # + the spin
    t, state, _, events, info, n_samples, endings = _play_batch(
        launches, settings, *_one_pitch(launches, settings, pitch), keep=True
    )
    width = int(n_samples.max()) if len(n_samples) else 1
    t, state = t[:, :width], state[:, :width]
    for k, n in enumerate(n_samples):  # pad each flight with its last sample
        t[k, n:] = t[k, n - 1]
        state[k, n:] = state[k, n - 1]
    return BatchTrajectory(
        t=t,
        position=state[:, :, :3],
        velocity=state[:, :, 3:],
        n_samples=n_samples,
        ended=np.array(ENDINGS, dtype="<U8")[endings],
        events=tuple(_events(events[k], int(info[k, play.I_EVENTS])) for k in range(len(n_samples))),
        result=np.array(RESULTS, dtype="<U5")[info[:, play.I_RESULT].astype(np.int64)],
    )


def outcome(trajectory: Trajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M) -> Outcome:
    """Judge one flight against the wall and the goal.

    The ball hits the wall when its centre crosses the wall's plane within a radius of the defenders' outline
    (width × height). Otherwise, where its centre crosses the goal's plane decides: the whole ball inside the posts
    and under the bar is a goal; outside a post is wide; inside the posts but touching or above the bar is over. A
    flight that ends (lands, or reaches ``t_max``) before the goal's plane is short. Posts and bar do not rebound.
    Each crossing is the root of the cubic Hermite interpolant of the step that crosses the plane.

    Args:
        trajectory: from :func:`simulate`.
        wall: the wall, e.g. from :func:`free_kick_panels`.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`Outcome`.
    """
    radius = _checks.positive("radius_m", radius_m)
    _checks.instance("trajectory", trajectory, Trajectory, "a Trajectory from simulate()")
    if trajectory.result is not None:
        raise ValueError(
            "trajectory was played on a pitch: its verdict, with the posts, the bar, the wall's players and the "
            f"keeper, is trajectory.result ({_checks.shown(trajectory.result)}); outcome() judges a free flight"
        )
    crossings = np.empty((2, 4))
    # Judged from a writable copy laid out as a batch's row (times strided, positions and velocities slices of one
    # state array), whatever the flight's own layout or flags (the scene keeps its flights read-only): the package
    # then compiles one judge for single flights and batches, not a variant per layout on the first start.
    n = len(trajectory.t)
    columns = np.empty((n, 7))
    columns[:, 0], columns[:, 1:4], columns[:, 4:7] = trajectory.t, trajectory.position, trajectory.velocity
    t, position, velocity = columns[:, 0], columns[:, 1:4], columns[:, 4:7]
    code = judge(t, position, velocity, n, panel_rows(wall, goal), radius, crossings)
    wall_ok, goal_ok = not math.isnan(crossings[0, 0]), not math.isnan(crossings[1, 0])
    return Outcome(
        result=RESULTS[code],
        wall_point=crossings[0, 1:] if wall_ok else None,
        goal_point=crossings[1, 1:] if goal_ok else None,
        wall_time=float(crossings[0, 0]) if wall_ok else None,
        goal_time=float(crossings[1, 0]) if goal_ok else None,
    )


def outcome_batch(batch: BatchTrajectory, wall: Panel, goal: Panel, *, radius_m: float = BALL_RADIUS_M) -> BatchOutcome:
    """:func:`outcome` for every kick of a batch, in parallel.

    Args:
        batch: from :func:`simulate_batch`.
        wall: the wall.
        goal: the goal mouth.
        radius_m: ball radius (m).

    Returns:
        :class:`BatchOutcome`.
    """
    radius = _checks.positive("radius_m", radius_m)
    _checks.instance("batch", batch, BatchTrajectory, "a BatchTrajectory from simulate_batch()")
    if batch.result is not None:
        raise ValueError(
            "batch was played on a pitch: its verdicts, with the posts, the bar, the wall's players and the keeper, "
            "are batch.result; outcome_batch() judges free flights"
        )
    k = len(batch.n_samples)
    results, crossings, panels = (np.empty(k, dtype=np.int64), np.empty((k, 2, 4)), panel_rows(wall, goal))
    run_rows(
        judge_rows, k, batch.t, batch.position, batch.velocity, batch.n_samples, panels, radius, results, crossings
    )
    return _batch_outcome(results, crossings)


def _batch_outcome(results: NDArray[np.int64], crossings: NDArray[np.float64]) -> BatchOutcome:
    return BatchOutcome(
        result=np.array(RESULTS, dtype="<U5")[results], wall_point=crossings[:, 0, 1:], goal_point=crossings[:, 1, 1:]
    )


def simulate_outcomes(
    positions: ArrayLike,
    velocities: ArrayLike,
    spins: ArrayLike,
    wall: Panel | None = None,
    goal: Panel | None = None,
    config: FlightConfig | None = None,
    *,
    knuckle_seeds: Sequence[int | None] | None = None,
    pitch: Pitch | None = None,
    **options: Any,
) -> BatchOutcome:
    """``outcome_batch(simulate_batch(...), wall, goal)`` without keeping the flights: the same verdicts and crossings.

    Each kick flies into a scratch buffer of its own and is judged at once, in parallel over the kicks, so memory
    stays K·(a few floats) however long the flights. This is what a sweep (an outcome map, an aiming search) wants.

    Args:
        positions, velocities, spins, knuckle_seeds: the K kicks, as for :func:`simulate_batch`.
        wall: the wall, or None for none (its crossings are then NaN).
        goal: the goal mouth (without a pitch, required).
        pitch: a :class:`Pitch` (then ``wall`` and ``goal`` are its own, and must be None or the same): each kick
            plays on to its end as :func:`simulate`'s does on it, and is judged by what it did (results gain
            ``"post"``, ``"bar"`` and ``"saved"``; a ball in off the post is a ``"goal"``); the wall's point is
            where it crossed the wall's plane.
        config, options: as for :func:`simulate`, shared by every kick; its ``radius_m`` also sizes the ball
            for the verdict.

    Returns:
        :class:`BatchOutcome`.
    """
    settings, launches = _checked_batch(positions, velocities, spins, knuckle_seeds, config, options)
    for name, panel in (("wall", wall), ("goal", goal)):
        if panel is not None:
            _checks.instance(name, panel, Panel)
    if pitch is not None:
        _checks.instance("pitch", pitch, Pitch)
        if (wall is not None and wall != pitch.wall) or (goal is not None and goal != pitch.goal):
            raise ValueError("with a pitch, wall and goal are the pitch's own: pass None (or the same panels)")
        return _pitch_outcome(launches, settings, pitch, strikes=False)
    if goal is None:
        raise ValueError("goal must be a Panel (or pass a pitch)")
    no_wall = wall is None
    if wall is None:  # a wall nobody can hit: below the turf
        wall = Panel(goal.centre_xy, goal.normal_xy, 1e-9, -1e300)
    k, panels = len(launches), panel_rows(wall, goal)
    results, crossings, endings = np.empty(k, np.int64), np.empty((k, 2, 4)), np.empty(k, np.int64)
    run_rows(fly_and_judge_rows, k, launches, settings, panels, results, crossings, endings)
    _refuse_overflow(endings, settings, launches)
    if no_wall:
        crossings[:, 0, :] = np.nan
    return _batch_outcome(results, crossings)


def spin_vector(rate_rev_s: float, axis: ArrayLike) -> NDArray[np.float64]:
    """Angular velocity (rad/s) from a spin rate in rev/s about ``axis`` (any length, normalised here).

    Args:
        rate_rev_s: spin rate (rev/s, ≥ 0).
        axis: (3,) spin axis; +z is sidespin curling a ball kicked along +x to the left.

    Returns:
        (3,) ω (rad/s).

    Raises:
        ValueError: ``rate_rev_s`` negative, not a finite number, or so large that |ω|² overflows (over about
            2.1·10¹⁵³ rev/s); ``axis`` not three finite numbers of non-zero length. The message names it.
    """
    rate = _checks.non_negative("rate_rev_s", rate_rev_s)
    omega = 2.0 * math.pi * rate
    if not math.isfinite(omega * omega):  # inf times an axis's 0 was NaN; |ω|² must be finite too
        bound = math.sqrt(sys.float_info.max) / (2.0 * math.pi)
        raise ValueError(f"rate_rev_s must be at most {bound:.3g} rev/s (|ω|² a finite number), got {rate:g}")
    return omega * _checks.direction("axis", checked_vector("axis", axis, 3), 3)


def launch_velocity(speed_ms: float, elevation_rad: float, azimuth_rad: float) -> NDArray[np.float64]:
    """Velocity (3,) in m/s from speed, elevation above the ground and azimuth to the left of +x."""
    speed = _checks.non_negative("speed_ms", speed_ms)
    elevation = _checks.finite_number("elevation_rad", elevation_rad)
    azimuth = _checks.finite_number("azimuth_rad", azimuth_rad)
    return speed * np.array(
        [math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth), math.sin(elevation)]
    )


def warm_up() -> None:
    """Compile, or load from the cache, every compiled core, on tiny inputs (both models, both methods, a knuckle,
    the coefficients and a bounce).

    Call once at start-up, off the thread that serves users: the first kick then runs at full speed. A cold compile
    takes several seconds; a warm cache loads in well under one.
    """
    wall, goal = free_kick_panels((0.0, 0.0), (12.0, 0.0), (1.0, 0.0))
    start, velocity, spin = (0.0, 0.0, BALL_RADIUS_M), (20.0, 0.0, 4.0), (0.0, 0.0, 30.0)
    flight = simulate(start, velocity, spin, dt=0.05, method="rk4", model="measured", knuckle_seed=0)
    outcome(flight, wall, goal)
    frozen = [a.view() for a in (flight.t, flight.position, flight.velocity)]  # same layouts, read-only views
    for array in frozen:
        array.setflags(write=False)  # callers that keep flights read-only (the scene does) get their own variant
    outcome(dataclasses.replace(flight, t=frozen[0], position=frozen[1], velocity=frozen[2]), wall, goal)
    rows = np.array([start, start])
    batch = simulate_batch(rows, [velocity, velocity], [spin, spin], dt=0.05, t_max=0.2)
    outcome_batch(batch, wall, goal)
    simulate_outcomes(rows, [velocity, velocity], [spin, spin], wall, goal, dt=0.05, x_stop=13.0)
    coefficients(20.0, 30.0)
    bounce(velocity, spin)
    pitch = Pitch(goal, wall, Keeper())
    simulate(start, velocity, spin, dt=0.05, method="rk4", model="measured", knuckle_seed=0, pitch=pitch)
    many = np.stack([pitch_vector(pitch, (0.0, 0.0), 0.0, BALL_RADIUS_M)] * 2)
    pitch_outcomes(
        kick_rows(rows, [velocity, velocity], [spin, spin], None),
        flight_config(None, {}).settings,
        many,
        np.array([0, 1]),
    )
    simulate_batch(rows, [velocity, velocity], [spin, spin], dt=0.05, t_max=0.2, pitch=pitch)
    simulate_outcomes(rows, [velocity, velocity], [spin, spin], dt=0.05, pitch=pitch)
    keeper_path(Keeper(), (11.0, 0.0), KeeperDive(0.2, (12.0, 2.0, 1.5)), np.array([0.0, 0.5]))
