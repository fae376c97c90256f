#!/bin/sh
# Makes the secrets a farm deployment reads, into DIR (for Compose: deploy/compose/secrets; for
# Kubernetes: deploy/k8s/secrets, replacing the placeholders there):
#   tokens             the servers' --tokens file: one '<sha256> <name> <roles>' line a token
#   scheduler.token    the schedulers' own token (role scheduler: they call the workers)
#   worker.token       the workers' token (role worker: they register and fetch assets)
#   admin.token        yours, for `farm submit`, `farm status` and the dashboard (role admin)
#   ci.token           a CI's, for `farm regress --scheduler` (role submit: its own jobs only)
#   postgres-password  the job store's password (PostgreSQL's superuser for the farm's database)
#   store.env          the same as PGPASSWORD=..., which libpq reads (Compose's env_file)
#
# Usage: make-secrets.sh [--force] DIR
# FARM names the farm binary (default: `farm` on PATH), e.g.
#   FARM=build/release/server/farm deploy/compose/make-secrets.sh deploy/compose/secrets
#   FARM='podman run --rm localhost/renderfarm:latest' deploy/compose/make-secrets.sh deploy/compose/secrets
# The tokens come from `farm token`, so their form and hash are the farm's own.
set -eu

force=no
if [ "${1:-}" = "--force" ]; then
  force=yes
  shift
fi
[ $# -eq 1 ] || { echo "usage: $0 [--force] DIR" >&2; exit 2; }
dir=$1
farm=${FARM:-farm}

# Replacing real secrets logs every worker and client out: only placeholders (or nothing) are
# replaced unless --force says so.
if [ -f "$dir/tokens" ] && ! grep -q PLACEHOLDER "$dir/tokens" && [ "$force" = no ]; then
  echo "$dir/tokens already holds tokens; give --force to replace every secret in $dir" >&2
  exit 1
fi

mkdir -p "$dir"
# The folder keeps the secrets from other users of this machine. The files themselves are
# world-readable because Compose bind-mounts them as they are, and the containers' non-root
# users (farm, postgres) are not their owner here.
chmod 700 "$dir"
umask 022

tokens_tmp=$(mktemp "$dir/.tokens.XXXXXX")
trap 'rm -f "$tokens_tmp" "$dir/.token.tmp" "$dir/.hash.tmp"' EXIT
echo "# <sha256 of the token> <holder> <roles>, made by make-secrets.sh: hashes, never the tokens" >"$tokens_tmp"
for entry in scheduler:scheduler worker:worker admin:admin ci:submit; do
  name=${entry%%:*}
  roles=${entry#*:}
  # `farm token` prints the token on stdout and, last on stderr, the line for the tokens file.
  $farm token "$name" --roles "$roles" >"$dir/.token.tmp" 2>"$dir/.hash.tmp"
  tail -n 1 "$dir/.hash.tmp" >>"$tokens_tmp"
  mv "$dir/.token.tmp" "$dir/$name.token"
done
mv "$tokens_tmp" "$dir/tokens"

# 32 random bytes as hex: no character that a URL or an env file would need quoted.
password=$(od -An -N32 -tx1 /dev/urandom | tr -d ' \n')
printf '%s' "$password" >"$dir/postgres-password"
printf 'PGPASSWORD=%s\n' "$password" >"$dir/store.env"
chmod 644 "$dir"/tokens "$dir"/*.token "$dir/postgres-password" "$dir/store.env"
echo "secrets written to $dir (keep them out of version control)"
