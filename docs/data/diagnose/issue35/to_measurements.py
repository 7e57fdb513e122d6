"""Measurement files of issue 35 from the DEM tables of make_sets.sh (standard library only).

Each fraction's value is the mean of its three runs; sd = the pooled replicate sd of one run over
the fractions, divided by sqrt(3) (as the earlier sets in docs/diagnose.md). A fraction whose runs
have no shear angle (nothing flowed out of the box: too cohesive) gives its bulk density only.
mu_pp and mu_r_pp are left unknown: the files fix every other parameter of the material.

    python3 docs/data/diagnose/issue35/to_measurements.py
"""

import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import sets  # noqa: E402  (docs/data/diagnose/sets.py)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "../../../.."))
SETS = [
    ("control", 0.0, "no cohesion (control)", "4.5e6"),
    ("ced1e4", 1e4, "cohesion ced_pp = 1e4 J/m3 hidden", "4.5e6"),
    ("ced2.5e4", 2.5e4, "cohesion ced_pp = 2.5e4 J/m3 hidden", "4.5e6"),
    ("ced4e4", 4e4, "cohesion ced_pp = 4e4 J/m3 hidden", "4.5e6"),
    # Outside the shipped models: K_p above their 1.96e5.
    ("outside", 5e4, "stiffer (E 20 MPa), cohesion ced_pp = 5e4 J/m3 hidden", "2e7"),
]
RESPONSES = ["shear_angle", "bulk_density"]


def main():
    for name, ced, what, e_p in SETS:
        by_d = sets.read(HERE, name, 3)
        if by_d is None:
            continue
        means, pooled = sets.summarise(by_d, RESPONSES)
        sd = {resp: pooled[resp][0] / math.sqrt(3) for resp in RESPONSES}
        out = os.path.join(ROOT, "examples", "measurements", f"issue35_{name}.toml")
        with open(out, "w") as f:
            f.write(
                f"# Synthetic (issue 35): three mbgc DEM shear-box runs per sieve fraction, {what};\n"
                f"# spheres E {float(e_p) / 1e6:g} MPa, nu 0.3, e 0.5, mu_pp 0.5, mu_pw 0.3, mu_r_pp 0.3, mu_r_pw 0,\n"
                "# rho_p 2600, walls not cohesive. mu_pp and mu_r_pp are searched (unknown).\n"
                "# Each value is the mean of 3 runs (campaign seed 35); sd = the pooled replicate sd\n"
                f"# ({pooled['shear_angle'][0]:.2f} deg, {pooled['bulk_density'][0]:.2f} kg/m3, "
                f"{pooled['shear_angle'][1]} and {pooled['bulk_density'][1]} dof) / sqrt(3).\n"
                f"# DEM table: docs/data/diagnose/issue35/{name}.csv (make_sets.sh).\n"
                f'name = "Spheres in {len(by_d)} sieve fractions, {what}"\n\n'
                '[model]\nclass = "hertz,mindlin,epsd2"\n\n'
                f"[fixed]\nE_p = {e_p}\nE_w = {e_p}\nnu_p = 0.3\ne_pp = 0.5\ne_pw = 0.5\n"
                "mu_pw = 0.3\nrho_p = 2600\n"
                "# The runs had mu_r_pw = 0; the shipped model's data start at 0.00047, so the\n"
                "# file gives its domain edge (no rolling resistance either way).\n"
                "mu_r_pw = 0.0005\n\n"
                "# Walls are not cohesive: the cohesion candidate fits the particle-particle energy\n"
                "# density only.\n[candidates.sjkr]\nfixed = { ced_pw = 0 }\n"
            )
            if name == "outside":
                # No shipped model covers it: the local model --build makes varies ced_pp over
                # this range (the shipped one's, 0-2.5e5, would spend the runs where the box
                # stops measuring).
                f.write(
                    "# The range a local model built by --build varies the cohesion over.\n"
                    "bounds = { ced_pp = [0, 1e5] }\n"
                )
            sets.write_samples(f, by_d, means, sd, RESPONSES)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
