#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for the tests: initdb and pg_ctl from Debian's postgresql
# package, on a free loopback port, trust authentication, no fsync.
#   tools/pg_cluster.sh start DIR    prints the connection string (also in DIR/conninfo)
#   tools/pg_cluster.sh stop DIR
#   tools/pg_cluster.sh restart DIR  starts a stopped cluster again on its port
# The cluster lives in DIR/cluster, or, where the cluster's user cannot reach DIR (a home
# folder closed to others), in a folder under /tmp that DIR/cluster_path names. Where
# PostgreSQL is not installed, `start` says so, writes no conninfo and exits 0 (the
# PostgreSQL tests then skip with a message).
set -euo pipefail
cmd=${1:?start, stop or restart}
dir=$(realpath -m "${2:?DIR}")
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
run=()
user=
if [ "$(id -u)" = 0 ]; then
  # initdb refuses root: the cluster belongs to the postgres user (Debian's package makes
  # it) or nobody.
  user=postgres
  id -u "$user" > /dev/null 2>&1 || user=nobody
  run=(runuser -u "$user" --)
fi
cluster() { cat "$dir/cluster_path" 2> /dev/null || echo "$dir/cluster"; }
pg_start() {  # PORT
  "${run[@]}" "$bin/pg_ctl" -D "$(cluster)/data" -l "$(cluster)/server.log" -w -t 60 \
    -o "-c listen_addresses=127.0.0.1 -p $1 -k $(cluster) -c fsync=off -c max_connections=200" start > /dev/null ||
    { cat "$(cluster)/server.log" >&2; exit 1; }
}
case $cmd in
  start)
    if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
      echo "pg_cluster: PostgreSQL is not installed (no /usr/lib/postgresql/*/bin/initdb); its tests skip"
      rm -f "$dir/conninfo"
      exit 0
    fi
    "$0" stop "$dir" > /dev/null 2>&1 || true
    [ -f "$dir/cluster_path" ] && rm -rf "$(cat "$dir/cluster_path")"
    rm -rf "$dir"
    mkdir -p "$dir/cluster"
    if [ -n "$user" ]; then
      chown "$user" "$dir/cluster"
      if ! "${run[@]}" test -w "$dir/cluster"; then
        where=$(mktemp -d /tmp/sheetmesh-pg.XXXXXX)
        chmod 755 "$where"
        chown "$user" "$where"
        echo "$where" > "$dir/cluster_path"
      fi
    fi
    "${run[@]}" "$bin/initdb" -D "$(cluster)/data" -U sheetmesh --auth=trust -E UTF8 > "$dir/initdb.log" 2>&1 ||
      { cat "$dir/initdb.log" >&2; exit 1; }
    port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    pg_start "$port"
    "${run[@]}" "$bin/createdb" -h 127.0.0.1 -p "$port" -U sheetmesh sheetmesh_test
    echo "host=127.0.0.1 port=$port user=sheetmesh dbname=sheetmesh_test connect_timeout=5" > "$dir/conninfo"
    cat "$dir/conninfo"
    ;;
  restart)
    pg_start "$(sed -n 's/.*port=\([0-9]*\).*/\1/p' "$dir/conninfo")"
    ;;
  stop)
    if [ -n "$bin" ] && [ -f "$(cluster)/data/postmaster.pid" ]; then
      "${run[@]}" "$bin/pg_ctl" -D "$(cluster)/data" -m fast -w stop > /dev/null
    fi
    ;;
  *)
    echo "usage: $0 start|stop|restart DIR" >&2
    exit 2
    ;;
esac
