"""Phase by phase cost of whole shear-box runs, from the cost tables of issue 38, in the order
they were made (docs/dem_benchmark.md, "Whole runs phase by phase").

    python3 docs/data/cost_phases.py

Per table and point: the median over the table's seeds of mbgc's fill, outflow and whole-run
seconds and steps (per rest rule) and of LIGGGHTS' whole-run seconds in the same invocation.
The machine's speed drifts between invocations, so each mbgc time is also given as a share of
LIGGGHTS' time of the same seed in the same invocation (median over seeds): that share, not the
seconds, compares across tables.
"""

import csv
import os
import statistics

HERE = os.path.dirname(os.path.abspath(__file__))
TABLES = [
    ("before issue 38 (live flag)", "shear_box_cost_before.tsv"),
    ("response rule added", "shear_box_cost_rules.tsv"),
    ("four-lane kernel", "shear_box_cost_lanes.tsv"),
    ("near list", "shear_box_cost_near.tsv"),
    ("rebuild's fine search", "shear_box_cost_fine.tsv"),
    ("near entries, fused kick (quiet machine)", "shear_box_cost_fused_full.tsv"),
    ("vector kick, bounded check (quiet machine)", "shear_box_cost_kick.tsv"),
]
POINTS = ["a-5cls", "b-5cls", "a2-5cls", "b2-5cls"]


def rows(name):
    with open(os.path.join(HERE, name)) as f:
        return [r for r in csv.DictReader(f, delimiter="\t") if r["skin"] in ("1", "1.0")]


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    print("| table | point | rule | seeds | fill s | outflow s | whole s | steps | "
          "LIGGGHTS s | fill / LIGGGHTS | outflow / LIGGGHTS | whole / LIGGGHTS | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for label, name in TABLES:
        rs = rows(name)
        for pt in POINTS:
            lig = {r["seed"]: float(r["wall_s"]) for r in rs
                   if r["code"] == "liggghts" and r["point"] == pt}
            for code, rule in (("mbgc", "kinetic"), ("mbgc-response", "response")):
                m = [r for r in rs if r["code"] == code and r["point"] == pt
                     and r["seed"] in lig]
                if not m:
                    continue
                share = lambda col: med([float(r[col]) / lig[r["seed"]] for r in m])
                whole = share("wall_s")
                print(f"| {label} | {pt} | {rule} | {len(m)} | "
                      f"{med([float(r['fill_s']) for r in m]):.2f} | "
                      f"{med([float(r['flow_s']) for r in m]):.2f} | "
                      f"{med([float(r['wall_s']) for r in m]):.2f} | "
                      f"{med([float(r['steps']) for r in m]):.0f} | "
                      f"{med([lig[r['seed']] for r in m]):.1f} | "
                      f"{share('fill_s'):.3f} | {share('flow_s'):.3f} | {whole:.3f} | "
                      f"{med([lig[r['seed']] / float(r['wall_s']) for r in m]):.2f} |")


if __name__ == "__main__":
    main()
