#!/usr/bin/env bash
# Creates the Python environment for the gplearn side of the GP benchmark.
# Idempotent: an existing venv is reused, and pip leaves already-satisfied
# exact pins alone (no network needed on a second run).
#
# Why these pins: gplearn 0.4.2 calls BaseEstimator._validate_data, which
# scikit-learn deprecated in 1.6 and removed in 1.7 (gplearn issue #304 /
# #307), so scikit-learn stays on 1.5.2, the last release before that change.
# Everything else, transitive dependencies included, is pinned so that runs
# are reproducible.
set -euo pipefail

VENV="${GP_VENV:-/work/venv-gp}"
PYTHON="${PYTHON:-python3}"

if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi

"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    gplearn==0.4.2 \
    scikit-learn==1.5.2 \
    numpy==2.2.6 \
    scipy==1.14.1 \
    joblib==1.4.2 \
    threadpoolctl==3.5.0 \
    sympy==1.14.0 \
    mpmath==1.3.0

"$VENV/bin/python" -c 'import gplearn, sklearn, numpy, sympy; print("gplearn", gplearn.__version__, "| scikit-learn", sklearn.__version__, "| numpy", numpy.__version__, "| sympy", sympy.__version__)'
echo "venv ready: $VENV"
