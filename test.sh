#!/usr/bin/env bash
# Every test: the C++ engines (GoogleTest through ctest), then the Python/YADE side (pytest; the
# tests that compare with YADE start yade-double themselves). `ctest --test-dir build` alone runs
# the same set (pytest is registered there as one test labelled "python"); this script runs pytest
# itself so that its progress shows. Arguments go to pytest (e.g. ./test.sh -k probe).
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
ctest --test-dir build --output-on-failure -j2 -LE python
/usr/bin/python3 -m pytest -q -p no:cacheprovider tests/py "$@"
