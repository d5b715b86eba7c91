#!/usr/bin/env bash
# Instructions per ray of glint's 8-wide BVH queries on the anchors bench's
# torus or Sponza (benches/examples/rays.rs: the same meshes, views and ray sets
# as `cargo bench --bench anchors`), counted by callgrind (deterministic, unlike
# wall time on a shared machine). Only the instructions inside the example's
# `trace_rays` and `trace_build` are collected (--toggle-collect, one pattern for
# both: of several such options only the last took effect), and callgrind
# dumps its counters each time it enters `trace_rays` (--dump-before, which takes
# the exact name: wildcards and --dump-after never fired here), so each ray set
# gets its own count, without mesh or ray construction in it, and the first dump
# holds the build's (binary build and collapse).
#   scripts/callgrind_rays.sh [100k|1M|both|sponza] [RAYS]   (defaults 100k, 65536)
# `sponza` needs ../shared/assets (the example prints why it skips without it).
# With GLINT_RAYS_PACKETS=1 in the environment, every row traces packets of 8
# consecutive rays (WideBvh::occluded_packet, closest_packet) instead of single rays.
# With GLINT_RAYS_EMBREE=1 (and GLINT_EMBREE_LIB), Embree traces the ray sets, one call
# a ray, for its counts beside glint's (the build row stays glint's).
# Under valgrind the AVX2 + FMA clone of the queries runs when the host CPU
# has them, as natively.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
which="${1:-100k}"
rays="${2:-65536}"
target="${CARGO_TARGET_DIR:-$root/target}"
cargo build --release --manifest-path "$root/Cargo.toml" -p glint-bench --example rays >&2
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# Prints one line per ray set and one for the build for the example's mesh `$2` (the
# torus of 4 n^2 triangles, or sponza).
count() {
  local label="$1" n="$2"
  rm -f "$tmp"/cg.out*
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" \
    --toggle-collect='rays::trace_*' \
    --dump-before='rays::trace_rays' \
    "$target/release/examples/rays" "$n" "$rays" >"$tmp/stdout" 2>"$tmp/stderr"
  if grep -q '^skipping' "$tmp/stdout"; then
    cat "$tmp/stdout"
    return
  fi
  # Dump k (taken on entering call k, so holding call k - 1) is primary for
  # k = 2, incoherent for k = 3; the final profile, cg.out, is shadow.
  local k=1 set nrays hits ir file
  while read -r set nrays _ hits _; do
    k=$((k + 1))
    file="$tmp/cg.out.$k"
    ((k < 4)) || file="$tmp/cg.out"
    ir="$(grep -E '^(summary|totals):' "$file" | head -1 | awk '{print $2}')"
    printf '%-10s %-10s %7d rays %7d hits %6d instructions/ray\n' \
      "$label" "$set" "$nrays" "$hits" $((ir / nrays))
  done < <(grep ' rays ' "$tmp/stdout")
  ir="$(grep -E '^(summary|totals):' "$tmp/cg.out.1" | head -1 | awk '{print $2}')"
  printf '%-10s build %d instructions; ' "$label" "$ir"
  grep 'bytes/tri' "$tmp/stdout"
}
case "$which" in
  100k) count torus100k 158 ;;
  1M) count torus1M 500 ;;
  both) count torus100k 158; count torus1M 500 ;;
  sponza) count sponza sponza ;;
  *) echo "usage: $0 [100k|1M|both|sponza] [RAYS]" >&2; exit 2 ;;
esac
