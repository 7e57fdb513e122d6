"""The accuracy a smooth interpolator reaches on a campaign's own rows: is a metamodel that misses
its noise bar held back by its equations or by its data?

A Gaussian-process regressor (scikit-learn, constant * ARD RBF + white noise, y normalised) is
fitted to the settled training rows of a campaign and scored on its validation rows, response by
response, beside the replicate noise (validation rows rerun with another seed, sd = rms
difference / sqrt 2). The inputs are what mbgc's fit sees: the stiffness and stress groups
K = E / (rho_p g d50) and S = normal_stress / (rho_p g d50) in their logarithm, the cohesion
groups C = ced / (rho_p g d50) linearly, the rest as they are; a response that the experiment
scales (bulk density by rho_p, the cell's cohesion and yield strength by the normal stress) is
fitted scaled. With --bond, the Bond-like groups C / K^(2/3) (cohesive pull over weight at
Hertz contacts) are offered too.

    python3 -m venv target/venv-metamodels
    target/venv-metamodels/bin/pip install numpy pandas scikit-learn
    target/venv-metamodels/bin/python benches/metamodels/gp_ceiling.py \
        docs/data/shear_cell/campaign shear_cell
    target/venv-metamodels/bin/python benches/metamodels/gp_ceiling.py . shear_box_sjkr --bond
"""

import os
import sys

import numpy as np
import pandas as pd
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

G = 9.81
NOT_INPUTS = {"run_id", "row", "status", "seed", "model_class", "settled", "steps", "particles",
              "wall_time_s", "warnings", "error", "backend"}
RESPONSES = ["shear_angle", "bulk_density", "internal_friction", "cohesion",
             "unconfined_yield_strength", "shear_ratio"]
DIAGNOSTICS = {"flank_r2", "flank_curvature", "outflow_fraction"}


def features(d, bond):
    w = d.rho_p * G * d.d50 * 1e-3
    x = pd.DataFrame(index=d.index)
    for c in d.columns:
        if c in ("rho_p", "d50"):
            continue
        if c.startswith("E_"):
            x[f"lnK{c[1:]}"] = np.log(d[c] / w)
        elif c == "normal_stress":
            x["lnS"] = np.log(d[c] / w)
        elif c.startswith("ced_"):
            x[f"C{c[3:]}"] = d[c] / w
            modulus = "E_p" if c == "ced_pp" else "E_w"
            if bond and modulus in d.columns:
                x[f"B{c[3:]}"] = (d[c] / w) / (d[modulus] / w) ** (2.0 / 3.0)
        else:
            x[c] = d[c]
    return x.loc[:, x.std() > 0]


def scale(d, r):
    if r == "bulk_density":
        return d.rho_p
    if r in ("cohesion", "unconfined_yield_strength"):
        return d.normal_stress
    return pd.Series(1.0, index=d.index)


def main():
    root, name = sys.argv[1], sys.argv[2]
    bond = "--bond" in sys.argv
    data = os.path.join(root, "training_data")
    train = pd.read_csv(os.path.join(data, f"{name}.csv"))
    valid = pd.read_csv(os.path.join(data, f"{name}_validation.csv"))
    reps = pd.read_csv(os.path.join(data, f"{name}_replicates.csv"))
    train = train[(train.status == "done") & (train.settled == True)]  # noqa: E712
    valid = valid[(valid.status == "done") & (valid.settled == True)]  # noqa: E712
    if "ced_pp" in valid.columns:
        # The cohesive spaces' limit (examples/space_shear_box_sjkr.toml): beyond it the box
        # stops measuring and the model is not used.
        train = train[train.ced_pp <= 0.01 * train.E_p]
        valid = valid[valid.ced_pp <= 0.01 * valid.E_p]
    first = list(train.columns).index("model_class") + 1
    inputs = [c for c in train.columns[first:] if c not in NOT_INPUTS and c not in RESPONSES
              and c not in DIAGNOSTICS]
    responses = [r for r in RESPONSES if r in train.columns]
    xt, xv = features(train[inputs], bond), features(valid[inputs], bond)
    xv = xv[xt.columns]
    mu, sd = xt.mean(), xt.std()
    pairs = valid.merge(reps, on=inputs, suffixes=("", "_r"))
    print(f"{name}: {len(train)} training rows, {len(valid)} validation rows, "
          f"{len(pairs)} replicate pairs; inputs {', '.join(xt.columns)}")
    cohesive = np.zeros(len(valid), dtype=bool)
    for c in ("ced_pp", "ced_pw"):
        if c in valid.columns:
            cohesive |= (valid[c] > 0).values
    print("| response | GP validation RMSE | replicate sd | RMSE / noise | RMSE on cohesive rows |")
    print("|---|---|---|---|---|")
    for r in responses:
        ok = train[r].notna()
        y = train[r][ok] / scale(train[ok], r)
        k = ConstantKernel() * RBF(np.ones(xt.shape[1])) + WhiteKernel()
        gp = GaussianProcessRegressor(k, normalize_y=True, n_restarts_optimizer=2, random_state=0)
        gp.fit(((xt[ok] - mu) / sd).values, y.values)
        p = gp.predict(((xv - mu) / sd).values) * scale(valid, r).values
        measured = valid[r].notna().values
        e = (valid[r].values - p)[measured]
        rmse = float(np.sqrt(np.mean(e ** 2)))
        ec = (valid[r].values - p)[measured & cohesive]
        rmse_c = f"{float(np.sqrt(np.mean(ec ** 2))):.4g} ({len(ec)} rows)" if len(ec) else "-"
        dd = (pairs[r] - pairs[f"{r}_r"]).dropna()
        noise = float(np.sqrt((dd ** 2).sum() / (2 * len(dd))))
        print(f"| {r} | {rmse:.4g} | {noise:.4g} | {rmse / noise:.2f} | {rmse_c} |")


if __name__ == "__main__":
    main()
