"""diagnose: the ranking and residuals as DataFrames, as `mbgc diagnose --json` reports them."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import mbgc
from conftest import Cli

SET = "examples/measurements/hidden_rolling.toml"


def test_the_hidden_rolling_resistance_is_ranked_first(root: Path, cli: Optional[Cli]) -> None:
    d = mbgc.diagnose(SET, samples=500)
    assert list(d.ranking["effect"])[:2] == ["epsd2", "sjkr"]
    assert len(d.residuals) == 8
    assert list(d.residuals.columns) == ["sample", "response", "measured", "predicted", "sd", "sigma", "z"]
    assert d.chi2_dof is not None and d.chi2_dof > 5
    assert d.ranking["chi2_dof_after"].iloc[0] < 0.2 * d.chi2_dof
    assert list(d.unavailable["effect"]) == ["cdt"]
    assert "Candidate effects, best first" in str(d)
    if cli is not None:
        reference = cli.json("diagnose", "--measurements", SET, "--samples", "500", "--json")
        assert d.chi2_dof == reference["chi2_dof"]
        assert list(d.ranking["log_bayes_factor"]) == [r["log_bayes_factor"] for r in reference["ranking"]]
        assert list(d.residuals["z"]) == [r["z"] for r in reference["residuals"]]
