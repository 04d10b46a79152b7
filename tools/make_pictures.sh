#!/usr/bin/env bash
# Regenerates docs/pictures/*.png: generated teeth, probes and cases drawn by render_asset.
#   tools/make_pictures.sh            (build directory: build, or $BUILD_DIR)
# The case commands are slow (each builds gingiva and bone from a chart): a few minutes in all.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build=${BUILD_DIR:-build}
out=docs/pictures
cmake --build "$build" --target sulcus-cli render_asset
cli="$build/bin/sulcus-cli"
render="$build/bin/render_asset"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"

# Teeth, each in its tooth frame (+X mesial, +Y occlusal, +Z buccal).
"$cli" content tooth 36 --out "$tmp/tooth_36.glb"
"$render" "$tmp/tooth_36.glb" "$out/tooth_36.png" --view iso
"$cli" content tooth 11 --out "$tmp/tooth_11.glb"
"$render" "$tmp/tooth_11.glb" "$out/tooth_11.png" --yaw 35 --pitch 12

# Probes: the working end (probe frame: tip end at the origin, +Y toward the handle), turned so
# the probe lies across the picture, tip on the left; the collision tip node is not drawn.
for k in williams unc15 cpi marquis; do
  "$cli" content probe "$k" --out "$tmp/probe_$k.glb"
  "$render" "$tmp/probe_$k.glb" "$out/probe_$k.png" --view front --roll 90 --hide collision \
    --fit-box-mm -2 -0.5 -2 2 17 2 --size 900x300
done
# The Nabers working end curves toward +X in its plane: framed upright.
"$cli" content probe nabers --out "$tmp/probe_nabers.glb"
"$render" "$tmp/probe_nabers.glb" "$out/probe_nabers.png" --view front --hide collision \
  --fit-box-mm -2 -0.5 -2 14 17 2 --size 600x600
# One whole probe, handle included.
"$render" "$tmp/probe_williams.glb" "$out/probe_williams_whole.png" --view front --roll 90 --yaw 20 \
  --pitch 15 --hide collision --size 900x400

# Cases (case frame: +X patient's left, +Y up, +Z anterior). The lower right quadrant's buccal
# side faces -X / +Z.
"$cli" content case content/assets/cases/quadrant_44_47/chart.json --out "$tmp/q"
"$render" "$tmp/q/case.glb" "$out/quadrant_44_47.png" --yaw -55 --pitch 12 --hide probe
"$render" "$tmp/q/case.glb" "$out/quadrant_44_47_pockets.png" --yaw -55 --pitch 18 --hide probe \
  --alpha gingiva=0.4

"$cli" content case content/assets/cases/healthy_11/chart.json --out "$tmp/h"
"$render" "$tmp/h/case.glb" "$out/healthy_11.png" --view front --pitch -10 --hide probe
"$cli" content case content/assets/cases/periodontitis_36/chart.json --out "$tmp/p"
"$render" "$tmp/p/case.glb" "$out/periodontitis_36_pockets.png" --yaw 90 --pitch 12 --hide probe \
  --alpha gingiva=0.45

ls -l "$out"/*.png
