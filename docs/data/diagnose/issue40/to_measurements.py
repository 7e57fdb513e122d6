"""Measurement files of issue 40 from the DEM tables of make_sets.sh (standard library only).

Each fraction's value is the mean of its three runs; sd = the pooled replicate sd of one run over
the fractions, divided by sqrt(3). mu_pp and mu_r_pp are left unknown: the files fix every other
parameter of the material, as a user who knows the material's stiffness and density would.

    python3 docs/data/diagnose/issue40/to_measurements.py
"""

import csv
import math
import os
import statistics

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "../../../.."))
# name: (E_p, rho_p, what)
SETS = {
    "fine_c": ("5e6", "1000", "E 5 MPa, rho_p 1000 kg/m3, no cohesion"),
    "fine_a": ("2e7", "2600", "E 20 MPa, rho_p 2600 kg/m3, no cohesion"),
    "fine_b": ("5e7", "1500", "E 50 MPa, rho_p 1500 kg/m3, no cohesion"),
}
RESPONSES = ["shear_angle", "bulk_density"]
RUNS = 3


def read(name):
    """The finished runs by d50, or None (with a message) while the set is incomplete."""
    table = os.path.join(HERE, f"{name}.csv")
    if not os.path.exists(table):
        print(f"{table}: not made yet; run make_sets.sh")
        return None
    with open(table, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "done"]
    with open(os.path.join(HERE, f"{name}_design.csv"), newline="") as f:
        planned = sum(1 for _ in csv.DictReader(f))
    by_d = {}
    for r in rows:
        by_d.setdefault(float(r["d50"]), []).append(r)
    if len(rows) < planned or any(len(v) < RUNS for v in by_d.values()):
        print(f"{table}: {len(rows)} of {planned} runs done; run make_sets.sh to finish")
        return None
    return by_d


def summarise(by_d):
    """Per (d50, response) the mean; per response the pooled sd of one run and its dof."""
    means, pooled = {}, {}
    for resp in RESPONSES:
        var, dof = 0.0, 0
        for d, runs in by_d.items():
            vals = [float(r[resp]) for r in runs]
            if all(math.isfinite(v) for v in vals):
                means[(d, resp)] = statistics.fmean(vals)
                var += statistics.variance(vals) * (len(vals) - 1)
                dof += len(vals) - 1
        pooled[resp] = (math.sqrt(var / dof), dof) if dof else (float("nan"), 0)
    return means, pooled


def main():
    for name, (e_p, rho, what) in SETS.items():
        by_d = read(name)
        if by_d is None:
            continue
        means, pooled = summarise(by_d)
        sd = {resp: pooled[resp][0] / math.sqrt(RUNS) for resp in RESPONSES}
        k = [float(e_p) / (float(rho) * 9.81 * d * 1e-3) for d in sorted(by_d)]
        out = os.path.join(ROOT, "examples", "measurements", f"issue40_{name}.toml")
        with open(out, "w") as f:
            f.write(
                "# Synthetic (issue 40): three mbgc DEM shear-box runs per sieve fraction of a fine\n"
                f"# material, {what}; spheres nu 0.3, e 0.5, mu_pp 0.5, mu_pw 0.3,\n"
                "# mu_r_pp 0.3, mu_r_pw 0. mu_pp and mu_r_pp are searched (unknown).\n"
                f"# K_p = E / (rho_p g d50) from {min(k):.3g} to {max(k):.3g}: beyond the shipped\n"
                "# model's training runs (9.8e3-1.94e5), answered by its rigid limit.\n"
                f"# Each value is the mean of {RUNS} runs (campaign seed 40); sd = the pooled replicate sd\n"
                f"# ({pooled['shear_angle'][0]:.2f} deg, {pooled['bulk_density'][0]:.2f} kg/m3, "
                f"{pooled['shear_angle'][1]} and {pooled['bulk_density'][1]} dof) / sqrt({RUNS}).\n"
                f"# DEM table: docs/data/diagnose/issue40/{name}.csv (make_sets.sh).\n"
                f'name = "Fine spheres in {len(by_d)} sieve fractions, {what}"\n\n'
                '[model]\nclass = "hertz,mindlin,epsd2"\n\n'
                f"[fixed]\nE_p = {e_p}\nE_w = {e_p}\nnu_p = 0.3\ne_pp = 0.5\ne_pw = 0.5\n"
                f"mu_pw = 0.3\nrho_p = {rho}\n"
                "# The runs had mu_r_pw = 0; the shipped model's data start at 0.00047, so the\n"
                "# file gives its domain edge (no rolling resistance either way).\n"
                "mu_r_pw = 0.0005\n\n"
                "# Walls are not cohesive: the cohesion candidate fits the particle-particle energy\n"
                "# density only.\n[candidates.sjkr]\nfixed = { ced_pw = 0 }\n"
            )
            for d in sorted(by_d):
                f.write(
                    f'\n[[sample]]\nname = "{d:g} mm"\nexperiment = "shear-box"\n'
                    f"psd = {{ d50_mm = {d:g}, sigma_ln = 0.12 }}\n"
                )
                for resp in RESPONSES:
                    if (d, resp) in means:
                        f.write(
                            f"measured.{resp} = {{ value = {means[(d, resp)]:.2f}, "
                            f"sd = {sd[resp]:.2f} }}\n"
                        )
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
