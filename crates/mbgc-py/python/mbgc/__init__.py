"""mbgc: metamodel-first calibration of DEM simulations, from Python.

The library behind the ``mbgc`` command (Rust), called directly: no binary, no files unless
asked for. A saved metamodel predicts on DataFrames and arrays (:class:`Model`); a material is
calibrated against it in milliseconds (:func:`calibrate`); a set of measurements is diagnosed
(:func:`diagnose`); designs are sampled (:func:`sample`), simulated by the embedded DEM
(:func:`simulate`) and fitted by genetic programming (:func:`fit`). Errors are
:class:`~mbgc.errors.MbgcError` subclasses whose messages are the command line's.

>>> import mbgc
>>> print(mbgc.calibrate("examples/gravel.toml"))        # doctest: +SKIP
"""

from mbgc._mbgc import __version__
from mbgc.calibration import Calibration, calibrate
from mbgc.diagnosis import Diagnosis, diagnose
from mbgc.errors import (
    ExtrapolationWarning,
    FileError,
    InfeasibleError,
    InputError,
    InvalidRequestError,
    MbgcError,
    NoSolutionError,
    OutOfDomainError,
)
from mbgc.fitting import fit
from mbgc.model import Model, load_model
from mbgc.numpy_equations import NumpyEquation
from mbgc.sampling import sample, sampling_methods
from mbgc.simulation import experiments, simulate

__all__ = [
    "__version__",
    "Calibration",
    "Diagnosis",
    "Model",
    "NumpyEquation",
    "calibrate",
    "diagnose",
    "experiments",
    "fit",
    "load_model",
    "sample",
    "sampling_methods",
    "simulate",
    "MbgcError",
    "InputError",
    "OutOfDomainError",
    "InvalidRequestError",
    "NoSolutionError",
    "InfeasibleError",
    "FileError",
    "ExtrapolationWarning",
]
