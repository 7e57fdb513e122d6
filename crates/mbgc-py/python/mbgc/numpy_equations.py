"""A fitted equation as a vectorised numpy function.

The model file stores each equation as a postfix program over the transformed inputs. It is
translated here, node by node, into Python source over numpy arrays: one statement per node, so
that, as in the library's evaluator, a row whose value is not finite at *any* node (the log of a
negative, a division by zero, an overflow that a later ``tanh`` would hide) gives NaN, never a
number the equation does not define. Arithmetic (``+ - * /``, square, cube, sqrt) is IEEE and
gives the library's values bit for bit; ``exp``, ``log``, ``tanh``, ``sin`` and ``cos`` are
numpy's, which may differ from the C library's in the last bit.
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np
import pandas as pd

from mbgc.errors import InputError

__all__ = ["NumpyEquation", "compile_equation"]

_BINARY = {"add": "+", "sub": "-", "mul": "*", "div": "/"}
_UNARY = {
    "neg": "-{a}",
    "square": "{a} * {a}",
    "cube": "{a} * {a} * {a}",
    "sqrt": "np.sqrt({a})",
    "log": "np.log({a})",
    "exp": "np.exp({a})",
    "tanh": "np.tanh({a})",
    "sin": "np.sin({a})",
    "cos": "np.cos({a})",
}


def _constant(value: float) -> str:
    text = repr(float(value))
    return f"({text})" if text.startswith("-") else text


def _transform(k: int, transform: Mapping[str, Any]) -> str:
    kind = transform["kind"]
    if kind == "identity":
        return f"x[{k}]"
    offset, width = _constant(transform["offset"]), _constant(transform["width"])
    if kind == "linear":
        return f"(x[{k}] - {offset}) / {width}"
    if kind == "log":
        return f"(np.log(x[{k}]) - {offset}) / {width}"
    raise ValueError(f"unknown input transform {kind!r}")


def _source(program: Sequence[Any], transforms: Sequence[Mapping[str, Any]]) -> str:
    lines = ["def equation(x):", "    bad = False"]
    used = sorted({node["var"] for node in program if isinstance(node, dict) and "var" in node})
    for k in used:
        lines.append(f"    u{k} = {_transform(k, transforms[k])}")
    stack: List[str] = []
    for i, node in enumerate(program):
        if isinstance(node, dict) and "var" in node:
            stack.append(f"u{node['var']}")
            continue
        if isinstance(node, dict) and "const" in node:
            stack.append(_constant(node["const"]))
            continue
        if node in _BINARY:
            b, a = stack.pop(), stack.pop()
            expr = f"{a} {_BINARY[node]} {b}"
        elif node in _UNARY:
            expr = _UNARY[node].format(a=stack.pop())
        else:
            raise ValueError(f"unknown node {node!r}")
        lines.append(f"    t{i} = {expr}")
        lines.append(f"    bad = bad | ~np.isfinite(t{i})")
        stack.append(f"t{i}")
    if len(stack) != 1:
        raise ValueError("a malformed postfix program")
    lines.append(f"    return np.where(bad, np.nan, {stack[0]})")
    return "\n".join(lines) + "\n"


ArrayLike = Union[np.ndarray, Sequence[float], float]


class NumpyEquation:
    """One response's equation as a vectorised function of the physical inputs.

    Call it with a DataFrame or a mapping holding the inputs by name, with keyword arguments by
    name, with one positional array per input (in :attr:`inputs` order), or with one 2-D array
    of shape ``(rows, len(inputs))``. Arrays broadcast; the result is a float64 array.
    """

    def __init__(self, response: str, inputs: Sequence[str], source: str) -> None:
        self.response = response
        #: The physical inputs, in the order positional arguments and array columns take them.
        self.inputs: List[str] = list(inputs)
        #: The generated Python source (one statement per node of the equation).
        self.source = source
        namespace: Dict[str, Any] = {"np": np}
        exec(compile(source, f"<mbgc equation {response}>", "exec"), namespace)
        self._equation = namespace["equation"]

    def __repr__(self) -> str:
        return f"<NumpyEquation {self.response}({', '.join(self.inputs)})>"

    def _columns(self, args: Sequence[Any], kwargs: Mapping[str, Any]) -> List[np.ndarray]:
        n = len(self.inputs)
        named: Union[pd.DataFrame, Mapping[str, Any], None] = None
        if len(args) == 1 and not kwargs and isinstance(args[0], (pd.DataFrame, Mapping)):
            named = args[0]
        elif kwargs and not args:
            named = kwargs
        if named is not None:
            missing = [name for name in self.inputs if name not in named]
            if missing:
                raise InputError(
                    f"{self.response}: input {missing[0]}: missing; expected values of "
                    f"{', '.join(self.inputs)}",
                    None,
                    f"input {missing[0]}",
                    "values of every input",
                )
            return [np.asarray(named[name], dtype=np.float64) for name in self.inputs]
        if len(args) == 1 and not kwargs and n != 1:
            matrix = np.asarray(args[0], dtype=np.float64)
            if matrix.shape[-1:] != (n,):
                raise InputError(
                    f"{self.response}: array: expected shape (rows, {n}), got {matrix.shape}",
                    None,
                    "array",
                    f"shape (rows, {n})",
                )
            return [matrix[..., k] for k in range(n)]
        if len(args) == n and not kwargs:
            return [np.asarray(a, dtype=np.float64) for a in args]
        raise TypeError(
            f"{self.response}() takes the inputs {', '.join(self.inputs)} by name, as {n} "
            f"arrays, or as one array of shape (rows, {n})"
        )

    def __call__(self, *args: Any, **kwargs: Any) -> np.ndarray:
        columns = np.broadcast_arrays(*self._columns(args, kwargs))
        with np.errstate(all="ignore"):
            result = self._equation(columns)
        # An equation that reads no input is a constant: one per row all the same.
        shape = columns[0].shape if columns else ()
        return np.array(np.broadcast_to(result, shape), dtype=np.float64)


def compile_equation(
    response: str, program: Sequence[Any], inputs: Sequence[Mapping[str, Any]]
) -> NumpyEquation:
    """The equation ``program`` (the model file's postfix form) over the model's ``inputs``."""
    names = [str(i["name"]) for i in inputs]
    return NumpyEquation(response, names, _source(program, [i["transform"] for i in inputs]))
