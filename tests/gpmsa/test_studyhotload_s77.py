"""A study file's hot record names its models' own parameters, of their shapes: on loading,
settings.hot_states.members refuses a name the model does not have (theta is the study's,
hot_states.theta) or a value of another shape, naming the file, the model and the parameter.
Before: only the chains and copies were checked; the continuation refused the record later."""

import pytest
from test_studyhot_s76 import _damaged

import gpmsa

COPIES = [[[1.0]] * 3] * 2  # (chains, hot copies, 1)


def _member(lab, name, value):
    def edit(settings):
        settings["hot_states"]["members"][lab][name] = value

    return edit


@pytest.mark.parametrize(
    ("lab", "name", "value", "message"),
    [("a", "lamVz", COPIES, r"members\.a\.lamVz: names no parameter of model 'a' \(its own: "
                            r"\['betaU', 'lamOs', 'lamUz', 'lamWOs', 'lamWs'\]"),
     ("b", "theta", [[[0.5]] * 3] * 2, r"members\.b\.theta: names no parameter of model 'b'.*"
                                       r"theta is the study's"),
     ("a", "lamOs", [[[1.0, 2.0]] * 3] * 2, r"members\.a\.lamOs: has shape \[2, 3, 2\], expected "
                                            r"\[2, 3, 1\].*lamOs's shape \[1\] in model 'a'"),
     ("b", "betaU", [[[1.0]] * 3] * 2, r"members\.b\.betaU: has shape \[2, 3, 1\], expected "
                                       r"\[2, 3, 1, 1\]")],
    ids=["not-its-own", "theta", "lamOs-shape", "betaU-shape"],
)  # fmt: skip
def test_a_hot_record_naming_another_parameter_or_shape_is_refused_on_loading(
    tmp_path, lab, name, value, message
):
    path = _damaged(tmp_path, _member(lab, name, value))
    with pytest.raises(gpmsa.EmulatorFileError, match=rf"s\.gpmsastudy: settings\.hot_states\."
                                                      rf"{message}"):  # fmt: skip
        gpmsa.load_study(path)
