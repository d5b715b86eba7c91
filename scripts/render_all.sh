#!/usr/bin/env bash
# Renders every scene in scenes/, the glTF fixture, a debug image and its dump with
# the given glint binary into OUTDIR, so two builds can be compared byte for byte:
#   scripts/render_all.sh target/release/glint /tmp/before
#   scripts/render_all.sh target/release/glint /tmp/after && diff -r /tmp/before /tmp/after
set -euo pipefail
bin=$(realpath "$1")
out=$2
cd "$(dirname "$0")/.."
mkdir -p "$out"
for scene in scenes/*.ron; do
    name=$(basename "$scene" .ron)
    "$bin" render "$scene" -o "$out/$name.png" --quiet
    "$bin" info "$scene" > "$out/$name.info.txt"
done
"$bin" render assets/fixture/glint_fixture.gltf -o "$out/gltf_fixture.png" --quiet
"$bin" debug scenes/cornell_box.ron --pixel 145,260 -o "$out/debug_cornell.png" \
    --set pixel_samples=4 --set pixel_sampling=stratified --dump "$out/debug_cornell.ron" 2>/dev/null
"$bin" debug scenes/cube_transparent_segment_light.ron --pixel 100,100 -o "$out/debug_cube.png" \
    --dump "$out/debug_cube.ron" 2>/dev/null
echo "rendered $(ls "$out" | wc -l) files into $out"
