#!/usr/bin/env bash
# Instructions of one one-thread build of the anchors bench's torus, glint's (binary
# SAH build and collapse, as a render builds) against Embree's medium build, counted
# by callgrind (deterministic: the build's time on a shared VM swings with its host's
# phases, see docs/benchmarks.md, twenty-first session). Embree needs GLINT_EMBREE_LIB
# (see docs/benchmarks.md); without it only glint's count is printed.
#   scripts/callgrind_build.sh [100k|1M]   (default 100k)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
case "${1:-100k}" in
  100k) n=100000 ;;
  1M) n=1000000 ;;
  *) echo "usage: $0 [100k|1M]" >&2; exit 2 ;;
esac
target="${CARGO_TARGET_DIR:-$root/target}"
cargo build --release --manifest-path "$root/Cargo.toml" -p glint-bench --example build_instructions >&2
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
declare -A count
for lib in glint embree; do
  valgrind --tool=callgrind --callgrind-out-file="$tmp/$lib.out" \
    --toggle-collect='build_instructions::measured_build*' \
    "$target/release/examples/build_instructions" "$lib" "$n" >"$tmp/$lib.txt" 2>/dev/null
  if grep -q '^skipping' "$tmp/$lib.txt"; then
    cat "$tmp/$lib.txt"
    continue
  fi
  count[$lib]="$(grep -E '^(summary|totals):' "$tmp/$lib.out" | head -1 | awk '{print $2}')"
  printf '%-7s %s: %d instructions\n' "$lib" "$(cat "$tmp/$lib.txt")" "${count[$lib]}"
done
if [[ -n "${count[embree]:-}" ]]; then
  awk -v g="${count[glint]}" -v e="${count[embree]}" \
    'BEGIN { printf "glint / embree medium: %.2f\n", g / e }'
fi
