"""``calibrate``: a material's parameters from its measurements, by inverting a metamodel."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import pandas as pd

from mbgc import _mbgc
from mbgc._convert import PathLike, document
from mbgc.model import Model

__all__ = ["Calibration", "calibrate"]

ModelArg = Union[None, PathLike, Model]


def _display(v: float) -> str:
    """A number as Rust's `{}` prints it: the shortest digits that read back, never an exponent."""
    return str(np.format_float_positional(v, trim="-"))


def _exp(v: float, digits: int) -> str:
    """A number as Rust's `{:.Ne}` prints it: `2.887e2`, not Python's `2.887e+02`."""
    mantissa, exponent = f"{v:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


@dataclass(frozen=True)
class Calibration:
    """One calibration of a material against one model: what ``mbgc calibrate`` reports.

    ``solutions`` holds every distinct optimum, best first: every model input (fixed ones
    included), the predicted responses, the objective (chi^2), whether it ``fits`` the
    measurements (chi^2 within the 95 % level) and how many starts reached it. Optima that do
    not fit are local minima (:attr:`local_minima`); several that fit mean the answer is not
    unique. With ``bayes=True``, :attr:`posterior` holds the TMCMC draws and
    :attr:`log_evidence` the model class's log evidence.
    """

    material: str
    source: str
    model: str
    model_class: Optional[str]
    notes: List[str]
    measured: pd.DataFrame
    fixed: Dict[str, float]
    free: List[str]
    bounds: Dict[str, Tuple[float, float]]
    unused: List[str]
    fit_threshold: float
    solutions: pd.DataFrame
    flat_directions: pd.DataFrame
    solution_ranges: pd.DataFrame
    posterior: Optional[pd.DataFrame]
    posterior_summary: Optional[pd.DataFrame]
    posterior_responses: Optional[pd.DataFrame]
    log_evidence: Optional[float]
    class_probability: Optional[float]
    json: Dict[str, Any] = field(repr=False)
    calibrated_toml: str = field(repr=False)

    @property
    def best(self) -> Dict[str, float]:
        """Every model input at the best optimum: the calibrated parameter set."""
        names = list(self.json["solutions"][0]["params"])
        return {n: float(self.solutions.iloc[0][n]) for n in names}

    @property
    def fitting(self) -> pd.DataFrame:
        """The optima that fit the measurements (chi^2 within :attr:`fit_threshold`)."""
        return self.solutions[self.solutions["fits"]]

    @property
    def local_minima(self) -> pd.DataFrame:
        """The optima that do not fit the measurements."""
        return self.solutions[~self.solutions["fits"]]

    @property
    def unique(self) -> bool:
        """Whether exactly one optimum fits and the data fix every free parameter."""
        cal = self.json["calibration"]
        return len(self.fitting) == 1 and cal["excess_parameters"] <= 0 and not cal["flat_directions"]

    @property
    def evidence(self) -> Optional[float]:
        """The evidence p(data | model class) (0.0 where it underflows); see :attr:`log_evidence`."""
        return None if self.log_evidence is None else math.exp(self.log_evidence)

    def write_toml(self, path: PathLike) -> None:
        """Writes the best parameter set as ``mbgc calibrate --out`` does, for ``mbgc validate``."""
        with open(os.fspath(path), "w", encoding="utf-8") as f:
            f.write(self.calibrated_toml)

    def __str__(self) -> str:
        """The report ``mbgc calibrate`` prints."""
        cal = self.json["calibration"]
        lines = [f"{self.material} ({self.source}) with {self.model}"]
        lines += [f"  {n}" for n in self.notes]
        lines += [f"  {n} = {_display(v)} fixed" for n, v in self.fixed.items()]
        measured = zip(self.measured["name"], self.measured["value"].tolist(), self.measured["sd"].tolist())
        lines.append("  measured: " + ", ".join(f"{n} {_display(v)} +- {_display(sd)}" for n, v, sd in measured))
        n_meas = len(self.measured)
        optima = cal["optima"]
        fitting = len(self.fitting)
        lines.append(
            f"{fitting} of {len(optima)} distinct optima from {cal['starts']} starts in "
            f"{cal['seconds']:.3f} s fit the measurements (chi2 <= {self.fit_threshold:.2f}, the "
            f"95 % level for {n_meas} measurement{'' if n_meas == 1 else 's'}):"
        )
        names = list(self.measured["name"])
        for i, o in enumerate(optima[:10]):
            if i == fitting and len(optima) > fitting:
                lines.append("  local minima that do not fit:")
            params = ", ".join(f"{n} = {v:.4f}" for n, v in zip(self.free, o["x"]))
            fits = ", ".join(
                f"{n} {p:.4f} ({r:+.2f} sd)" for n, p, r in zip(names, o["predictions"], o["residuals"])
            )
            lines.append(f"  #{i + 1} chi2 {_exp(o['chi2'], 3)} ({o['starts']} starts): {params}")
            lines.append(f"      predicted {fits}")
        if len(optima) > 10:
            lines.append(f"  ... {len(optima) - 10} more (see .solutions)")
        if self.unused:
            lines.append(
                "Not in any equation of the measured responses (any value in range fits equally): "
                + ", ".join(self.unused)
            )
        if cal["excess_parameters"] > 0:
            equal = sum(1 for o in optima if o["chi2"] <= optima[0]["chi2"] + 1.0)
            if equal > 1:
                lines.append(
                    f"{equal} of the optima are equally good points of one continuous solution set, "
                    "not separate answers."
                )
            lines.append(
                f"{len(self.free)} free parameters but {n_meas} measurements: the data fix at most "
                f"{n_meas} combinations; the solutions form a set of dimension >= "
                f"{cal['excess_parameters']}."
            )
        if len(self.flat_directions):
            lines.append(
                "Directions at the best optimum along which the predictions do not change (unit-box steps):"
            )
            for d in cal["flat_directions"]:
                comp = " ".join(f"{c:+.2f} {n}" for n, c in zip(self.free, d["components"]) if abs(c) >= 0.05)
                lines.append(f"  {comp}  (singular value {_exp(d['singular_value'], 1)})")
            lines.append("Range of each parameter over the equally good optima (chi2 within 1 of the best):")
            for r in cal["solution_ranges"]:
                lines.append(f"  {r['name']} in [{r['min']:.4f}, {r['max']:.4f}]")
        details = self.json.get("posterior_details")
        if details:
            lines.append(
                f"Posterior (TMCMC, {details['samples']} samples, {details['stages']} stages): "
                f"log evidence {details['ln_evidence']:.3f}"
            )
            for p in details["parameters"]:
                lines.append(
                    f"  {p['name']:>12}: mean {p['mean']:.4f}, COV {p['cov']:.3f}, 5 % {p['q05']:.4f}, "
                    f"95 % {p['q95']:.4f}"
                )
            lines.append("Posterior-robust predictions (mean +- sd over the posterior):")
            for r in details["responses"]:
                lines.append(f"  {r['name']:>12}: {r['mean']:.4f} +- {r['sd']:.4f}")
        if self.class_probability is not None:
            lines.append(f"P(model class | data) = {self.class_probability:.4f} (equal prior probabilities)")
        return "\n".join(lines)

    def __repr__(self) -> str:
        best = ", ".join(f"{n} = {self.solutions.iloc[0][n]:.4g}" for n in self.free)
        return (
            f"<mbgc.Calibration {self.material} with {self.model}: {len(self.fitting)} of "
            f"{len(self.solutions)} optima fit; best {best}>"
        )


