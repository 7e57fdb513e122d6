"""Does the cohesive model's cohesion effect depend on C_pp = ced_pp / (rho_p g d50) alone, or on
C_pp K_p^(-alpha), K_p = E_p / (rho_p g d50)? (Issue 40: how a cohesive model could answer beyond
its stiffness range.)

Physics: SJKR pulls with ced_pp times the contact area pi R delta; under gravity the Hertz
overlap delta / d50 scales as K_p^(-2/3), so the cohesive force over a grain's weight scales as
C_pp K_p^(-2/3): a stiffer grain of the same C_pp is less cohesive. If the response's cohesion
effect Delta(K, C) = y(K, C) - y(K, 0) depends on C K^(-alpha) alone, then
Delta(K1, C1) = Delta(K2, C1 (K2 / K1)^alpha). This script reads that from the shipped cohesive
model's own equations, at three points of the space (the stiffness study's a and b, and a middle
one; rho_p 2600, d50 8 mm, walls not cohesive), with C_pp up to its constraint 0.01 K_p, and
prints the rms mismatch for several alpha. Standard library only:

    python3 docs/data/stiffness/cohesion_similarity.py [path/to/mbgc]
"""

import csv
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../.."))
MODEL = os.environ.get("MBGC_MODEL", os.path.join(ROOT, "models", "shear_box_sjkr.json"))
COLS = "E_p,E_w,nu_p,e_pp,e_pw,mu_pp,mu_pw,mu_r_pp,mu_r_pw,rho_p,d50,sigma_ln,ced_pp,ced_pw".split(",")
POINTS = {"a": (0.1, 0.1), "b": (0.7, 0.6), "c": (0.4, 0.3)}  # mu_pp, mu_r_pp
KS = [1.5e4, 3e4, 6e4, 1.5e5]
CS = [0, 10, 20, 40, 60, 100, 150, 200, 300, 450, 700, 950]
RHO, D50, G = 2600.0, 8.0, 9.81
# The DEM lines at Bo = C_pp = 100 through a and b (bench stiffness), beside the model.
DEM_KS = [1e4, 3e4, 1e5, 194000.0]
DEM_TABLES = ["runs.tsv", "runs_bond_edges.tsv"]


def dem_effects():
    """Seed means of (Bo 100) - (Bo 0) per (point, K_p, response) on the DEM lines."""
    sums = {}
    for t in DEM_TABLES:
        with open(os.path.join(ROOT, "docs", "data", "stiffness", t), newline="") as f:
            for r in csv.DictReader(f, delimiter="\t"):
                key = (r["point"], float(r["k_p"]), float(r["bond"]))
                s = sums.setdefault(key, [0.0, 0.0, 0])
                s[0] += float(r["shear_angle"])
                s[1] += float(r["bulk_density"])
                s[2] += 1
    mean = {k: (v[0] / v[2], v[1] / v[2], v[2]) for k, v in sums.items()}
    return {
        (p, k): (mean[(p, k, 100.0)][0] - mean[(p, k, 0.0)][0],
                 mean[(p, k, 100.0)][1] - mean[(p, k, 0.0)][1],
                 mean[(p, k, 100.0)][2], mean[(p, k, 0.0)][2])
        for (p, k, b) in mean
        if b == 100.0 and (p, k, 0.0) in mean
    }


