# Type stubs of the native module (crates/mbgc-py/src): thin calls of the Rust library that take
# and return plain values. Use the `mbgc` package's functions, which wrap these.

from typing import Any, Callable, List, Optional, Sequence, Tuple

__version__: str

class NativeModel:
    @staticmethod
    def load(path: str) -> NativeModel: ...
    @staticmethod
    def from_json(text: str, label: str) -> NativeModel: ...
    @staticmethod
    def shipped(name: str) -> NativeModel: ...
    @property
    def label(self) -> str: ...
    def input_names(self) -> List[str]: ...
    def response_names(self) -> List[str]: ...
    def constants(self) -> List[Tuple[str, float]]: ...
    def to_json(self) -> str: ...
    def save(self, path: str) -> None: ...
    def export(self, format: str) -> str: ...
    def sympy_equations(self) -> Tuple[List[Tuple[str, str]], List[str]]: ...
    def predict(
        self, rows: int, inputs: bytes, held_names: List[str], held: bytes
    ) -> Tuple[bytes, int, Optional[str]]: ...

def calibrate(
    material_path: Optional[str],
    material_json: Optional[str],
    material_label: str,
    models: Sequence[NativeModel],
    free: List[str],
    starts: int,
    seed: int,
    bayes: bool,
    samples: int,
    sigma_max: float,
) -> Tuple[List[Tuple[str, str, List[str], List[List[float]]]], Optional[List[float]]]: ...
def diagnose(
    measurements_path: Optional[str],
    measurements_json: Optional[str],
    measurements_label: str,
    models: Sequence[NativeModel],
    starts: int,
    samples: int,
    seed: int,
    alpha: float,
) -> Tuple[str, str]: ...
def sample(
    method: str,
    n: Optional[int],
    add: Optional[int],
    space_path: Optional[str],
    space_json: Optional[str],
    space_label: str,
    dim: Optional[int],
    seed: int,
    extend: Optional[str],
    mipt_alpha: float,
    fssf_candidates: Optional[int],
    out: Optional[str],
) -> Tuple[List[str], bytes, str]: ...
def simulate(
    design: str,
    experiment: str,
    out: str,
    set: List[Tuple[str, float]],
    seed: int,
    threads: Optional[int],
    shard: Optional[str],
    model_class: Optional[str],
    box_scale: Optional[float],
    backend: str,
    mpi: Optional[int],
    retry_failed: bool,
    vtk: Optional[str],
    progress: Optional[Callable[[int, int], object]],
) -> str: ...
def fit(
    data_path: Optional[str],
    columns: Optional[List[Tuple[str, List[float]]]],
    label: str,
    inputs: List[str],
    targets: List[str],
    options: dict[str, Any],
    test_fraction: float,
    space: Optional[str],
    model_class: Optional[str],
    similarity: Optional[str],
    validation_path: Optional[str],
    validation_columns: Optional[List[Tuple[str, List[float]]]],
    correct: Optional[NativeModel],
    figures: Optional[str],
    out: Optional[str],
    progress: Optional[Callable[[str, int, float], object]],
) -> Tuple[NativeModel, List[str], List[str]]: ...
def experiment_names() -> List[str]: ...
def sampling_methods() -> List[str]: ...
