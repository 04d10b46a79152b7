#!/usr/bin/env bash
# Runs every paper scene headless with plots into docs/paper/<scene>/ and prints a Markdown
# table of the measured figures (for README.md). Build first (tools/test.sh or tools/run.sh).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cli=build/bin/sulcus-cli
[ -x "$cli" ] || { echo "paper_report: $cli not built (run tools/test.sh first)" >&2; exit 2; }
echo "machine: $(lscpu | sed -n 's/^Model name:[[:space:]]*//p'), $(nproc) cores"
echo
echo "| scene | ticks | contact ticks | max penetration (m) | max gap in contact (m) | max force (N) | max force step (N) | step time median / p99 / max (µs) |"
echo "|---|---|---|---|---|---|---|---|"
for scene in content/assets/scenes/paper/*.json; do
  name=$(basename "$scene" .json)
  out=docs/paper/$name
  "$cli" run "$scene" --out "$out" --plot > /dev/null
  python3 - "$out/summary.json" "$name" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t = s["step_time_us"]
print(f"| {sys.argv[2]} | {s['steps']} | {s['contact_steps']} | {s['max_penetration_m']:.2g} | "
      f"{s['max_gap_in_contact_m']:.2g} | {s['max_force_N']:.3g} | {s['max_force_step_N']:.3g} | "
      f"{t['median']:.1f} / {t['p99']:.1f} / {t['max']:.0f} |")
PY
  rm -f "$out/steps.csv"
done
