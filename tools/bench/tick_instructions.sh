#!/bin/sh
# Instructions per servo tick of one bench scene, counted by callgrind: the measure of a step's
# cost that a noisy machine does not blur. callgrind dumps its counts before every call of
# sulcus::step, so each dump holds one tick (and the bench's few hundred instructions of
# book-keeping round it). On the dense wedge the counts follow the least of several timed runs
# per tick closely (a correlation of 0.97).
#
#   tools/bench/tick_instructions.sh SCENE [OUT_DIR] [MAX_TICKS]
#
# Writes OUT_DIR/SCENE_instructions.csv (tick,instructions; the scene's name with '/' as '_')
# and prints the median, p99, p99.9 and max over the ticks. Needs valgrind and a built
# build/bin/sulcus-cli; the tick indices match `sulcus-cli bench SCENE --ticks DIR`.
set -eu
scene=${1:?usage: tools/bench/tick_instructions.sh SCENE [OUT_DIR] [MAX_TICKS]}
out=${2:-out/tick_instructions}
max=${3:-0}
root=$(cd "$(dirname "$0")/../.." && pwd)
cli="$root/build/bin/sulcus-cli"
[ -x "$cli" ] || { echo "tick_instructions.sh: $cli: not built" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "tick_instructions.sh: valgrind: not installed" >&2; exit 2; }
mkdir -p "$out"
step='sulcus::step(sulcus::Model const&, sulcus::State&, sulcus::Pose const&)'
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
set -- bench "$scene" --check-every 0
[ "$max" -gt 0 ] && set -- "$@" --max-ticks "$max"
# The step's full name: a pattern ending in a wildcard also matches a lambda of step() that the
# compiler leaves out of line, and each of its calls would then start a "tick".
valgrind --tool=callgrind --dump-before="$step" --callgrind-out-file="$tmp/part" "$cli" "$@" \
    >"$tmp/log" 2>&1 || { cat "$tmp/log" >&2; exit 1; }
# Dump 1 holds the loading, dump 2 the warm-up step, dump k >= 3 tick k - 3; the last tick's
# counts end up in the final file with the exit, which is left out.
csv="$out/$(printf '%s' "$scene" | tr '/' '_')_instructions.csv"
echo "tick,instructions" >"$csv"
for f in "$tmp"/part.*; do
    awk -v k="${f##*.}" '/^totals:/ { if (k >= 3) print k - 3 "," $2; exit }' "$f"
done | sort -t, -k1,1n >>"$csv"
tail -n +2 "$csv" | cut -d, -f2 | sort -n | awk -v csv="$csv" '
    { v[NR] = $1 }
    END {
        if (NR == 0) { print "tick_instructions.sh: no ticks counted" > "/dev/stderr"; exit 1 }
        printf "%s: %d ticks; instructions per tick median %d, p99 %d, p99.9 %d, max %d\n", csv, NR,
               v[int(0.5 * NR) + 1], v[int(0.99 * NR) + 1], v[int(0.999 * NR) + 1], v[NR]
    }'
