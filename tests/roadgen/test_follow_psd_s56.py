"""psd_slope's errors name no method= (it takes none); estimate_gd's still name theirs."""

import pytest

import roadgen


@pytest.fixture(scope="module")
def road():
    return roadgen.iso8608_profile(150.0, gd=450, seed=0, band=(1.0, 10.0))


def test_psd_slope_outside_the_content_band_names_no_method(road):
    """Before: '... cycles/m, with method='fit': the road has no content there'."""
    with pytest.raises(roadgen.RoadgenError, match=r"settings.band=\(1, 10\) cycles/m: the road"
                       ) as info:  # fmt: skip
        roadgen.psd_slope(road, band=(20.0, 40.0))
    assert "method" not in str(info.value)


@pytest.mark.parametrize("method", ["fit", "welch"])
def test_estimate_gd_outside_the_content_band_still_names_its_method(road, method):
    with pytest.raises(roadgen.RoadgenError, match=rf", with method='{method}': the road"):
        roadgen.estimate_gd(road, band=(20.0, 40.0), method=method)
