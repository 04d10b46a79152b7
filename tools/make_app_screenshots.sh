#!/usr/bin/env bash
# Makes the desktop app's pictures in docs/pictures/ (docs/app.md): the simulated hand probes a
# bundled case and the app writes the frame at a given servo tick. Runs under Xvfb when there is
# no display. Uses the build directory `build`, or $BUILD_DIR.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${BUILD_DIR:-build}
app="$build/bin/sulcus"
[ -x "$app" ] || { echo "make_app_screenshots: $app not built" >&2; exit 2; }
out=docs/pictures

run() {
  if [ -n "${DISPLAY:-}" ]; then "$app" "$@"; else tests/app/xvfb.sh 1920x1080x24 "$app" "$@"; fi
}

# The quadrant: the probe on the floor of the 6 mm buccal pocket of 46 (pass 46 B of case.json
# holds from t = 21.41 s to 21.90 s), gingiva see-through.
run --case "$build/cases/quadrant_44_47" --device sim --ticks 21700 --size 1600x900 --gingiva 0.4 \
    --sextant 6 --msaa 4 --screenshot "$out/app_pocket.png"
# The same run to the end of its trajectory: every site charted, against the reference chart.
run --case "$build/cases/quadrant_44_47" --device sim --ticks 42600 --size 1600x900 --gingiva 0.4 \
    --sextant 6 --msaa 4 --reference --screenshot "$out/app_chart.png"
# healthy_11 at the floor of its distobuccal pocket (pass 11 DB holds 3.43 - 3.73 s): the force
# plot shows the three buccal sites' probing.
run --case "$build/cases/healthy_11" --device sim --ticks 3600 --size 1600x900 --gingiva 0.4 \
    --msaa 4 --screenshot "$out/app_force.png"
# The periodontitis 36 lesson with the simulated hand, at the floor of the lingual pocket (pass
# 36 L holds 10.7 - 11.0 s): the lesson panel's step, sites and feedback.
run --lesson content/assets/lessons/periodontitis_36.json --device sim --record none --ticks 10900 \
    --size 1600x900 --gingiva 0.4 --msaa 4 --screenshot "$out/app_lesson.png"
