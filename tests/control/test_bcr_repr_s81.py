"""``repr(BCR)`` is one short line (method, feature, update interval, estimates since the
start, the newest status), never the default ``<... object at 0x...>``, and never
raises."""

from control_doubles import FakeCalibrator, stream

from control import BCR, PAPER_WINDOW


def test_a_changepoint_bcr_names_its_settings_and_counts(block_model):
    bcr = BCR(block_model)
    every = bcr.settings.samples_per_update
    seconds = f"{every / bcr.settings.rate_hz:.3g}"
    name = bcr.settings.feature.name
    assert repr(bcr) == (
        f"BCR(method=changepoint, feature={name}, every={every} samples ({seconds} s), "
        "estimates=0, last=filling)"
    )
    t, pos, acc, spd = stream(lambda s: 400.0, 1.0, 3 * every / 120.0 + 0.1)
    bcr.update(t, pos, acc, spd)
    text = repr(bcr)
    assert f"estimates={t.size // every}, last={bcr.last.status})" in text, text
    assert str(bcr) == text and "\n" not in text and len(text) < 160


def test_a_window_bcr_names_its_method_and_feature():
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    text = repr(bcr)
    assert text.startswith(f"BCR(method=window, feature={PAPER_WINDOW.name}, every="), text
    bcr.reset()
    assert "estimates=0, last=" in repr(bcr)


def test_the_repr_never_raises():
    assert repr(BCR.__new__(BCR)) == "BCR(?)"
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    bcr.last = None  # an odd state: still a line
    assert repr(bcr) == "BCR(?)"
