"""fit: a DataFrame fitted in memory gives the equation `mbgc fit` gives for its CSV file."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import List, Optional, Tuple

import numpy as np
import pandas as pd
import pytest

import mbgc
from conftest import Cli


def plane() -> pd.DataFrame:
    """y = 0.2 + 0.5 a + 0.3 b on a 6 x 6 grid of the unit square (tests/library_api.rs's)."""
    a, b = np.meshgrid(np.arange(6) / 5.0, np.arange(6) / 5.0, indexing="ij")
    a, b = a.ravel(), b.ravel()
    return pd.DataFrame({"a": a, "b": b, "y": 0.2 + 0.5 * a + 0.3 * b})


def test_a_dataframe_fits_as_its_csv_file(tmp_path: Path, cli: Optional[Cli]) -> None:
    calls: List[Tuple[str, int, float]] = []
    model = mbgc.fit(
        plane(), ["a", "b"], ["y"], population=300, generations=10, seed=3, test_fraction=0.0,
        progress=lambda r, g, e: calls.append((r, g, e)),
    )
    info = model.info["responses"][0]
    assert info["train"]["r2"] > 0.999
    assert calls and calls[0][:2] == ("y", 1)
    assert model.inputs == ["a", "b"] and model.responses == ["y"]
    np.testing.assert_allclose(model.predict(plane())["y"], plane()["y"], atol=1e-3)
    data = tmp_path / "plane.csv"
    plane().to_csv(data, index=False)
    from_file = mbgc.fit(data, ["a", "b"], ["y"], population=300, generations=10, seed=3, test_fraction=0.0)
    assert from_file.equation("y") == model.equation("y")
    if cli is not None:
        out = tmp_path / "cli.json"
        cli.ok("fit", "--data", str(data), "--inputs", "a,b", "--targets", "y", "--population", "300",
               "--generations", "10", "--seed", "3", "--test-fraction", "0", "--no-figures", "--out", str(out))
        assert json.loads(out.read_text())["responses"][0]["equation"] == model.equation("y")


def test_fit_refuses_what_the_command_line_refuses() -> None:
    with pytest.raises(mbgc.InvalidRequestError, match="--parsimony"):
        mbgc.fit(plane(), ["a", "b"], ["y"], parsimony=-1.0)
    with pytest.raises(mbgc.InputError, match="DataFrame: column z: no such column"):
        mbgc.fit(plane(), ["a", "b"], ["z"])


def test_the_search_runs_without_the_gil() -> None:
    """A Python thread keeps running while the fit searches (it would stall if the GIL were held)."""
    ticks = 0
    running = True

    def count() -> None:
        nonlocal ticks
        while running:
            ticks += 1
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    thread.start()
    try:
        # A target no small tree fits, so the search runs every generation (about half a second).
        rng = np.random.default_rng(1)
        a, b = rng.random(200), rng.random(200)
        wavy = pd.DataFrame({"a": a, "b": b, "y": np.sin(7 * a) + 0.3 * np.cos(31 * b)})
        t0 = time.perf_counter()
        mbgc.fit(wavy, ["a", "b"], ["y"], population=2000, generations=5, seed=5, test_fraction=0.0)
        seconds = time.perf_counter() - t0
        during = ticks
    finally:
        running = False
        thread.join()
    # A millisecond sleep wakes a few hundred times per second; held, the GIL would allow ~0.
    assert seconds > 0.1 and during > 20 * seconds, (during, seconds)
