#!/usr/bin/env bash
# Every test: the C++ engines (GoogleTest through ctest) and the Python/YADE side (pytest; the
# tests that compare with YADE start yade-double themselves).
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
ctest --test-dir build --output-on-failure -j2
/usr/bin/python3 -m pytest -q -p no:cacheprovider tests/py "$@"
