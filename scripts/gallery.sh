#!/usr/bin/env bash
# Regenerates docs/gallery.md and its pictures (docs/gallery/*.png): the same
# moment of the densest urban map with traffic, seen by the UAV chasing the
# car, the car's first-person and chase cameras and an eye-level camera by
# walkers, in the flat look of --quality fast ("before") and in every
# conditions preset. Deterministic: rerunning gives the same PNGs.
#   bash scripts/gallery.sh            (after a build in build/)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${SIM4CV_BUILD_DIR:-build}
OUT=docs/gallery
cmake --build "$BUILD_DIR" -j"$(nproc)" --target sim4cv_gallery > /dev/null
rm -rf "$OUT"
mkdir -p "$OUT"
start=$(date +%s%N)
"$BUILD_DIR/tools/sim4cv_gallery" --out "$OUT" --width 320 --height 180 > /dev/null
rm -f "$OUT/sheet.png"
seconds=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { print (b - a) / 1e9 }')

# The "Realism probe" section (bench/realism_probe.py writes its table) is kept as it is.
probe_section=$(sed -n '/^## Realism probe/,$p' docs/gallery.md 2>/dev/null || true)
views="uav car_front car_chase walkers"
looks="fast $(sed -n 's/^ *X(\([A-Z_]*\), "\([a-z_]*\)".*/\2/p' protocol/conditions.h | tr '\n' ' ') noise randomised_0 randomised_1 randomised_2"
looks="$looks antialias exposure_plus_1ev white_balance_3200k motion_blur lens jpeg_15 action_camera"
{
  echo "# Gallery"
  echo
  echo "Made by \`bash scripts/gallery.sh\` ($(nproc) cores, $(printf '%.1f' "$seconds") s, $(date -u +%Y-%m-%d)): the"
  echo "map \`scenes/driving/train/01_urban.map\` with 12 moving cars, 20 parked and 16 walkers, 10 s after"
  echo "the start, 320x180. Rows: the flat look of \`--quality fast\` (what every frame looked like before"
  echo "the look existed), then each \`--conditions\` preset at its own hour (protocol/conditions.h),"
  echo "then clear_noon with sensor noise (\`--noise-read 3 --noise-shot 1.5\`) and three draws of domain"
  echo "randomisation (\`--randomize 2026\`: draws 0, 1, 2). Then clear_noon through each camera effect"
  echo "(protocol/effects.h, docs/protocol.md \"Camera effects\"): \`--antialias 1\`, \`--exposure-ev 1\`,"
  echo "\`--white-balance 3200\` (a camera set for tungsten light, in daylight), \`--motion-blur 1\`"
  echo "(a shutter open the whole 1/30 s frame; the flow is from the frame before), a wide-angle lens"
  echo "(\`--lens-k1 -0.28 --lens-k2 0.07 --lens-p1 0.002 --lens-p2 -0.0015 --lens-k3 -0.005\`),"
  echo "\`--jpeg 15\`, and a cheap action camera: that lens, \`--motion-blur 0.5\`, sensor noise,"
  echo "\`--antialias 1 --jpeg 60\`."
  echo "Columns: the UAV chasing the target car, the car's first-person camera, the chase camera, an"
  echo "eye-level camera by a walker. Depth, masks, boxes, semantic labels, normals and flow are the"
  echo "same in every row but the lens rows (tests/unit/look_test.cpp, effects_test.cpp); through the lens"
  echo "they are distorted exactly as the RGB is."
  echo
  echo "| look | $(echo $views | sed 's/ / | /g') |"
  echo "|---|$(for _ in $views; do printf -- '---|'; done)"
  for look in $looks; do
    printf '| %s |' "$look"
    for view in $views; do printf ' ![%s %s](gallery/%s_%s.png) |' "$view" "$look" "$view" "$look"; done
    echo
  done
  if [ -n "$probe_section" ]; then echo; echo "$probe_section"; fi
} > docs/gallery.md
echo "gallery: docs/gallery.md, $(ls "$OUT" | wc -l) pictures in $OUT/ ($(du -sh "$OUT" | cut -f1))"
