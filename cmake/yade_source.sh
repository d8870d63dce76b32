#!/usr/bin/env bash
# Puts the YADE 2023.02a source tree (the headers our YADE plugin compiles against; Debian ships
# the libraries only) into build/yade-source and prints its root on stdout. Exit status 0: the
# tree is there; 3: no source can be had (one line on stderr says why; the rest of the project
# builds without the plugin); 1: a source was found but is not the right one.
#
# Where the source comes from, in order:
#  - TRUEANISO_YADE_SOURCE: the orig tarball, the directory that holds it, or an unpacked source
#    directory;
#  - `apt-get source yade=2023.02a-1` through a temporary deb-src list, downloading only (the
#    system's apt configuration is not changed, no root needed).
# The tarball's sha256 is the one in Debian's signed source description of yade 2023.02a-1. A
# failed apt attempt is remembered for a day (build/yade-source.none) so that every setup does
# not ask the mirror again; TRUEANISO_YADE_SOURCE or deleting that file asks again.
set -euo pipefail
cd "$(dirname "$0")/.."
SHA256=b9444ae333ad7d02197cf3a5f6ad087653a0ba90f2840ab72530063ba22d4a4d
TARBALL=yade_2023.02a.orig.tar.bz2
dest=build/yade-source
none=build/yade-source.none
mkdir -p build

unpack() {  # $1: a tarball whose sha256 was checked
  local tmp
  tmp=$(mktemp -d build/yade-source.tmp.XXXXXX)
  tar -xjf "$1" -C "$tmp"
  rm -rf "$dest"
  mv "$tmp"/* "$dest"
  rm -rf "$tmp"
  echo "$SHA256" >"$dest/.trueaniso-sha256"
}

if [ -f "$dest/.trueaniso-sha256" ] && [ "$(cat "$dest/.trueaniso-sha256")" = "$SHA256" ]; then
  echo "$PWD/$dest"; exit 0
fi

# An unpacked tree is used where it lies, not copied: its path is remembered, so that a later setup
# without TRUEANISO_YADE_SOURCE finds it as it finds an unpacked tarball (without this, such a setup
# found no source and removed the plugin built from that tree).
remembered=build/yade-source.dir
src="${TRUEANISO_YADE_SOURCE:-}"
if [ -z "$src" ] && [ -f "$remembered" ] && [ -f "$(cat "$remembered")/core/Scene.hpp" ]; then
  src=$(cat "$remembered")
fi
if [ -n "$src" ]; then
  if [ -d "$src" ] && [ ! -f "$src/core/Scene.hpp" ] && [ -f "$src/$TARBALL" ]; then
    src="$src/$TARBALL"  # the directory the tarball lies in (../shared/deps), as the docs name it
  fi
  if [ -d "$src" ]; then
    # A directory: the tree of that same release, recognised by its version file and a core header.
    if [ ! -f "$src/core/Scene.hpp" ] || ! grep -q "2023.02a" "$src/RELEASE" 2>/dev/null; then
      echo "TRUEANISO_YADE_SOURCE=$src is not a YADE 2023.02a source tree (no core/Scene.hpp, or RELEASE is not 2023.02a) and holds no $TARBALL" >&2
      exit 1
    fi
    tree=$(cd "$src" && pwd)
    echo "$tree" >"$remembered"
    echo "$tree"
    exit 0
  fi
  if [ ! -f "$src" ]; then
    echo "TRUEANISO_YADE_SOURCE=$src: no such file or directory" >&2; exit 1
  fi
  sum=$(sha256sum "$src" | cut -d' ' -f1)
  if [ "$sum" != "$SHA256" ]; then
    echo "TRUEANISO_YADE_SOURCE=$src has sha256 $sum, not that of Debian's yade 2023.02a-1 ($SHA256)" >&2
    exit 1
  fi
  unpack "$src"; rm -f "$none"
  echo "$PWD/$dest"; exit 0
fi

if [ -f "$none" ] && [ -n "$(find "$none" -mmin -1440 2>/dev/null)" ]; then
  echo "no YADE source: the YADE plugin is not built; set TRUEANISO_YADE_SOURCE=<yade_2023.02a.orig.tar.bz2 or its directory> ($(cat "$none"))" >&2
  exit 3
fi

reason=""
if command -v apt-get >/dev/null; then
  T=$(mktemp -d)
  mirror=$(grep -rhoE 'https?://[^ ]*debian[^ ]*' /etc/apt/sources.list /etc/apt/sources.list.d/ 2>/dev/null | grep -v security | head -n1 || true)
  mirror=${mirror:-http://deb.debian.org/debian}
  echo "deb-src [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] $mirror bookworm main" >"$T/src.list"
  mkdir -p "$T/lists/partial" "$T/cache/archives/partial"
  O=(-o Dir::Etc::SourceList="$T/src.list" -o Dir::Etc::SourceParts=/dev/null -o Dir::State::Lists="$T/lists"
     -o Dir::Cache="$T/cache" -o Debug::NoLocking=1)
  if timeout 120 apt-get "${O[@]}" -qq update >"$T/log" 2>&1 &&
     (cd "$T" && timeout 300 apt-get "${O[@]}" -qq source --download-only yade=2023.02a-1 >>"$T/log" 2>&1) &&
     [ -f "$T/$TARBALL" ]; then
    sum=$(sha256sum "$T/$TARBALL" | cut -d' ' -f1)
    if [ "$sum" = "$SHA256" ]; then
      unpack "$T/$TARBALL"; rm -rf "$T"; rm -f "$none"
      echo "$PWD/$dest"; exit 0
    fi
    reason="apt-get source gave a tarball with sha256 $sum"
  else
    reason="apt-get source yade=2023.02a-1 failed: $(grep -E '^(E|W):' "$T/log" | head -n1 || true)"
  fi
  rm -rf "$T"
else
  reason="no apt-get"
fi
echo "$reason" >"$none"
echo "no YADE source: the YADE plugin is not built; set TRUEANISO_YADE_SOURCE=<yade_2023.02a.orig.tar.bz2 or its directory> ($reason)" >&2
exit 3
