#!/usr/bin/env bash
# The quick suite: the C++ engines (GoogleTest through ctest), then the Python/YADE side (pytest,
# the tests marked `long` left out; the tests that compare with YADE start yade-double themselves).
#   ./test.sh           setup of the engines, their module and tests (./setup.sh all), ctest,
#                       pytest -m "not long"
#   ./test.sh --long    the whole setup (./setup.sh: the YADE plugin too), then only the long tests
#                       (pytest -m long), the plugin's among them
#   ./test.sh --help    this text
# The YADE plugin is left to --long: its one large translation unit costs more than two minutes of
# a core on a fresh clone, a quarter of the quick suite's time, and nothing else needs it.
# Other arguments go to pytest (e.g. ./test.sh -k probe). pytest runs its test files on as many
# workers as there are cores (pytest-xdist, a file stays on one worker so that its module fixtures
# are made once) and names the 15 slowest tests at the end. `ctest --test-dir build` alone runs
# both pytest sets too (labels python and python_long).
set -euo pipefail
cd "$(dirname "$0")"
long=0
args=()
for a in "$@"; do
  case "$a" in
    --long) long=1 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) args+=("$a") ;;
  esac
done
if ((long)); then ./setup.sh; else ./setup.sh all; fi
# One engine thread per process: ctest runs two test programs at once and pytest two workers on
# two cores, and two OpenMP teams of two on two cores spin against each other (a statics test took
# 1.2 s alone, 25.7 s so).
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
if ((long)); then
  marker=long
else
  ctest --test-dir build --output-on-failure -j"$(nproc)" -LE python
  marker="not long"
fi
/usr/bin/python3 -m pytest -q -rs -p no:cacheprovider -n auto --dist loadfile --durations=15 -m "$marker" \
  tests/py "${args[@]}"
