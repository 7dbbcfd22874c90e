# ctcsim-server with its page, for classes: one container serves the API and the page on port
# 8080 and keeps the jobs in SQLite on the volume /data.
#
#   docker build -t ctcsim .
#   docker run -d --name ctcsim -p 8080:8080 -v ctcsim-data:/data ctcsim
#
# Settings are the server's environment variables (ctcsim-server --help), e.g.
# -e CTCSIM_WORKERS=4 or -e CTCSIM_TOKEN=secret. The command line is in the image too:
# docker run --rm ctcsim ctcsim presets.
#
# Whoever changes the build steps or the libraries the programs link builds the image again and
# checks that it serves /api/health (README, "Run in Docker").

# ---------------------------------------------------------------------------- build
FROM debian:bookworm AS build

# the Makefile's RUN_PACKAGES (what make run installs; the test stack is left out) and Debian's
# own node and npm, enough for npm ci (node >= 18); ca-certificates so npm can check the
# registry's TLS
RUN apt-get update \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      gcc make libc6-dev libcjson-dev liblapacke-dev libsundials-dev libmicrohttpd-dev \
      libsqlite3-dev libxml2-dev libpq-dev zlib1g-dev nodejs npm ca-certificates \
 && rm -rf /var/lib/apt/lists/*

WORKDIR /src

# uPlot first, in its own layer: it only changes with the lock file, so editing C or the page
# does not download it again. EXTRA_CA_CERTS is for a build network behind a TLS-inspecting
# proxy, where npm would refuse the registry's certificate: the proxy's CA as PEM text
# (--build-arg EXTRA_CA_CERTS="$(cat proxy-ca.crt)"); empty elsewhere. The runtime stage does not
# carry it.
COPY Makefile ./
COPY web/package.json web/package-lock.json web/
ARG EXTRA_CA_CERTS=
RUN if [ -n "$EXTRA_CA_CERTS" ]; then \
      printf '%s\n' "$EXTRA_CA_CERTS" >/tmp/extra-ca.pem \
      && export NODE_EXTRA_CA_CERTS=/tmp/extra-ca.pem; \
    fi \
 && make build/web-npm/node_modules/.package-lock.json \
 && rm -f /tmp/extra-ca.pem

COPY src src/
COPY server server/
COPY web web/
COPY api api/
RUN make -j"$(nproc)" all web

# the tree the runtime stage takes in one COPY; stripped, since nobody debugs inside the image
# (build it with `make` outside to get the symbols)
RUN install -D -m 0755 -s build/ctcsim-server build/ctcsim -t /out/usr/local/bin \
 && mkdir -p /out/usr/local/share/ctcsim \
 && cp -R build/web api /out/usr/local/share/ctcsim/ \
 && rm -f /out/usr/local/share/ctcsim/web/.stamp

# ---------------------------------------------------------------------------- runtime
FROM debian:bookworm-slim

# the libraries the two programs NEED (readelf -d): Debian's libsundials_cvode.so.6 carries the
# serial vector and the dense matrix and solver, so no other SUNDIALS package; liblapacke pulls
# the reference BLAS and LAPACK (and libgfortran)
RUN apt-get update \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      libcjson1 libmicrohttpd12 libsqlite3-0 libpq5 libsundials-cvode6 liblapacke libxml2 zlib1g \
 && rm -rf /var/lib/apt/lists/*

# a fixed id, so a bind-mounted host directory can be chown'ed to 10001 ahead of time; /data is
# created owned by it, so a new named volume starts out writable
RUN groupadd --gid 10001 ctcsim \
 && useradd --uid 10001 --gid ctcsim --home-dir /data --no-create-home \
      --shell /usr/sbin/nologin ctcsim \
 && install -d -o ctcsim -g ctcsim -m 0750 /data

COPY --from=build /out/ /

# fails the build, not the first start, when a shared library is missing
RUN ctcsim-server --version && ctcsim presets >/dev/null

# 0.0.0.0: the server's default 127.0.0.1 would be unreachable through a published port
ENV CTCSIM_BIND=0.0.0.0 \
    CTCSIM_PORT=8080 \
    CTCSIM_DB=/data/ctcsim.db \
    CTCSIM_WEB=/usr/local/share/ctcsim/web \
    CTCSIM_API=/usr/local/share/ctcsim/api

VOLUME /data
WORKDIR /data
# numeric, so that runtimes that enforce non-root (Kubernetes runAsNonRoot) can check it
USER 10001:10001
EXPOSE 8080

# bash's /dev/tcp instead of curl: curl would add 16 packages (12 MB, libcurl, Kerberos, LDAP) to
# the image for one request; a status line other than 200 (503 when the database fails) or no
# answer within the timeout counts as unhealthy
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
  CMD bash -c 'exec 3<>/dev/tcp/127.0.0.1/"${CTCSIM_PORT:-8080}" \
      && printf "GET /api/health HTTP/1.0\r\nHost: localhost\r\n\r\n" >&3 \
      && read -r _ code _ <&3 && [ "$code" = 200 ]'

# exec form: the server is PID 1 and gets docker stop's SIGTERM itself; it sigwaits for it, puts
# running jobs back in the queue and exits 0
STOPSIGNAL SIGTERM
CMD ["ctcsim-server"]
