# Multi-stage build of the `mpm` binary (solver, CLI and job service).
# Build:  docker build -t mpm .
# Run:    docker run -p 8080:8080 -v mpm-data:/data mpm          (serves and solves, SQLite)
# Group:  docker-compose.yml (PostgreSQL, `serve --workers 0`, `worker` x N)
FROM rust:1.95-slim-bookworm AS build
WORKDIR /src
# gcc is in the image; SQLite is compiled in (sqlx's bundled libsqlite3);
# the PostgreSQL driver is pure Rust.
#
# The dependencies first, on placeholder sources: this layer is rebuilt
# only when a manifest or the lock file changes, not on every change of
# the project's own code.
COPY Cargo.toml Cargo.lock ./
COPY crates/mpm/Cargo.toml crates/mpm/
COPY crates/mpm-lab/Cargo.toml crates/mpm-lab/
RUN mkdir -p src/cli crates/mpm/src crates/mpm-lab/src \
 && echo 'fn main() {}' > src/cli/main.rs \
 && touch src/lib.rs crates/mpm/src/lib.rs crates/mpm-lab/src/lib.rs \
 && cargo build --release --locked --bin mpm \
 && rm -rf src crates/mpm/src crates/mpm-lab/src
COPY crates ./crates
COPY src ./src
COPY migrations ./migrations
COPY openapi.yaml ./
# COPY keeps the files' own times, which may be older than the
# placeholders': touch them so that cargo rebuilds the project's crates.
RUN touch src/lib.rs src/cli/main.rs crates/mpm/src/lib.rs crates/mpm-lab/src/lib.rs \
 && cargo build --release --locked --bin mpm \
 && strip target/release/mpm

FROM debian:bookworm-slim
RUN apt-get update \
 && apt-get install -y --no-install-recommends curl ca-certificates \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --home-dir /data --shell /usr/sbin/nologin mpm \
 && mkdir -p /data && chown mpm /data
COPY --from=build /src/target/release/mpm /usr/local/bin/mpm
USER mpm
WORKDIR /data
# No VOLUME here: each container of a worker would get an anonymous volume
# of its own. Mount one where the SQLite file lives (`-v mpm-data:/data`).
ENV MPM_ADDR=0.0.0.0:8080 \
    MPM_DATABASE=/data/mpm.sqlite \
    MPM_LOG=info
EXPOSE 8080
# Exec form: no shell between Docker and curl. /health answers 503 when the
# database is unreachable or its writes fail (a full disk).
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
  CMD ["curl", "-fsS", "-o", "/dev/null", "http://127.0.0.1:8080/health"]
ENTRYPOINT ["mpm"]
CMD ["serve"]
