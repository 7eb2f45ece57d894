#!/usr/bin/env bash
# A bake across ranks against one process (docs/distributed.md): the default preset with its
# avalanches and skiers off (the decomposed season alone; --events keeps them), SIZE² cells of 10 m, DAYS
# days, baked alone (2 threads) and by `mpiexec -n N` (N = 2, 4; one thread a rank, oversubscribed
# past the cores), no cache. Prints each run's season and total seconds and its peak resident
# memory per process (the alone bake's manifest; a bake across ranks' log gathers every rank's),
# each rank's peak in the season alone (below the precompute's, which every rank still runs whole;
# against the one process's whole peak), and checks that every output file has the single
# process's bytes.
# --weak: weak scaling instead, SIZE² cells a rank (1 rank SIZE², 2 ranks about 1.41 SIZE², 4
# ranks 2 SIZE²); no byte check (the grids differ).
# --events: the default preset with its spontaneous avalanches and skiers, which every rank runs
# on its replica of the whole grid; the last column says how often the replica was brought up to
# date and what rank 0 sent for it.
# --tiles: the default preset's layers (its displacement maps, VDB and meshes left out) in png16,
# EXR and PNG as Unreal tiles of 505, which each rank writes for the tiles that start in its
# subdomain (bake/tiles_on_ranks.h); the one process writes the same.
# --whole: the same layers as --tiles as whole files (no [outputs.tiles]), which rank 0 writes one
# at a time, each gathered from the ranks; --sun-wind, --displacement and --resize apply alike.
# --sun-wind: with --tiles, the layers sun_exposure, temperature, wind_speed and wind_shadow_mask
# too (each rank's from its part of the precompute).
# --ski-tracks F: with --tiles or --whole, the layer ski_tracks too, at F texels a cell
# (outputs.ski_track_factor; every rank holds the whole texture, which the memory guard counts).
# --displacement PX: with --tiles, displacement maps of PX x PX pixels too (each rank resamples the
# cells its tiles read, gathered from their owners).
# --resize PX: with --tiles, the layers resampled to PX x PX pixels (outputs.resize) before they
# are cut (each rank resamples the cells its tiles read).
# --tiles-resize PX: with --tiles, the tiles cut from the layers resampled to PX x PX pixels
# (outputs.tiles.resize, PX = n 504 + 1) and the whole files beside them at the grid's size or
# --resize's, which rank 0 writes one at a time, each gathered from the ranks.
# --sun-method M: precompute.sun_method = M (horizon or embree).
# --set KEY=VALUE: a scene key for every run, as `snowbake bake --set` (repeatable), e.g.
# --set outputs.vdb=false.
# --ranks-only N: N ranks alone, for a grid one process cannot hold (no byte check, no ratios);
# prints rank 0's log lines of each stage's time, the memory and the mass balance beside the row.
# Otherwise, after the table, rank 0's log lines of each run: the memory guard's prediction, and
# the sun exposure's time, its parts and, by Embree, the rays traced.
#   tools/bench-distributed-bake.sh [--weak] [--events] [--tiles|--whole [--sun-wind] [--ski-tracks F] [--displacement PX] [--resize PX]
#                                   [--tiles-resize PX]] [--sun-method M] [--set KEY=VALUE ...]
#                                   [--ranks-only N] [BUILD=build] [SIZE=1024] [DAYS=30]
set -euo pipefail
cd "$(dirname "$0")/.."
mode=strong events=0 tiles=0 whole=0 sunwind="" skitracks="" only="" displacement="" resize="" tilesresize=""
sets=()
while [ "${1:-}" = --weak ] || [ "${1:-}" = --events ] || [ "${1:-}" = --tiles ] || [ "${1:-}" = --whole ] || [ "${1:-}" = --sun-wind ] ||
  [ "${1:-}" = --ski-tracks ] || [ "${1:-}" = --displacement ] || [ "${1:-}" = --resize ] || [ "${1:-}" = --tiles-resize ] ||
  [ "${1:-}" = --sun-method ] || [ "${1:-}" = --set ] || [ "${1:-}" = --ranks-only ]; do
  case "$1" in
    --weak) mode=weak ;;
    --events) events=1 ;;
    --tiles) tiles=1 ;;
    --whole) tiles=1 whole=1 ;;
    --sun-wind) sunwind=', "sun_exposure", "temperature", "wind_speed", "wind_shadow_mask"' ;;
    --ski-tracks) skitracks=', "ski_tracks"' factor="ski_track_factor = $2"; shift ;;
    --displacement) displacement="displacement_size = [$2, $2]"; shift ;;
    --resize) resize="resize = [$2, $2]"; shift ;;
    --tiles-resize) tilesresize="resize = [$2, $2]"; shift ;;
    --sun-method) sets+=(--set "precompute.sun_method=$2"); shift ;;
    --set) sets+=(--set "$2"); shift ;;
    --ranks-only) mode=only only="$2"; shift ;;
  esac
  shift
done
build="${1:-build}" size="${2:-1024}" days="${3:-30}"
bin="$(realpath "$build/snowbake")"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
scene=preset:default
if [ "$tiles" = 1 ]; then  # the preset with its [outputs] table replaced
  scene="$work/tiles.toml"
  awk '/^\[outputs\]$/ { skip = 1 } /^\[outputs\.ranges\]$/ { skip = 0 } !skip' presets/default.toml > "$scene"
  cat >> "$scene" <<TOML
[outputs]
layers = ["compacted", "stable", "unstable", "powder", "depth", "surface", "snow_coverage", "weight_snow", "weight_rock",
          "splat_map", "snow_normal", "preview"$sunwind$skitracks]
