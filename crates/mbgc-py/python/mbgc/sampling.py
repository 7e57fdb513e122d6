"""``sample``: a space-filling design of a parameter space, as a DataFrame."""

from __future__ import annotations

import os
from typing import Any, List, Mapping, Optional, Union

import numpy as np
import pandas as pd

from mbgc import _mbgc
from mbgc._convert import PathLike, document, summary

__all__ = ["sample", "sampling_methods"]


def sampling_methods() -> List[str]:
    """The design methods, by the names ``sample`` and ``mbgc sample --method`` take."""
    return list(_mbgc.sampling_methods())


def sample(
    space: Union[None, PathLike, Mapping[str, Any]] = None,
    method: str = "fssf-f",
    n: Optional[int] = None,
    seed: int = 1,
    *,
    dim: Optional[int] = None,
    extend: Optional[PathLike] = None,
    add: Optional[int] = None,
    mipt_alpha: float = 0.5,
    fssf_candidates: Optional[int] = None,
    out: Optional[PathLike] = None,
) -> pd.DataFrame:
    """A design as ``mbgc sample`` makes it: the same points for the same arguments.

    ``space`` is a space file or a dict of the same content (values then in physical units,
    every parameter a column, fixed ones included); without one, ``dim`` gives a bare unit cube
    (columns ``x0``, ``x1``, ...). ``method`` is one of :func:`sampling_methods`; ``n`` points of
    a new design, or ``add`` points after the design file ``extend`` (its points stay first and
    unchanged). ``out`` also writes the design file. ``df.attrs["summary"]`` holds the design's
    summary (MID, COV; points outside the space's constraints).
    """
    path = text = None
    label = "space dict"
    if space is not None:
        path, text, label = document(space, label)
    header, values, info = _mbgc.sample(
        method,
        n,
        add,
        path,
        text,
        label,
        dim,
        seed,
        None if extend is None else os.fspath(extend),
        mipt_alpha,
        fssf_candidates,
        None if out is None else os.fspath(out),
    )
    data = np.frombuffer(values, dtype=np.float64).reshape(-1, len(header))
    frame = pd.DataFrame(data.copy(), columns=header)
    frame.attrs["summary"] = summary(info)
    return frame
