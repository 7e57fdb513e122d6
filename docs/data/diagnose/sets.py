"""What the measurement-file scripts of the DEM sets share (issue35/ and issue40/
to_measurements.py): reading a set's table of runs, the per-fraction means with the pooled
replicate sd, and the [[sample]] entries. Standard library only."""

import csv
import math
import os
import statistics


def read(here, name, runs):
    """The finished runs of set `name` by d50, or None (with a message) while it is incomplete."""
    table = os.path.join(here, f"{name}.csv")
    if not os.path.exists(table):
        print(f"{table}: not made yet; run make_sets.sh")
        return None
    with open(table, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "done"]
    by_d = {}
    for r in rows:
        by_d.setdefault(float(r["d50"]), []).append(r)
    with open(os.path.join(here, f"{name}_design.csv"), newline="") as f:
        planned = sum(1 for _ in csv.DictReader(f))
    if len(rows) < planned or any(len(v) < runs for v in by_d.values()):
        print(f"{table}: {len(rows)} of {planned} runs done; run make_sets.sh to finish")
        return None
    return by_d


def summarise(by_d, responses):
    """Per (d50, response) the mean of its runs (where all have a value); per response the
    pooled sd of one run and its degrees of freedom."""
    means, pooled = {}, {}
    for resp in responses:
        var, dof = 0.0, 0
        for d, runs in by_d.items():
            vals = [float(r[resp]) for r in runs if not math.isnan(float(r[resp]))]
            if len(vals) == len(runs):
                means[(d, resp)] = statistics.fmean(vals)
                var += statistics.variance(vals) * (len(vals) - 1)
                dof += len(vals) - 1
        pooled[resp] = (math.sqrt(var / dof), dof) if dof else (float("nan"), 0)
    return means, pooled


def write_samples(f, by_d, means, sd, responses):
    """One [[sample]] per fraction (sigma_ln 0.12), with each response it has a mean of."""
    for d in sorted(by_d):
        f.write(
            f'\n[[sample]]\nname = "{d:g} mm"\nexperiment = "shear-box"\n'
            f"psd = {{ d50_mm = {d:g}, sigma_ln = 0.12 }}\n"
        )
        for resp in responses:
            if (d, resp) in means:
                f.write(
                    f"measured.{resp} = {{ value = {means[(d, resp)]:.2f}, "
                    f"sd = {sd[resp]:.2f} }}\n"
                )
