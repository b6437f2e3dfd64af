#!/usr/bin/env bash
# Builds the satmesh container image (docker/Dockerfile) with buildah on a machine that has
# no Docker engine and no registry: the Debian 12 base image is made locally with
# debootstrap from the host's configured Debian archive. Idempotent: installs the host
# tools and makes the base image only when missing; --layers reuses unchanged stages.
# Run as root.
#
#   scripts/build-image.sh [--tag localhost/satmesh:latest] [--base localhost/debian:12-slim]
#                          [--jobs 2] [--git REV] [--mirror URL] [--rebuild-base] [--ccache DIR]
#                          [--redis-tag localhost/satmesh-redis:latest]
# --git REV builds the committed tree REV (git archive) instead of the working tree.
# --ccache DIR mounts the compiler cache DIR into the compile step (reuses a host build's
# objects: CI passes the cache its `scripts/build.sh` filled).
# Also builds --redis-tag from docker/redis.Dockerfile (Debian's redis-server on the same
# base; the Redis of docker/compose-redis.yaml); "" skips it.
# Exit status: 0 built; 2 usage; 3 this machine cannot build images at all (not root, host
# tools not installable, no working container storage), named on stderr; else the build failed.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"

tag="localhost/satmesh:latest"   # image to build
base="localhost/debian:12-slim"  # local Debian 12 base image (FROM of both stages)
jobs=2                           # compile jobs inside the image build (ninja -j)
mirror=""                        # Debian mirror for debootstrap; default: the host's
rebuild_base=0                   # 1: remake the base image even if present
git_rev=""                       # build context: "" = working tree, else this commit
ccache_dir=""                    # host compiler cache mounted at /ccache; "" = none
redis_tag="localhost/satmesh-redis:latest"  # Redis image for compose-redis.yaml; "" = none

usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --tag) tag="$2"; shift 2 ;;
    --base) base="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --mirror) mirror="$2"; shift 2 ;;
    --git) git_rev="$2"; shift 2 ;;
    --rebuild-base) rebuild_base=1; shift ;;
    --ccache) ccache_dir="$2"; shift 2 ;;
    --redis-tag) redis_tag="$2"; shift 2 ;;
    -h|--help) usage ;;
    *) echo "build-image: unknown argument '$1'" >&2; usage ;;
  esac
done
# A machine that cannot build images at all: exit 3 with the reason (CI tells it apart).
cannot() { echo "build-image: this machine cannot build images: $*" >&2; exit 3; }
[ "$(id -u)" -eq 0 ] || cannot "not root (uid $(id -u)); debootstrap and buildah mount need root"
case "$jobs" in ''|*[!0-9]*) echo "build-image: --jobs '$jobs' is not a positive integer" >&2; exit 2 ;; esac

# Host tools (not project dependencies: docker/deps-debian12.txt is what the image installs).
install_host_tools() {
  local missing="" p
  for p in buildah debootstrap uidmap; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
  [ -z "$missing" ] && return 0
  echo "build-image: installing host tools:$missing"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq || cannot "apt-get update failed (host tools:$missing)"
  apt-get install -y -qq --no-install-recommends $missing || cannot "apt-get install$missing failed"
}

# overlay where the kernel allows it, else vfs (slower, always works).
pick_storage_driver() {
  [ -n "${STORAGE_DRIVER:-}" ] && return 0
  local ctr
  if ctr=$(buildah from scratch 2>/dev/null) && buildah mount "$ctr" >/dev/null 2>&1; then
    buildah umount "$ctr" >/dev/null; buildah rm "$ctr" >/dev/null
  else
    [ -n "${ctr:-}" ] && buildah rm "$ctr" >/dev/null 2>&1 || true
    echo "build-image: overlay storage does not work here, using vfs"
    export STORAGE_DRIVER=vfs
    local err
    if ! ctr=$(buildah from scratch 2>"${TMPDIR:-/tmp}/build-image-storage.err") \
        || ! buildah mount "$ctr" >/dev/null 2>>"${TMPDIR:-/tmp}/build-image-storage.err"; then
      err="$(tail -3 "${TMPDIR:-/tmp}/build-image-storage.err")"
      [ -n "${ctr:-}" ] && buildah rm "$ctr" >/dev/null 2>&1 || true
      rm -f "${TMPDIR:-/tmp}/build-image-storage.err"
      cannot "buildah cannot create and mount a container with overlay nor vfs storage: $err"
    fi
    buildah umount "$ctr" >/dev/null; buildah rm "$ctr" >/dev/null
    rm -f "${TMPDIR:-/tmp}/build-image-storage.err"
  fi
}

# The host's Debian apt sources: enabled files that name a .../debian URI.
host_source_files() {
  grep -lE '^(URIs:|deb )[^#]*https?://[^ ]*/debian' \
    /etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list 2>/dev/null || true
}

