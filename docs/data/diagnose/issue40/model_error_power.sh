#!/bin/bash
# The sjkr ln Bayes factor of the issue-40 fine sets with every model's own error replaced by the
# set's [model_error] (docs/metamodel_wide.md, "What would make the verdict name sjkr").
# Run from the repository root after `cargo build --release`; about 8 s per diagnosis.
set -euo pipefail
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for c in fine_c fine_a fine_b fine_c_sjkr fine_a_sjkr fine_c_sjkr_strong; do
  for me in "" "1.38 6.3" "0.7 3" "0.3 1.5"; do
    set -- $me
    if [ -z "$me" ]; then
      cp examples/measurements/issue40_$c.toml "$tmp/set.toml"
    else
      awk -v a="$1" -v d="$2" '/^\[model\]$/ && !done {print "[model_error]\nshear_angle = " a "\nbulk_density = " d "\n"; done=1} {print}' \
        examples/measurements/issue40_$c.toml > "$tmp/set.toml"
    fi
    out=$(target/release/mbgc diagnose --measurements "$tmp/set.toml" \
      --model models/shear_box_wide.json --model models/shear_box_sjkr_wide.json 2>&1)
    sj=$(echo "$out" | grep -E "^\| sjkr \|" | awk -F'|' '{print "ln B" $5 "; chi^2 ratio" $6}')
    v=$(echo "$out" | grep "^Verdict" | cut -c10-45)
    echo "$c | model error ${me:-own} | $sj | $v"
  done
done
