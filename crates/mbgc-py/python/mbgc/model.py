"""A saved metamodel: predictions on DataFrames and arrays, its equations as a PySR-like table,
as numpy functions and as sympy expressions."""

from __future__ import annotations

import json
import math
import os
import warnings
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union, overload

import numpy as np
import pandas as pd

from mbgc import _mbgc
from mbgc._convert import FRAME, PathLike, float_column, frame_columns, from_bytes, to_bytes, unique_name
from mbgc.errors import ExtrapolationWarning, InputError
from mbgc.numpy_equations import NumpyEquation, compile_equation

__all__ = ["Model", "load_model", "SHIPPED"]

#: The model a calibration uses when none is given, as the command line's ``--model`` default.
SHIPPED = "models/shear_box.json"


class Model:
    """A metamodel written by ``mbgc fit`` or ``mbgc train``: one equation per response.

    Load one with :meth:`load` (or :func:`load_model`); :meth:`shipped` gives the models
    built into mbgc. ``source`` is the name it is reported under (its path).
    """

    def __init__(self, native: "_mbgc.NativeModel") -> None:
        self._native = native
        self._info: Optional[Dict[str, Any]] = None
        self._numpy: Optional[Dict[str, NumpyEquation]] = None

    @classmethod
    def load(cls, path: PathLike) -> "Model":
        """Reads a model file (JSON)."""
        return cls(_mbgc.NativeModel.load(os.fspath(path)))

    @classmethod
    def shipped(cls, name: str = "shear_box") -> "Model":
        """A model shipped with mbgc: ``shear_box`` (the default of :func:`mbgc.calibrate`),
        ``shear_box_sjkr`` (with cohesion) or ``shear_cell`` (the shear cell's yield locus)."""
        return cls(_mbgc.NativeModel.shipped(name))

    @classmethod
    def from_json(cls, text: str, source: str = "<json>") -> "Model":
        """A model from the text of its JSON file; ``source`` names it in errors."""
        return cls(_mbgc.NativeModel.from_json(text, source))

    @property
    def source(self) -> str:
        """The path (or label) the model is reported under."""
        return self._native.label

    @property
    def inputs(self) -> List[str]:
        """The physical inputs, in the order the equations number them."""
        return self._native.input_names()

    @property
    def responses(self) -> List[str]:
        """The responses, one equation each."""
        return self._native.response_names()

    @property
    def constants(self) -> Dict[str, float]:
        """Parameters the model's campaign held at one value (the model holds there only)."""
        return dict(self._native.constants())

    @property
    def info(self) -> Dict[str, Any]:
        """The model file's content (equations, metrics, Pareto fronts, settings) as a dict."""
        if self._info is None:
            self._info = json.loads(self._native.to_json())
        return self._info

    @property
    def domain(self) -> pd.DataFrame:
        """Each input's valid range (the training data's) and scaling, indexed by input."""
        rows = [
            {"input": i["name"], "min": i["domain"][0], "max": i["domain"][1], "scale": i["transform"]["kind"]}
            for i in self.info["inputs"]
        ]
        return pd.DataFrame(rows).set_index("input")

    @property
    def equations(self) -> pd.DataFrame:
        """Every response's Pareto front of size against error, as PySR's ``equations_``:
        ``complexity`` (nodes), ``loss`` (1 - R^2 on the training rows), ``score`` (the drop of
        ln loss per added node), ``equation``, the R^2 on train, test and cross-validation, and
        ``selected`` marking the equation the model uses."""
        rows = []
        for r in self.info["responses"]:
            previous = None
            for f in r["pareto_front"]:
                loss = 1.0 - f["train_r2"]
                score = 0.0
                if previous is not None and f["size"] > previous[0]:
                    score = -(math.log(max(loss, 1e-300)) - math.log(max(previous[1], 1e-300))) / (
                        f["size"] - previous[0]
                    )
                previous = (f["size"], loss)
                rows.append(
                    {
                        "response": r["name"],
                        "complexity": f["size"],
                        "loss": loss,
                        "score": score,
                        "equation": f["equation"],
                        "train_r2": f["train_r2"],
                        "test_r2": f.get("test_r2"),
                        "cv_r2": f.get("cv_r2"),
                        "selected": f["size"] == r["size"],
                    }
                )
        return pd.DataFrame(
            rows,
            columns=["response", "complexity", "loss", "score", "equation", "train_r2", "test_r2", "cv_r2", "selected"],
        )

    def equation(self, response: str) -> str:
        """The selected equation of ``response`` in the inputs' symbols (Python syntax)."""
        for r in self.info["responses"]:
            if r["name"] == response:
                return str(r["equation"])
        raise KeyError(f"{self.source}: no response {response}; expected one of: {', '.join(self.responses)}")

    def export(self, format: str) -> str:
        """The equations as ``mbgc export --format`` writes them: ``rust``, ``latex`` or ``sympy``."""
        return self._native.export(format)

    def to_json(self) -> str:
        """The model file's JSON text."""
        return self._native.to_json()

    def save(self, path: PathLike) -> None:
        """Writes the model file."""
        self._native.save(os.fspath(path))

    def __repr__(self) -> str:
        return f"<mbgc.Model {self.source}: {', '.join(self.responses)} of {', '.join(self.inputs)}>"

    # -- predictions ------------------------------------------------------------------------

    def _predict_columns(self, columns: Sequence[np.ndarray], held: Mapping[str, np.ndarray], rows: int, where: str) -> np.ndarray:
        out, outside, first = self._native.predict(rows, to_bytes(columns), list(held), to_bytes(list(held.values())))
        predictions = from_bytes(out, len(self.responses))
        if outside:
            warnings.warn(
                f"{outside} of {rows} rows {where}lie outside the model's valid domain "
                f"(extrapolation); first: {first}",
                ExtrapolationWarning,
                stacklevel=3,
            )
        nan = int(np.count_nonzero(~np.isfinite(predictions)))
        if nan:
            warnings.warn(f"{nan} predictions are not finite (NaN)", ExtrapolationWarning, stacklevel=3)
        return predictions

    @overload
    def predict(self, data: pd.DataFrame) -> pd.DataFrame: ...
    @overload
    def predict(self, data: Mapping[str, Any]) -> Dict[str, np.ndarray]: ...
    @overload
    def predict(self, data: np.ndarray) -> np.ndarray: ...

    def predict(self, data: Union[pd.DataFrame, Mapping[str, Any], np.ndarray]) -> Any:
        """Evaluates every response, as ``mbgc predict`` does.

        - a DataFrame with (at least) the input columns: the DataFrame with one column per
          response appended (``<name>_predicted`` if it already has one of that name);
        - a mapping of input name to 1-D array: a dict of response name to array;
        - an array of shape ``(rows, len(inputs))`` in :attr:`inputs` order: an array of shape
          ``(rows, len(responses))`` (a single point of shape ``(len(inputs),)`` gives
          ``(len(responses),)``).

        Rows outside the model's valid domain (an input outside its training range, a
        dimensionless group outside its range, a held constant of another value) are
        predicted anyway, with an :class:`~mbgc.errors.ExtrapolationWarning`; values that are
        not finite are NaN. Inputs must be finite numbers (:class:`~mbgc.errors.InputError`).
        """
        names = self.inputs
        if isinstance(data, pd.DataFrame):
            columns = frame_columns(data, names)
            taken = [str(c) for c in data.columns]
            held = {
                c: float_column(data[c].to_numpy(), FRAME, c)
                for c in self.constants
                if c in taken and c not in names
            }
            predictions = self._predict_columns(columns, held, len(data), "of the DataFrame ")
            result = data.copy()
            for name, values in zip(self.responses, predictions):
                label = unique_name(name, taken)
                taken.append(label)
                result[label] = values
            return result
        if isinstance(data, Mapping):
            missing = [n for n in names if n not in data]
            if missing:
                field = f"column {missing[0]}"
                expected = f"no such column; expected one of: {', '.join(map(str, data))}"
                raise InputError(f"{FRAME}: {field}: {expected}", FRAME, field, expected)
            columns = [float_column(np.ravel(np.asarray(data[n], dtype=np.float64)), "input", n) for n in names]
            rows = len(columns[0]) if columns else 0
            held = {
                c: float_column(np.ravel(np.asarray(data[c], dtype=np.float64)), "input", c)
                for c in self.constants
                if c in data and c not in names
            }
            predictions = self._predict_columns(columns, held, rows, "")
            return dict(zip(self.responses, predictions))
        matrix = np.asarray(data, dtype=np.float64)
        single = matrix.ndim == 1
        if single:
            matrix = matrix[np.newaxis, :]
        if matrix.ndim != 2 or matrix.shape[1] != len(names):
            field = "array"
            expected = f"shape (rows, {len(names)}) with columns {', '.join(names)}, got {np.shape(data)}"
            raise InputError(f"input: {field}: expected {expected}", "input", field, expected)
        columns = [float_column(matrix[:, k], "input", n) for k, n in enumerate(names)]
        predictions = self._predict_columns(columns, {}, matrix.shape[0], "").T
        return predictions[0] if single else predictions

    # -- the equations in other forms -------------------------------------------------------

    def to_numpy(self) -> Dict[str, NumpyEquation]:
        """Each response's equation as a vectorised numpy function of the physical inputs
        (see :class:`~mbgc.numpy_equations.NumpyEquation` for how to call it). Agrees with
        :meth:`predict` to the last bits (``exp``/``log``/``tanh`` are numpy's) wherever the
        dimensionless groups lie in their training range; beyond it, where a model with a rigid
        limit reads the equations on the range's edge and adds the measured shift, these are
        the equations alone."""
        if self._numpy is None:
            inputs = self.info["inputs"]
            self._numpy = {
                r["name"]: compile_equation(r["name"], r["program"], inputs) for r in self.info["responses"]
            }
        return dict(self._numpy)

    def to_sympy(self) -> Dict[str, Any]:
        """Each response's equation as a sympy expression in the physical inputs (the input
        scaling written out), read from ``mbgc export --format sympy``'s text. Needs sympy."""
        try:
            import sympy  # type: ignore[import-untyped]
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Model.to_sympy() needs sympy: pip install sympy") from e
        equations, _ = self._native.sympy_equations()
        return {name: sympy.sympify(text) for name, text in equations}


def load_model(path: Optional[PathLike] = None) -> Model:
    """The model file at ``path``; the shipped shear-box model (``models/shear_box.json``,
    built into mbgc) when ``path`` is ``None``."""
    return Model.shipped() if path is None else Model.load(path)
