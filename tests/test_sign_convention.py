"""A sensor whose sign convention is the model's opposite (a load cell reading tension where the model's force is
compression, an accelerometer mounted upside down): the linear nominal then fits no calibration file, and the
diagnosis says which channel fits once its sign is changed, and how to write that in the sidecar, before trying
any effect. The files are written by the independent CasADi reference with a random noise seed; the channel's
sign is changed by the sidecar (`invert = true`), as a lab's opposite convention would record it."""
import re

import numpy as np
import pytest

from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap.polarity import with_signs_changed
from pyfit.gap.simulate import Record

from gap_cases import CI


def test_a_sensor_recorded_in_the_opposite_sign_convention_is_named_with_its_fix(tmp_path, fmu_dir):
    seed = int(np.random.default_rng().integers(1 << 30))
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "none", seed=seed, periods=2)
    flipped = []
    for side in sorted(data.glob("*.toml")):
        text = side.read_text()
        outputs = text[text.index("[outputs]"):]
        # every output column of the sidecar gets `invert = true` (the SDOF records one)
        changed = re.sub(r"^(\S+ = \{.*?model_variable = \"(\w+)\".*?) \}$", r"\1, invert = true }", outputs,
                         flags=re.M)
        flipped += re.findall(r"model_variable = \"(\w+)\"", outputs)
        side.write_text(text.replace(outputs, changed))
    assert flipped and len(set(flipped)) == 1, flipped
    with pytest.raises(dg.DiagnoseError) as err:
        dg.diagnose("sdof", data, tmp_path / "out", CI, fmu_dir, workers=2, progress=False)
    msg = str(err.value)
    found = re.search(r"fits no calibration file as recorded \(NRMSE ([\d.]+)\) but fits them with the sign of "
                      rf"{flipped[0]} changed \(NRMSE ([\d.]+)\)", msg)
    assert found, msg
    as_recorded, changed = map(float, found.groups())
    # as recorded no better than predicting zero; changed in sign within the nominal's own fit criterion
    assert as_recorded > 0.95 and changed <= CI.nominal_max_nrmse, msg
    assert "`invert = true` on the column recorded as" in msg and str(data) in msg and "\n" not in msg


def test_signs_are_changed_only_on_the_outputs_named():
    rec = Record("r", "1", 1.0, 100.0, {"u": np.ones(4)}, {"y": np.arange(4.0), "a": np.ones(4)}, 0)
    (changed,) = with_signs_changed([rec], ("y",))
    assert np.array_equal(changed.outputs["y"], -np.arange(4.0)) and np.array_equal(changed.outputs["a"], np.ones(4))
    assert changed.inputs is rec.inputs and np.array_equal(rec.outputs["y"], np.arange(4.0))  # the record kept
