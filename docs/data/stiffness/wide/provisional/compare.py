"""Scores shear-box models on the stiffness-validation rows a widened model covers (issue 40).

Runs `mbgc predict` for each model on docs/data/stiffness/validation.tsv (never trained on) and
prints, for the rows with K_p and K_w at most --k-max and mu_pw at least --mu-pw-min (where the
widened models answer), the RMSE and the mean miss (measured minus predicted, with its standard
error) of each response, inside the shipped model's K range (max(K_p, K_w) below 1.95e5) and
beyond it.

    python3 docs/data/stiffness/wide/provisional/compare.py models/shear_box.json \
        docs/data/stiffness/wide/provisional/len48.json
"""
import argparse
import csv
import math
import os
import subprocess
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("models", nargs="+")
ap.add_argument("--mbgc", default="target/release/mbgc")
ap.add_argument("--table", default="docs/data/stiffness/validation.tsv")
ap.add_argument("--k-max", type=float, default=9.77e6)
ap.add_argument("--mu-pw-min", type=float, default=0.0237)
a = ap.parse_args()

with tempfile.TemporaryDirectory() as tmp:
    data = os.path.join(tmp, "validation.csv")
    rows = list(csv.DictReader(open(a.table), delimiter="\t"))
    with open(data, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    for model in a.models:
        out = os.path.join(tmp, "p.csv")
        subprocess.run([a.mbgc, "predict", "--model", model, "--data", data, "--out", out],
                       check=True, capture_output=True)
        pred = list(csv.DictReader(open(out)))
        print(model)
        for band, lo, hi in [("inside 1.95e5", 0, 1.95e5), ("beyond 1.95e5", 1.95e5, 1e99),
                             ("all", 0, 1e99)]:
            for resp in ["shear_angle", "bulk_density"]:
                col = resp + "_predicted"
                if col not in pred[0]:
                    continue
                e = []
                for x in pred:
                    g = float(x["rho_p"]) * 9.81 * float(x["d50"]) * 1e-3
                    k = max(float(x["E_p"]) / g, float(x["E_w"]) / g)
                    if k > a.k_max or float(x["mu_pw"]) < a.mu_pw_min or not lo <= k < hi:
                        continue
                    y, p = float(x[resp]), float(x[col])
                    if math.isfinite(y) and math.isfinite(p):
                        e.append(y - p)
                n = len(e)
                if n < 2:
                    continue
                m = sum(e) / n
                se = math.sqrt(sum((v - m) ** 2 for v in e) / (n - 1) / n)
                rmse = math.sqrt(sum(v * v for v in e) / n)
                print(f"  {band:14s} {resp:13s} n {n:3d}  RMSE {rmse:7.3f}  mean miss {m:+7.3f} ({se:.3f})")
