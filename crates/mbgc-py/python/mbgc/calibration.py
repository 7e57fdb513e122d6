"""``calibrate``: a material's parameters from its measurements, by inverting a metamodel."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, overload

import pandas as pd

from mbgc import _mbgc
from mbgc._convert import PathLike, document
from mbgc.model import Model

__all__ = ["Calibration", "calibrate"]

ModelArg = Union[None, PathLike, Model]


@dataclass(frozen=True)
class Calibration:
    """One calibration of a material against one model: what ``mbgc calibrate`` reports.

    ``solutions`` holds every distinct optimum, best first: every model input (fixed ones
    included), the predicted responses, the objective (chi^2; beyond the model's stiffness
    data -2 ln L, chi^2 plus 2 sum ln(sd / measured sd)), whether it ``fits`` the
    measurements (chi^2 within the 95 % level) and how many starts reached it. Optima that do
    not fit are local minima (:attr:`local_minima`); several that fit mean the answer is not
    unique. With ``bayes=True``, :attr:`posterior` holds the TMCMC draws and
    :attr:`log_evidence` the model class's log evidence. ``json`` is the ``--json`` report,
    ``report`` the text one (also ``str()``, with the class probability when there is one).
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
    report: str = field(repr=False)

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
        """The report ``mbgc calibrate`` prints, and the model class's probability."""
        if self.class_probability is None:
            return self.report
        return (
            f"{self.report}\nP(model class | data) = {self.class_probability:.4f} (equal prior "
            "probabilities)"
        )

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
        report=r["report"].rstrip("\n"),
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
