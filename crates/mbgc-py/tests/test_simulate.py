"""simulate: the embedded DEM on a DataFrame of rows into a table that the command line and a
repeated call resume (wall-impact: one particle against a wall, milliseconds per run)."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import List, Optional, Tuple

import pandas as pd
import pytest

import mbgc
from conftest import Cli

# The constants tests/campaign.rs holds wall-impact at: Hertz-Mindlin, a steel sphere.
SET = {"E_p": 380e9, "nu_p": 0.23, "E_w": 1e13, "e_pw": 0.98, "impact_speed": 3.9}
OPTIONS = ["--model-class", "hertz,mindlin"] + [a for k, v in SET.items() for a in ("--set", f"{k}={v!r}")]


def design() -> pd.DataFrame:
    return pd.DataFrame(
        {"impact_angle": [10.0 + 6 * i for i in range(4)], "mu_pw": [0.05 + 0.03 * i for i in range(4)],
         "rho_p": 4000.0, "d50": 5.0}
    )


def test_a_campaign_runs_resumes_and_is_the_command_lines(tmp_path: Path, cli: Optional[Cli]) -> None:
    out = tmp_path / "wall.csv"
    calls: List[Tuple[int, int, bool]] = []
    main = threading.main_thread()

    def progress(done: int, total: int) -> None:
        calls.append((done, total, threading.current_thread() is main))

    table = mbgc.simulate(design(), "wall-impact", out, set=SET, model_class="hertz,mindlin",
                          shard="1/2", threads=2, progress=progress)
    assert list(table["row"]) == [0, 2]
    assert (table["status"] == "done").all()
    assert table["cnr"].between(0.9, 1.0).all()
    assert calls[0][:2] == (0, 2) and calls[-1][:2] == (2, 2)
    assert all(on_main for _, _, on_main in calls), "called on the calling thread, with the GIL"
    summary = table.attrs["summary"]
    assert (summary["done"], summary["skipped"], summary["planned"]) == (2, 0, 2)
    # The whole design: the two rows of the first shard are already in the table.
    table = mbgc.simulate(design(), "wall-impact", out, set=SET, model_class="hertz,mindlin")
    assert list(table["row"]) == [0, 1, 2, 3]
    assert (table.attrs["summary"]["done"], table.attrs["summary"]["skipped"]) == (2, 2)
    again = mbgc.simulate(design(), "wall-impact", out, set=SET, model_class="hertz,mindlin")
    assert again.attrs["summary"]["done"] == 0
    pd.testing.assert_frame_equal(again, table)
    assert Path(mbgc.simulation.design_path(out)).exists()
    if cli is not None:
        # The command line on the same design file resumes the table to a no-op ...
        stdout = cli.ok("simulate", "--design", mbgc.simulation.design_path(out), "--experiment",
                        "wall-impact", "--out", str(out), *OPTIONS)
        assert "4 already in the table, ran 0" in stdout, stdout
        # ... and a fresh run of its own gives the same runs (run ids, seeds, responses).
        fresh = tmp_path / "cli.csv"
        cli.ok("simulate", "--design", mbgc.simulation.design_path(out), "--experiment", "wall-impact",
               "--out", str(fresh), *OPTIONS)
        theirs = pd.read_csv(fresh, float_precision="round_trip").sort_values("row").reset_index(drop=True)
        columns = ["run_id", "row", "seed", "cnr", "ctr", "steps"]
        pd.testing.assert_frame_equal(table[columns], theirs[columns])


def test_a_table_of_another_design_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "wall.csv"
    mbgc.simulate(design().iloc[:2], "wall-impact", out, set=SET, model_class="hertz,mindlin")
    other = design().iloc[2:]
    with pytest.raises(mbgc.InvalidRequestError, match="holds another design"):
        mbgc.simulate(other, "wall-impact", out, set=SET, model_class="hertz,mindlin")
    with pytest.raises(mbgc.InvalidRequestError, match="unknown experiment"):
        mbgc.simulate(design(), "wall-impakt", set=SET)
    with pytest.raises(mbgc.InputError, match=r"column spin_rate"):
        mbgc.simulate(design().assign(spin_rate=1.0), "wall-impact", set=SET, model_class="hertz,mindlin")


def test_a_failing_callback_is_raised_after_the_campaign(tmp_path: Path) -> None:
    def progress(done: int, total: int) -> None:
        if done == 1:
            raise KeyError("stop")

    out = tmp_path / "wall.csv"
    with pytest.raises(KeyError, match="stop"):
        mbgc.simulate(design(), "wall-impact", out, set=SET, model_class="hertz,mindlin", threads=1, progress=progress)
    # The runs were kept: nothing is left to run.
    assert mbgc.simulate(design(), "wall-impact", out, set=SET, model_class="hertz,mindlin").attrs["summary"]["done"] == 0


@pytest.fixture
def ctrl_c_raises():
    """Python turns SIGINT into KeyboardInterrupt only where its parent left SIGINT alone: a test
    run started in the background of a shell inherits it ignored, and interrupt_main then does
    nothing. This installs the handler a terminal's Python has, whatever started this one."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_the_campaign_and_keeps_its_runs(tmp_path: Path, ctrl_c_raises: None) -> None:
    import _thread

    out = tmp_path / "wall.csv"
    many = pd.concat([design()] * 250, ignore_index=True)
    many["impact_angle"] += 1e-4 * many.index  # distinct rows

    def progress(done: int, total: int) -> None:
        # A Ctrl-C as soon as a run is recorded: the signal, as a terminal sends it.
        if done == 1:
            _thread.interrupt_main()

    with pytest.raises(KeyboardInterrupt):
        mbgc.simulate(many, "wall-impact", out, set=SET, model_class="hertz,mindlin", threads=1,
                      progress=progress)
    kept = pd.read_csv(out)
    # Stopped early, and every run that finished before the stop is in the table, whole.
    assert 0 < len(kept) < len(many)
    assert (kept["status"] == "done").all()
    assert kept["row"].is_unique
    # A repeated call goes on from there.
    table = mbgc.simulate(many, "wall-impact", out, set=SET, model_class="hertz,mindlin", threads=1,
                          progress=False)
    assert len(table) == len(many)
    assert table.attrs["summary"]["skipped"] == len(kept)


def test_without_a_callback_a_tqdm_bar_shows_the_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import sys
    import types

    bars: list = []

    class Bar:
        def __init__(self, **kwargs: object) -> None:
            self.total, self.n, self.closed, self.seen = None, 0, False, []
            bars.append(self)

        def refresh(self) -> None:
            self.seen.append((self.n, self.total))

        def close(self) -> None:
            self.closed = True

    auto = types.ModuleType("tqdm.auto")
    auto.tqdm = Bar  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", auto)
    mbgc.simulate(design(), "wall-impact", tmp_path / "a.csv", set=SET, model_class="hertz,mindlin")
    assert len(bars) == 1 and bars[0].closed
    assert bars[0].seen[0] == (0, 4) and bars[0].seen[-1] == (4, 4)
    # False: no bar; anything else that is not a callable is refused.
    mbgc.simulate(design(), "wall-impact", tmp_path / "b.csv", set=SET, model_class="hertz,mindlin", progress=False)
    assert len(bars) == 1
    with pytest.raises(mbgc.InvalidRequestError, match="progress=True"):
        mbgc.simulate(design(), "wall-impact", tmp_path / "c.csv", set=SET, model_class="hertz,mindlin", progress=True)
