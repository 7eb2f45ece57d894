#!/usr/bin/env bash
# `snowbake plan` against the bake it plans: for each scene below, plan --json, then the bake under
# /usr/bin/time (Debian's `time`); prints docs/command-line.md's table: the files planned and
# written (and whether the lists are equal), the predicted and measured peak memory, the time class
# and the wall time. Files the plan marks as depending on the snow count as planned when written.
#   tools/plan-vs-bake.sh [SNOWBAKE]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${1:-$root/build/snowbake}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

printf 'v 0 0 0\nv 3 0 0\nv 3 3 0\nv 0 3 0\nv 1 1 0\nv 2 1 0\nv 2 2 0\nv 1 2 0\nv 1 1 1\nv 2 1 1\nv 2 2 1\nv 1 2 1\n' > "$work/box.obj"
printf 'f 1 2 3\nf 1 3 4\nf 9 10 11\nf 9 11 12\nf 5 6 10\nf 5 10 9\nf 6 7 11\nf 6 11 10\nf 7 8 12\nf 7 12 11\nf 8 5 9\nf 8 9 12\n' >> "$work/box.obj"
printf 'mode = "mesh"\n[terrain]\nfile = "box.obj"\n[mesh_snow]\nsite_spacing_m = 0.02\n[outputs]\nmeshes = ["obj", "glb"]\nvdb = true\n' > "$work/mesh.toml"

echo "| scene | mode | files planned | files written | lists equal | predicted peak (MiB) | measured peak (MiB) | error | time class | wall (s) |"
echo "|---|---|---|---|---|---|---|---|---|---|"

# row NAME ARGS...: plan, bake, one row.
row() {
  local name="$1"; shift
  rm -rf "$work/out"
  "$bin" plan "$@" --no-cache --out "$work/out" --json > "$work/plan.json"
  [ ! -e "$work/out" ] || { echo "plan-vs-bake: $name: the plan wrote into its output folder" >&2; exit 1; }
  local t0 t1
  t0=$(date +%s.%N)
  if ! /usr/bin/time -f '%M' -o "$work/rss" "$bin" bake "$@" --no-cache --quiet --out "$work/out" > "$work/log" 2>&1; then
    echo "plan-vs-bake: $name failed:" >&2; tail -5 "$work/log" >&2; exit 1
  fi
  t1=$(date +%s.%N)
  python3 - "$work/plan.json" "$work/out" "$(tail -1 "$work/rss")" "$name" "$t0" "$t1" <<'PY'
import json, os, sys
plan = json.load(open(sys.argv[1]))
out, rss_kib, name = sys.argv[2], int(sys.argv[3]), sys.argv[4]
written = {os.path.relpath(os.path.join(d, f), out) for d, _, fs in os.walk(out) for f in fs}
always = {f["path"] for f in plan["files"] if not f["condition"]}
maybe = {f["path"] for f in plan["files"] if f["condition"]}
equal = always <= written and written - always <= maybe
predicted = plan["memory"]["peak_bytes"] / 2**20
measured = rss_kib / 1024
print(f"| {name} | {plan['mode']} | {len(plan['files'])} | {len(written)} | {'yes' if equal else 'NO'} | {predicted:.0f} | {measured:.0f} | "
      f"{100 * (predicted - measured) / measured:+.1f} % | {plan['time_class']} | {float(sys.argv[6]) - float(sys.argv[5]):.1f} |")
if not equal:
    print("plan-vs-bake: not planned:", sorted(written - always - maybe), "not written:", sorted(always - written), file=sys.stderr)
    sys.exit(1)
PY
}

short=(--set season.days=20 --set 'outputs.frames_days=[]')
row "default preset, builtin 256², 20 days, a frame" preset:default --set terrain.size=256 --set season.days=20 --set 'outputs.frames_days=[10]'
row "builtin 512², encodings png16/png8/r16/r32, multi-channel EXR" preset:default --set terrain.size=512 "${short[@]}" \
  --set 'outputs.encodings=["png16","png8","r16","r32"]' --set outputs.multichannel_exr=true
row "builtin 512², Unreal tiles of 127 px, mesh tiles, VDB" preset:default --set terrain.size=512 "${short[@]}" \
  --set outputs.tiles.convention=unreal --set outputs.tiles.size_px=127 --set outputs.mesh_tile_size_m=2000 --set outputs.vdb=true
row "builtin 256², GeoTIFF, resize 300², 3 frames" preset:default --set terrain.size=256 --set season.days=20 \
  --set 'outputs.frames_days=[5,10,15]' --set outputs.format=tiff --set 'outputs.resize=[300,300]'
row "occlusion mode, builtin 512²" preset:default --set terrain.size=512 --set mode=occlusion --set 'outputs.frames_days=[]'
row "mesh mode, a box on a 3 m ground, 2 cm sites" "$work/mesh.toml"
