#!/usr/bin/env bash
# Runs a command under an X server of its own (Xvfb) and exits with the command's status.
#   xvfb.sh WIDTHxHEIGHTxDEPTH COMMAND [ARGS...]
# Xvfb picks the display itself (-displayfd): the first number whose lock file, file socket and
# abstract socket are all free. A fixed number (xvfb-run -n N) can start with only its file socket
# when another network namespace holds the abstract one, and clients, which try the abstract
# socket first, then reach that other server and are refused. The server takes a fresh cookie,
# so no client of another server gets into this one either.
set -u
if [ $# -lt 2 ]; then
  echo "usage: xvfb.sh WIDTHxHEIGHTxDEPTH COMMAND [ARGS...]" >&2
  exit 2
fi
screen=$1
shift

dir=$(mktemp -d -t sulcus-xvfb.XXXXXX) || exit 70
server=""
cleanup() {
  if [ -n "$server" ]; then
    kill "$server" 2>/dev/null
    wait "$server" 2>/dev/null
  fi
  rm -rf "$dir"
}
trap cleanup EXIT

export XAUTHORITY=$dir/Xauthority
cookie=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
# The server loads every cookie of the file whatever its display; the client looks its display up.
touch "$XAUTHORITY"
xauth -q add :0 . "$cookie" || exit 70

display=""
for attempt in 1 2 3; do
  : >"$dir/display"
  Xvfb -displayfd 3 -screen 0 "$screen" -nolisten tcp -auth "$XAUTHORITY" 3>"$dir/display" >"$dir/log" 2>&1 &
  server=$!
  # Xvfb writes the number once it accepts connections.
  for _ in $(seq 1 600); do
    read -r display <"$dir/display" 2>/dev/null || display=""
    [ -n "$display" ] && break
    kill -0 "$server" 2>/dev/null || break
    sleep 0.05
  done
  [ -n "$display" ] && break
  kill "$server" 2>/dev/null
  wait "$server" 2>/dev/null
  server=""
  echo "xvfb.sh: Xvfb did not start (attempt $attempt): $(tail -n 1 "$dir/log")" >&2
done
if [ -z "$display" ]; then
  echo "xvfb.sh: no X server; see Xvfb's log above" >&2
  exit 70
fi
xauth -q add ":$display" . "$cookie" || exit 70

DISPLAY=":$display" "$@"
