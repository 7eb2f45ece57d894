#!/usr/bin/env bash
# What [outputs.tiles] and [outputs.ranges] cost: the 1024² builtin range with every output
# (layers, png16/png8/r16, multi-channel EXR, displacement maps, VDB, glb, a frame day) baked
# untiled with "own" ranges, as Unity tiles of 257 (4 x 4, 1025² pixels: one padded row and
# column) and as Unreal tiles of 505 (3 x 3, 1513² pixels: Unreal has no size that fits 1024, so
# 2.2 times the pixels) and, resized to Unreal's 1009², as 2 x 2 Unreal tiles of 505, with
# "season" ranges; runs interleaved,
# the median of each printed as a table (docs/benchmarks.md, Deliverables).
#   bash tools/bench-deliverables.sh [SNOWBAKE_BINARY] [RUNS]   (default build/snowbake, 3)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="$(realpath "${1:-$root/build/snowbake}")"
runs="${2:-3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
layers='"compacted", "stable", "unstable", "powder", "depth", "bedrock", "surface", "snow_coverage", "wind_speed", "wind_direction",
        "wind_shadow_depth", "wind_shadow_mask", "sun_exposure", "temperature", "wind_scour", "wind_deposit", "melt", "preview"'
scene() {  # RANGE_MODE TILES_TABLE [OUTPUTS_KEYS]
  local ranges=""
  for l in compacted stable unstable powder depth bedrock surface wind_speed wind_direction wind_shadow_depth sun_exposure temperature wind_scour wind_deposit melt; do
    ranges+="$l = \"$1\""$'\n'
  done
  cat <<TOML
name = "bench-deliverables"
[terrain]
builtin = "ridged"
size = 1024
cell_size_m = 10.0
[season]
days = 10
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 2.0
wind_speed_mps = 8.0
[outputs]
layers = [$layers]
encodings = ["png16", "png8", "r16"]
multichannel_exr = true
displacement_size = [1024, 1024]
vdb = true
meshes = ["glb"]
frames_days = [5]
${3:-}
[outputs.ranges]
$ranges
$2
[run]
seed = 1
threads = 2
TOML
}
scene own "" > "$work/plain.toml"
scene season $'[outputs.tiles]\nconvention = "unity"\nsize_px = 257' > "$work/unity.toml"
scene season $'[outputs.tiles]\nconvention = "unreal"\nsize_px = 505' > "$work/unreal.toml"
# Unreal at an Unreal size: the outputs resized to 1009² (2 x 2 tiles of 505, no padding).
scene season $'[outputs.tiles]\nconvention = "unreal"\nsize_px = 505' 'resize = [1009, 1009]' > "$work/unreal1009.toml"
"$bin" bake "$work/plain.toml" --out "$work/warm" --quiet > /dev/null 2>&1  # fills the precompute cache
seconds() {  # LOG KEY: the seconds of the "outputs:" or "total:" line
  sed -n "s/^$2: .*(\([0-9.]*\) s)\$/\1/p; s/^$2: \([0-9.]*\) s\$/\1/p" "$1" | head -1
}
for i in $(seq "$runs"); do
  for kind in plain unity unreal unreal1009; do
    rm -rf "$work/out"
    # CPU seconds (user + system) beside the wall clock: on a shared machine the CPU time of the
    # bake moves less with the other load than its wall time.
    local_start=$(awk '{print $14 + $15 + $16 + $17}' /proc/$$/stat)
    ( "$bin" bake "$work/$kind.toml" --out "$work/out" > "$work/$kind.$i.log" 2>&1 )
    cpu=$(awk -v s="$local_start" -v hz="$(getconf CLK_TCK)" '{printf "%.2f", ($14 + $15 + $16 + $17 - s) / hz}' /proc/$$/stat)
    echo "$(seconds "$work/$kind.$i.log" outputs) $(seconds "$work/$kind.$i.log" total) $(ls -R "$work/out" | grep -c '\.') $cpu" >> "$work/$kind.times"
  done
done
median() { sort -n | awk '{a[NR]=$0} END {print a[int((NR+1)/2)]}'; }
echo "| 1024², every output | outputs (s) | total (s) | CPU, user + system (s) | files |"
echo "|---|---|---|---|---|"
for kind in plain unity unreal unreal1009; do
  case "$kind" in
    plain) label='untiled, "own" ranges' ;;
    unity) label='Unity tiles of 257 (4 x 4), "season" ranges' ;;
    unreal) label='Unreal tiles of 505 (3 x 3, 2.2 x the pixels), "season" ranges' ;;
    unreal1009) label='resized to 1009², Unreal tiles of 505 (2 x 2), "season" ranges' ;;
  esac
  echo "| $label | $(cut -d' ' -f1 "$work/$kind.times" | median) | $(cut -d' ' -f2 "$work/$kind.times" | median) | $(cut -d' ' -f4 "$work/$kind.times" | median) | $(cut -d' ' -f3 "$work/$kind.times" | median) |"
done
