#!/bin/sh
# Seed 000's 36-run full factorial (mu_s x mu_r x e = 4 x 3 x 3) on mbgc's hopper; resumable.
exec cargo run --release -- simulate --design docs/data/sensitivity/seed000_design.csv \
  --experiment hopper --out docs/data/sensitivity/seed000_hopper.csv --seed 1 \
  --set E_p=2e7 --set E_w=2e7 --set nu_p=0.3 --set rho_p=2500 --set d50=2 \
  --set e_pw=0.45 --set mu_pw=0.25 --set mu_r_pw=0.25 "$@"
