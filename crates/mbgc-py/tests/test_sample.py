"""sample: the same design points as `mbgc sample` for the same arguments."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import pandas as pd
import pytest

import mbgc
from conftest import Cli

# `mbgc sample --method fssf-f --n 10 --space examples/space_shear_box.toml --seed 1`: the
# first two rows of the design file (recorded from the binary).
FSSF_FIRST = [
    [8294193.138667748, 13354560.170222988, 0.4964488983154297, 0.5279819786548614, 0.941893720626831,
     0.8084786832332611, 0.802483081817627, 0.38560688495635986, 0.1983705759048462, 2600.0, 10.0,
     0.1467831075191498],
    [46702159.17636169, 33771706.89060033, 0.1181419849395752, 0.9241588711738586, 0.33683655261993406,
     0.7016806244850159, 0.02715468406677246, 0.09962689876556396, 0.9074063301086426, 2600.0, 10.0,
     0.19865415453910829],
]
HEADER = ["E_p", "E_w", "nu_p", "e_pp", "e_pw", "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "rho_p", "d50", "sigma_ln"]


def test_a_design_starts_with_the_command_lines_points(root: Path, cli: Optional[Cli], tmp_path: Path) -> None:
    design = mbgc.sample("examples/space_shear_box.toml", "fssf-f", 10, seed=1)
    assert list(design.columns) == HEADER
    assert len(design) == 10
    assert design.iloc[:2].to_numpy().tolist() == FSSF_FIRST
    assert design.attrs["summary"]["metrics"]["mid"] > 0
    if cli is not None:
        out = tmp_path / "d.csv"
        cli.ok("sample", "--method", "fssf-f", "--n", "10", "--space", "examples/space_shear_box.toml",
               "--seed", "1", "--out", str(out))
        pd.testing.assert_frame_equal(design, pd.read_csv(out, float_precision="round_trip"), check_exact=True)


def test_out_writes_the_file_the_command_line_writes_and_extend_adds_after_it(root: Path, tmp_path: Path) -> None:
    out = tmp_path / "sobol.csv"
    first = mbgc.sample(dim=3, method="sobol", n=8, seed=4, out=out)
    assert list(first.columns) == ["x0", "x1", "x2"]
    more = mbgc.sample(dim=3, method="sobol", extend=out, add=8, seed=4)
    at_once = mbgc.sample(dim=3, method="sobol", n=16, seed=4)
    assert np.array_equal(more.to_numpy(), at_once.to_numpy())
    assert more.attrs["summary"]["existing"] == 8
    with pytest.raises(mbgc.InvalidRequestError, match="--n with --extend"):
        mbgc.sample(dim=3, method="sobol", extend=out, n=4)


def test_a_space_dict_samples_as_its_file(root: Path) -> None:
    space = {"parameters": {"mu": {"min": 0.1, "max": 0.9}, "E": {"min": 1e6, "max": 1e8, "scale": "log"}}}
    design = mbgc.sample(space, "halton", 5, seed=2)
    assert list(design.columns) == ["mu", "E"]
    assert design["E"].between(1e6, 1e8).all()
    with pytest.raises(mbgc.InputError) as e:
        mbgc.sample({"parameters": {"mu": {"min": 1.0, "max": 0.0}}}, "sobol", 4)
    assert e.value.file == "space dict" and "mu" in str(e.value)
    with pytest.raises(mbgc.InvalidRequestError, match="expected one of fssf-f"):
        mbgc.sample(space, "grid", 4)
