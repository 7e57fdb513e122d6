#!/usr/bin/env python3
"""Runs gplearn's SymbolicRegressor on the Feynman datasets made by feynman.py.

    python run_gplearn.py --dir DIR [--population 5000] [--generations 20]
                          [--seed 1] [--only NAME,...] [--force] [--verbose]

Settings are the seed paper's: functions add, sub, mul, div, sqrt, log, exp,
tanh; parsimony_coefficient 0.001; one thread; every other parameter at
gplearn's default (tournament_size 20, p_crossover 0.9, p_subtree_mutation
0.01, p_hoist_mutation 0.01, p_point_mutation 0.01, const_range (-1, 1),
init_depth (2, 6), metric 'mean absolute error').

Results go to DIR/gplearn_results.json, rewritten after every equation so a
killed run keeps what it finished. An equation already there with the same
population, generations and seed is skipped unless --force is given.
"""

import argparse
import json
import math
import os
import time

import numpy as np
import sympy
from gplearn.functions import make_function
from gplearn.genetic import SymbolicRegressor
from sklearn.metrics import r2_score

from srbench_check import DEFAULT_TIMEOUT_S, is_recovered, parse

RESULTS_FILE = "gplearn_results.json"
METRIC = "mean absolute error"  # gplearn's default, kept on purpose
PARSIMONY = 0.001
EXP_CLIP = 50.0


def _protected_exp(x):
    # gplearn needs closed functions (finite output for any input); clipping
    # the argument to +-50 bounds exp by e**50 ~ 5e21 instead of overflowing.
    return np.exp(np.clip(x, -EXP_CLIP, EXP_CLIP))


# wrap=False: with n_jobs=1 nothing is pickled, and wrapping slows evaluation.
EXP = make_function(function=_protected_exp, name="exp", arity=1, wrap=False)
TANH = make_function(function=np.tanh, name="tanh", arity=1, wrap=False)
FUNCTION_SET = ("add", "sub", "mul", "div", "sqrt", "log", EXP, TANH)

# gplearn's protected operators are div (1 when |b| < 0.001), sqrt(|a|),
# log(|a|) (0 when |a| < 0.001) and, here, exp of a clipped argument. They
# become the plain operations, as in SRBench, except where sympy can tell that
# the protection fires: a constant argument, or one of known sign (all
# variables are positive). Keeping those cases exact stops, e.g., sqrt of a
# negative constant from turning into an imaginary number. Where protection
# fires on the data but not provably, the expression differs from what
# gplearn predicts; R^2 is always measured with gplearn's own predict.
PROTECTION_THRESHOLD = 0.001


def _magnitude(a):
    return -a if a.is_negative else a


def _div(a, b):
    if b.is_number and abs(b) < PROTECTION_THRESHOLD:
        return sympy.Integer(1)
    return a / b


def _log(a):
    if a.is_number and abs(a) < PROTECTION_THRESHOLD:
        return sympy.Integer(0)
    return sympy.log(_magnitude(a))


def _exp(a):
    if a.is_number:
        a = min(max(a, -EXP_CLIP), EXP_CLIP)
    return sympy.exp(a)


_TO_SYMPY = {
    "add": lambda a, b: a + b,
    "sub": lambda a, b: a - b,
    "mul": lambda a, b: a * b,
    "div": _div,
    "sqrt": lambda a: sympy.sqrt(_magnitude(a)),
    "log": _log,
    "exp": _exp,
    "tanh": sympy.tanh,
}


def program_to_sympy(program, variables):
    """Converts a fitted gplearn program (prefix list of functions, feature
    indices and float constants) to a sympy expression.

    Reads the node list rather than str(program), which prints constants
    with only 3 decimals."""
    symbols = [sympy.Symbol(v, positive=True) for v in variables]
    stack = []  # (function name, arity, [converted arguments])
    for node in program.program:
        if isinstance(node, (int, np.integer)):
            value = symbols[node]
        elif isinstance(node, (float, np.floating)):
            value = sympy.Float(float(node))
        else:
            stack.append((node.name, node.arity, []))
            continue
        while True:
            if not stack:
                return value
            name, arity, args = stack[-1]
            args.append(value)
            if len(args) < arity:
                break
            stack.pop()
            value = _TO_SYMPY[name](*args)
    raise ValueError("incomplete gplearn program")