def main():
    mbgc = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "mbgc")
    keys = []
    with tempfile.TemporaryDirectory() as tmp:
        grid, out = os.path.join(tmp, "grid.csv"), os.path.join(tmp, "pred.csv")
        with open(grid, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(COLS)
            for name, (mu, mu_r) in POINTS.items():
                for k in KS:
                    for c in CS:
                        if c > 0.01 * k:
                            continue
                        e = k * RHO * G * D50 * 1e-3
                        ced = c * RHO * G * D50 * 1e-3
                        w.writerow([e, e, 0.3, 0.5, 0.5, mu, 0.3, mu_r, 0.3, RHO, D50, 0.15, ced, 0])
                        keys.append((name, k, c))
                for k in DEM_KS:
                    for c in (0, 100):
                        e = k * RHO * G * D50 * 1e-3
                        ced = c * RHO * G * D50 * 1e-3
                        w.writerow([e, e, 0.3, 0.5, 0.5, mu, 0.3, mu_r, 0.3, RHO, D50, 0.15, ced, 0])
                        keys.append((name, k, c))
        subprocess.run([mbgc, "predict", "--model", MODEL, "--data", grid, "--out", out], check=True)
        with open(out, newline="") as f:
            pred = list(csv.DictReader(f))
    val = {key: (float(r["shear_angle"]), float(r["bulk_density"])) for key, r in zip(keys, pred)}

    def delta(n, k, c, i):
        return val[(n, k, c)][i] - val[(n, k, 0)][i]

    def interp(n, k, c, i):
        xs = [x for x in CS if (n, k, x) in val]
        if c > xs[-1]:
            return math.nan
        j = max(q for q in range(len(xs)) if xs[q] <= c)
        if xs[j] == c or j + 1 == len(xs):
            return delta(n, k, xs[j], i)
        t = (c - xs[j]) / (xs[j + 1] - xs[j])
        return (1 - t) * delta(n, k, xs[j], i) + t * delta(n, k, xs[j + 1], i)

    print("| point | response | Delta at C 40 / 150 for K " + ", ".join(f"{k:.1e}" for k in KS) + " |")
    print("|---|---|---|")
    for n in POINTS:
        for i, resp in enumerate(["shear_angle", "bulk_density"]):
            cells = [
                " / ".join(f"{delta(n, k, c, i):+.2f}" for c in (40, 150) if (n, k, c) in val)
                for k in KS
            ]
            print(f"| {n} | {resp} | " + "; ".join(cells) + " |")
    print()
    dem = dem_effects()
    print("Cohesion effect at C_pp = 100: DEM lines (seed means, Bo 100 minus Bo 0) against the model")
    print()
    print("| point | K_p | DEM shear_angle | model | DEM bulk_density | model | runs (Bo 100, Bo 0) |")
    print("|---|---|---|---|---|---|---|")
    for n in ("a", "b"):
        for k in DEM_KS:
            if (n, k) not in dem:
                continue
            da, dd, n1, n0 = dem[(n, k)]
            print(
                f"| {n} | {k:.3g} | {da:+.2f} | {delta(n, k, 100, 0):+.2f} | {dd:+.1f} | "
                f"{delta(n, k, 100, 1):+.1f} | {n1}, {n0} |"
            )
    print()
    print("| point | alpha | rms mismatch, shear_angle deg | rms mismatch, bulk_density kg/m3 | pairs |")
    print("|---|---|---|---|---|")
    for n in POINTS:
        for alpha in (0.0, 1 / 3, 0.5, 2 / 3, 0.8, 1.0):
            err = ([], [])
            for k1 in KS[:2]:
                for k2 in KS[2:]:
                    for c1 in CS[1:]:
                        if (n, k1, c1) not in val:
                            continue
                        c2 = c1 * (k2 / k1) ** alpha
                        for i in range(2):
                            e = interp(n, k2, c2, i) - delta(n, k1, c1, i)
                            if not math.isnan(e):
                                err[i].append(e)
            rms = [math.sqrt(sum(x * x for x in e) / len(e)) for e in err]
            print(f"| {n} | {alpha:.2f} | {rms[0]:.2f} | {rms[1]:.2f} | {len(err[0])} |")
    lines_test()


def lines_test():
    """The DEM test beyond the edge: on random lines r1-r8, the cohesion effect at the edge
    (C_pp 600, K_p 1.94e5) against K_p 1e6 at the same C_pp K_p^(-2/3) (C_pp 1790) and at the
    same C_pp (600), each minus the same line's run without cohesion at that K_p."""
    table = os.path.join(ROOT, "docs", "data", "stiffness", "runs_bond_lines.tsv")
    if not os.path.exists(table):
        return
    runs = {}
    for t in (table, os.path.join(ROOT, "docs", "data", "stiffness", "runs_random.tsv")):
        with open(t, newline="") as f:
            for r in csv.DictReader(f, delimiter="\t"):
                if r["seed"] == "1":
                    key = (r["point"], float(r["bond"]), float(r["k_p"]))
                    runs[key] = (float(r["shear_angle"]), float(r["bulk_density"]))
    cases = [("edge, C_pp 600", 600.0, 194000.0), ("1e6, C_pp 1790 (same C_pp K_p^-2/3)", 1790.0, 1e6),
             ("1e6, C_pp 600 (same C_pp)", 600.0, 1e6)]
    print()
    print("Cohesion effect on the random lines (one run each, minus the line's run without cohesion "
          "at the same K_p): shear_angle deg / bulk_density kg/m3")
    print()
    print("| line | " + " | ".join(c[0] for c in cases) + " |")
    print("|---|" + "---|" * len(cases))
    diffs = {1: ([], []), 2: ([], [])}
    for i in range(1, 9):
        p = f"r{i}"
        eff = []
        for _, bo, k in cases:
            a, b = runs.get((p, bo, k)), runs.get((p, 0.0, k))
            eff.append(None if a is None or b is None else (a[0] - b[0], a[1] - b[1]))
        if eff[0] is None:
            continue
        cells = ["-" if e is None else f"{e[0]:+.2f} / {e[1]:+.1f}" for e in eff]
        print(f"| {p} | " + " | ".join(cells) + " |")
        for c in (1, 2):
            if eff[c] is not None:
                diffs[c][0].append(eff[c][0] - eff[0][0])
                diffs[c][1].append(eff[c][1] - eff[0][1])
    print()
    for c in (1, 2):
        n = len(diffs[c][0])
        if n < 2:
            continue
        for q, unit in ((0, "deg"), (1, "kg/m3")):
            v = diffs[c][q]
            mean = sum(v) / n
            sd = math.sqrt(sum((x - mean) ** 2 for x in v) / (n - 1))
            rms = math.sqrt(sum(x * x for x in v) / n)
            print(f"- {cases[c][0]} minus the edge, {['shear_angle', 'bulk_density'][q]}: mean "
                  f"{mean:+.2f} {unit} (se {sd / math.sqrt(n):.2f}), rms {rms:.2f}, {n} lines")


if __name__ == "__main__":
    main()
