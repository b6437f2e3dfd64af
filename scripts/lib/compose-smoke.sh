# Shared by scripts/smoke-compose.sh and scripts/smoke-compose-queue.sh (sourced, not run).
# The caller defines: tag (the satmesh image), compose (podman-compose of its project),
# fail (message, exit 1), url (the API node), work (scratch folder, inputs/ in it), up (0
# until the stack is up), and exports SATMESH_TOKEN.

# The image's satmesh CLI on the host network, the inputs folder at /inputs.
cli() { podman run --rm --no-healthcheck --network host -e SATMESH_TOKEN -v "$work/inputs:/inputs" --entrypoint satmesh "$tag" "$@"; }

# Checks that podman runs the image and that the port is free; else fails naming why.
compose_smoke_preflight() {
  local out
  out=$(podman run --rm --no-healthcheck --entrypoint true "$tag" 2>&1) \
    || fail "podman cannot run a container here: $out (see docker/README.md, CONTAINERS_CONF)"
  curl -s -o /dev/null "$url/health" && fail "port ${url##*:} is already in use"
  return 0
}

# Writes the small synthetic scene into the inputs folder with the image's CLI, brings the
# stack up and waits for GET /health (30 s at most); its answer is left in $health.
compose_smoke_up_with_small_scene() {
  cli synth --preset small --out /inputs >"$work/synth.log" 2>&1 || { cat "$work/synth.log" >&2; fail "satmesh synth"; }
  up=1
  compose up -d --no-build >"$work/up.log" 2>&1 || { cat "$work/up.log" >&2; fail "podman-compose up"; }
  for _ in $(seq 100); do
    curl -fsS -o /dev/null "$url/health" 2>/dev/null && break
    sleep 0.3
  done
  health=$(curl -fsS "$url/health") || fail "GET /health of the API node"
}
