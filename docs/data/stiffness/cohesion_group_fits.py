"""Does the cohesive model fit better in C_pp K_p^(-2/3) than in C_pp? (docs/cohesion_stiffness.md)

Writes the shipped cohesive campaign's rows (training_data/shear_box_sjkr.csv, its validation
table beside it; settled runs inside ced_pp <= 0.01 E_p, as the shipped fit took them) as
dimensionless columns, then fits the shear angle and the solid fraction by `mbgc fit` twice with
the same settings and seeds, once with C = ced / (rho_p g d50) and once with
Co = C (K / 1e5)^(-2/3) (equal at K 1e5), and prints the validation RMSEs. A smaller GP budget
than the shipped model's (population 3000, 80 generations, 2 restarts): the comparison, not the
model, is the point. About 20 minutes per seed on 2 cores. Standard library only:

    python3 docs/data/stiffness/cohesion_group_fits.py [path/to/mbgc] [seed ...]
"""

import csv
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../.."))
REST = "mu_pp,mu_pw,mu_r_pp,mu_r_pw,e_pp,e_pw,nu_p,sigma_ln"


def convert(src, dst):
    with open(src, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "done" and r["settled"] == "true"]
    out = []
    for r in rows:
        e, ew = float(r["E_p"]), float(r["E_w"])
        w = float(r["rho_p"]) * 9.81 * float(r["d50"]) * 1e-3
        ced, cw = float(r["ced_pp"]), float(r["ced_pw"])
        a, b = float(r["shear_angle"] or "nan"), float(r["bulk_density"] or "nan")
        if ced > 0.01 * e or math.isnan(a) or math.isnan(b):
            continue
        kp, kw, c, c_w = e / w, ew / w, ced / w, cw / w
        d = {"lnKp": math.log(kp), "lnKw": math.log(kw), "C_pp": c, "C_pw": c_w,
             "Co_pp": c * (kp / 1e5) ** (-2 / 3), "Co_pw": c_w * (kw / 1e5) ** (-2 / 3)}
        d.update({k: r[k] for k in REST.split(",")})
        d.update({"shear_angle": a, "solid_fraction": b / float(r["rho_p"])})
        out.append(d)
    with open(dst, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(out[0]))
        wr.writeheader()
        wr.writerows(out)
    return len(out)


def main():
    mbgc = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "mbgc")
    seeds = [int(s) for s in sys.argv[2:]] or [1, 7]
    with tempfile.TemporaryDirectory() as tmp:
        train, val = os.path.join(tmp, "train.csv"), os.path.join(tmp, "val.csv")
        n = convert(os.path.join(ROOT, "training_data", "shear_box_sjkr.csv"), train)
        m = convert(os.path.join(ROOT, "training_data", "shear_box_sjkr_validation.csv"), val)
        print(f"{n} training rows, {m} validation rows\n")
        print("| seed | cohesion input | shear_angle validation RMSE (deg) | solid_fraction validation RMSE |")
        print("|---|---|---|---|")
        for seed in seeds:
            for group in ("C", "Co"):
                out = os.path.join(tmp, f"fit_{group}_{seed}.json")
                cmd = [mbgc, "fit", "--data", train, "--inputs",
                       f"lnKp,lnKw,{group}_pp,{group}_pw,{REST}",
                       "--targets", "shear_angle,solid_fraction", "--out", out,
                       "--population", "3000", "--generations", "80", "--max-length", "56",
                       "--parsimony", "0.0001", "--restarts", "2", "--select", "cv",
                       "--test-fraction", "0", "--no-figures", "--seed", str(seed),
                       "--validation", val, "--json"]
                res = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
                rmse = {r["name"]: r["validation"]["rmse"] for r in res["responses"]}
                print(f"| {seed} | {group} | {rmse['shear_angle']:.3f} | {rmse['solid_fraction']:.5f} |")


if __name__ == "__main__":
    main()
