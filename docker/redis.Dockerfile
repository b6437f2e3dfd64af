# Redis for the queue deployment (docker/compose-redis.yaml): Debian 12's redis-server
# (7.0, the version the tests run), so the stack needs no image beyond Debian's base:
# scripts/build-image.sh builds it beside the satmesh image (localhost/satmesh-redis).
# The data directory /data is a volume; the compose file turns AOF on.
ARG DEBIAN_IMAGE=debian:12-slim
FROM ${DEBIAN_IMAGE}
ENV DEBIAN_FRONTEND=noninteractive
RUN apt-get update -qq \
 && apt-get install -y -qq --no-install-recommends redis-server \
 && rm -rf /var/lib/apt/lists/* \
 && mkdir -p /data && chown redis:redis /data
USER redis
WORKDIR /data
VOLUME ["/data"]
EXPOSE 6379
# No config file: every setting on the command line. Protected mode off: the other
# containers connect over the compose network (keep the port off public interfaces).
CMD ["redis-server", "--protected-mode", "no", "--dir", "/data", "--appendonly", "yes"]
