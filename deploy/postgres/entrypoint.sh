#!/bin/sh
# First start: a cluster with the sheetmesh user and database; then PostgreSQL in the
# foreground (SIGTERM stops it cleanly).
set -e
bin=/usr/lib/postgresql/15/bin
data=/var/lib/sheetmesh-pg/data
if [ ! -f "$data/PG_VERSION" ]; then
  "$bin/initdb" -D "$data" -U sheetmesh --auth=trust -E UTF8 > /dev/null
  echo "listen_addresses = '*'" >> "$data/postgresql.conf"
  echo "host all all 0.0.0.0/0 trust" >> "$data/pg_hba.conf"
  "$bin/pg_ctl" -D "$data" -w -o "-c listen_addresses=''" start > /dev/null
  "$bin/createdb" -U sheetmesh sheetmesh
  "$bin/pg_ctl" -D "$data" -w stop > /dev/null
fi
exec "$bin/postgres" -D "$data" -k /tmp
