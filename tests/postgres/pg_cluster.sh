#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A throwaway PostgreSQL server for the archive's tests: a cluster in a
# folder of its own, listening only on a Unix socket in that folder, with
# trust authentication, run by a user that is not root (PostgreSQL refuses
# root: as root the script runs the server as the "postgres" user that
# Debian's postgresql package makes).
#
#   pg_cluster.sh start DIR     initdb (first time) and start; prints the
#                               libpq connection string on stdout
#   pg_cluster.sh stop DIR      stop (fast: connections are cut)
#   pg_cluster.sh restart DIR   stop and start again
#   pg_cluster.sh remove DIR    stop and delete DIR
#
# Needs Debian's postgresql package (.ci/deps). DIR should be short: the
# socket's path must stay under 107 bytes.
set -euo pipefail
cmd=${1:?start|stop|restart|remove}
dir=${2:?a folder}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n1)
[[ -x "$bin/pg_ctl" ]] || { echo "pg_cluster: no PostgreSQL server (Debian postgresql)" >&2; exit 77; }
as_user=()
if [[ $(id -u) == 0 ]]; then
  id postgres >/dev/null 2>&1 || { echo "pg_cluster: root, and no 'postgres' user" >&2; exit 77; }
  as_user=(runuser -u postgres --)
fi
data=$dir/data
log=$dir/server.log

start() {
  if [[ ! -f $data/PG_VERSION ]]; then
    mkdir -p "$dir"
    [[ ${#as_user[@]} -gt 0 ]] && chown postgres "$dir"
    "${as_user[@]}" "$bin/initdb" -D "$data" -U postgres --auth=trust -E UTF8 --no-locale \
      >"$dir/initdb.log" 2>&1 || { cat "$dir/initdb.log" >&2; exit 1; }
  fi
  "${as_user[@]}" "$bin/pg_ctl" -D "$data" -l "$log" -w -t 60 \
    -o "-c listen_addresses='' -k $dir -c fsync=off -c max_connections=20" start >/dev/null ||
    { tail -n 20 "$log" >&2; exit 1; }
  echo "host=$dir dbname=postgres user=postgres connect_timeout=5"
}

stop() {
  [[ -f $data/postmaster.pid ]] || return 0
  "${as_user[@]}" "$bin/pg_ctl" -D "$data" -w -t 60 -m fast stop >/dev/null
}

case $cmd in
  start) start ;;
  stop) stop ;;
  restart) stop; start >/dev/null ;;
  remove) stop; rm -rf "$dir" ;;
  *) echo "pg_cluster: unknown command $cmd" >&2; exit 2 ;;
esac
