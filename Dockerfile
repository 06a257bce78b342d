# Multi-stage build of the `mpm` binary (solver, CLI and job service).
# Build:  docker build -t mpm .
# Run:    docker run -p 8080:8080 -v mpm-data:/data mpm          (serves and solves, SQLite)
# Group:  docker-compose.yml (PostgreSQL, `serve --workers 0`, `worker` x N)
FROM rust:1.95-slim-bookworm AS build
WORKDIR /src
# gcc is in the image; SQLite is compiled in (sqlx's bundled libsqlite3);
# the PostgreSQL driver is pure Rust.
COPY Cargo.toml Cargo.lock ./
COPY crates ./crates
COPY src ./src
COPY migrations ./migrations
COPY openapi.yaml ./
RUN cargo build --release --locked --bin mpm \
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
VOLUME ["/data"]
ENV MPM_ADDR=0.0.0.0:8080 \
    MPM_DATABASE=/data/mpm.sqlite \
    MPM_LOG=info
EXPOSE 8080
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
  CMD curl -fsS http://127.0.0.1:8080/health || exit 1
ENTRYPOINT ["mpm"]
CMD ["serve"]
