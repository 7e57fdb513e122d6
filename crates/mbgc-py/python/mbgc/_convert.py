"""Conversions between what Python callers pass and what the native module takes: documents
(a path or a dict), float columns (as float64 bytes) and DataFrames."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import pandas as pd

from mbgc.errors import InputError

PathLike = Union[str, "os.PathLike[str]"]

#: The label that names a DataFrame in error messages, where a file's path would stand.
FRAME = "DataFrame"


def document(
    value: Union[PathLike, Mapping[str, Any]], label: str
) -> Tuple[Optional[str], Optional[str], str]:
    """``(path, json, label)`` of a document given as a file path or as a dict."""
    if isinstance(value, Mapping):
        return None, json.dumps(value, allow_nan=False), label
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value), None, label
    raise TypeError(f"{label}: expected a file path or a dict, got {type(value).__name__}")


def float_column(values: Any, file: str, column: str) -> np.ndarray:
    """A column as a float64 array; a value that is not a finite number is refused as the
    command line refuses it in a CSV file (row numbers count from 0, as a DataFrame's positions)."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(
            f"{file}: column {column}: expected numbers ({e})", file, f"column {column}", "numbers"
        ) from None
    if array.ndim != 1:
        raise InputError(
            f"{file}: column {column}: expected one value per row, got shape {array.shape}",
            file,
            f"column {column}",
            "one value per row",
        )
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        row = int(bad[0])
        field = f"column {column}, row {row}"
        expected = f"a finite number, found {array[row]}"
        raise InputError(f"{file}: {field}: expected {expected}", file, field, expected)
    return array


def frame_columns(
    frame: pd.DataFrame, names: Sequence[str], file: str = FRAME
) -> List[np.ndarray]:
    """The columns ``names`` of a DataFrame as float64 arrays, refused by name when missing."""
    columns = [str(c) for c in frame.columns]
    out = []
    for name in names:
        if name not in columns:
            expected = f"no such column; expected one of: {', '.join(columns)}"
            raise InputError(f"{file}: column {name}: {expected}", file, f"column {name}", expected)
        out.append(float_column(frame[name].to_numpy(), file, name))
    return out


def frame_to_columns(frame: pd.DataFrame, names: Sequence[str], file: str) -> List[Tuple[str, List[float]]]:
    """``(name, values)`` pairs of a DataFrame's columns, as the library's in-memory tables take them."""
    return [(n, c.tolist()) for n, c in zip(names, frame_columns(frame, names, file))]


def to_bytes(columns: Sequence[np.ndarray]) -> bytes:
    """Columns one after the other as native float64 bytes."""
    if not columns:
        return b""
    return np.ascontiguousarray(np.stack(columns), dtype=np.float64).tobytes()


def from_bytes(data: bytes, count: int) -> np.ndarray:
    """``count`` columns from native float64 bytes: an array of shape (count, rows)."""
    values = np.frombuffer(data, dtype=np.float64)
    return values.reshape(count, -1) if count else values.reshape(0, 0)


def unique_name(name: str, taken: Sequence[str]) -> str:
    """``name``, or with ``_predicted`` appended until no column has it (as ``mbgc predict``)."""
    while name in taken:
        name = f"{name}_predicted"
    return name


def records(items: Sequence[Mapping[str, Any]], columns: Optional[Sequence[str]] = None) -> pd.DataFrame:
    """A DataFrame of JSON objects (one row each)."""
    frame = pd.DataFrame(list(items))
    if columns is not None:
        frame = frame.reindex(columns=list(columns))
    return frame


def summary(text: str) -> Dict[str, Any]:
    """A JSON object from the native module."""
    value: Dict[str, Any] = json.loads(text)
    return value