def _calibration(record: str, toml: str, names: List[str], draws: List[List[float]], probability: Optional[float]) -> Calibration:
    r = json.loads(record)
    s = r["session"]
    measured = pd.DataFrame(r["measured"], columns=["name", "value", "sd"])
    rows = []
    for sol in s["solutions"]:
        row: Dict[str, Any] = dict(sol["params"])
        row.update(sol["predicted"])
        row.update(
            objective=sol["objective"],
            fits=sol["fits"],
            constraint_violation=sol["constraint_violation"],
            starts=sol["starts"],
        )
        rows.append(row)
    solutions = pd.DataFrame(rows)
    cal = s["calibration"]
    free = list(r["free"])
    directions = pd.DataFrame(
        [dict(zip(free, d["components"]), singular_value=d["singular_value"]) for d in cal["flat_directions"]],
        columns=free + ["singular_value"],
    )
    ranges = pd.DataFrame(cal["solution_ranges"], columns=["name", "min", "max"]).set_index("name")
    details = s.get("posterior_details")
    posterior = summary = responses = None
    if details:
        posterior = pd.DataFrame(draws, columns=names)
        summary = pd.DataFrame(details["parameters"]).set_index("name")
        responses = pd.DataFrame(details["responses"]).set_index("name")
    return Calibration(
        material=s["material"],
        source=r["source"],
        model=s["model"],
        model_class=s["model_class"],
        notes=list(s["notes"]),
        measured=measured,
        fixed={n: v for n, v in r["fixed"]},
        free=free,
        bounds={n: (lo, hi) for n, (lo, hi) in zip(free, r["bounds"])},
        unused=list(r["unused"]),
        fit_threshold=s["fit_threshold"],
        solutions=solutions,
        flat_directions=directions,
        solution_ranges=ranges,
        posterior=posterior,
        posterior_summary=summary,
        posterior_responses=responses,
        log_evidence=s["log_evidence"],
        class_probability=probability,
        json=s,
        calibrated_toml=toml,
    )


