#!/usr/bin/env bash
# The main job: the default study (a sphere specimen consolidated to 100 kPa, its state written to
# results/default/). Options are passed on to pyscripts/run_study.py (see --help there).
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh _trueaniso  # the Python module: test.sh builds the engines' tests too
# yade-double runs one OpenMP thread unless told (-j); the engines use all cores.
exec yade-double -j "$(nproc)" -n -x pyscripts/run_study.py "$@"
