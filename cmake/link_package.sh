#!/usr/bin/env bash
# Makes this checkout's Python package `trueaniso` importable by Debian's python3 and by
# yade-double (the same interpreter) from any folder: a file trueaniso.pth in the interpreter's
# site directory names pyscripts/ (the local site directory as root, the user's otherwise). Called
# by setup.sh. As with an editable install, the checkout set up last is the one linked, and a line
# says so when that changes; our own scripts and tests put their own checkout first whatever is
# linked. Never fails the setup: without a writable site directory it says how to import instead.
set -uo pipefail
cd "$(dirname "$0")/.."
pyscripts="$PWD/pyscripts"
if [ -n "${TRUEANISO_SITE:-}" ]; then
  site=$TRUEANISO_SITE  # another site directory (the tests use one of their own)
elif [ "$(id -u)" -eq 0 ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
else
  site=$(/usr/bin/python3 -c 'import site; print(site.getusersitepackages())')
fi
pth="$site/trueaniso.pth"
[ "$(cat "$pth" 2>/dev/null)" = "$pyscripts" ] && exit 0
before=$(cat "$pth" 2>/dev/null || true)
if mkdir -p "$site" 2>/dev/null && printf '%s\n' "$pyscripts" >"$pth.tmp.$$" 2>/dev/null && mv "$pth.tmp.$$" "$pth"; then
  if [ -n "$before" ]; then
    echo "setup: python3 and yade-double now import trueaniso from $pyscripts (was $before)"
  else
    echo "setup: python3 and yade-double import trueaniso from $pyscripts ($pth)"
  fi
else
  rm -f "$pth.tmp.$$"
  echo "setup: could not write $pth: to import trueaniso, put $pyscripts on PYTHONPATH" >&2
fi
exit 0
