#!/usr/bin/env bash
# CI on a machine that has only Debian's base packages: makes a minimal Debian 12 root with
# debootstrap, puts a clean clone of this repository and a copy of ../shared in it, and runs
# `.ci/run` there (chroot). Whatever setup.sh forgets to install fails here, not on a new machine.
#
#   sudo tests/fresh_machine.sh [--rev REV] [--root DIR] [--keep] [--log FILE] [-- COMMAND]
#
#   --rev REV    the commit to clone (default HEAD; uncommitted changes are not in the root)
#   --root DIR   where the root is made (default /var/tmp/trueaniso-fresh-root; it is made anew)
#   --keep       leave the root in place afterwards (to look inside: chroot DIR bash)
#   --log FILE   the log of the run inside the root (default build/fresh-machine.log)
#   COMMAND      run this in the clone instead of `bash .ci/run` (e.g. -- ./main.sh)
#
# Needs root (debootstrap, chroot, mounts) and the network this machine's apt uses. The root uses
# this machine's apt sources and apt settings, /etc/hosts and resolv.conf, as a new machine here
# would; nothing else of this machine reaches it. The environment inside is that of a fresh login
# (HOME, PATH, LANG) plus the OPENBLAS_* variables set here, which some machines set for their
# processor. Exit status: that of the command inside the root. The manual (docs/howto/build-options.md,
# "A fresh machine") gives the time it takes.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
rev=HEAD
root=/var/tmp/trueaniso-fresh-root
keep=0
log="$here/build/fresh-machine.log"
command=(bash .ci/run)
while (($#)); do
  case "$1" in
    --rev) rev=${2:?--rev needs a commit}; shift 2 ;;
    --root) root=${2:?--root needs a directory}; shift 2 ;;
    --keep) keep=1; shift ;;
    --log) log=${2:?--log needs a file}; shift 2 ;;
    --) shift; command=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "fresh_machine: unknown argument $1 (--help lists them)" >&2; exit 2 ;;
  esac
done
if [ "$(id -u)" -ne 0 ]; then
  echo "fresh_machine: needs root (debootstrap, chroot and mounts)" >&2; exit 2
fi
shared=$(cd "$here/.." && pwd)/shared
[ -d "$shared" ] || { echo "fresh_machine: no ../shared beside the repository ($shared)" >&2; exit 2; }
commit=$(git -C "$here" rev-parse --verify "$rev^{commit}") || { echo "fresh_machine: no commit $rev" >&2; exit 2; }
case "$root" in /|/usr|/var|/tmp|/var/tmp|"$here"*) echo "fresh_machine: refusing root $root" >&2; exit 2 ;; esac

# The mirror this machine's apt uses (deb822 sources first, then the one-line format).
mirror=$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
[ -n "$mirror" ] || mirror=$(awk '$1 == "deb" && $0 !~ /security/ {print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
[ -n "$mirror" ] || { echo "fresh_machine: no Debian mirror found in this machine's apt sources" >&2; exit 2; }
if ! command -v debootstrap >/dev/null; then
  echo "fresh_machine: installing debootstrap"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null
fi

mounted=()
unmount_all() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do umount -l "${mounted[i]}" 2>/dev/null || true; done
  mounted=()
}
finish() {
  unmount_all
  if ((keep == 0)) && [ -d "$root" ]; then rm -rf --one-file-system "$root"; fi
}
trap finish EXIT
trap 'exit 130' INT TERM
mount_in() {  # $1: target under the root, the rest: mount's arguments
  local target="$root$1"; shift
  mkdir -p "$target"
  mount "$@" "$target"
  mounted+=("$target")
}

start=$(date +%s)
stamp() { printf '[%4d s] %s\n' $(($(date +%s) - start)) "$*"; }
if [ -d "$root" ]; then
  # a root left by an interrupted run may still have mounts inside: never delete through them
  grep -q " $root/" /proc/mounts && { echo "fresh_machine: $root still has mounts; umount them first" >&2; exit 2; }
  rm -rf --one-file-system "$root"
fi
mkdir -p "$root" "$(dirname "$log")"
stamp "debootstrap --variant=minbase bookworm from $mirror"
debootstrap --variant=minbase bookworm "$root" "$mirror" >"$log.debootstrap" 2>&1 \
  || { tail -n 20 "$log.debootstrap" >&2; echo "fresh_machine: debootstrap failed (log: $log.debootstrap)" >&2; exit 1; }
# This machine's apt sources and settings, as a new machine here has them.
rm -f "$root/etc/apt/sources.list"
cp /etc/apt/sources.list.d/*.sources "$root/etc/apt/sources.list.d/" 2>/dev/null || cp /etc/apt/sources.list "$root/etc/apt/"
cp /etc/apt/apt.conf.d/99* "$root/etc/apt/apt.conf.d/" 2>/dev/null || true
cp /etc/hosts /etc/resolv.conf "$root/etc/"
mount_in /proc -t proc proc
mount_in /sys -t sysfs sysfs
mount_in /dev --rbind /dev
mount --make-rslave "$root/dev"
mount_in /dev/shm -t tmpfs tmpfs
stamp "installing git and ca-certificates (what a new machine has to clone with)"
chroot "$root" bash -c 'apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends git ca-certificates' \
  >>"$log.debootstrap" 2>&1 || { echo "fresh_machine: apt-get inside the root failed (log: $log.debootstrap)" >&2; exit 1; }
stamp "cloning $commit and copying $shared"
mkdir -p "$root/w"
git clone -q --no-local "$here" "$root/w/main"
git -C "$root/w/main" checkout -q "$commit"
cp -a "$shared" "$root/w/shared"
stamp "running '${command[*]}' inside the root (log: $log)"
env=(HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 TERM=dumb)
while IFS= read -r v; do env+=("$v"); done < <(env | grep '^OPENBLAS_' || true)
set +e
chroot "$root" /usr/bin/env -i "${env[@]}" bash -c 'cd /w/main && "$@"' _ "${command[@]}" >"$log" 2>&1
rc=$?
set -e
tail -n 15 "$log"
stamp "exit status $rc ($commit)"
exit $rc
