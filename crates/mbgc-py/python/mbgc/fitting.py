"""``fit``: one readable equation per response by genetic programming, from a DataFrame."""

from __future__ import annotations

import os
import warnings
from typing import Callable, List, Optional, Sequence, Union

import pandas as pd

from mbgc import _mbgc
from mbgc._convert import FRAME, PathLike, frame_to_columns
from mbgc.model import Model

__all__ = ["fit"]

FitProgress = Callable[[str, int, float], object]

#: The default function set of ``mbgc fit`` (seed 004's).
FUNCTIONS = "add,sub,mul,div,sqrt,log,exp,tanh"


def _table(data: Union[pd.DataFrame, PathLike], inputs: Sequence[str], targets: Sequence[str], label: str):  # type: ignore[no-untyped-def]
    """``(path, columns)`` of a table file or a DataFrame. A campaign table (one with a
    ``status`` column) loses the rows ``mbgc fit`` leaves out: runs not ``done``, runs that did
    not come to rest (``settled`` false) and runs that measured no value of a target (NaN)."""
    if isinstance(data, pd.DataFrame):
        if "status" in data.columns:
            data = data[data["status"] == "done"]
            if "settled" in data.columns:
                data = data[data["settled"].astype(str).str.lower() != "false"]
            data = data.dropna(subset=[t for t in targets if t in data.columns])
        return None, frame_to_columns(data, list(inputs) + list(targets), label)
    return os.fspath(data), None


def fit(
    data: Union[pd.DataFrame, PathLike],
    inputs: Sequence[str],
    targets: Sequence[str],
    *,
    seed: int = 1,
    population: int = 5000,
    generations: int = 20,
    time_limit: Optional[float] = None,
    test_fraction: float = 0.1,
    space: Optional[PathLike] = None,
    functions: str = FUNCTIONS,
    parsimony: float = 0.001,
    islands: int = 4,
    restarts: int = 1,
    select: str = "best",
    tournament: int = 20,
    max_length: int = 64,
    linear_scaling: bool = True,
    model_class: Optional[str] = None,
    similarity: Optional[str] = None,
    validation: Union[None, pd.DataFrame, PathLike] = None,
    correct: Union[None, Model, PathLike] = None,
    figures: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    progress: Optional[FitProgress] = None,
) -> Model:
    """Fits one equation per target on the inputs, as ``mbgc fit`` does, with its defaults.

    ``data`` is a DataFrame or a table file; of a campaign table (with a ``status`` column) the
    runs ``mbgc fit`` leaves out are left out (not done, not settled, no value of a target).
    The keyword arguments are ``mbgc fit``'s flags (``time_limit`` in seconds, ``select``
    ``"best"`` or ``"cv"``, ``linear_scaling=False`` for ``--no-linear-scaling``); ``space``
    scales the inputs as the space file says, ``similarity`` fits in an experiment's
    dimensionless groups, ``validation`` is a table never trained on, ``correct`` a model whose
    equations the fit corrects. ``figures`` draws parity and residual plots into that
    directory; ``out`` saves the model file. The search runs without the GIL;
    ``progress(response, generation, 1 - R^2)`` is called after each generation. The fit's
    warnings (few test rows, many constants) are issued as :class:`UserWarning`.
    """
    inputs, targets = list(inputs), list(targets)
    data_path, columns = _table(data, inputs, targets, FRAME)
    validation_path = validation_columns = None
    if validation is not None:
        validation_path, validation_columns = _table(validation, inputs, targets, "validation")
    options = {
        "seed": seed,
        "population": population,
        "generations": generations,
        "time_limit": time_limit,
        "functions": functions,
        "parsimony": parsimony,
        "islands": islands,
        "restarts": restarts,
        "select": select,
        "tournament": tournament,
        "max_length": max_length,
        "linear_scaling": linear_scaling,
    }
    corrected = None
    if correct is not None:
        corrected = (correct if isinstance(correct, Model) else Model.load(correct))._native
    native, messages, _figures = _mbgc.fit(
        data_path,
        columns,
        FRAME,
        inputs,
        targets,
        options,
        test_fraction,
        None if space is None else os.fspath(space),
        model_class,
        similarity,
        validation_path,
        validation_columns,
        corrected,
        None if figures is None else os.fspath(figures),
        None if out is None else os.fspath(out),
        progress,
    )
    for message in messages:
        warnings.warn(message, UserWarning, stacklevel=2)
    return Model(native)
