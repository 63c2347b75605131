"""The exact rotation: correct against scipy, exact and smooth at zero angular velocity."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sim.bodies.rotation import matrix_to_quat, quat_to_matrix, rotation_quat


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-6, 1e-4, 1e-3, 0.1, 1.0, 3.0])
def test_rotation_quat_matches_scipy_at_all_scales(angle):
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    q = rotation_quat(angle * axis)
    expected = Rotation.from_rotvec(angle * axis).as_quat(scalar_first=True)
    np.testing.assert_allclose(q, expected, rtol=0, atol=2e-16)
    assert q @ q == pytest.approx(1.0, abs=5e-16)  # two ulps


def test_zero_rotation_is_exactly_identity():
    """No 0/0 and no artificial spin needed: w = 0 gives the identity to the bit."""
    assert np.array_equal(rotation_quat(np.zeros(3)), [1.0, 0.0, 0.0, 0.0])


def test_matrix_quaternion_round_trip():
    for q in Rotation.random(50, random_state=1).as_quat(scalar_first=True):
        R = quat_to_matrix(q)
        np.testing.assert_allclose(R, Rotation.from_quat(q, scalar_first=True).as_matrix(), atol=1e-15)
        q2 = matrix_to_quat(R)
        np.testing.assert_allclose(q2, q * np.sign(q[0]), atol=1e-15)