host_mirror() {
  host_source_files | xargs -r grep -hoE 'https?://[^ ]*/debian/?( |$)' | head -1 | tr -d ' '
}

make_base_image() {
  [ -n "$mirror" ] || mirror="$(host_mirror)"
  [ -n "$mirror" ] || { echo "build-image: no Debian mirror in /etc/apt (use --mirror URL)" >&2; exit 1; }
  local rootfs ctr mnt f
  rootfs="$(mktemp -d /tmp/satmesh-rootfs.XXXXXX)"
  echo "build-image: debootstrap bookworm from $mirror into $rootfs"
  debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$rootfs.log" 2>&1 \
    || { tail -20 "$rootfs.log" >&2; exit 1; }
  rm -f "$rootfs.log"
  # apt inside the image uses the host's sources and archive settings (e.g. a snapshot
  # archive whose Release files are past Valid-Until).
  rm -f "$rootfs/etc/apt/sources.list"
  for f in $(host_source_files); do cp "$f" "$rootfs/etc/apt/sources.list.d/"; done
  apt-config dump | grep -E '^Acquire::Check-(Valid-Until|Date) ' \
    > "$rootfs/etc/apt/apt.conf.d/99host-archive" || true
  rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/archives/*.deb \
         "$rootfs"/var/cache/apt/*.bin "$rootfs"/var/log/*.log "$rootfs"/tmp/*
  : > "$rootfs/etc/resolv.conf"; : > "$rootfs/etc/hostname"
  ctr=$(buildah from scratch)
  mnt=$(buildah mount "$ctr")
  cp -a "$rootfs"/. "$mnt"/
  buildah umount "$ctr" >/dev/null
  buildah config --env PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    --cmd /bin/bash --label "org.opencontainers.image.source=debootstrap bookworm $mirror" "$ctr"
  buildah commit --rm -q "$ctr" "$base" >/dev/null
  # debootstrap unmounts what it mounted; never delete through a mount left behind.
  findmnt -rn -o TARGET | grep -q "^$rootfs" || rm -rf "$rootfs"
  echo "build-image: base image $base created"
}

install_host_tools
pick_storage_driver
if [ "$rebuild_base" -eq 1 ] || ! buildah inspect --type image "$base" >/dev/null 2>&1; then
  make_base_image
else
  echo "build-image: base image $base present"
fi

# The RUN steps need `buildah run` (chroot isolation: mounts, namespaces) to work here.
check_run() {
  local ctr out
  ctr=$(buildah from --pull=never "$base") || cannot "buildah from $base failed"
  if ! out=$(buildah run --isolation chroot "$ctr" -- true 2>&1); then
    buildah rm "$ctr" >/dev/null 2>&1 || true
    cannot "buildah run --isolation chroot fails: $(echo "$out" | tail -3)"
  fi
  buildah rm "$ctr" >/dev/null
}
check_run

context="$here"
if [ -n "$git_rev" ]; then
  context="$(mktemp -d /tmp/satmesh-context.XXXXXX)"
  trap 'rm -rf "$context"' EXIT
  git -C "$here" archive "$git_rev" | tar -x -C "$context"
  # One fixed mtime: --layers then reuses the dependency layers across commits.
  find "$context" -exec touch -h -d @946684800 {} +
fi
volume=()
if [ -n "$ccache_dir" ]; then
  mkdir -p "$ccache_dir"
  volume=(--volume "$(cd "$ccache_dir" && pwd):/ccache")
fi
# The host's CA certificates for the build's npm ci (on a network that inspects TLS, the
# host trusts its CA; apt fetches over plain HTTP and needs none). Mounted, not copied.
host_ca=/etc/ssl/certs/ca-certificates.crt
[ -r "$host_ca" ] && volume+=(--volume "$host_ca:/host-ca-certificates.crt:ro")
echo "build-image: building $tag from ${git_rev:-the working tree} (niced, -j$jobs${ccache_dir:+, ccache $ccache_dir})"
cd "$context"
nice -n 10 buildah bud --isolation chroot --layers --pull=never --format docker "${volume[@]}" \
  --build-arg DEBIAN_IMAGE="$base" --build-arg BUILD_JOBS="$jobs" \
  -f docker/Dockerfile -t "$tag" .
buildah images --format '{{.Name}}:{{.Tag}} {{.Size}}' "$tag"
if [ -n "$redis_tag" ]; then
  echo "build-image: building $redis_tag (docker/redis.Dockerfile)"
  nice -n 10 buildah bud --isolation chroot --layers --pull=never --format docker \
    --build-arg DEBIAN_IMAGE="$base" -f docker/redis.Dockerfile -t "$redis_tag" docker/
  buildah images --format '{{.Name}}:{{.Tag}} {{.Size}}' "$redis_tag"
fi
