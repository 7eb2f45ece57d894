#!/usr/bin/env bash
# Bakes six scenes that cover every mode and most outputs and prints one SHA-256 a file, so a
# refactoring can show it keeps the bytes: run it before and after, then diff the two lists.
# Manifests and resolved scenes name the work and source folders: those are hashed as WORK and ROOT;
# a manifest's "memory" line (its measured peak varies between runs) is left out.
#   bash tools/hash-bakes.sh [SNOWBAKE_BINARY] [WORK_DIR] > hashes.txt
# The scenes: the demo (preset:default); presets/art_direction.toml; presets/bedforms.toml;
# occlusion mode on the builtin range; mesh mode on a block on the ground; a real DEM from ../shared/data with every
# layer, encoding, mesh, VDB, displacement and frames (skipped with a message when absent).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="$(realpath "${1:-$root/build/snowbake}")"
work="${2:-$(mktemp -d)}"
mkdir -p "$work"
data="$root/../shared/data"
bake() {  # NAME SCENE [ARGS...]
  local name="$1" scene="$2"; shift 2
  "$bin" bake "$scene" --out "$work/$name" --no-cache --quiet --threads 2 "$@" > "$work/$name.log" 2>&1 ||
    { echo "hash-bakes: $name failed (log: $work/$name.log)" >&2; cat "$work/$name.log" >&2; exit 1; }
}
bake demo preset:default
bake art_direction "$root/presets/art_direction.toml"
bake bedforms "$root/presets/bedforms.toml"
cat > "$work/occlusion.toml" <<'TOML'
name = "hash-bakes: occlusion mode"
mode = "occlusion"
[terrain]
builtin = "ridged"
size = 128
cell_size_m = 20.0
[outputs]
layers = ["ambient_occlusion", "sun_visibility", "occlusion_accumulation", "occlusion_dissipation", "stable", "depth", "preview"]
encodings = ["png16"]
meshes = ["obj"]
TOML
bake occlusion "$work/occlusion.toml"
# A 2 m ground square with a 0.6 m block on it (the mesh-snow tests' block).
cat > "$work/block.obj" <<'OBJ'
v 0 0 0
v 2 0 0
v 2 2 0
v 0 2 0
v 0.7 0.7 0.5
v 1.3 0.7 0.5
v 1.3 1.3 0.5
v 0.7 1.3 0.5
v 0.7 0.7 0
v 1.3 0.7 0
v 1.3 1.3 0
v 0.7 1.3 0
f 1 2 3
f 1 3 4
f 5 6 7
f 5 7 8
f 9 10 6
f 9 6 5
f 10 11 7
f 10 7 6
f 11 12 8
f 11 8 7
f 12 9 5
f 12 5 8
OBJ
cat > "$work/mesh.toml" <<'TOML'
name = "hash-bakes: mesh mode"
mode = "mesh"
[terrain]
file = "block.obj"
[mesh_snow]
depth_m = 0.3
site_spacing_m = 0.04
flutter_mean_m = 0.02
flutter_sigma_m = 0.01
smoothing_steps = 4
[outputs]
meshes = ["obj", "glb", "ply"]
vdb = true
[run]
seed = 3
TOML
bake mesh "$work/mesh.toml"
if [ -f "$data/dem/tyrol_avaWog_5m.asc" ]; then
  cat > "$work/dem.toml" <<TOML
name = "hash-bakes: a real DEM with every output"
[terrain]
file = "$data/dem/tyrol_avaWog_5m.asc"
[season]
start_date = 2025-12-01
days = 40
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 4.0
wind_direction_deg = 250
wind_speed_mps = 9.0
[[events]]
type = "skier"
day = 20
count = 3
position_m = [600.0, 600.0]
[outputs]
layers = ["compacted", "stable", "unstable", "powder", "depth", "bedrock", "surface", "valid_mask", "wind_speed",
          "wind_direction", "wind_shadow_depth", "wind_shadow_mask", "sun_exposure", "temperature", "wind_scour",
          "wind_deposit", "melt", "avalanche_scour", "avalanche_deposit", "avalanche_preview", "preview",
          "ski_tracks", "ski_route_map"]
encodings = ["png16", "png8", "r16"]
multichannel_exr = true
displacement_size = [300, 300]
vdb = true
meshes = ["obj", "ply", "glb", "fbx"]
mesh_parts = ["surface", "body"]
mesh_tile_size_m = 400.0
frames_days = [10, 30]
avalanche_maps = true
ski_track_factor = 4
TOML
  bake dem "$work/dem.toml"
else
  echo "hash-bakes: $data absent: the real-DEM bake is skipped" >&2
fi
# Manifests name the scene and input files by path: hashed with the work folder and the checkout
# written as WORK and ROOT, so two checkouts (or two work folders) compare; their "memory" line
# (the measured peak, which varies from run to run) is left out.
cd "$work"
find . -mindepth 2 -type f | LC_ALL=C sort | while read -r f; do
  case "$f" in
    */manifest.json | */scene.resolved.toml) printf '%s  %s\n' "$(sed -e "s|$work|WORK|g" -e "s|$root|ROOT|g" -e '/^  "memory": /d' "$f" | sha256sum | cut -d' ' -f1)" "$f" ;;
    *) sha256sum "$f" ;;
  esac
done
