import numpy as np
import pytest

from stsf_gym.vision.landmarks import (
    LandmarkPattern,
    decode_landmark_id,
    landmark_image,
    lit_cells,
    square_centres,
)

PATTERN = LandmarkPattern()


@pytest.mark.parametrize("landmark_id", [0, 1, 8, 77, 255])
def test_id_round_trip(landmark_id):
    assert decode_landmark_id(set(lit_cells(landmark_id, PATTERN)), PATTERN) == landmark_id


def test_pattern_is_symmetric_ring_plus_centre():
    ring_and_centre = set(lit_cells(0, PATTERN))
    assert len(ring_and_centre) == 17
    centres = square_centres(0, PATTERN)
    np.testing.assert_allclose(centres.mean(axis=0), 0.0, atol=1e-12)
    for landmark_id in range(1, 9):
        assert ring_and_centre <= set(lit_cells(landmark_id, PATTERN))


def test_image_squares_are_5cm_white_on_black():
    px_per_m = 480.0
    image = landmark_image(5, PATTERN, px_per_m)
    assert image.shape[0] == round(PATTERN.size * px_per_m)
    assert set(np.unique(image)) == {0, 255}
    white = (image == 255).sum() / px_per_m**2
    assert white == pytest.approx(len(lit_cells(5, PATTERN)) * 0.05**2, rel=1e-6)


def test_bad_ids_and_patterns():
    with pytest.raises(ValueError, match="256"):
        lit_cells(256, PATTERN)
    with pytest.raises(ValueError, match="square_size"):
        LandmarkPattern(square_size=0.2, pitch=0.1)
