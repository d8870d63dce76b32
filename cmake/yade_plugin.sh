#!/usr/bin/env bash
# Builds, tests and installs the YADE plugin (engines/yade) into build/yade-prefix; called by
# setup.sh. Never fails the setup: the rest of the project works without the plugin. It says in
# one line why the plugin is not there, and writes the answer to build/yade-plugin.status:
#   installed | failed: <reason> | no-source: <reason>
# which the plugin's tests read to skip with that reason.
#
# Steps: the YADE source (cmake/yade_source.sh), the plugin's own CMake project in
# build/yade-plugin (one unity translation unit; never two of them compiled at once), the ABI
# self-test (engines/yade/selftest.py) in yade-double from a staging prefix, then the install:
#   build/yade-prefix/lib/x86_64-linux-gnu/yade-double/libtrueanisoYade.so
#   build/yade-prefix/lib/x86_64-linux-gnu/yade-double/py -> Debian's YADE Python package
#   build/yade-prefix/bin/yade-double -> /usr/bin/yade-double (yade-batch runs $YADE_PREFIX/bin/yade-double)
# Use: YADE_PREFIX=$PWD/build/yade-prefix yade-double -n -x script.py
set -uo pipefail
cd "$(dirname "$0")/.."
status=build/yade-plugin.status
log=build/yade-plugin.log
libdir=lib/x86_64-linux-gnu/yade-double
prefix=build/yade-prefix
YADE_LIBS=/usr/lib/x86_64-linux-gnu/yade-double
mkdir -p build

say() { echo "setup: $*" >&2; }
refuse() {  # $1: status word, $2: reason
  rm -f "$prefix/$libdir/libtrueanisoYade.so"
  echo "$1: $2" >"$status"
  say "the YADE plugin is not installed: $2"
  exit 0
}

if ! command -v yade-double >/dev/null; then
  refuse failed "yade-double is not installed"
fi
src=$(cmake/yade_source.sh 2>"$log.source")
rc=$?
if [ $rc -eq 3 ]; then
  line=$(tail -n1 "$log.source")
  echo "no-source: $line" >"$status"
  rm -f "$prefix/$libdir/libtrueanisoYade.so"
  echo "setup: $line" >&2
  exit 0
elif [ $rc -ne 0 ]; then
  refuse failed "$(tail -n1 "$log.source")"
fi

bdir=build/yade-plugin
if ! cmake -S engines/yade -B "$bdir" -DCMAKE_BUILD_TYPE=Release -DYADE_SOURCE_DIR="$src" \
       -DPython3_EXECUTABLE=/usr/bin/python3 >"$log" 2>&1; then
  tail -n 20 "$log" >&2
  refuse failed "CMake refused to configure the plugin (log: $log)"
fi
# One job: the unity translation unit alone needs about 4 GB.
if ! nice -n 5 cmake --build "$bdir" -j1 >>"$log" 2>&1; then
  tail -n 30 "$log" >&2
  refuse failed "the plugin did not compile (log: $log)"
fi
built="$bdir/stage/$libdir/libtrueanisoYade.so"
installed="$prefix/$libdir/libtrueanisoYade.so"
if [ -f "$installed" ] && cmp -s "$built" "$installed" && grep -qx installed "$status" 2>/dev/null; then
  exit 0  # this very library passed its self-test already
fi
ln -sfn "$YADE_LIBS/py" "$bdir/stage/$libdir/py"
if ! out=$(YADE_PREFIX="$PWD/$bdir/stage" OMP_NUM_THREADS=1 timeout 600 yade-double -n -x engines/yade/selftest.py 2>&1); then
  echo "$out" >>"$log"
  refuse failed "its ABI self-test failed: $(echo "$out" | grep '^self-test:' | tail -n1)"
fi
echo "$out" | grep '^self-test passed' >>"$log"
mkdir -p "$prefix/$libdir" "$prefix/bin"
cp "$built" "$installed.tmp" && mv "$installed.tmp" "$installed"
ln -sfn "$YADE_LIBS/py" "$prefix/$libdir/py"
ln -sfn /usr/bin/yade-double "$prefix/bin/yade-double"
echo installed >"$status"
say "the YADE plugin passed its ABI self-test and is installed: YADE_PREFIX=$PWD/$prefix yade-double"
