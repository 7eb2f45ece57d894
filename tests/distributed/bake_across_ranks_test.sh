#!/usr/bin/env bash
# mpiexec -n N snowbake bake gives the single process's files, byte for byte, for N = 1..4
# (docs/distributed.md): the default preset with its avalanches and skiers off (sun, a wind that
# moves snow, frames, every default output), and a real DEM with NODATA from ../shared/data
# (skipped with a message when absent), and art direction (painted masks, initial snow, a snowfall
# multiplier, timeline edits). Their manifests differ in the "memory" line alone (the
# measured peak varies from run to run). Then what a launch refuses: a scene with avalanches, and
# a missing terrain, each exit 2 with one message and nothing written.
#   bash bake_across_ranks_test.sh SNOWBAKE MPIEXEC DATA_DIR [MPIEXEC_FLAGS...]
set -euo pipefail
bin="$(realpath "$1")" mpiexec="$2" data="$3"
root="$(cd "$(dirname "$0")/../.." && pwd)"
shift 3
launch=("$mpiexec" "$@")
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # CI runs as root
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# bake NAME FOLDER RANKS SCENE [ARGS...]: the same --out in every folder, so the manifests'
# command lines agree.
bake() {
  local name="$1" folder="$2" ranks="$3" scene="$4"
  shift 4
  mkdir -p "$folder"
  local cmd=("$bin" bake "$scene" --out out --no-cache --quiet --threads 1 "$@")
  [ "$ranks" = alone ] || cmd=("${launch[@]}" -n "$ranks" "${cmd[@]}")
  (cd "$folder" && "${cmd[@]}" > log 2>&1) || { fail "$name on $ranks ranks: exit $?"; cat "$folder/log" >&2; return 1; }
}

# same NAME ALONE ACROSS: every file of ALONE/out in ACROSS/out with the same bytes, and no other.
same() {
  local name="$1" a="$2/out" b="$3/out"
  diff <(cd "$a" && find . -type f | LC_ALL=C sort) <(cd "$b" && find . -type f | LC_ALL=C sort) > /dev/null ||
    fail "$name: the file lists differ ($a, $b)"
  local n=0 f
  while read -r f; do
    n=$((n + 1))
    if [ "$f" = ./manifest.json ]; then
      cmp -s <(sed '/^  "memory": /d' "$a/$f") <(sed '/^  "memory": /d' "$b/$f") || fail "$name: $f differs beyond its memory line"
    else
      cmp -s "$a/$f" "$b/$f" || fail "$name: $f differs"
    fi
  done < <(cd "$a" && find . -type f | LC_ALL=C sort)
  echo "$name: $n files compared"
}

check_scene() {  # NAME SCENE [ARGS...]
  local name="$1"
  shift
  bake "$name" "$work/$name/alone" alone "$@" || return 0
  grep -q "season: across" "$work/$name/alone/log" && fail "$name: the single process ran across ranks"
  for ranks in 1 2 3 4; do
    bake "$name" "$work/$name/$ranks" "$ranks" "$@" || continue
    if [ "$ranks" -gt 1 ]; then
      grep -q "season: across $ranks ranks" "$work/$name/$ranks/log" || fail "$name on $ranks ranks: the season did not run across them"
    fi
    same "$name on $ranks ranks" "$work/$name/alone" "$work/$name/$ranks"
  done
}

no_avalanches=(--set parameters.avalanche_rate_per_km2_per_day=0 --set parameters.skiers_per_hour=0)
check_scene default preset:default --set terrain.size=120 --set season.days=45 --set 'outputs.frames_days=[20,40]' "${no_avalanches[@]}"
# The frames gathered on rank 0 and written beside the season, or held until its end.
for timing in beside after_season; do
  frames=(preset:default --set terrain.size=120 --set season.days=45 --set 'outputs.frames_days=[20,40]' --set "run.frame_writing=\"$timing\"")
  bake "$timing" "$work/$timing/alone" alone "${frames[@]}" "${no_avalanches[@]}" &&
    bake "$timing" "$work/$timing/3" 3 "${frames[@]}" "${no_avalanches[@]}" &&
    same "frames $timing on 3 ranks" "$work/$timing/alone" "$work/$timing/3"
done
# The season must have moved snow for the comparison to mean something.
grep -qE "added [1-9]" "$work/default/alone/log" || fail "default: no snowfall"

