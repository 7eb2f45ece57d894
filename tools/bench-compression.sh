#!/usr/bin/env bash
# The lossless images' deflate effort (outputs.compression_level) against their size and writing
# time (docs/outputs.md, Compression): the default preset at SIZE² cells of 10 m, DAYS days, its
# layers and the ski tracks as EXR with 16-bit PNG beside them (no VDB, meshes or frames), baked
# once per level with the precompute cached after the first. Prints per level the EXR and PNG
# files' total size and the log's writing time of each format, and the ski-track PNG's size (a
# sparse texture).
#   tools/bench-compression.sh [BUILD=build] [SIZE=1024] [DAYS=30] [LEVELS="1 4 6 9"]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}" size="${2:-1024}" days="${3:-30}" levels="${4:-1 4 6 9}"
bin="$(realpath "$build/snowbake")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
layers='["compacted", "stable", "unstable", "powder", "depth", "surface", "snow_coverage", "weight_snow", "weight_rock", "splat_map", "snow_normal", "preview", "ski_tracks"]'
mib() { find "$1" -type f -name "$2" -printf '%s\n' | awk '{ s += $1 } END { printf "%.2f", s / 1048576 }'; }
echo "outputs.compression_level: the default preset at ${size}², ${days} days, its layers and ski_tracks as EXR and png16;" \
     "$(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); commit $(git rev-parse --short HEAD)"
echo "| level | EXR MiB | EXR s | PNG MiB | PNG s | ski_tracks PNG MiB |"
echo "|---|---|---|---|---|---|"
for level in $levels; do
  out="$work/$level"
  "$bin" bake preset:default --set "terrain.size=$size" --set "season.days=$days" --set 'outputs.frames_days=[]' \
    --set outputs.vdb=false --set 'outputs.meshes=[]' --set "outputs.layers=$layers" --set "outputs.compression_level=$level" \
    --cache-dir "$work/cache" --threads 2 --quiet --out "$out" > "$work/log-$level" 2>&1
  exr_s="$(sed -n 's/^  OpenEXR  *\([0-9.]*\) s$/\1/p' "$work/log-$level")"
  png_s="$(sed -n 's/^  PNG  *\([0-9.]*\) s$/\1/p' "$work/log-$level")"
  printf '| %s | %s | %s | %s | %s | %s |\n' "$level" "$(mib "$out" '*.exr')" "${exr_s:--}" "$(mib "$out" '*.png')" "${png_s:--}" \
    "$(mib "$out" 'ski_tracks*.png')"
done
