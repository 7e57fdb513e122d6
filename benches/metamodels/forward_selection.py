"""How far a sum of short terms gets on the shipped shear-box campaign (docs/metamodel_levers.md).

Greedy forward selection of terms, least-squares coefficients, from a basis of x, sqrt x, x^2,
ln(x + 0.05), tanh(2x), tanh(5x) of every input scaled to [0, 1] (K_p and K_w log-scaled, as
mbgc's GP sees them) and the products of two such features of different inputs; the bulk density
is fitted as the solid fraction. Prints the validation RMSE / replicate noise after each term.

    target/venv-metamodels/bin/python benches/metamodels/forward_selection.py bulk_density
"""

import itertools
import sys

import numpy as np
import pandas as pd

LINEAR = [("nu_p", 0.1, 0.5), ("e_pp", 0.3, 0.95), ("e_pw", 0.3, 0.95), ("mu_pp", 0.05, 1.0),
          ("mu_pw", 0.0, 1.0), ("mu_r_pp", 0.0, 1.0), ("mu_r_pw", 0.0, 1.0),
          ("sigma_ln", 0.07, 0.28)]
NOISE = {"shear_angle": 1.060, "bulk_density": 0.0026}  # deg; share of the mean density


def load(path):
    d = pd.read_csv(path)
    d = d[d.status == "done"].dropna(subset=["shear_angle", "bulk_density"])
    x = pd.DataFrame({f"{c}_u": (d[c] - lo) / (hi - lo) for c, lo, hi in LINEAR})
    for g, e in [("K_p_u", "E_p"), ("K_w_u", "E_w")]:
        x[g] = np.log(d[e] / (d.rho_p * 9.81 * d.d50 * 1e-3))
    return d, x


def basis(x):
    out = {}
    for c in x.columns:
        v = x[c].values
        out[c] = v
        out[f"sqrt({c})"] = np.sqrt(v)
        out[f"{c}^2"] = v * v
        out[f"log({c}+0.05)"] = np.log(v + 0.05)
        for k in (2, 5):
            out[f"tanh({k}{c})"] = np.tanh(k * v)
    return out


def main():
    response = sys.argv[1] if len(sys.argv) > 1 else "bulk_density"
    terms = int(sys.argv[2]) if len(sys.argv) > 2 else 14
    tr, xt = load("training_data/shear_box.csv")
    va, xv = load("training_data/shear_box_validation.csv")
    for g in ("K_p_u", "K_w_u"):
        lo, hi = xt[g].min(), xt[g].max()
        xt[g], xv[g] = (xt[g] - lo) / (hi - lo), (xv[g] - lo) / (hi - lo)
    if response == "bulk_density":
        yt = (tr.bulk_density / tr.rho_p).values
        yv, factor = (va.bulk_density / va.rho_p).values, va.rho_p.values
        noise = NOISE[response] * va.bulk_density.mean()
    else:
        yt, yv, factor = tr[response].values, va[response].values, np.ones(len(va))
        noise = NOISE[response]
    bt, bv = basis(xt), basis(xv)

    def var(name):
        return next(c for c in xt.columns if c in name)

    ft, fv = dict(bt), dict(bv)
    for a, b in itertools.combinations(list(bt), 2):
        if var(a) != var(b):
            ft[f"{a}*{b}"], fv[f"{a}*{b}"] = bt[a] * bt[b], bv[a] * bv[b]
    names = list(ft)
    mt = np.column_stack([ft[n] for n in names])
    mv = np.column_stack([fv[n] for n in names])
    print(f"{len(names)} candidate features, {len(yt)} training rows, {len(yv)} validation rows")
    chosen = []
    for step in range(terms):
        best = None
        for j in range(len(names)):
            if j in chosen:
                continue
            a = np.column_stack([np.ones(len(yt))] + [mt[:, k] for k in chosen + [j]])
            c = np.linalg.lstsq(a, yt, rcond=None)[0]
            sse = np.sum((a @ c - yt) ** 2)
            if best is None or sse < best[0]:
                best = (sse, j)
        chosen.append(best[1])
        a = np.column_stack([np.ones(len(yt))] + [mt[:, k] for k in chosen])
        c = np.linalg.lstsq(a, yt, rcond=None)[0]
        av = np.column_stack([np.ones(len(yv))] + [mv[:, k] for k in chosen])
        rmse = np.sqrt(np.mean(((av @ c - yv) * factor) ** 2))
        print(f"{step + 1:2d} {names[best[1]]:40s} validation RMSE / noise {rmse / noise:.3f}")


if __name__ == "__main__":
    main()
