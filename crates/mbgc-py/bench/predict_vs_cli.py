"""Times a 1,000-row prediction through the Python package and through the `mbgc` binary on the
same rows, in one invocation, and prints both times and their ratio (not a test).

    python crates/mbgc-py/bench/predict_vs_cli.py [--bin target/release/mbgc] [--repeat 30]

The rows are a Sobol design of the shipped model's space (examples/space_shear_box.toml). The
binary's time is a whole `mbgc predict --model models/shear_box.json --data rows.csv --out
pred.csv`: process start, reading the model and the CSV, predicting, writing the CSV. Python's
is timed twice: the same work from Python (load the model, read the CSV with pandas, predict,
write the CSV), and a predict alone on a DataFrame already in memory with a model already
loaded (what a script calling predict in a loop pays). Each time is the median of --repeat
runs; the outputs are checked to be the same numbers. Most of the file-to-file Python time is
pandas' `to_csv` (shortest round-trip float formatting), not the package.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import pandas as pd

import mbgc

ROOT = Path(__file__).resolve().parents[3]


def median_seconds(run, repeat: int) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default=str(ROOT / "target/release/mbgc"))
    parser.add_argument("--rows", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args()
    # A Sobol design of the space reaches a little beyond the model's training range (mu_pw
    # from 0.024): those rows are predicted alike by both, and the warning would flood the output.
    warnings.simplefilter("ignore", mbgc.ExtrapolationWarning)
    model_path = ROOT / "models/shear_box.json"
    rows = mbgc.sample(ROOT / "examples/space_shear_box.toml", "sobol", args.rows, seed=1)
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "rows.csv")
        rows.to_csv(data, index=False)
        cli_out = os.path.join(tmp, "cli.csv")
        py_out = os.path.join(tmp, "py.csv")
        command = [args.bin, "predict", "--model", str(model_path), "--data", data, "--out", cli_out]

        def cli() -> None:
            subprocess.run(command, check=True, capture_output=True)

        def python_end_to_end() -> None:
            model = mbgc.load_model(model_path)
            model.predict(pd.read_csv(data, float_precision="round_trip")).to_csv(py_out, index=False)

        model = mbgc.load_model(model_path)

        def python_predict() -> None:
            model.predict(rows)

        cli()
        python_end_to_end()
        t_cli = median_seconds(cli, args.repeat)
        t_e2e = median_seconds(python_end_to_end, args.repeat)
        t_predict = median_seconds(python_predict, args.repeat)
        same = pd.read_csv(cli_out, float_precision="round_trip")[model.responses].equals(pd.read_csv(py_out, float_precision="round_trip")[model.responses])
    print(f"{args.rows} rows, median of {args.repeat} runs each (mbgc {mbgc.__version__}):")
    print(f"  {'mbgc predict (binary, file to file)':<50}{t_cli * 1e3:8.2f} ms")
    print(f"  {'Python: load model, read CSV, predict, write CSV':<50}{t_e2e * 1e3:8.2f} ms  ratio {t_e2e / t_cli:.2f}")
    print(f"  {'Python: predict on a DataFrame in memory':<50}{t_predict * 1e3:8.2f} ms  ratio {t_predict / t_cli:.2f}")
    print(f"  same predictions in both files: {same}")


if __name__ == "__main__":
    main()
