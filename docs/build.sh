#!/usr/bin/env bash
# Builds the manual into build/manual/index.html, warnings as errors. The Python module is built
# first: the API reference imports the package, and the script reference runs each script's --help.
set -euo pipefail
cd "$(dirname "$0")/.."
./setup.sh _trueaniso
exec /usr/bin/python3 -m sphinx -E -W --keep-going -b html docs build/manual "$@"
