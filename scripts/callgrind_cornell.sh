#!/usr/bin/env bash
# Instructions per ray of the whole-render benchmark's scene, counted by
# callgrind (deterministic, unlike wall time on a shared machine): renders
# scenes/cornell_box_parallelogram_light.ron at SIZE x SIZE (default 96) on
# one thread twice, at 16 spp and at 1 spp, and divides the difference in
# instructions by the difference in rays: what the 15 extra passes cost per
# ray, without process start, parsing, BVH build and PNG writing (rayon runs
# the passes on a worker thread, so callgrind's --toggle-collect cannot pick
# them out). The 16-spp run's total per ray is printed too.
#   scripts/callgrind_cornell.sh [SIZE] [direct|scene] [extra glint args...]
# direct (default): the render bench's settings (Lambertian, no reflection or
# transparency rays, 4 shadow samples, uniform pixel samples); scene: the
# scene file's own settings (Phong, mirror reflections, stratified samples).
# With CALLGRIND_KEEP=FILE, the 16-spp run's callgrind output is copied to FILE
# (for callgrind_annotate's split by function).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
size="${1:-96}"
mode="${2:-direct}"
shift $(( $# > 2 ? 2 : $# ))
target="${CARGO_TARGET_DIR:-$root/target}"
cargo build --release --manifest-path "$root/Cargo.toml" --bin glint >&2
args=(render "$root/scenes/cornell_box_parallelogram_light.ron" --width "$size" --height "$size"
  --threads 1)
if [[ "$mode" == direct ]]; then
  # The same overrides as DIRECT_ONLY in benches/benches/render.rs.
  for s in shading_model=lambertian reflections=false transparency=false \
    pixel_sampling=uniform sampler=independent shadow_samples=4; do
    args+=(--set "$s")
  done
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# Prints "instructions rays summary-line" for one run at $1 spp.
count() {
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" \
    "$target/release/glint" "${args[@]}" --set "pixel_samples=$1" -o "$tmp/out.png" "${extra[@]}" \
    >"$tmp/stdout" 2>"$tmp/stderr"
  local summary ir rays
  summary="$(cat "$tmp/stdout" "$tmp/stderr" | grep -m1 'rays:')"
  ir="$(grep -E '^(summary|totals):' "$tmp/cg.out" | head -1 | awk '{print $2}')"
  rays="$(echo "$summary" | grep -oE '[0-9]+ (camera|shadow|reflection|pass-through)' | awk '{s += $1} END {print s}')"
  echo "$ir $rays $summary"
}
extra=("$@")
read -r ir16 rays16 summary16 < <(count 16)
if [[ -n "${CALLGRIND_KEEP:-}" ]]; then cp "$tmp/cg.out" "$CALLGRIND_KEEP"; fi
read -r ir1 rays1 _ < <(count 1)
echo "glint, 16 spp: $summary16"
echo "16 spp: $ir16 instructions, $rays16 rays, $(( ir16 / rays16 )) per ray (whole process)"
echo "1 spp: $ir1 instructions, $rays1 rays"
echo "instructions per ray of the render passes (16 spp - 1 spp): $(( (ir16 - ir1) / (rays16 - rays1) ))"
