#!/usr/bin/env bash
# The memory model (bake/memory_model.h) against the measured peak: bakes each scene below with
# /usr/bin/time (Debian's `time`), reads the prediction from the bake's "memory:" line and the
# peak resident set from time, and prints docs/memory.md's table (Markdown), or CSV with --csv.
#   tools/measure-memory.sh [--small] [--csv] [SNOWBAKE]
# --small bakes only the scenes of a few seconds each (tests/memory_model_test.cpp runs those and
# asserts every row within 25 %). The real DEMs come from ../shared/data/dem; rows whose file is
# absent are left out with a note on standard error. Every bake runs with --no-cache, so the
# precompute's peak is measured as the model predicts it (computed, not read from the cache).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
small=0 csv=0 bin="$root/build/snowbake"
for a in "$@"; do
  case "$a" in
    --small) small=1 ;;
    --csv) csv=1 ;;
    *) bin="$a" ;;
  esac
done
dem="$root/../shared/data/dem"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Mesh mode's mesh: a 3 m x 3 m ground with a 1 m box on it (OBJ, z up).
{
  echo "v 0 0 0"; echo "v 3 0 0"; echo "v 3 3 0"; echo "v 0 3 0"
  echo "v 1 1 0"; echo "v 2 1 0"; echo "v 2 2 0"; echo "v 1 2 0"
  echo "v 1 1 1"; echo "v 2 1 1"; echo "v 2 2 1"; echo "v 1 2 1"
  echo "f 1 2 3"; echo "f 1 3 4"
  echo "f 9 10 11"; echo "f 9 11 12"
  echo "f 5 6 10"; echo "f 5 10 9"; echo "f 6 7 11"; echo "f 6 11 10"
  echo "f 7 8 12"; echo "f 7 12 11"; echo "f 8 5 9"; echo "f 8 9 12"
} > "$work/box.obj"
printf 'mode = "mesh"\n[terrain]\nfile = "box.obj"\n[mesh_snow]\nsite_spacing_m = 0.02\n[outputs]\nmeshes = ["obj"]\nvdb = true\n' > "$work/mesh.toml"

# A real DEM in the default preset's season: dem_scene FILE writes $work/dem.toml.
dem_scene() {
  printf '[terrain]\nfile = "%s"\n[season]\nstart_date = 2025-12-01\ndays = 120\n' "$1" > "$work/dem.toml"
  printf '[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 4.0\nwind_direction_deg = 280\nwind_speed_mps = 8.0\n' >> "$work/dem.toml"
}

season=(--set season.days=20 --set 'outputs.frames_days=[10]')
if [ $csv = 1 ]; then echo "scene,predicted_mib,measured_mib,error_percent,phase,measured_stage"; else
  echo "| scene | predicted peak (MiB) | measured peak (MiB) | error | predicted peak phase | measured peak by the end of |"
  echo "|---|---|---|---|---|---|"
fi

