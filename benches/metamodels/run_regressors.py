"""The Python side of `mbgc bench metamodels`: other regressors on the regression problems mbgc's
GP solves, on identical columns and rows.

Reads one JSON file written by the bench (`--problems`): per response the columns GP is offered
(scaled inputs and dimensionless groups), the fitted quantity on every training row and the
validation rows' columns, the length limits, the seeds, and mbgc's equations (sympy syntax) whose
nodes are to be counted by the same rule as everyone else's. Writes one JSON object to standard
output:

- PyOperon at every length limit (its own `max_length`, which counts a weighted variable `w*x` as
  one node), the Pareto-optimal model its MDL criterion picks;
- a Gaussian-process regressor (scikit-learn, constant * ARD Matern 5/2 + white noise, y
  normalised, 5 optimizer restarts): the accuracy ceiling of a smooth interpolator;
- a quadratic response surface (all linear, square and interaction terms, least squares): what
  most DEM calibration papers fit;

each with its validation predictions (in the fitted quantity's units), its training predictions,
its wall time and, for the equations, the printed model and its node count: the nodes of the
sympy expression tree, every function, operator, symbol and number one node, after sympy's
automatic canonicalisation (a - b is a + (-1) * b) and nothing more. mbgc's equations are counted
by the same rule.
"""

import argparse
import importlib.metadata
import json
import sys
import time

import numpy as np
import sympy


def sympy_nodes(text, symbols):
    """Nodes of the expression tree of `text` (see the module's description)."""
    local = {s: sympy.Symbol(s) for s in symbols}
    expr = sympy.sympify(text, locals=local)
    return sum(1 for _ in sympy.preorder_traversal(expr))


def operon(xt, yt, xv, limit, seed, threads, generations, population, max_evaluations):
    from pyoperon.sklearn import SymbolicRegressor

    est = SymbolicRegressor(
        allowed_symbols="add,sub,mul,div,sqrt,log,exp,tanh,constant,variable",
        max_length=limit,
        # Operon's default 10 would exceed the smallest limits; start at most at the limit.
        initialization_max_length=min(10, limit),
        max_depth=max(4, min(10, limit)),
        population_size=population,
        generations=generations,
        max_evaluations=max_evaluations,
        optimizer_iterations=10,
        n_threads=threads,
        random_state=seed,
    )
    t0 = time.perf_counter()
    est.fit(xt, yt)
    seconds = time.perf_counter() - t0
    return est, seconds


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--problems", required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--operon-generations", type=int, default=1000)
    ap.add_argument("--operon-population", type=int, default=1000)
    ap.add_argument("--operon-evaluations", type=int, default=1_000_000)
    ap.add_argument("--skip-gpr", action="store_true")
    a = ap.parse_args()
    with open(a.problems) as f:
        spec = json.load(f)

    import sklearn
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel
    from sklearn.linear_model import LinearRegression
    from sklearn.preprocessing import PolynomialFeatures

    out = {
        "versions": {
            "python": sys.version.split()[0],
            "pyoperon": importlib.metadata.version("pyoperon"),
            "scikit-learn": sklearn.__version__,
            "sympy": sympy.__version__,
            "numpy": np.__version__,
        },
        "operon_settings": {
            "generations": a.operon_generations,
            "population": a.operon_population,
            "max_evaluations": a.operon_evaluations,
            "threads": a.threads,
        },
        "responses": [],
    }
    for p in spec["problems"]:
        names = p["symbols"]
        xt = np.array(p["train_x"], dtype=float).T
        yt = np.array(p["train_y"], dtype=float)
        xv = np.array(p["validation_x"], dtype=float).T
        res = {"response": p["response"], "methods": [], "mbgc_nodes": []}
        for eq in p["mbgc_equations"]:
            res["mbgc_nodes"].append(sympy_nodes(eq, names))
        for limit, seed in [(lim, s) for lim in p["limits"] for s in p["seeds"]]:
            est, seconds = operon(
                xt, yt, xv, limit, seed, a.threads,
                a.operon_generations, a.operon_population, a.operon_evaluations,
            )
            text = est.get_model_string(est.model_, 6, names)
            res["methods"].append({
                "method": "pyoperon",
                "limit": limit,
                "seed": seed,
                "own_length": int(est.model_.Length),
                "equation": text,
                "nodes": sympy_nodes(text, names),
                "seconds": seconds,
                "train_pred": est.predict(xt).tolist(),
                "validation_pred": est.predict(xv).tolist(),
            })
            print(f"{p['response']}: pyoperon limit {limit} seed {seed}: length {est.model_.Length}, "
                  f"{seconds:.1f} s", file=sys.stderr)
        # The quadratic response surface.
        poly = PolynomialFeatures(degree=2, include_bias=False)
        t0 = time.perf_counter()
        lin = LinearRegression().fit(poly.fit_transform(xt), yt)
        seconds = time.perf_counter() - t0
        terms = poly.get_feature_names_out(names)
        text = " + ".join(
            [repr(float(lin.intercept_))]
            + [f"({float(c)!r})*{t.replace(' ', '*').replace('^', '**')}"
               for c, t in zip(lin.coef_, terms)]
        )
        res["methods"].append({
            "method": "quadratic",
            "limit": None,
            "own_length": len(terms) + 1,
            "equation": text,
            "nodes": sympy_nodes(text, names),
            "seconds": seconds,
            "train_pred": lin.predict(poly.transform(xt)).tolist(),
            "validation_pred": lin.predict(poly.transform(xv)).tolist(),
        })
        if not a.skip_gpr:
            d = xt.shape[1]
            kernel = ConstantKernel(1.0, (1e-3, 1e3)) * Matern(
                length_scale=np.ones(d), length_scale_bounds=(1e-2, 1e3), nu=2.5
            ) + WhiteKernel(1e-2, (1e-8, 1.0))
            gpr = GaussianProcessRegressor(
                kernel=kernel, normalize_y=True, n_restarts_optimizer=5,
                random_state=p["seeds"][0],
            )
            t0 = time.perf_counter()
            gpr.fit(xt, yt)
            seconds = time.perf_counter() - t0
            res["methods"].append({
                "method": "gaussian_process",
                "limit": None,
                "own_length": None,
                "equation": str(gpr.kernel_),
                "nodes": None,
                "seconds": seconds,
                "train_pred": gpr.predict(xt).tolist(),
                "validation_pred": gpr.predict(xv).tolist(),
            })
            print(f"{p['response']}: gaussian process {seconds:.1f} s: {gpr.kernel_}",
                  file=sys.stderr)
        out["responses"].append(res)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
