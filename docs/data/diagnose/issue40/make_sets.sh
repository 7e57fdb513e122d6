#!/usr/bin/env bash
# The fine-material measurement sets of issue 40: spheres in three sieve fractions (d50 0.5, 1
# and 2 mm, sigma_ln 0.12), three runs per fraction (campaign seed 40, box scale 10), made by
# mbgc's DEM and diagnosed with the shipped models alone (docs/diagnose_fine.md).
#
# Cohesionless sets, one per stiffness and density (K_p = E / (rho_p g d50)):
#   fine_c: E 5 MPa,  rho_p 1000: K_p 2.5e5-1.0e6
#   fine_a: E 20 MPa, rho_p 2600: K_p 3.9e5-1.6e6
#   fine_b: E 50 MPa, rho_p 1500: K_p 1.7e6-6.8e6
# all beyond the shipped base model's training runs (K_p 9.8e3-1.94e5), inside its rigid limit.
#
# Cohesive sets, the same materials with an SJKR cohesion between the particles (walls not
# cohesive), chosen so that C_pp (K_p / 1.955e5)^(-2/3), the cohesion the material has at the
# cohesive model's stiffness edge (docs/cohesion_stiffness.md), lies at 200-700 of its 0-978:
#   fine_c_sjkr: ced_pp 1e4 J/m3
#   fine_a_sjkr: ced_pp 2.5e4 J/m3
#   fine_b_sjkr: ced_pp 5e4 J/m3 (not run: the weaker two were not told apart from friction)
#   fine_c_sjkr_strong: ced_pp 1.4e4 J/m3, C_pp carried to the edge 600-950
# The rest of the material is issue 35's: nu 0.3, e 0.5, mu_pp 0.5, mu_pw 0.3, mu_r_pp 0.3,
# mu_r_pw 0, walls as the particles.
#
# Resumable: rerun to continue; finished rows are kept. Then
#   python3 docs/data/diagnose/issue40/to_measurements.py
# writes examples/measurements/issue40_*.toml from the tables.
#
#   MBGC=target/release/mbgc THREADS=1 bash docs/data/diagnose/issue40/make_sets.sh [set ...]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
mbgc=${MBGC:-target/release/mbgc}
threads=${THREADS:-1}
sets=("$@")
if [ ${#sets[@]} -eq 0 ]; then sets=(fine_c fine_a fine_b fine_c_sjkr fine_a_sjkr fine_c_sjkr_strong); fi
for name in "${sets[@]}"; do
    case $name in
        fine_c) E=5e6; rho=1000; ced=0 ;;
        fine_a) E=2e7; rho=2600; ced=0 ;;
        fine_b) E=5e7; rho=1500; ced=0 ;;
        fine_c_sjkr) E=5e6; rho=1000; ced=1e4 ;;
        fine_a_sjkr) E=2e7; rho=2600; ced=2.5e4 ;;
        fine_b_sjkr) E=5e7; rho=1500; ced=5e4 ;;
        fine_c_sjkr_strong) E=5e6; rho=1000; ced=1.4e4 ;;
        *) echo "make_sets.sh: unknown set '$name' (fine_a, fine_b, fine_c, or one of them with _sjkr)" >&2; exit 2 ;;
    esac
    header="E_p,E_w,nu_p,e_pp,e_pw,mu_pp,mu_pw,mu_r_pp,mu_r_pw,rho_p,sigma_ln,d50"
    class=hertz,mindlin,epsd2
    coh=""
    if [ "$ced" != 0 ]; then
        header="$header,ced_pp,ced_pw"
        class=$class,sjkr
        coh=",$ced,0"
    fi
    design="$here/${name}_design.csv"
    if [ ! -f "$design" ]; then
        {
            echo "$header"
            for d in 0.5 1 2; do
                for _ in 1 2 3; do
                    echo "$E,$E,0.3,0.5,0.5,0.5,0.3,0.3,0,$rho,0.12,$d$coh"
                done
            done
        } > "$design"
    fi
    "$mbgc" simulate --design "$design" --experiment shear-box --box-scale 10 \
        --model-class "$class" --seed 40 --threads "$threads" \
        --out "$here/${name}.csv"
done