# bake NAME ARGS...: one row.
bake() {
  local name="$1"; shift
  rm -rf "$work/out"
  if ! /usr/bin/time -f '%M' -o "$work/rss" "$bin" bake "$@" --no-cache --quiet --out "$work/out" > "$work/log" 2>&1; then
    echo "measure-memory: $name failed:" >&2; tail -5 "$work/log" >&2; exit 1
  fi
  local line predicted phase measured stage
  line="$(grep -m1 '^memory: predicted peak' "$work/log")"
  predicted="$(sed -E 's/^memory: predicted peak ([0-9]+) MiB.*/\1/' <<< "$line")"
  phase="$(sed -E 's/^memory: predicted peak [0-9]+ MiB, in the ([a-z ]+) \(.*/\1/' <<< "$line")"
  measured=$(( $(tail -1 "$work/rss") / 1024 ))
  # The stage by whose end the process's peak was reached: the manifest's "memory" line.
  stage="$(grep -o '"measured_peak_stage": "[^"]*"' "$work/out/manifest.json" | sed -E 's/.*: "(.*)"/\1/' || true)"
  stage="${stage:-not noted}"  # a manifest without a "memory" line (mesh mode's before 2026-12-03)
  local error
  error="$(awk -v p="$predicted" -v m="$measured" 'BEGIN { printf "%+.1f", 100 * (p - m) / m }')"
  if [ $csv = 1 ]; then echo "$name,$predicted,$measured,$error,$phase,$stage"; else
    echo "| $name | $predicted | $measured | $error % | $phase | $stage |"
  fi
}

bake "default preset, builtin 256², 20 days, a frame" preset:default --set terrain.size=256 "${season[@]}"
bake "builtin 512², png16 encodings, multi-channel EXR" preset:default --set terrain.size=512 "${season[@]}" \
  --set 'outputs.encodings=["png16"]' --set outputs.multichannel_exr=true
bake "builtin 512², VDB, 4096² displacement" preset:default --set terrain.size=512 "${season[@]}" \
  --set outputs.vdb=true --set 'outputs.displacement_size=[4096,4096]'
bake "builtin 512², ski_tracks at factor 16" preset:default --set terrain.size=512 "${season[@]}" \
  --set 'outputs.layers=["depth","ski_tracks"]' --set outputs.ski_track_factor=16
bake "occlusion mode, builtin 512²" preset:default --set terrain.size=512 --set mode=occlusion --set 'outputs.frames_days=[]'
bake "mesh mode, a box on a 3 m ground, 2 cm sites" "$work/mesh.toml"
bake "builtin 512² resized to 1009², Unreal tiles of 505, splat and normal maps" preset:default --set terrain.size=512 "${season[@]}" \
  --set 'outputs.resize=[1009,1009]' --set 'outputs.tiles.convention="unreal"' --set outputs.tiles.size_px=505 \
  --set 'outputs.layers=["depth","surface","splat_map","snow_normal"]' --set 'outputs.encodings=["png16","r16"]'
if [ -f "$dem/tyrol_avaKot_5m.asc" ]; then
  dem_scene "$dem/tyrol_avaKot_5m.asc"
  bake "tyrol_avaKot_5m.asc (439 × 517), 20 days, a frame" "$work/dem.toml" "${season[@]}"
else
  echo "measure-memory: $dem/tyrol_avaKot_5m.asc absent: its row left out" >&2
fi
[ $small = 1 ] && exit 0

bake "builtin 512², the untiled files and a tile set of Unreal 505 at 1009², multi-channel EXR" preset:default --set terrain.size=512 \
  "${season[@]}" --set 'outputs.tiles.convention="unreal"' --set outputs.tiles.size_px=505 --set 'outputs.tiles.resize=[1009,1009]' \
  --set outputs.multichannel_exr=true

bake "builtin 1024², production sun" preset:default --set terrain.size=1024 "${season[@]}" --set precompute.sun_quality=production
bake "builtin 2048², 20 days, a frame" preset:default --set terrain.size=2048 "${season[@]}"
bake "occlusion mode, builtin 2048²" preset:default --set terrain.size=2048 --set mode=occlusion --set 'outputs.frames_days=[]'
if [ -f "$dem/front_range_srtm3.asc" ]; then
  dem_scene "$dem/front_range_srtm3.asc"
  bake "front_range_srtm3.asc (758 × 758), VDB" "$work/dem.toml" "${season[@]}" --set outputs.vdb=true
else
  echo "measure-memory: $dem/front_range_srtm3.asc absent: its row left out" >&2
fi
# The Poisson snowfall's storms come when the draws say (memory_vdb.h's VDB term is their
# expectation): run 1's first storm at 4096² comes after its day-10 frame, so a fixed storm (days
# 2 to 6) puts snow in the frame the model predicts, and the Poisson row shows the spread.
bake "builtin 4096², 20 days, a storm on days 2 to 6, a frame" preset:default --set terrain.size=4096 "${season[@]}" \
  --set 'weather.snowfall=[{start_day=2.0,end_day=6.0}]'
bake "builtin 4096², 20 days, Poisson snowfall, a frame" preset:default --set terrain.size=4096 "${season[@]}"
