"""calibrate: the gravel example's solutions, posterior and evidence, as `mbgc calibrate`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import pandas as pd
import pytest

import mbgc
from conftest import Cli

# `mbgc calibrate --material examples/gravel.toml --json`: the first solution (recorded from the
# binary; the same numbers as tests/shipped_model.rs checks the range of).
GRAVEL_BEST = {
    "mu_pp": 0.23281466728246303,
    "rho_p": 2494.8309046328536,
    "d50": 11.157682393638199,
    "sigma_ln": 0.2632605712620108,
    "E_p": 4e7,
    "mu_r_pp": 0.8,
}
GRAVEL_PREDICTED = {"shear_angle": 35.52999999999997, "bulk_density": 1478.8}
# ... with --bayes --samples 200: the log evidence.
GRAVEL_LOG_EVIDENCE = -11.111350490274198


def close(a: float, b: float, rel: float = 1e-12) -> bool:
    return math.isclose(a, b, rel_tol=rel, abs_tol=1e-300)


def test_the_gravel_calibration_gives_the_command_lines_first_solution(root: Path, cli: Optional[Cli]) -> None:
    result = mbgc.calibrate("examples/gravel.toml")
    assert result.model == "models/shear_box.json", "the shipped model is the default"
    best = result.solutions.iloc[0]
    if cli is not None:
        reference = cli.json("calibrate", "--material", "examples/gravel.toml", "--json")
        first = reference["solutions"][0]
        for name, value in first["params"].items():
            assert best[name] == value, name
        for name, value in first["predicted"].items():
            assert best[name] == value, name
        assert best["objective"] == first["objective"]
        assert list(result.solutions["fits"]) == [s["fits"] for s in reference["solutions"]]
    for name, value in {**GRAVEL_BEST, **GRAVEL_PREDICTED}.items():
        assert close(float(best[name]), value), (name, best[name], value)
    # Two free parameters, two measurements: one optimum fits, one local minimum does not.
    assert list(result.solutions["fits"]) == [True, False]
    assert len(result.fitting) == 1 and len(result.local_minima) == 1
    assert result.unique
    assert result.free == ["mu_pp", "rho_p"]
    assert result.best["mu_pp"] == best["mu_pp"]
    assert result.posterior is None and result.log_evidence is None
    assert list(result.measured["name"]) == ["shear_angle", "bulk_density"]
    text = str(result)
    assert "1 of 2 distinct optima" in text and "mu_pp = 0.2328" in text, text
    assert "local minima that do not fit" in text


def test_a_dict_calibrates_as_its_file(root: Path) -> None:
    material = {
        "name": "Gravel 8/16",
        "psd": {"sieve": str(root / "examples/sieve_gravel_8_16.csv")},
        "measured": {
            "shear_angle": {"value": 35.53, "sd": 0.5},
            "bulk_density": {"value": 1478.8, "sd": 10},
        },
        "fixed": {
            "mu_pw": 0.363, "e_pp": 0.6, "e_pw": 0.6, "mu_r_pp": 0.8, "mu_r_pw": 0.8,
            "E_p": 4e7, "E_w": 4e7, "nu_p": 0.25,
        },
    }
    from_dict = mbgc.calibrate(material)
    from_file = mbgc.calibrate(root / "examples/gravel.toml")
    pd.testing.assert_frame_equal(from_dict.solutions, from_file.solutions)
    assert from_dict.source == "material dict"


def test_the_posterior_is_a_dataframe_and_the_evidence_the_command_lines(root: Path, cli: Optional[Cli]) -> None:
    result = mbgc.calibrate("examples/gravel.toml", bayes=True, samples=200)
    assert result.posterior is not None and result.posterior_summary is not None
    assert list(result.posterior.columns) == ["mu_pp", "rho_p", "sigma"]
    assert len(result.posterior) == 200
    assert result.log_evidence is not None
    reference = GRAVEL_LOG_EVIDENCE
    if cli is not None:
        reference = cli.json("calibrate", "--material", "examples/gravel.toml", "--bayes", "--samples", "200", "--json")["log_evidence"]
    assert close(result.log_evidence, reference), (result.log_evidence, reference)
    mean = result.posterior["mu_pp"].mean()
    assert close(mean, float(result.posterior_summary.loc["mu_pp", "mean"]), 1e-9)
    assert "Posterior (TMCMC, 200 samples" in str(result)


def test_several_models_compare_as_model_classes(root: Path) -> None:
    results = mbgc.calibrate("examples/gravel.toml", ["models/shear_box.json", mbgc.Model.shipped()], bayes=True, samples=100)
    assert len(results) == 2
    probabilities = [r.class_probability for r in results]
    assert all(p is not None for p in probabilities)
    assert math.isclose(sum(probabilities), 1.0)  # type: ignore[arg-type]


def test_free_searches_a_fixed_parameter_and_refuses_one_that_is_not_fixed(root: Path) -> None:
    result = mbgc.calibrate("examples/gravel.toml", free=["mu_r_pp"])
    assert result.free == ["mu_pp", "mu_r_pp", "rho_p"]
    assert "mu_r_pp" not in result.fixed
    # Three free parameters, two measurements: a set of solutions, not one answer.
    assert result.json["calibration"]["excess_parameters"] == 1
    assert not result.unique
    with pytest.raises(mbgc.InvalidRequestError) as e:
        mbgc.calibrate("examples/gravel.toml", free=["mu_p"])
    assert str(e.value).startswith("--free mu_p: examples/gravel.toml does not fix mu_p (it fixes: mu_pw,")
