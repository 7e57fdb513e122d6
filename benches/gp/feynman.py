#!/usr/bin/env python3
"""Generates Feynman symbolic-regression datasets for the GP benchmark.

    python feynman.py --out DIR [--rows 1000] [--seed 1] [--noise 0.0]

Writes DIR/<stem>_train.csv and DIR/<stem>_test.csv for each equation below
(header: the variable names, then `y`; values written with repr, so full f64
precision) and DIR/equations.json describing them.

Following SRBench: rows are split 75/25 into train/test after a seeded
shuffle, and with --noise > 0 Gaussian noise of standard deviation
noise * RMS(y_train) is added to the training target only.

Each equation draws from its own generator seeded by (seed, CRC32 of its
name), so an equation's data do not change when the list changes.
"""

import argparse
import json
import os
import zlib

import numpy as np
import sympy

from srbench_check import parse

TRAIN_FRACTION = 0.75

# Equations of the AI Feynman database (Udrescu & Tegmark 2020) that use only
# + - * / sqrt log exp tanh and constants, with 1 to 4 variables. Formulas and
# uniform sampling ranges are those of its FeynmanEquations.csv; I.12.2 is
# written with q1*q2*r/r**3 already reduced to q1*q2/r**2.
# (name, truth, [(variable, low, high), ...])
EQUATIONS = [
    ("I.6.2a", "exp(-theta**2/2)/sqrt(2*pi)", [("theta", 1, 3)]),
    ("I.10.7", "m_0/sqrt(1-v**2/c**2)",
     [("m_0", 1, 5), ("v", 1, 2), ("c", 3, 10)]),
    ("I.12.1", "mu*Nn", [("mu", 1, 5), ("Nn", 1, 5)]),
    ("I.12.2", "q1*q2/(4*pi*epsilon*r**2)",
     [("q1", 1, 5), ("q2", 1, 5), ("epsilon", 1, 5), ("r", 1, 5)]),
    ("I.14.3", "m*g*z", [("m", 1, 5), ("g", 1, 5), ("z", 1, 5)]),
    ("I.14.4", "k_spring*x**2/2", [("k_spring", 1, 5), ("x", 1, 5)]),
    ("I.25.13", "q/C", [("q", 1, 5), ("C", 1, 5)]),
    ("I.34.27", "h/(2*pi)*omega", [("omega", 1, 5), ("h", 1, 5)]),
    ("I.39.1", "3/2*pr*V", [("pr", 1, 5), ("V", 1, 5)]),
    ("II.11.27", "n*alpha/(1-(n*alpha/3))*epsilon*Ef",
     [("n", 0, 1), ("alpha", 0, 1), ("epsilon", 1, 2), ("Ef", 1, 2)]),
    ("II.38.14", "Y/(2*(1+sigma))", [("Y", 1, 5), ("sigma", 1, 5)]),
    ("III.4.32", "1/(exp(h/(2*pi)*omega/(kb*T))-1)",
     [("h", 1, 5), ("omega", 1, 5), ("kb", 1, 5), ("T", 1, 5)]),
]


def file_stem(name):
    return name.replace(".", "_")


def write_csv(path, header, columns):
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for row in zip(*columns, strict=True):
            f.write(",".join(repr(float(v)) for v in row) + "\n")


def generate(name, truth, ranges, rows, seed, noise):
    """Returns (variables, X_train, y_train, X_test, y_test)."""
    rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
    variables = [v for v, _, _ in ranges]
    X = np.column_stack([rng.uniform(lo, hi, rows) for _, lo, hi in ranges])
    # Evaluating the same parsed truth that equations.json publishes keeps the
    # data and the recorded formula from drifting apart.
    f = sympy.lambdify([sympy.Symbol(v, positive=True) for v in variables],
                       parse(truth, variables), "numpy")
    y = np.broadcast_to(f(*X.T), (rows,)).astype(float)
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{name}: non-finite target values")

    order = rng.permutation(rows)
    n_train = int(round(TRAIN_FRACTION * rows))
    train, test = order[:n_train], order[n_train:]
    y_train = y[train].copy()
    if noise > 0:
        y_train += rng.normal(0.0, noise * np.sqrt(np.mean(y_train ** 2)),
                              n_train)
    return variables, X[train], y_train, X[test], y[test]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--rows", type=int, default=1000,
                    help="rows per equation, before the split")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--noise", type=float, default=0.0,
                    help="training-target noise, as a fraction of RMS(y)")
    args = ap.parse_args(argv)
    if args.rows < 4:
        ap.error("--rows must be at least 4")

    os.makedirs(args.out, exist_ok=True)
    described = []
    for name, truth, ranges in EQUATIONS:
        variables, X_train, y_train, X_test, y_test = generate(
            name, truth, ranges, args.rows, args.seed, args.noise)
        stem = file_stem(name)
        header = variables + ["y"]
        write_csv(os.path.join(args.out, f"{stem}_train.csv"), header,
                  [*X_train.T, y_train])
        write_csv(os.path.join(args.out, f"{stem}_test.csv"), header,
                  [*X_test.T, y_test])
        described.append({
            "name": name,
            "file_stem": stem,
            "variables": variables,
            "truth": truth,
            "rows_train": len(y_train),
            "rows_test": len(y_test),
            "noise": args.noise,
        })
    with open(os.path.join(args.out, "equations.json"), "w") as f:
        json.dump(described, f, indent=2)
        f.write("\n")
    print(f"wrote {len(described)} equations to {args.out}")


if __name__ == "__main__":
    main()
