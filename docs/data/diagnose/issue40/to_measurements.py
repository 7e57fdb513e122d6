"""Measurement files of issue 40 from the DEM tables of make_sets.sh (standard library only).

Each fraction's value is the mean of its three runs; sd = the pooled replicate sd of one run over
the fractions, divided by sqrt(3). mu_pp and mu_r_pp are left unknown: the files fix every other
parameter of the material, as a user who knows the material's stiffness and density would.

    python3 docs/data/diagnose/issue40/to_measurements.py
"""

import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import sets  # noqa: E402  (docs/data/diagnose/sets.py)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "../../../.."))
# name: (E_p, rho_p, what)
SETS = {
    "fine_c": ("5e6", "1000", "E 5 MPa, rho_p 1000 kg/m3, no cohesion"),
    "fine_a": ("2e7", "2600", "E 20 MPa, rho_p 2600 kg/m3, no cohesion"),
    "fine_b": ("5e7", "1500", "E 50 MPa, rho_p 1500 kg/m3, no cohesion"),
    # The same materials with a hidden SJKR cohesion between the particles (walls not
    # cohesive): the files do not say it, as a user who does not know would write them.
    "fine_c_sjkr": ("5e6", "1000", "E 5 MPa, rho_p 1000 kg/m3, hidden cohesion ced_pp 1e4 J/m3"),
    "fine_a_sjkr": ("2e7", "2600", "E 20 MPa, rho_p 2600 kg/m3, hidden cohesion ced_pp 2.5e4 J/m3"),
    "fine_c_sjkr_strong": ("5e6", "1000", "E 5 MPa, rho_p 1000 kg/m3, hidden cohesion ced_pp 1.4e4 J/m3"),
}
RESPONSES = ["shear_angle", "bulk_density"]
RUNS = 3


def main():
    for name, (e_p, rho, what) in SETS.items():
        by_d = sets.read(HERE, name, RUNS)
        if by_d is None:
            continue
        means, pooled = sets.summarise(by_d, RESPONSES)
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
            sets.write_samples(f, by_d, means, sd, RESPONSES)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