format = "exr"
encodings = ["png16"]
${factor:-}
$displacement
$resize
TOML
  [ "$whole" = 1 ] || printf '[outputs.tiles]\nconvention = "unreal"\nsize_px = 505\n%s\n' "$tilesresize" >> "$scene"
fi
args=(bake "$scene" --set "season.days=$days" --set 'outputs.frames_days=[]' --no-cache --quiet --out out)
[ "$events" = 1 ] || args+=(--set parameters.avalanche_rate_per_km2_per_day=0 --set parameters.skiers_per_hour=0)
args+=(${sets[@]+"${sets[@]}"})
# run RANKS SIZE: bakes into $work/RANKS-SIZE; prints its table row ($one: the alone bake's peak).
run() {
  local ranks="$1" size="$2" dir="$work/$1-$2" peaks largest season total season_peaks season_largest
  mkdir -p "$dir"
  if [ "$ranks" = 1 ]; then
    (cd "$dir" && "$bin" "${args[@]}" --set "terrain.size=$size" --threads 2 > log 2>&1)
    peaks="$(grep -o '"measured_peak_mib": [0-9.]*' "$dir/out/manifest.json" | grep -o '[0-9.]*$')"
    [ -n "$one" ] || one="$peaks"
  else
    (cd "$dir" && mpiexec --oversubscribe -n "$ranks" "$bin" "${args[@]}" --set "terrain.size=$size" --threads 1 > log 2>&1)
    peaks="$(sed -n 's/^memory: peak resident per rank \(.*\) MiB$/\1/p' "$dir/log")"
  fi
  season="$(sed -n 's/^season: .* on cpu (\([0-9.]*\) s)$/\1/p' "$dir/log")"
  total="$(sed -n 's/^total: \([0-9.]*\) s$/\1/p' "$dir/log")"
  largest="$(echo "$peaks" | tr ',' '\n' | sort -g | tail -1 | tr -d ' ')"
  season_peaks="$(sed -n 's/^memory: peak resident per rank in the season \(.*\) MiB; after it.*$/\1/p' "$dir/log")"
  season_largest="$(echo "$season_peaks" | tr ',' '\n' | sort -g | tail -1 | tr -d ' ')"
  replica="$(sed -n 's/^season: .*brought up to date \([0-9]*\) times (\([0-9.]*\) MiB sent by rank 0)$/\1 times, \2 MiB/p' "$dir/log")"
  printf '| %s | %s² | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$ranks" "$size" "$([ "$ranks" = 1 ] && echo 2 || echo 1)" "$season" "$total" \
    "$peaks" "$([ -n "$one" ] && awk -v a="$largest" -v b="$one" 'BEGIN { printf "%.2f", a / b }' || echo -)" "${season_peaks:--}" \
    "$([ -n "$season_largest" ] && [ -n "$one" ] && awk -v a="$season_largest" -v b="$one" 'BEGIN { printf "%.2f", a / b }' || echo -)" "${replica:--}"
}
# same RANKS SIZE: every output file but the manifest has the alone bake's bytes.
same() {
  local f
  for f in $(cd "$work/1-$2/out" && find . -type f ! -name manifest.json); do
    cmp -s "$work/1-$2/out/$f" "$work/$1-$2/out/$f" || { echo "bench-distributed-bake: $f differs on $1 ranks" >&2; exit 1; }
  done
}

echo "bake across ranks ($mode): the default preset $([ "$events" = 1 ] && echo with || echo without) avalanches and skiers$([ "$tiles" = 1 ] && echo ", its layers as $([ "$whole" = 1 ] && echo "whole files" || echo "Unreal tiles of 505") ($([ -n "$displacement" ] && echo "${displacement#displacement_size = }" displacement maps, no || echo no displacement maps,) VDB or meshes)")$([ -n "$resize" ] && echo ", outputs.$resize")$([ -n "$tilesresize" ] && echo ", outputs.tiles.$tilesresize")$([ -n "$skitracks" ] && echo ", ski_tracks at ${factor#ski_track_factor = } texels a cell")$([ ${#sets[@]} -gt 0 ] && printf ' %s' "${sets[@]}"), 10 m cells, $days days;" \
     "$(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); commit $(git rev-parse --short HEAD)"
printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' ranks grid "threads/rank" "season s" "total s" "peak MiB per rank" \
  "largest rank / one process" "season's peak MiB per rank" "largest / one process" "replica gathers"
echo "|---|---|---|---|---|---|---|---|---|---|"
one=""
if [ "$mode" = strong ]; then
  for ranks in 1 2 4; do
    run "$ranks" "$size"
    [ "$ranks" = 1 ] || same "$ranks" "$size"
  done
elif [ "$mode" = only ]; then
  run "$only" "$size"
  echo
  echo "rank 0's log:"
  grep -E '^(terrain|precompute|  sun exposure|wind|season|outputs|total|memory|mass)' "$work/$only-$size/log" | sed 's/^/    /'
else  # weak: SIZE² cells a rank (1448² is 2.0 x 1024²)
  run 1 "$size"
  run 2 "$(awk -v s="$size" 'BEGIN { printf "%d", s * sqrt(2) + 0.5 }')"
  run 4 "$((2 * size))"
fi
if [ "$mode" != only ]; then  # each run's memory guard lines and sun exposure lines (their parts; by Embree, the rays)
  echo
  for dir in "$work"/*-*/; do
    name="$(basename "$dir")"
    echo "rank 0's log, ${name%%-*} rank$([ "${name%%-*}" = 1 ] || echo s), ${name#*-}²:"
    grep -E '^(memory: (across|predicted)|precompute: sun exposure|  sun exposure)' "$dir/log" | sed 's/^ */    /'
  done
fi
