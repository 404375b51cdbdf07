#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for the tests: initdb and pg_ctl from Debian's postgresql
# package, in DIR, on a free loopback port, trust authentication, no fsync.
#   tools/pg_cluster.sh start DIR    prints the connection string (also in DIR/conninfo)
#   tools/pg_cluster.sh stop DIR
#   tools/pg_cluster.sh restart DIR  starts a stopped cluster again on its port
# Where PostgreSQL is not installed, `start` says so, writes no conninfo and exits 0 (the
# PostgreSQL tests then skip with a message).
set -euo pipefail
cmd=${1:?start or stop}
dir=$(realpath -m "${2:?DIR}")
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
run=()
if [ "$(id -u)" = 0 ]; then
  # initdb refuses root: the cluster belongs to the postgres user (Debian's package makes
  # it) or nobody.
  user=postgres
  id -u "$user" >/dev/null 2>&1 || user=nobody
  run=(runuser -u "$user" --)
fi
case $cmd in
  start)
    if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
      echo "pg_cluster: PostgreSQL is not installed (no /usr/lib/postgresql/*/bin/initdb); its tests skip"
      rm -f "$dir/conninfo"
      exit 0
    fi
    "$0" stop "$dir" >/dev/null 2>&1 || true
    rm -rf "$dir"
    mkdir -p "$dir"
    if [ ${#run[@]} -gt 0 ]; then
      chown "${run[2]}" "$dir"
      "${run[@]}" test -w "$dir" ||
        { echo "pg_cluster: $dir is not reachable by user ${run[2]}: make its parents traversable" >&2; exit 1; }
    fi
    "${run[@]}" "$bin/initdb" -D "$dir/data" -U sheetmesh --auth=trust -E UTF8 > "$dir/initdb.log" 2>&1 ||
      { cat "$dir/initdb.log" >&2; exit 1; }
    port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    "${run[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
      -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=off -c max_connections=200" start > /dev/null ||
      { cat "$dir/server.log" >&2; exit 1; }
    "${run[@]}" "$bin/createdb" -h 127.0.0.1 -p "$port" -U sheetmesh sheetmesh_test
    echo "host=127.0.0.1 port=$port user=sheetmesh dbname=sheetmesh_test connect_timeout=5" > "$dir/conninfo"
    cat "$dir/conninfo"
    ;;
  restart)
    port=$(sed -n 's/.*port=\([0-9]*\).*/\1/p' "$dir/conninfo")
    "${run[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
      -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=off -c max_connections=200" start > /dev/null
    ;;
  stop)
    if [ -n "$bin" ] && [ -f "$dir/data/postmaster.pid" ]; then
      "${run[@]}" "$bin/pg_ctl" -D "$dir/data" -m fast -w stop > /dev/null
    fi
    ;;
  *)
    echo "usage: $0 start|stop|restart DIR" >&2
    exit 2
    ;;
esac
