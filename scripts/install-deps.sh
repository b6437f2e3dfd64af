#!/usr/bin/env bash
# Installs satmesh's build and runtime dependencies from Debian's archive (docker/deps-debian12.txt).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
pkgs=$(grep -v '^\s*#' "$here/docker/deps-debian12.txt" | grep -v '^\s*$' | tr '\n' ' ')
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -z "$missing" ]; then echo "install-deps: all packages present"; exit 0; fi
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends $missing
