"""Strided views of Pinocchio's data vectors (mcdm_pin.model.placements)."""

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin.exceptions import ModelError
from mcdm_pin.model.placements import stacked_view


def test_views_follow_every_update_of_the_data():
    model = pin.buildSampleModelHumanoidRandom()
    data = model.createData()
    R = stacked_view(data.oMi, model.njoints, lambda M: M.rotation)
    t = stacked_view(data.oMi, model.njoints, lambda M: M.translation)
    f = stacked_view(data.f, model.njoints, lambda F: F.vector)
    rng = np.random.default_rng(0)
    for _ in range(3):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        v, a = rng.standard_normal(model.nv), rng.standard_normal(model.nv)
        pin.rnea(model, data, q, v, a)
        pin.forwardKinematics(model, data, q)
        for j in range(model.njoints):
            assert np.array_equal(R[j], data.oMi[j].rotation)
            assert np.array_equal(t[j], data.oMi[j].translation)
            assert np.array_equal(f[j], data.f[j].vector)
    assert not R.flags.writeable


def test_a_vector_whose_elements_are_not_at_one_stride_is_refused():
    M = pin.SE3.Random()
    with pytest.raises(ModelError, match="one stride"):
        stacked_view([M, M, M], 3, lambda M: M.rotation)  # the same element thrice: no stride
