"""The arm's error chart always gets data uPlot can draw: equal-length finite arrays with at least one point.

An empty series made viser's client throw "object null is not iterable" and leave the chart without its red curve;
a solve that saw no admissible pose ("infeasible") sent exactly that."""

from __future__ import annotations

import numpy as np
import pytest
import viser
from helpers.properties import examples
from helpers.scenes import scene_fixture
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenes.arm import OBSTACLE_STARTS, TARGET_START, ArmParams, ArmScene, chart_points, solve_arm

scene = scene_fixture(ArmScene)


def assert_drawable(counts: np.ndarray, errors: np.ndarray) -> None:
    assert counts.shape == errors.shape and counts.ndim == 1 and len(counts) >= 1, (counts, errors)
    assert np.all(np.isfinite(counts)) and np.all(np.isfinite(errors)) and np.all(errors > 0.0), (counts, errors)
    assert np.all(np.diff(counts) > 0.0), counts


def test_a_solve_that_sees_no_admissible_pose_still_charts_its_error() -> None:
    # Found by a random walk of the controls: 3D, Jacobian DLS capped at 3 iterations, 45° cones and three obstacles,
    # from a pose bent 90° at joint 4. No iterate kept every limit, and the chart got two empty arrays.
    params = ArmParams(
        n_links=6, link_length_m=0.5, three_d=True, limits=True, n_obstacles=3, solver="Jacobian DLS",
        tolerance_mm=50.0, max_iterations=3,
    )  # fmt: skip
    joints = np.array(
        [
            [0.0, 0.0, 0.0],
            [-0.20888368898222465, 0.0, 0.45427701293063166],
            [-0.30727456051929597, 0.0, 0.9445006724965237],
            [-0.04498072923117724, 0.0, 1.3701788914227448],
            [0.4515209397678642, 0.0, 1.3111357488813258],
            [0.9041393459122393, 0.0, 1.0986820399955417],
            [0.8502284526163822, 0.0, 0.6015969209424334],
        ]
    )
    report = solve_arm(params, joints, TARGET_START, OBSTACLE_STARTS)
    assert report.result.status == "infeasible"
    counts, errors = report.best_history
    np.testing.assert_array_equal(counts, [report.result.iterations])
    np.testing.assert_allclose(errors, [report.result.error])
    x, y = chart_points(report)
    assert_drawable(x, y)
    assert y[-1] == pytest.approx(report.result.error * 1000.0)  # the chart ends on the readout's error


def test_the_testers_sequence_sends_the_chart_drawable_data(scene: ArmScene) -> None:
    steps = [
        ("n_links", 12), ("link_length_m", 0.05), ("link_length_m", 0.5), ("n_links", 2), ("limits", True),
        ("half_angle_deg", 0.0), ("half_angle_deg", 180.0), ("n_links", 12), ("half_angle_deg", 10.0),
        ("max_iterations", 4),
    ]  # fmt: skip
    for name, value in steps:
        scene.controls[name].value = value
        counts, errors = (np.asarray(d, dtype=np.float64) for d in scene.plot.data)
        assert_drawable(counts, errors)
        assert scene.report is not None
        assert errors[-1] == pytest.approx(max(scene.report.result.error * 1000.0, 1e-6))


CONTROL_VALUES = {
    "n_links": st.integers(2, 12),
    "link_length_m": st.sampled_from([0.05, 0.1, 0.2, 0.3, 0.5]),
    "three_d": st.booleans(),
    "limits": st.booleans(),
    "half_angle_deg": st.sampled_from([0.0, 1.0, 5.0, 10.0, 45.0, 90.0, 179.0, 180.0]),
    "avoid": st.booleans(),
    "n_obstacles": st.integers(0, 4),
    "solver": st.sampled_from(["FABRIK", "CCD", "Jacobian DLS"]),
    "tolerance_mm": st.sampled_from([0.01, 1.0, 50.0]),
    "max_iterations": st.sampled_from([1, 2, 3, 4, 5, 50]),
}
steps_strategy = st.lists(
    st.sampled_from(list(CONTROL_VALUES)).flatmap(lambda k: st.tuples(st.just(k), CONTROL_VALUES[k])),
    min_size=1,
    max_size=40,
)


@settings(max_examples=examples(15), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(steps=steps_strategy)
def test_every_chart_update_is_drawable_across_random_control_changes(
    server: viser.ViserServer, steps: list[tuple[str, object]]
) -> None:
    """After every control change, whatever the order: equal-length, finite, positive, increasing data with at
    least one point, ending on the readout's error."""
    shown = ArmScene(server)  # a fresh scene per example: each sequence starts from the opening state
    try:
        for name, value in steps:
            shown.controls[name].value = value
            counts, errors = (np.asarray(d, dtype=np.float64) for d in shown.plot.data)
            assert_drawable(counts, errors)
            assert shown.report is not None
            assert errors[-1] == pytest.approx(max(shown.report.result.error * 1000.0, 1e-6)), steps
    finally:
        shown.close()
