#!/usr/bin/env bash
# Installs what is missing (Debian 12 packages, with apt-get) and builds trueaniso into build/.
# Used by main.sh and test.sh; safe to run again (it only installs and rebuilds what is needed).
# Arguments: CMake targets to build. None: everything (target all) and the YADE plugin; given
# targets (`all` too) build those alone, without the plugin.
#   --with-lammps   install Debian's lammps too (the speed benchmark's peer, bench/bench_stepper.py;
#                   docs/benchmarks.md); TRUEANISO_WITH_LAMMPS=1 does the same.
set -euo pipefail
cd "$(dirname "$0")"
with_lammps="${TRUEANISO_WITH_LAMMPS:-0}"
args=()
for a in "$@"; do
  case "$a" in
    --with-lammps) with_lammps=1 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "setup: unknown option $a (--with-lammps, --help, or CMake targets)" >&2; exit 2 ;;
    *) args+=("$a") ;;
  esac
done
set -- ${args[@]+"${args[@]}"}

# Everything ./main.sh, ./test.sh, ./test.sh --long, the YADE plugin and ./docs/build.sh need on a
# machine with only Debian's base packages (tests/fresh_machine.sh checks that on a debootstrap root):
# libopenmpi-dev for the plugin's FindMPI (YADE's headers are built with MPI), bzip2 to unpack the
# YADE source, python3-pyflakes for the layout test's unused-import check, python3-threadpoolctl to
# hold numpy's BLAS to a run's --threads (resources.use_threads), libjs-mathjax for the
# manual's formulas without a network, chromium for the test that no table of the built manual is
# clipped (tests/py/test_manual.py).
PACKAGES=(g++ cmake make ninja-build bzip2 yade libeigen3-dev libboost-python-dev libboost-numpy-dev
          libgtest-dev libsuitesparse-dev libcgal-dev libopenmpi-dev openmpi-bin
          python3-numpy python3-scipy python3-matplotlib python3-pytest python3-pytest-xdist
          python3-jsonschema python3-mpi4py python3-pyflakes python3-threadpoolctl
          python3-sphinx python3-myst-parser python3-sphinx-rtd-theme libjs-mathjax
          chromium)
# LAMMPS is no dependency of trueaniso: only the speed benchmark compares with it.
if [ "$with_lammps" = 1 ]; then PACKAGES+=(lammps); fi
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
    SUDO=sudo
  fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Targets to build: all by default; main.sh asks for the Python module alone, which is all a study
# needs (a fresh build is about a third shorter), and ./test.sh for `all` without the plugin.
targets="${*:-}"

# Debian's interpreter: the one yade-double embeds and the one with numpy/scipy.
# The build log goes to build/build.log; on failure its tail is shown and setup exits non-zero
# (a stale module from an earlier build must never pass for a fresh one).
mkdir -p build
log=build/build.log
# The default build makes the engines' module for the portable baseline and for x86-64-v3, and the
# package loads the fastest the processor runs (CMakeLists.txt, docs/howto/build-options.md).
# TRUEANISO_ARCH=x86-64-v3 ./setup.sh (or ./main.sh, ./test.sh; x86-64, -v2, -v4 likewise) builds for
# that level alone; unset, the build keeps what it was configured with, TRUEANISO_ARCH= returns to both.
# A new build directory uses Ninja (a fresh build is faster than with make); one configured before
# keeps its generator, as CMake requires.
generator=()
[ -f build/CMakeCache.txt ] || generator=(-G Ninja)
# The YADE plugin (engines/yade, docs/yade-peer.md), when no target is named: its own CMake
# project, built, self-tested and installed into build/yade-prefix when the YADE source can be had
# (TRUEANISO_YADE_SOURCE or apt-get source), else one line says why; it never stops the setup
# (cmake/yade_plugin.sh). It shares nothing with the build below, and its one large translation
# unit leaves a core idle for most of its compile, so it runs beside it (about a minute less on 2
# cores); a failing build below waits for it, so that nothing writes into build/ after setup ends.
plugin=""
if [ -z "$targets" ]; then
  cmake/yade_plugin.sh &
  plugin=$!
fi
finish_plugin() { if [ -n "$plugin" ]; then wait "$plugin" || true; plugin=""; fi; }
if ! cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 \
       ${TRUEANISO_ARCH+"-DTRUEANISO_ARCH=$TRUEANISO_ARCH"} >"$log" 2>&1; then
  tail -n 40 "$log" >&2
  echo "setup: CMake refused to configure the build (full log: $log)" >&2
  finish_plugin
  exit 1
fi
if ! cmake --build build -j"$(nproc)" ${targets:+--target $targets} >>"$log" 2>&1; then
  tail -n 40 "$log" >&2
  echo "setup: build failed (full log: $log)" >&2
  finish_plugin
  exit 1
fi
# The level of the module just linked (written beside it when it is linked), not CMake's cache; a
# build for one level alone has no folder of other levels beside it.
level=$(cat build/python/_trueaniso.arch 2>/dev/null || true)
if [ -n "$level" ] && [ ! -d build/python/_trueaniso_levels ]; then  # sticky: say so on every run
  echo "setup: the engines are built for $level alone (TRUEANISO_ARCH; TRUEANISO_ARCH= ./setup.sh returns to the baseline and x86-64-v3, chosen at load)"
fi
grep -E "warning:" "$log" || true
cmake/link_package.sh

finish_plugin
