"""``simulate``: a DEM calibration experiment for every row of a design, into a resumable table."""

from __future__ import annotations

import os
import tempfile
import warnings
from typing import Callable, List, Mapping, Optional, Union

import pandas as pd

from mbgc import _mbgc
from mbgc._convert import FRAME, PathLike, float_column, summary
from mbgc.errors import InvalidRequestError

__all__ = ["simulate", "experiments", "design_path"]

Progress = Callable[[int, int], object]


def _tqdm_progress(experiment: str):
    """A ``progress`` callable drawing a tqdm bar, and the bar; ``(None, None)`` without tqdm."""
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, None
    bar = tqdm(desc=f"mbgc simulate {experiment}", unit="run")

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    return progress, bar


def experiments() -> List[str]:
    """The experiments ``simulate`` runs, by the names ``mbgc simulate --experiment`` takes."""
    return list(_mbgc.experiment_names())


def design_path(out: PathLike) -> str:
    """Where :func:`simulate` keeps the design of a DataFrame for the table ``out``: beside it,
    ``<out stem>.design.csv``, so that the campaign can be resumed (also by ``mbgc simulate
    --design <that file> --out <out>``)."""
    out = os.fspath(out)
    stem, _ = os.path.splitext(out)
    return f"{stem}.design.csv"


def _design_csv(design: pd.DataFrame) -> str:
    lines = [",".join(str(c) for c in design.columns)]
    columns = [float_column(design[c].to_numpy(), FRAME, str(c)) for c in design.columns]
    for row in zip(*columns):
        # repr: the shortest text that reads back as the same float64.
        lines.append(",".join(repr(float(v)) for v in row))
    return "\n".join(lines) + "\n"


def _keep_design(design: pd.DataFrame, path: str) -> None:
    """Writes the DataFrame's design file; one already there must be this design or its start
    (the rows of a design extended since), or the table beside it belongs to another campaign."""
    text = _design_csv(design)
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            old = f.read()
        if old == text:
            return
        if not text.startswith(old):
            message = (
                f"{path}: holds another design than this DataFrame (the table beside it is that "
                f"design's campaign); choose another out, or pass that file as the design"
            )
            raise InvalidRequestError(message)
    tmp = f"{path}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def simulate(
    design: Union[pd.DataFrame, PathLike],
    experiment: str,
    out: Optional[PathLike] = None,
    *,
    set: Optional[Mapping[str, float]] = None,
    seed: int = 1,
    threads: Optional[int] = None,
    shard: Optional[str] = None,
    model_class: Optional[str] = None,
    box_scale: Optional[float] = None,
    backend: str = "embedded",
    mpi: Optional[int] = None,
    retry_failed: bool = False,
    vtk: Optional[PathLike] = None,
    progress: Union[Progress, None, bool] = None,
) -> pd.DataFrame:
    """Runs ``experiment`` (one of :func:`experiments`) on every row of ``design``, as
    ``mbgc simulate --out`` does, and returns the campaign table as a DataFrame.

    ``design`` is a DataFrame (one run per row, a column per parameter) or a design file. With
    ``out``, every finished run is appended to that table as it ends, and a repeated call (or
    ``mbgc simulate``) resumes: rows already there are not run again. A DataFrame's design is
    kept beside the table (:func:`design_path`). Without ``out`` the table is temporary.

    ``set`` holds parameters constant for every row (``--set``); ``model_class`` names the
    contact law's effects (e.g. ``"hertz,mindlin"``); ``shard="K/N"`` runs one slice of the
    rows. The DEM runs on ``threads`` threads (default: all cores) without holding the GIL;
    ``progress(done, total)`` is called with the GIL at the start and after each run; without
    it a tqdm bar shows the runs when tqdm is installed (``progress=False``: nothing).
    ``df.attrs["summary"]`` holds the counts ``--json`` prints; failed runs are in the table
    (``status`` ``failed``, their reason in ``error``) and are warned of. A Ctrl-C
    (``KeyboardInterrupt``) stops the campaign after the runs in flight, which are kept in the
    table ``out`` (without ``out`` they go with the temporary table): call again to go on. On
    the LIGGGHTS backend a terminal's Ctrl-C also reaches the solver processes, so their runs in
    flight are recorded as failed (``retry_failed=True`` runs them again).
    """
    with tempfile.TemporaryDirectory(prefix="mbgc-simulate-") as scratch:
        table = os.path.join(scratch, "campaign.csv") if out is None else os.fspath(out)
        if isinstance(design, pd.DataFrame):
            path = design_path(table)
            _keep_design(design, path)
        else:
            path = os.fspath(design)
        pairs = [(str(k), float(v)) for k, v in (set or {}).items()]
        bar = None
        if progress is None:
            progress, bar = _tqdm_progress(experiment)
        elif progress is False:
            progress = None
        elif not callable(progress):
            raise InvalidRequestError(
                f"progress={progress!r}: expected a callable progress(done, total), None (a tqdm "
                "bar when tqdm is installed) or False (nothing)"
            )
        try:
            native = _mbgc.simulate(
                path,
                experiment,
                table,
                pairs,
                seed,
                threads,
                shard,
                model_class,
                box_scale,
                backend,
                mpi,
                retry_failed,
                None if vtk is None else os.fspath(vtk),
                progress,
            )
        finally:
            if bar is not None:
                bar.close()
        info = summary(native)
        # round_trip: pandas' default parser can be one bit off the float64 the table holds.
        frame = pd.read_csv(table, float_precision="round_trip").sort_values("row", kind="stable").reset_index(drop=True)
    if out is None:
        info["out"] = None
    failed = info["failed"] + info["failed_before"]
    if failed:
        first = info.get("first_failure")
        warnings.warn(
            f"{failed} of the {info['planned']} runs of {info['out'] or 'the campaign'} failed "
            f"({info['failed']} in this call, {info['failed_before']} earlier): they have "
            "status=failed and their reason in the error column; rerun with retry_failed=True"
            + (f"; the first failed here, run {first['run_id']}: {first['error']}" if first else ""),
            RuntimeWarning,
            stacklevel=2,
        )
    if info.get("added_columns"):
        warnings.warn(
            f"{info['out']}: added the column(s) {', '.join(info['added_columns'])} that the "
            "experiment records since the table was written, filled for its earlier runs from "
            "what their lines tell, NaN where they cannot",
            RuntimeWarning,
            stacklevel=2,
        )
    frame.attrs["summary"] = info
    return frame
