#!/usr/bin/env bash
# The Dockerfile's base images where no image registry can be reached: Debian 12 made with
# debootstrap from this machine's own Debian mirror (the first URIs of its apt sources),
# its apt sources (security updates included) copied in, imported and tagged as the names
# the Dockerfile's FROM lines use (debian:bookworm, debian:bookworm-slim). Does nothing when
# those images exist already (pulled from a registry, or made before).
# Usage: tools/docker-base.sh [--force]
set -euo pipefail
force=${1:-}
if [ "$force" != --force ] && docker image inspect debian:bookworm >/dev/null 2>&1 &&
   docker image inspect debian:bookworm-slim >/dev/null 2>&1; then
  echo "docker-base: debian:bookworm and debian:bookworm-slim are there"
  exit 0
fi
mirror=$(sed -n 's/^URIs: *\([^ ]*\).*/\1/p' /etc/apt/sources.list.d/*.sources 2>/dev/null | head -1)
if [ -z "$mirror" ]; then
  mirror=$(sed -n 's/^deb \(\[[^]]*\] \)\{0,1\}\([^ ]*\) bookworm .*/\2/p' /etc/apt/sources.list 2>/dev/null | head -1)
fi
[ -n "$mirror" ] || { echo "docker-base: no Debian mirror in this machine's apt sources" >&2; exit 1; }
dir=$(mktemp -d /tmp/sheetmesh-base.XXXXXX)
trap 'rm -rf "$dir"' EXIT
echo "docker-base: debootstrap bookworm from $mirror"
debootstrap --variant=minbase bookworm "$dir" "$mirror" > "$dir.log" 2>&1 ||
  { tail -20 "$dir.log" >&2; exit 1; }
rm -f "$dir.log"
# The host's sources (with its security suite), not debootstrap's single line.
rm -f "$dir/etc/apt/sources.list"
mkdir -p "$dir/etc/apt/sources.list.d"
for f in /etc/apt/sources.list.d/*.sources /etc/apt/sources.list; do
  [ -f "$f" ] && grep -q "bookworm" "$f" && cp "$f" "$dir$f"
done
rm -rf "$dir/var/cache/apt/archives/"*.deb "$dir/var/lib/apt/lists/"*
tar -C "$dir" -c . | docker import - debian:bookworm > /dev/null
docker tag debian:bookworm debian:bookworm-slim
echo "docker-base: made debian:bookworm and debian:bookworm-slim"