def _native_model(model: Union[PathLike, Model]) -> Any:
    if isinstance(model, Model):
        return model._native
    return Model.load(model)._native


@overload
def calibrate(
    material: Union[PathLike, Mapping[str, Any]],
    model: ModelArg = None,
    *,
    free: Sequence[str] = (),
    starts: int = 64,
    seed: int = 1,
    bayes: bool = False,
    samples: int = 2000,
    sigma_max: float = 0.1,
) -> Calibration: ...
@overload
def calibrate(
    material: Union[PathLike, Mapping[str, Any]],
    model: Union[List[Union[PathLike, Model]], Tuple[Union[PathLike, Model], ...]],
    *,
    free: Sequence[str] = (),
    starts: int = 64,
    seed: int = 1,
    bayes: bool = False,
    samples: int = 2000,
    sigma_max: float = 0.1,
) -> List[Calibration]: ...


def calibrate(
    material: Union[PathLike, Mapping[str, Any]],
    model: Union[ModelArg, List[Union[PathLike, Model]], Tuple[Union[PathLike, Model], ...]] = None,
    *,
    free: Sequence[str] = (),
    starts: int = 64,
    seed: int = 1,
    bayes: bool = False,
    samples: int = 2000,
    sigma_max: float = 0.1,
) -> Union[Calibration, List[Calibration]]:
    """Calibrates a material against a metamodel, as ``mbgc calibrate`` does.

    ``material`` is a material file (TOML: measurements, PSD or sieve analysis, fixed
    parameters, bounds, constraints) or a dict of the same content. ``model`` is a model file,
    a :class:`Model`, or ``None`` for the shipped shear-box model (``models/shear_box.json``);
    a list of models gives one :class:`Calibration` each, and with ``bayes=True`` their model
    classes' probabilities (:attr:`Calibration.class_probability`).

    ``free`` names parameters the material fixes that are searched instead; ``starts`` L-BFGS
    starts (Sobol points) with ``seed``; ``bayes`` also samples the posterior by TMCMC
    (``samples`` per stage, relative model error up to ``sigma_max``).
    """
    path, text, label = document(material, "material dict")
    several = isinstance(model, (list, tuple))
    if isinstance(model, (list, tuple)):
        models = [_native_model(m) for m in model]
    else:
        models = [] if model is None else [_native_model(model)]
    results, probabilities = _mbgc.calibrate(
        path, text, label, models, list(free), starts, seed, bayes, samples, sigma_max
    )
    calibrations = [
        _calibration(record, toml, names, draws, None if probabilities is None else probabilities[k])
        for k, (record, toml, names, draws) in enumerate(results)
    ]
    return calibrations if several else calibrations[0]
