"""Model.predict on DataFrames and arrays, as `mbgc predict`; to_numpy, to_sympy, equations."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Optional

import numpy as np
import pandas as pd
import pytest

import mbgc
from conftest import Cli

# The gravel calibration's best point, and what `mbgc predict --model models/shear_box.json`
# writes for it (recorded from the binary).
ROW = {
    "E_p": 4e7, "E_w": 4e7, "nu_p": 0.25, "e_pp": 0.6, "e_pw": 0.6, "mu_pp": 0.23281466728246303,
    "mu_pw": 0.363, "mu_r_pp": 0.8, "mu_r_pw": 0.8, "rho_p": 2494.8309046328536,
    "d50": 11.157682393638199, "sigma_ln": 0.2632605712620108,
}
PREDICTED = {"shear_angle": 35.52999999999997, "bulk_density": 1478.8}


@pytest.fixture(scope="module")
def model() -> mbgc.Model:
    return mbgc.load_model(Path(__file__).resolve().parents[3] / "models/shear_box.json")


@pytest.fixture(scope="module")
def points(model: mbgc.Model) -> pd.DataFrame:
    """1,000 points of the box of the model's input domains (a Sobol design)."""
    space = {"parameters": {n: {"min": r["min"], "max": r["max"]} for n, r in model.domain.iterrows()}}
    return mbgc.sample(space, "sobol", 1000, seed=3)


def test_a_row_predicts_as_the_command_line(model: mbgc.Model, cli: Optional[Cli], tmp_path: Path) -> None:
    frame = pd.DataFrame([ROW])
    predicted = model.predict(frame)
    for name, value in PREDICTED.items():
        assert predicted[name].iloc[0] == value, name
    if cli is not None:
        data, out = tmp_path / "row.csv", tmp_path / "pred.csv"
        frame.to_csv(data, index=False)
        cli.ok("predict", "--model", "models/shear_box.json", "--data", str(data), "--out", str(out))
        pd.testing.assert_frame_equal(predicted, pd.read_csv(out, float_precision="round_trip"), check_exact=True)


def test_a_dataframe_comes_back_with_its_columns_and_the_responses(model: mbgc.Model) -> None:
    frame = pd.DataFrame([ROW, {**ROW, "mu_pp": 0.5}])
    frame.insert(0, "note", ["a", "b"])
    frame["shear_angle"] = [1.0, 2.0]
    out = model.predict(frame)
    assert list(out.columns) == list(frame.columns) + ["shear_angle_predicted", "bulk_density"]
    pd.testing.assert_frame_equal(out[frame.columns], frame)
    assert out["shear_angle_predicted"].iloc[0] == PREDICTED["shear_angle"]
    assert out["shear_angle_predicted"].iloc[1] > out["shear_angle_predicted"].iloc[0]
    assert "shear_angle_predicted" not in frame.columns, "the input is not modified"


# Half of the box lies outside the model's K_p range: predicted all the same, with a warning.
@pytest.mark.filterwarnings("ignore::mbgc.ExtrapolationWarning")
def test_arrays_and_mappings_predict_the_same(model: mbgc.Model, points: pd.DataFrame) -> None:
    from_frame = model.predict(points)[model.responses].to_numpy()
    matrix = points[model.inputs].to_numpy()
    # NaN where the model does not answer (past its rigid limit's reach), alike in every form.
    assert np.array_equal(model.predict(matrix), from_frame, equal_nan=True)
    as_dict = model.predict({n: points[n].to_numpy() for n in model.inputs})
    assert np.array_equal(np.column_stack([as_dict[r] for r in model.responses]), from_frame, equal_nan=True)
    single = model.predict(np.array([ROW[n] for n in model.inputs]))
    assert single.tolist() == [PREDICTED["shear_angle"], PREDICTED["bulk_density"]]


def test_points_outside_the_domain_are_predicted_with_a_warning(model: mbgc.Model) -> None:
    frame = pd.DataFrame([ROW, {**ROW, "mu_pp": 1.5}])
    with pytest.warns(mbgc.ExtrapolationWarning, match=r"1 of 2 rows of the DataFrame lie outside .* first: row 1: mu_pp = 1.5 outside"):
        model.predict(frame)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.predict(frame.iloc[:1])


@pytest.mark.filterwarnings("ignore::mbgc.ExtrapolationWarning")
def test_to_numpy_agrees_with_predict(model: mbgc.Model) -> None:
    # The stiffnesses over the campaign's range (the model's domain reaches seed 004's 5e8 Pa
    # through its rigid limit), so that most points lie where the equations answer alone.
    space = {
        "parameters": {
            n: {"min": r["min"], "max": min(r["max"], 5e7) if n in ("E_p", "E_w") else r["max"]}
            for n, r in model.domain.iterrows()
        }
    }
    points = mbgc.sample(space, "sobol", 1000, seed=3)
    expected = model.predict(points)
    functions = model.to_numpy()
    assert sorted(functions) == sorted(model.responses)
    # The equations alone: they agree with predict wherever the groups lie in their training
    # range (beyond it predict reads them on the edge and adds the rigid limit's shift).
    inside = np.ones(len(points), dtype=bool)
    for g in model.info.get("groups", []):
        m = g["group"]["monomial"]
        value = m["coefficient"] * np.prod([points[n].to_numpy() ** p for n, p in m["powers"]], axis=0)
        inside &= (value >= g["domain"][0]) & (value <= g["domain"][1])
    assert inside.sum() > 100
    for name, f in functions.items():
        assert f.inputs == model.inputs
        values = f(points)
        np.testing.assert_allclose(values[inside], expected[name].to_numpy()[inside], rtol=1e-9, atol=0)
        assert np.array_equal(f(points[model.inputs].to_numpy()), values)
        assert np.array_equal(f(**{n: points[n].to_numpy() for n in model.inputs}), values)
    # Where the library's evaluator finds a node not finite, so does the numpy function: NaN.
    bad = dict(ROW, rho_p=-1.0)
    with pytest.warns(mbgc.ExtrapolationWarning):
        library = model.predict(pd.DataFrame([bad]))["bulk_density"].iloc[0]
    assert math.isnan(library) and math.isnan(float(functions["bulk_density"](bad)))


def test_to_sympy_agrees_with_predict(model: mbgc.Model) -> None:
    sympy = pytest.importorskip("sympy")
    expressions = model.to_sympy()
    for name, expr in expressions.items():
        symbols = {s.name: s for s in expr.free_symbols}
        value = float(expr.subs({symbols[n]: ROW[n] for n in symbols}).evalf(30))
        assert math.isclose(value, PREDICTED[name], rel_tol=1e-9), (name, value)
        assert isinstance(expr, sympy.Expr)


def test_equations_are_a_pareto_table_like_pysrs(model: mbgc.Model) -> None:
    eq = model.equations
    assert list(eq.columns)[:5] == ["response", "complexity", "loss", "score", "equation"]
    for response in model.responses:
        front = eq[eq["response"] == response]
        assert front["complexity"].is_monotonic_increasing
        assert (front["loss"].diff().dropna() <= 1e-12).all(), "a Pareto front: error falls with size"
        assert front["selected"].sum() == 1
    assert set(model.domain.index) == set(model.inputs)
    assert "shear_angle" in model.export("sympy")
