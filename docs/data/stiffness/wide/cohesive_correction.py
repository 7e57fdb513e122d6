"""Can the cohesive model be the widened base plus a cohesion correction that reads the stiffness
only through the contact's pull Ca = C K^(-2/3)? (issue 40)

The shipped cohesive model is the old base plus a correction fitted in C_pp, C_pw and the
stiffnesses; beyond its K range it is read on the edge with the cohesion carried there. A model
on the widened base needs a correction that holds from K 1e4 to 1e7 while its cohesive runs
stop at 1.95e5. The DEM says the cohesion effect at fixed Ca does not depend on K
(docs/cohesion_stiffness.md: lines r1-r8 at K 1.94e5, 1e6 and 1e7), so a correction that sees K
only through Ca extrapolates by that similarity. This script tests it without changing mbgc:

1. the base model (a widened one with its rigid limit) predicts the shipped cohesive campaign's
   rows (`mbgc predict`);
2. `mbgc fit` fits the residual (shear angle in deg; bulk density over rho_p, a solid fraction)
   twice with the same settings and seeds, once from lnK_p, lnK_w, Ca_pp, Ca_pw and the rest
   ("with K"), once without lnK_p and lnK_w ("Ca only");
3. both are scored, base plus correction, on the campaign's validation rows (inside K 1.95e5)
   and on the cohesive stiffness-validation rows (docs/data/stiffness/validation_sjkr.tsv, K_p
   6.6e3 to 5e8, never trained on), beside the shipped cohesive model.

Standard library only; about 10 minutes per fit and core:

    python3 docs/data/stiffness/wide/cohesive_correction.py --base <base.json> [--seeds 1 7]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../.."))
REST = ["mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "e_pp", "e_pw", "nu_p", "sigma_ln"]
INPUTS = ["E_p", "E_w", "nu_p", "e_pp", "e_pw", "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "rho_p",
          "d50", "sigma_ln", "ced_pp", "ced_pw"]
G = 9.81


def usable_campaign_rows(path):
    out = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["status"] != "done" or r["settled"] != "true":
                continue
            if float(r["ced_pp"]) > 0.01 * float(r["E_p"]):
                continue
            a, b = float(r["shear_angle"] or "nan"), float(r["bulk_density"] or "nan")
            if math.isnan(a) or math.isnan(b):
                continue
            out.append({**{k: r[k] for k in INPUTS}, "shear_angle": a, "bulk_density": b})
    return out


def validation_rows(path):
    out = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f, delimiter="\t"):
            a, b = float(r["shear_angle"] or "nan"), float(r["bulk_density"] or "nan")
            if math.isnan(a) and math.isnan(b):
                continue
            out.append({**{k: r[k] for k in INPUTS}, "shear_angle": a, "bulk_density": b})
    return out


def write(path, rows, fields):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def predict(mbgc, model, rows, tmp, tag):
    data, out = os.path.join(tmp, f"{tag}_in.csv"), os.path.join(tmp, f"{tag}_out.csv")
    write(data, rows, list(rows[0].keys()))
    subprocess.run([mbgc, "predict", "--model", model, "--data", data, "--out", out],
                   check=True, capture_output=True)
    with open(out, newline="") as f:
        rows_out = list(csv.DictReader(f))
    # A prediction is `<response>_predicted` when the table holds the response, `<response>`
    # when it does not.
    names = {k[: -len("_predicted")] for k in rows_out[0] if k.endswith("_predicted")}
    if not names:
        with open(data, newline="") as f:
            names = set(rows_out[0]) - set(next(csv.reader(f)))
    return [{f"{n}_predicted": float(r.get(f"{n}_predicted", r.get(n))) for n in names}
            for r in rows_out]


def groups(r):
    w = float(r["rho_p"]) * G * float(r["d50"]) * 1e-3
    kp, kw = float(r["E_p"]) / w, float(r["E_w"]) / w
    cp, cw = float(r["ced_pp"]) / w, float(r["ced_pw"]) / w
    d = {"lnKp": math.log(kp), "lnKw": math.log(kw),
         "Ca_pp": cp * (kp / 1e5) ** (-2 / 3), "Ca_pw": cw * (kp / 1e5) ** (-2 / 3)}
    d.update({k: r[k] for k in REST})
    return d, kp, kw


def residual_rows(rows, base):
    out = []
    for r, p in zip(rows, base):
        d, _, _ = groups(r)
        d["r_angle"] = r["shear_angle"] - p["shear_angle_predicted"]
        d["r_phi"] = (r["bulk_density"] - p["bulk_density_predicted"]) / float(r["rho_p"])
        out.append(d)
    return out


def stats(e):
    e = [v for v in e if math.isfinite(v)]
    n = len(e)
    if n < 2:
        return "-"
    m = sum(e) / n
    return f"{math.sqrt(sum(v * v for v in e) / n):.3f} ({n})"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--base", required=True, help="widened base model with its rigid limit")
    ap.add_argument("--mbgc", default=os.path.join(ROOT, "target", "release", "mbgc"))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--population", default="3000")
    ap.add_argument("--generations", default="80")
    ap.add_argument("--restarts", default="2")
    ap.add_argument("--max-length", default="48")
    ap.add_argument("--keep", help="directory to keep the fitted corrections in")
    a = ap.parse_args()
    train = usable_campaign_rows(os.path.join(ROOT, "training_data", "shear_box_sjkr.csv"))
    val = usable_campaign_rows(os.path.join(ROOT, "training_data", "shear_box_sjkr_validation.csv"))
    stiff = validation_rows(os.path.join(ROOT, "docs", "data", "stiffness", "validation_sjkr.tsv"))
    shipped = os.path.join(ROOT, "models", "shear_box_sjkr.json")
    with tempfile.TemporaryDirectory() as tmp:
        base_train = predict(a.mbgc, a.base, train, tmp, "bt")
        base_val = predict(a.mbgc, a.base, val, tmp, "bv")
        base_stiff = predict(a.mbgc, a.base, stiff, tmp, "bs")
        ship_val = predict(a.mbgc, shipped, val, tmp, "sv")
        ship_stiff = predict(a.mbgc, shipped, stiff, tmp, "ss")
        rt, rv = residual_rows(train, base_train), residual_rows(val, base_val)
        cols = list(rt[0].keys())
        ft, fv = os.path.join(tmp, "rt.csv"), os.path.join(tmp, "rv.csv")
        write(ft, rt, cols)
        write(fv, rv, cols)
        rs = []
        for r in stiff:
            d, kp, kw = groups(r)
            rs.append({**d, "kp": kp, "kw": kw, "cohesive": float(r["ced_pp"]) + float(r["ced_pw"]) > 0})
        fs = os.path.join(tmp, "rs.csv")
        write(fs, rs, [c for c in cols if not c.startswith("r_")])
        print(f"{len(rt)} training rows, {len(rv)} campaign validation rows, {len(rs)} stiffness-"
              f"validation rows; base {a.base}\n")

        def score(name, ang_v, phi_v, ang_s, phi_s):
            ev_a = [r["shear_angle"] - p for r, p in zip(val, ang_v)]
            ev_d = [r["bulk_density"] - p for r, p in zip(val, phi_v)]
            bands = [("inside 1.95e5", 0, 1.95e5), ("1.95e5-1e7", 1.95e5, 1e7), ("beyond 1e7", 1e7, 1e99)]
            cells = [stats(ev_a), stats(ev_d)]
            for _, lo, hi in bands:
                idx = [i for i, x in enumerate(rs) if lo <= max(x["kp"], x["kw"]) < hi]
                cells.append(stats([stiff[i]["shear_angle"] - ang_s[i] for i in idx]))
                cells.append(stats([stiff[i]["bulk_density"] - phi_s[i] for i in idx]))
            print(f"| {name} | " + " | ".join(cells) + " |")

        print("| model | campaign validation angle RMSE (n) | density | stiffness-validation angle, "
              "K < 1.95e5 | density | angle, 1.95e5-1e7 | density | angle, beyond 1e7 | density |")
        print("|---|---|---|---|---|---|---|---|---|")
        score("shipped cohesive", [p["shear_angle_predicted"] for p in ship_val],
              [p["bulk_density_predicted"] for p in ship_val],
              [p["shear_angle_predicted"] for p in ship_stiff],
              [p["bulk_density_predicted"] for p in ship_stiff])
        score("widened base alone", [p["shear_angle_predicted"] for p in base_val],
              [p["bulk_density_predicted"] for p in base_val],
              [p["shear_angle_predicted"] for p in base_stiff],
              [p["bulk_density_predicted"] for p in base_stiff])
        for seed in a.seeds:
            for label, inputs in [("with K", ["lnKp", "lnKw", "Ca_pp", "Ca_pw"] + REST),
                                  ("Ca only", ["Ca_pp", "Ca_pw"] + REST)]:
                out = os.path.join(tmp, f"fit_{seed}_{label.replace(' ', '_')}.json")
                cmd = [a.mbgc, "fit", "--data", ft, "--inputs", ",".join(inputs),
                       "--targets", "r_angle,r_phi", "--out", out,
                       "--population", a.population, "--generations", a.generations,
                       "--max-length", a.max_length, "--parsimony", "0.0001",
                       "--restarts", a.restarts, "--select", "cv", "--test-fraction", "0",
                       "--no-figures", "--seed", str(seed), "--validation", fv, "--json"]
                subprocess.run(cmd, check=True, capture_output=True, text=True)
                if a.keep:
                    os.makedirs(a.keep, exist_ok=True)
                    with open(out) as src, open(os.path.join(a.keep, os.path.basename(out)), "w") as dst:
                        dst.write(src.read())
                cv = predict(a.mbgc, out, rv, tmp, "cv")
                cs = predict(a.mbgc, out, rs, tmp, "cs")
                score(f"base + correction, {label}, seed {seed}",
                      [b["shear_angle_predicted"] + c["r_angle_predicted"] for b, c in zip(base_val, cv)],
                      [b["bulk_density_predicted"] + c["r_phi_predicted"] * float(r["rho_p"])
                       for b, c, r in zip(base_val, cv, val)],
                      [b["shear_angle_predicted"] + c["r_angle_predicted"] for b, c in zip(base_stiff, cs)],
                      [b["bulk_density_predicted"] + c["r_phi_predicted"] * float(r["rho_p"])
                       for b, c, r in zip(base_stiff, cs, stiff)])


if __name__ == "__main__":
    main()
