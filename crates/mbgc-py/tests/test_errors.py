"""Bad input raises the exception of its kind, with the command line's message: the file, the
field and what was expected."""

from __future__ import annotations

import errno
from pathlib import Path
from typing import Optional

import numpy as np
import pandas as pd
import pytest

import mbgc
from conftest import Cli


def test_a_missing_file_is_a_file_error_naming_it(root: Path, cli: Optional[Cli]) -> None:
    with pytest.raises(mbgc.FileError) as e:
        mbgc.calibrate("nope.toml")
    assert isinstance(e.value, OSError) and isinstance(e.value, mbgc.MbgcError)
    assert e.value.file == "nope.toml" and e.value.errno == errno.ENOENT
    assert str(e.value) == "nope.toml: No such file or directory (os error 2)"
    if cli is not None:
        assert str(e.value) == cli.error("calibrate", "--material", "nope.toml")
    with pytest.raises(mbgc.FileError, match="no_model.json"):
        mbgc.load_model("no_model.json")


def test_a_bad_field_is_an_input_error_naming_file_field_and_expectation(tmp_path: Path, cli: Optional[Cli]) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[measured]\nshear_angle = { value = 35, sd = -1 }\n")
    with pytest.raises(mbgc.InputError) as e:
        mbgc.calibrate(path)
    assert isinstance(e.value, ValueError)
    assert (e.value.file, e.value.field) == (str(path), "measured.shear_angle.sd")
    assert str(e.value) == f"{path}: measured.shear_angle.sd: expected a standard deviation > 0, got -1"
    if cli is not None:
        assert str(e.value) == cli.error("calibrate", "--material", str(path))
    path.write_text("[measured]\nshear_angle = { value = 35, sd = 1 }\n[fixd]\nmu_pp = 0.3\n")
    with pytest.raises(mbgc.InputError, match=r"bad.toml: fixd: unknown key; expected one of: name, psd, measured"):
        mbgc.calibrate(path)
    # A dict is named as such, and None (which TOML cannot hold) is refused by its key.
    with pytest.raises(mbgc.InputError) as e:
        mbgc.calibrate({"measured": {"shear_angle": {"value": 35, "sd": 0}}})
    assert e.value.file == "material dict" and e.value.field == "measured.shear_angle.sd"
    with pytest.raises(mbgc.InputError, match=r"material dict: measured.shear_angle.sd: expected a value; TOML has no None"):
        mbgc.calibrate({"measured": {"shear_angle": {"value": 35, "sd": None}}})


def test_a_fixed_value_outside_the_models_domain_is_out_of_domain(root: Path) -> None:
    material = {
        "measured": {"shear_angle": {"value": 35.0, "sd": 0.5}},
        "psd": {"d50_mm": 11.0, "sigma_ln": 0.2},
        "fixed": {"mu_pw": 5.0},
    }
    with pytest.raises(mbgc.OutOfDomainError) as e:
        mbgc.calibrate(material)
    assert e.value.file == "material dict" and e.value.field == "fixed.mu_pw"


def test_bad_data_frames_are_refused_naming_the_column_and_row() -> None:
    model = mbgc.Model.shipped()
    frame = pd.DataFrame({n: [1.0, 2.0] for n in model.inputs})
    with pytest.raises(mbgc.InputError) as e:
        model.predict(frame.drop(columns=["mu_pp"]))
    assert e.value.file == "DataFrame" and e.value.field == "column mu_pp"
    assert str(e.value).startswith("DataFrame: column mu_pp: no such column; expected one of: E_p, E_w")
    frame.loc[1, "rho_p"] = np.nan
    with pytest.raises(mbgc.InputError, match=r"DataFrame: column rho_p, row 1: expected a finite number, found nan"):
        model.predict(frame)
    with pytest.raises(mbgc.InvalidRequestError, match=r"--starts 0: expected 1 to"):
        mbgc.calibrate({"measured": {"shear_angle": {"value": 35, "sd": 1}}}, starts=0)
