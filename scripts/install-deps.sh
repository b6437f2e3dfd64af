#!/usr/bin/env bash
# Installs satmesh's dependencies:
#  1. Debian packages: docker/deps-debian12.txt (build and run; the Dockerfile installs the
#     same list) and, unless --no-test-tools, docker/deps-debian12-test.txt (the clients the
#     tests drive: headless Chromium, OWSLib).
#  2. web/: `npm ci` from web/package-lock.json (CesiumJS, which the build copies next to
#     the binaries for the job viewer; with the test tools also glTF-Validator and
#     puppeteer-core). Skipped when web/node_modules already matches the lock file.
# Needs Debian's archive and the npm registry; nothing is fetched at build or run time.
# --only debian|web does one of the two steps (the Dockerfile caches them as two layers).
#   scripts/install-deps.sh [--no-test-tools] [--only debian|web]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
test_tools=1 only=""
usage() { echo "usage: scripts/install-deps.sh [--no-test-tools] [--only debian|web]" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --no-test-tools) test_tools=0; shift ;;
    --only) [ "${2:-}" = debian ] || [ "${2:-}" = web ] || usage; only="$2"; shift 2 ;;
    *) usage ;;
  esac
done
if [ "$only" != web ]; then
lists=("$here/docker/deps-debian12.txt")
[ "$test_tools" = 1 ] && lists+=("$here/docker/deps-debian12-test.txt")
pkgs=$(cat "${lists[@]}" | sed 's/#.*//' | grep -v '^\s*$' | tr '\n' ' ')
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" && continue
  # npm (or chromium) may come with another distribution of Node.js (e.g. NodeSource's
  # nodejs bundles npm and conflicts with Debian's npm): a command of that name will do.
  case "$p" in npm|chromium) command -v "$p" >/dev/null && continue ;; esac
  missing="$missing $p"
done
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
if [ -z "$missing" ]; then
  echo "install-deps: all packages present"
else
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends $missing
fi
fi
[ "$only" = debian ] && exit 0

web="$here/web"
stamp="$web/node_modules/.satmesh-installed"
want="$(sha256sum "$web/package-lock.json" | cut -d' ' -f1) test_tools=$test_tools"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "install-deps: web/node_modules up to date"
else
  omit=(); [ "$test_tools" = 1 ] || omit=(--omit=dev)
  (cd "$web" && npm ci --no-audit --no-fund --ignore-scripts "${omit[@]}")
  echo "$want" > "$stamp"
fi