def load_csv(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return header[:-1], data[:, :-1], data[:, -1]


def finite_or_none(x):
    """JSON has no NaN or infinity; an unusable score is written as null."""
    x = float(x)
    return x if math.isfinite(x) else None


def score(y, y_pred):
    if not np.all(np.isfinite(y_pred)):
        return None
    return finite_or_none(r2_score(y, y_pred))


def run_equation(eq, data_dir, population, generations, seed, verbose,
                 check_timeout):
    variables, X_train, y_train = load_csv(
        os.path.join(data_dir, f"{eq['file_stem']}_train.csv"))
    test_vars, X_test, y_test = load_csv(
        os.path.join(data_dir, f"{eq['file_stem']}_test.csv"))
    if variables != eq["variables"] or test_vars != variables:
        raise ValueError(f"{eq['name']}: CSV header does not match "
                         f"equations.json variables {eq['variables']}")

    est = SymbolicRegressor(
        population_size=population,
        generations=generations,
        function_set=FUNCTION_SET,
        metric=METRIC,
        parsimony_coefficient=PARSIMONY,
        n_jobs=1,
        random_state=seed,
        verbose=1 if verbose else 0,
    )
    start = time.perf_counter()
    est.fit(X_train, y_train)
    wall = time.perf_counter() - start

    expr = program_to_sympy(est._program, variables)
    recovered, note = is_recovered(parse(eq["truth"], variables), expr,
                                   check_timeout)
    result = {
        "name": eq["name"],
        "engine": "gplearn",
        "population": population,
        "generations": generations,
        "seed": seed,
        "train_r2": score(y_train, est.predict(X_train)),
        "test_r2": score(y_test, est.predict(X_test)),
        "size": int(est._program.length_),
        "wall_time_s": wall,
        "expression": str(expr),
        "recovered": bool(recovered),
        "metric": METRIC,
    }
    if note:
        result["recovery_note"] = note
    return result


def write_results(path, results):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(results, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dir", required=True,
                    help="dataset directory written by feynman.py")
    ap.add_argument("--population", type=int, default=5000)
    ap.add_argument("--generations", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", help="comma-separated equation names")
    ap.add_argument("--force", action="store_true",
                    help="rerun equations that already have a result")
    ap.add_argument("--verbose", action="store_true",
                    help="print gplearn's per-generation progress table")
    ap.add_argument("--check-timeout", type=float, default=DEFAULT_TIMEOUT_S,
                    help="seconds allowed for the recovery check's simplify")
    args = ap.parse_args(argv)

    with open(os.path.join(args.dir, "equations.json")) as f:
        equations = json.load(f)
    if args.only:
        wanted = args.only.split(",")
        unknown = set(wanted) - {eq["name"] for eq in equations}
        if unknown:
            ap.error(f"unknown equations: {', '.join(sorted(unknown))}")
        equations = [eq for eq in equations if eq["name"] in wanted]

    results_path = os.path.join(args.dir, RESULTS_FILE)
    results = []
    if os.path.exists(results_path):
        with open(results_path) as f:
            results = json.load(f)

    def same_run(r, name):
        return (r["name"] == name and r["population"] == args.population
                and r["generations"] == args.generations
                and r["seed"] == args.seed)

    for eq in equations:
        if not args.force and any(same_run(r, eq["name"]) for r in results):
            print(f"{eq['name']}: already in {RESULTS_FILE}, skipped",
                  flush=True)
            continue
        print(f"{eq['name']}: fitting {eq['truth']} "
              f"(population {args.population}, generations "
              f"{args.generations}, seed {args.seed})", flush=True)
        result = run_equation(eq, args.dir, args.population, args.generations,
                              args.seed, args.verbose, args.check_timeout)
        results = [r for r in results if not same_run(r, eq["name"])]
        results.append(result)
        write_results(results_path, results)
        print(f"{eq['name']}: {result['wall_time_s']:.1f} s, "
              f"test R^2 {result['test_r2']}, size {result['size']}, "
              f"recovered {result['recovered']}: {result['expression']}",
              flush=True)


if __name__ == "__main__":
    main()