# Art direction: the art-direction preset's painted masks, initial snow, snowfall multiplier,
# no-snow road and timeline edits, without its avalanches and skiers.
art="$root/presets/art_direction"
cat > "$work/art.toml" <<TOML
name = "across ranks: art direction without avalanches or skiers"
[terrain]
builtin = "ridged"
size = 128
cell_size_m = 10.0
[season]
start_date = 2025-12-01
days = 50
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 5.0
wind_direction_deg = 280
wind_speed_mps = 8.0
[masks.release]
file = "$art/release_zone.png"
[masks.ski_area]
file = "$art/ski_area.png"
[initial_snow]
stable = 0.2
powder = { mask = "$art/precipitation.png", depth_m = 0.3 }
[multipliers]
snowfall = { file = "$art/precipitation.png", range = [0.6, 1.4] }
no_snow = "$art/road.png"
[[edits]]
day = 20
op = "add"
layer = "compacted"
depth_m = 0.4
mask = "ski_area"
[[edits]]
day = 45
op = "set"
layer = "unstable"
depth_m = 1.2
mask = "release"
[parameters]
rain_snow_limit_m = 1200.0
avalanche_rate_per_km2_per_day = 0.0
skiers_per_hour = 0.0
[outputs]
layers = ["depth", "compacted", "unstable", "powder", "preview"]
frames_days = [0, 46]
TOML
check_scene art "$work/art.toml"
grep -qE "edit 1: .*: [1-9]" "$work/art/alone/log" || fail "art: its first edit added no snow"
grep -qE "no-snow mask: [1-9]" "$work/art/alone/log" || fail "art: its no-snow mask removed no snow"

dem="$data/dem/tyrol_avaWog_5m.asc"
if [ -f "$dem" ]; then
  cat > "$work/dem.toml" <<TOML
name = "across ranks: a real DEM with NODATA"
[terrain]
file = "$dem"
[season]
start_date = 2025-12-01
days = 40
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 4.0
wind_direction_deg = 250
wind_speed_mps = 9.0
[parameters]
avalanche_rate_per_km2_per_day = 0.0
skiers_per_hour = 0.0
[outputs]
layers = ["compacted", "stable", "unstable", "powder", "depth", "surface", "valid_mask", "wind_shadow_depth", "temperature",
          "wind_scour", "wind_deposit", "melt", "preview"]
encodings = ["png16"]
vdb = true
meshes = ["glb"]
frames_days = [10, 30]
TOML
  check_scene dem "$work/dem.toml"
  grep -q "NODATA cells" "$work/dem/alone/log" || fail "dem: the DEM's NODATA cells are not in its log"
else
  echo "bake_across_ranks_test: $dem absent: the real-DEM bakes are skipped" >&2
fi

# Refused before any season work on every rank, one message.
refused() {  # NAME EXPECTED ARGS...
  local name="$1" expected="$2"
  shift 2
  mkdir -p "$work/$name"
  local status=0
  (cd "$work/$name" && "${launch[@]}" -n 2 "$bin" bake "$@" --out out --no-cache > log 2>&1) || status=$?
  [ "$status" = 2 ] || fail "$name: exit $status, not 2"
  [ "$(grep -c '^snowbake: error' "$work/$name/log")" = 1 ] || { fail "$name: not one error line"; cat "$work/$name/log" >&2; }
  grep -q -- "$expected" "$work/$name/log" || fail "$name: the message does not name $expected"
  [ ! -e "$work/$name/out" ] || fail "$name: an output folder was written"
}
refused avalanches parameters.avalanche_rate_per_km2_per_day preset:default
cat > "$work/event.toml" <<'TOML'
name = "across ranks: an avalanche event"
[terrain]
builtin = "ridged"
size = 64
cell_size_m = 10.0
[parameters]
avalanche_rate_per_km2_per_day = 0.0
skiers_per_hour = 0.0
[[events]]
type = "avalanche"
day = 5
position_m = [300.0, 300.0]
TOML
refused avalanche-event "event.toml:[0-9]*: an avalanche event: a bake across ranks" "$work/event.toml"
refused missing-terrain /nonexistent/dem.asc preset:default --terrain /nonexistent/dem.asc "${no_avalanches[@]}"
# Found once the ranks have joined (the terrain loaded): they agree on the status.
refused tiny-grid "cannot be baked across ranks" preset:default --set terrain.size=12 "${no_avalanches[@]}"

# One rank alone fails (rank 0 makes the output folder and opens the log file): the others learn
# it at the season's start, and every rank ends with exit 2, rank 0's one message, no hang.
alone_fails() {  # NAME EXPECTED ARGS...
  local name="$1" expected="$2" status=0
  shift 2
  mkdir -p "$work/$name"
  (cd "$work/$name" && timeout 300 "${launch[@]}" -n 3 "$bin" bake preset:default --set terrain.size=64 "${no_avalanches[@]}" \
     --no-cache "$@" > log 2>&1) || status=$?
  [ "$status" = 2 ] || fail "$name: exit $status, not 2 (124: it hung)"
  [ "$(grep -c '^snowbake: error' "$work/$name/log")" = 1 ] || { fail "$name: not one error line"; cat "$work/$name/log" >&2; }
  grep -q -- "$expected" "$work/$name/log" || fail "$name: the message does not name $expected"
}
alone_fails rank0-output-folder /proc/snowbake-out --out /proc/snowbake-out
alone_fails rank0-log-file /proc/snowbake.log --out out --log-file /proc/snowbake.log

if [ "$failures" -gt 0 ]; then
  echo "bake_across_ranks_test: $failures failures" >&2
  exit 1
fi
echo "bake_across_ranks_test: passed"
