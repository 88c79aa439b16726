"""Channel conventions: per-rail inspection channels and the four spectral channels round-trip."""

import numpy as np

from ttbpipe.channels import rails_from_spectral, spectral_from_inspection


def test_rail_inputs_round_trip_with_inspection_channels():
    rng = np.random.default_rng(0)
    z_left, z_right, y_left, y_right = rng.normal(size=(4, 100))
    inspection = {
        "vertical_left_mm": z_left, "vertical_right_mm": z_right,
        "alignment_left_mm": y_left, "alignment_right_mm": y_right,
        # definitions in ttbpipe.channels: cross-level = left - right height; gauge = widening
        "cross_level_mm": z_left - z_right, "gauge_mm": y_left - y_right,
    }
    spectral = spectral_from_inspection(inspection)
    rails = rails_from_spectral(**spectral)
    np.testing.assert_allclose(rails["z_left"], z_left, atol=1e-12)
    np.testing.assert_allclose(rails["z_right"], z_right, atol=1e-12)
    np.testing.assert_allclose(rails["y_left"], y_left, atol=1e-12)
    np.testing.assert_allclose(rails["y_right"], y_right, atol=1e-12)


def test_positive_gauge_widens_the_track():
    # y is positive to the left: a wider gauge moves the left rail left and the right rail right.
    rails = rails_from_spectral(np.zeros(1), np.zeros(1), np.zeros(1), np.array([2.0]))
    assert rails["y_left"][0] == 1.0 and rails["y_right"][0] == -1.0


def test_inspection_columns_from_spectral_inverts_spectral_from_inspection():
    from ttbpipe.channels import INSPECTION_COLUMNS, inspection_columns_from_spectral
    rng = np.random.default_rng(1)
    vertical, alignment, cross_level, gauge = rng.normal(size=(4, 50))
    columns = inspection_columns_from_spectral(vertical, alignment, cross_level, gauge)
    assert tuple(columns) == INSPECTION_COLUMNS
    back = spectral_from_inspection(columns)
    for name, original in zip(("vertical", "alignment", "cross_level", "gauge"),
                              (vertical, alignment, cross_level, gauge)):
        np.testing.assert_allclose(back[name], original, atol=1e-12)
