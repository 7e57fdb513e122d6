"""``diagnose``: where the models fail on a measurement set and which physical effect is missing."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Dict, Mapping, Optional, Sequence, Union

import pandas as pd

from mbgc import _mbgc
from mbgc._convert import PathLike, document
from mbgc.model import Model

__all__ = ["Diagnosis", "diagnose"]


@dataclass(frozen=True)
class Diagnosis:
    """What ``mbgc diagnose`` reports: the fit of the set's own model class (``chi2_dof``,
    ``p_value``, the ``residuals`` per sample and response), the candidate effects ranked by
    how much they explain (``ranking``), those no model could evaluate (``unavailable``) and the
    ``verdict``. ``json`` is the ``--json`` report, ``report`` the Markdown one (also
    ``str(diagnosis)``)."""

    set: str
    model_class: str
    chi2_dof: Optional[float]
    p_value: Optional[float]
    verdict: str
    residuals: pd.DataFrame
    structure: pd.DataFrame
    ranking: pd.DataFrame
    unavailable: pd.DataFrame
    json: Dict[str, Any] = field(repr=False)
    report: str = field(repr=False)

    def __str__(self) -> str:
        return self.report


def diagnose(
    measurements: Union[PathLike, Mapping[str, Any]],
    models: Optional[Sequence[Union[PathLike, Model]]] = None,
    *,
    starts: int = 16,
    samples: int = 2000,
    seed: int = 1,
    alpha: float = 0.01,
) -> Diagnosis:
    """Diagnoses a measurement set (a file or a dict: several samples of one material) with the
    models (files or :class:`Model`); without models, the shipped shear-box models (the base
    class and its cohesive extension), as ``mbgc diagnose`` does. ``starts`` L-BFGS starts per
    joint fit, ``samples`` TMCMC samples per stage, ``alpha`` the family-wise significance level.
    Local models are not built here (``mbgc diagnose --build`` runs DEM campaigns)."""
    path, text, label = document(measurements, "measurements dict")
    native = [m._native if isinstance(m, Model) else Model.load(m)._native for m in (models or [])]
    report_json, report = _mbgc.diagnose(path, text, label, native, starts, samples, seed, alpha)
    d = json.loads(report_json)
    ranking = pd.DataFrame(
        d["ranking"],
        columns=["effect", "chi2_dof_after", "p_value_after", "log_bayes_factor", "chi2_ratio", "structure_left", "strength"],
    )
    return Diagnosis(
        set=d["set"],
        model_class=d["class"],
        chi2_dof=d["chi2_dof"],
        p_value=d["p_value"],
        verdict=d["verdict"],
        residuals=pd.DataFrame(d["residuals"], columns=["sample", "response", "measured", "predicted", "sd", "sigma", "z"]),
        structure=pd.DataFrame(d["structure"]),
        ranking=ranking,
        unavailable=pd.DataFrame(d["unavailable"], columns=["effect", "reason"]),
        json=d,
        report=report,
    )
