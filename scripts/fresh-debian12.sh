#!/usr/bin/env bash
# Times the README's two commands on a fresh Debian 12, as docs/results.md reports them: a minimal
# `debootstrap bookworm` tree per command (its base system only), a clean clone of this
# repository's HEAD inside it, entered with chroot as root. Needs root and Debian's mirror.
#   bash scripts/fresh-debian12.sh WORKDIR [main|tests]   (WORKDIR: an empty folder, ~10 GB free)
# Writes WORKDIR/main.log and WORKDIR/tests.log (or the one named), each ending with `time`'s
# figures. The trees
# stay in WORKDIR (unmount WORKDIR/*/{proc,sys,dev} before removing them).
set -euo pipefail
[ $# -ge 1 ] && [ $# -le 2 ] || { echo "usage: $0 WORKDIR [main|tests]" >&2; exit 2; }
jobs=${2:-main tests}
case "$jobs" in main | tests | "main tests") ;; *) echo "$0: no job '$jobs'" >&2; exit 2 ;; esac
[ "$(id -u)" -eq 0 ] || { echo "$0: needs root (debootstrap, chroot)" >&2; exit 2; }
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
work="$(mkdir -p "$1" && cd "$1" && pwd)"
command -v debootstrap >/dev/null || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap
debootstrap bookworm "$work/base" http://deb.debian.org/debian
# A Debian 12 installation's sources: the release, its updates and security updates.
cat > "$work/base/etc/apt/sources.list" <<'EOF'
deb http://deb.debian.org/debian bookworm main
deb http://deb.debian.org/debian bookworm-updates main
deb http://deb.debian.org/debian-security bookworm-security main
EOF
cp /etc/resolv.conf "$work/base/etc/resolv.conf"

# in_tree ROOT COMMAND: COMMAND as root in ROOT, clean environment, with /proc, /sys and /dev.
in_tree() {
  local root=$1
  shift
  mountpoint -q "$root/proc" || mount -t proc proc "$root/proc"
  mountpoint -q "$root/sys" || mount --rbind /sys "$root/sys"
  mountpoint -q "$root/dev" || mount --rbind /dev "$root/dev"
  chroot "$root" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 bash -c "$*"
}

declare -A command=([main]="bash scripts/run-main-job.sh" [tests]="bash .ci/run")
for job in $jobs; do
  cp -a "$work/base" "$work/$job"
  git clone -q "$repo" "$work/$job/root/shelfcross"
  in_tree "$work/$job" "cd /root/shelfcross && time ${command[$job]}" > "$work/$job.log" 2>&1
  tail -n 4 "$work/$job.log"
done
