#!/usr/bin/env bash
# mpiexec -n N snowbake bake gives the single process's files, byte for byte, for N = 1..4
# (docs/distributed.md): the default preset with its spontaneous avalanches and skiers (some set
# off by skiers, their ski-track texture), frames written beside the season or after it; the
# art-direction preset whole (painted masks, initial snow, multipliers, no-snow road, timeline
# edits, a masked avalanche event and a skier group); the bedform window; and a real DEM with NODATA
# from ../shared/data (skipped with a message when absent); tiles each rank writes for its own
# subdomain, with art direction placed on each rank's local grid, resampled images (outputs.resize,
# displacement maps) and the avalanche maps' and skiers' tiles from each rank's replica; whole
# files rank 0 writes one at a time from the ranks' cells, and beside a tile set; the ranks' parts
# of the precompute, read from the cache by a second bake, Embree's rays traced for each rank's
# cells alone, and the replica's sun exposure gathered from the ranks' shares. Their manifests
# differ in the "memory" line alone (the measured peak varies from run to run). Then what a launch
# refuses (the CUDA backend, a missing terrain, a grid too small for the ranks), each exit 2 with
# one message and nothing written, a failure on rank 0 alone, and one rank failing to write its
# tile.
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
default=(preset:default --set terrain.size=120 --set season.days=45 --set 'outputs.frames_days=[20,40]')
check_scene default "${default[@]}"
# The season must have moved snow, released avalanches and run skiers for the comparison to mean
# something; across ranks they ran on the whole grid's replica.
grep -qE "added [1-9]" "$work/default/alone/log" || fail "default: no snowfall"
grep -qE "avalanche day .* cells released" "$work/default/alone/log" || fail "default: no avalanche released"
grep -qE "skiers: [0-9]+ .*, [1-9][0-9]* skied" "$work/default/alone/log" || fail "default: nobody skied"
grep -qE "[1-9][0-9]* set off an avalanche" "$work/default/alone/log" || fail "default: no skier set off an avalanche"
grep -q "replica of the whole grid, brought up to date [1-9]" "$work/default/2/log" || fail "default on 2 ranks: no replica"
# The replica's sun exposure and wind: each rank makes its local grid's, then every rank gathers the whole.
for ranks in 2 3 4; do
  grep -q "sun exposure: the ranks' local grids' gathered whole on every rank" "$work/default/$ranks/log" ||
    fail "default on $ranks ranks: each rank swept the whole grid's sun exposure"
  grep -q "wind: the ranks' local grids' gathered whole on every rank" "$work/default/$ranks/log" ||
    fail "default on $ranks ranks: each rank solved the whole grid's wind"
done
# The frames gathered on rank 0 and written beside the season, or held until its end.
for timing in beside after_season; do
  frames=("${default[@]}" --set "run.frame_writing=\"$timing\"")
  bake "$timing" "$work/$timing/alone" alone "${frames[@]}" &&
    bake "$timing" "$work/$timing/3" 3 "${frames[@]}" &&
    same "frames $timing on 3 ranks" "$work/$timing/alone" "$work/$timing/3"
done

# The art-direction preset at a quarter of its size: its painted masks, initial snow, snowfall
# multiplier, no-snow road and skier spawn, timeline edits, the masked avalanche and skier events,
# spontaneous avalanches and skiers.
check_scene art "$root/presets/art_direction.toml" --set terrain.size=128 --set season.days=52
grep -qE "edit 1: .*: [1-9]" "$work/art/alone/log" || fail "art: its first edit added no snow"
grep -qE "no-snow mask: [1-9]" "$work/art/alone/log" || fail "art: its no-snow mask removed no snow"
grep -qE "skiers: [0-9]+ \(20 from the scene\)" "$work/art/alone/log" || fail "art: its skier group did not ski"

# A frame whose instant falls inside an avalanche (the preset's masked release moved to 43 s
# before day 45, which it outlasts; one process sets the frame aside until it settles), on 2 ranks.
sed -e "s#\"art_direction/#\"$root/presets/art_direction/#g" -e '/^type = "avalanche"$/{n;s/^day = 45$/day = 44.9995/}' \
  "$root/presets/art_direction.toml" > "$work/mid.toml"
grep -q '^day = 44.9995$' "$work/mid.toml" || fail "mid-avalanche: the release's day was not moved"
mid=("$work/mid.toml" --set terrain.size=128 --set season.days=50 --set 'outputs.frames_days=[45]')
bake mid "$work/mid/alone" alone "${mid[@]}" && bake mid "$work/mid/2" 2 "${mid[@]}" &&
  same "a frame inside an avalanche on 2 ranks" "$work/mid/alone" "$work/mid/2"
grep -qE "avalanche day 45.00 .* \(user\)" "$work/mid/alone/log" || fail "mid-avalanche: the release did not run across day 45"

# The bedform window (periodic, slab hops across every subdomain's border), shortened.
check_scene bedforms "$root/presets/bedforms.toml" --set terrain.size=96 --set season.days=2 --set 'outputs.frames_days=[1]'
grep -qE "wind bedforms: [0-9]+ cells, [1-9][0-9]* rounds, [1-9][0-9]* slabs lifted" "$work/bedforms/alone/log" || fail "bedforms: no slab lifted"

# Without avalanches, skiers or bedforms each rank fills each day's static fields from its own
# cells of the precompute and frees the whole grid's: a wind that varies (two states and a calm
# keyframe), and the sun and wind layers rank 0 reads from the whole grid's it keeps.
cat > "$work/winds.toml" <<TOML
name = "across ranks: a varying wind and no events"
[terrain]
builtin = "ridged"
size = 96
cell_size_m = 10.0
[season]
start_date = 2025-12-01
days = 60
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 4.0
wind_direction_deg = 280
wind_speed_mps = 8.0
[[weather.keyframe]]
day = 25
wind_speed_mps = 0.0
[[weather.keyframe]]
day = 45
sea_level_temperature_c = 8.0
wind_direction_deg = 190
wind_speed_mps = 12.0
[parameters]
avalanche_rate_per_km2_per_day = 0.0
skiers_per_hour = 0.0
[outputs]
layers = ["depth", "wind_shadow_depth", "wind_speed", "wind_scour", "sun_exposure", "temperature", "preview"]
frames_days = [20, 40]
TOML
check_scene winds "$work/winds.toml"
grep -q "precompute: wind, 2 states" "$work/winds/alone/log" || fail "winds: not two wind states"
grep -q "replica" "$work/winds/2/log" && fail "winds on 2 ranks: a replica without events"
# The varying wind on the replica (skiers on): each rank solves its local grid's two states, then
# every rank gathers the whole grid's; on 3 ranks.
replica_winds=("$work/winds.toml" --set parameters.skiers_per_hour=1.0 --set season.days=50)
if bake replica_winds "$work/replica_winds/alone" alone "${replica_winds[@]}" && bake replica_winds "$work/replica_winds/3" 3 "${replica_winds[@]}"; then
  same "the varying wind on the replica on 3 ranks" "$work/replica_winds/alone" "$work/replica_winds/3"
  grep -q "replica of the whole grid" "$work/replica_winds/3/log" || fail "replica_winds on 3 ranks: no replica"
  grep -q "precompute: wind, 2 states (2 computed, 0 from the cache, each rank its local grid's" "$work/replica_winds/3/log" &&
    grep -q "wind: the ranks' local grids' gathered whole on every rank" "$work/replica_winds/3/log" ||
    fail "replica_winds on 3 ranks: each rank solved the whole grid's wind"
fi
# The Embree path (precompute.sun_method = "embree"): each rank traces its own cells' rays against
# the whole terrain's scene, in the whole grid's ray packets; on 3 ranks.
embree=("$work/winds.toml" --set precompute.sun_method=embree --set season.days=25 --set 'outputs.frames_days=[20]')
if bake embree "$work/embree/alone" alone "${embree[@]}" && bake embree "$work/embree/3" 3 "${embree[@]}"; then
  same "embree on 3 ranks" "$work/embree/alone" "$work/embree/3"
  grep -q "sun exposure (Embree rays)" "$work/embree/3/log" || fail "embree on 3 ranks: not the Embree path"
  rays() { sed -n "s/^  sun exposure (Embree rays): .*$1 [0-9.]* s (\([0-9]*\) rays).*\$/\1/p" "$2"; }
  for term in direct sky; do
    [ "$(rays $term "$work/embree/3/log")" -lt "$(rays $term "$work/embree/alone/log")" ] ||
      fail "embree on 3 ranks: rank 0 traced as many $term rays as the whole grid's"
  done
fi
# The season's peak per rank, where the kernel lets a process reset its peak count.
if (echo 5 > /proc/self/clear_refs) 2> /dev/null; then
  grep -qE "^memory: peak resident per rank in the season [0-9]+, [0-9]+ MiB; after it [0-9]+, [0-9]+ MiB" "$work/winds/2/log" ||
    fail "winds on 2 ranks: no season peak per rank in the log"
fi

# [outputs.tiles] of layers each rank can write from its own cells: the ranks' subdomains cut on
# the tiles' starts, each rank writing the tiles that start in its subdomain (frames, "season",
# "own" and fixed ranges combined over the ranks, r32, layers.exr, the engine maps and previews, whose normals
# read the next cells, the preview's altitude range and the contact sheet's thumbnails put
# together; the sun's and the wind's layers from each rank's part of the precompute); one manifest
# in the single process's order.
rich=("$work/winds.toml" --set 'outputs.layers=["depth", "powder", "surface", "snow_coverage", "weight_rock", "wind_scour",
      "melt", "splat_map", "snow_normal", "avalanche_preview", "preview", "sun_exposure", "temperature", "wind_speed",
      "wind_direction", "wind_shadow_depth", "wind_shadow_mask"]' --set 'outputs.encodings=["png16", "png8", "r32"]'
      --set 'outputs.ranges.surface="own"' --set outputs.multichannel_exr=true)
tiles=("${rich[@]}" --set 'outputs.tiles.convention="unity"' --set outputs.tiles.size_px=33)
check_scene tiles "${tiles[@]}"
for ranks in 2 3 4; do
  grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/tiles/$ranks/log" ||
    fail "tiles on $ranks ranks: the ranks did not write their own tiles"
done
# Resampled images under [outputs.tiles]: the layers at outputs.resize (finer than the grid) and
# the displacement maps (coarser), each tile written by the rank owning the cell under its first
# pixel from the cells its pixels read, gathered from their owners (OutputSources::gatherCells);
# the normal map's slopes one pixel past the tiles; on 1-4 ranks.
resized=("${tiles[@]}" --set 'outputs.resize=[129,129]' --set 'outputs.displacement_size=[65,65]')
check_scene resized "${resized[@]}"
for ranks in 2 3 4; do
  grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/resized/$ranks/log" ||
    fail "resized tiles on $ranks ranks: the ranks did not write their own tiles"
done
[ -f "$work/resized/4/out/displacement_depth_1_1.exr" ] || fail "resized tiles: no displacement tile"
# Whole files, each written by rank 0 from the cells every rank sends it, one file at a time
# (OutputWriter::untiledWindow): the tiles case's layers, encodings, ranges and layers.exr without
# [outputs.tiles], resampled (outputs.resize, displacement maps), as GeoTIFF, frames beside the
# season; on 2 and 4 ranks.
whole=("${rich[@]}" --set 'outputs.resize=[160,150]' --set 'outputs.displacement_size=[65,65]' --set 'outputs.format="tiff"'
       --set 'run.frame_writing="beside"')
bake whole "$work/whole/alone" alone "${whole[@]}"
for ranks in 2 4; do
  bake whole "$work/whole/$ranks" "$ranks" "${whole[@]}" && same "whole files on $ranks ranks" "$work/whole/alone" "$work/whole/$ranks"
  grep -q "^outputs: rank 0 writes every file, each gathered from the ranks one at a time" "$work/whole/$ranks/log" ||
    fail "whole files on $ranks ranks: rank 0 did not write them one at a time"
done
[ -f "$work/whole/4/out/layers.exr" ] && [ -f "$work/whole/4/out/frames/splat_map.0020.png" ] || fail "whole files: no layers.exr or frame"
# A grid so small that a rank's local grid is all of it (5 x 5 cells on 2 ranks, halo 2): the
# writers cannot tell that rank's window of the cells from an image every rank holds whole by its
# size, so rank 0 gathers the grid (a rank that skipped a gather the others made failed the launch
# with MPI_ERR_TRUNCATE); the single process's files, within two minutes.
printf 'ncols 5\nnrows 5\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n' > "$work/five.asc"
for y in 0 1 2 3 4; do echo "$((2000 + 15 * y)) $((2010 + 15 * y)) $((2020 + 15 * y)) $((2030 + 15 * y)) $((2040 + 15 * y))"; done >> "$work/five.asc"
five=("$work/winds.toml" --terrain "$work/five.asc")
bake five "$work/five/alone" alone "${five[@]}"
whole_launch=("${launch[@]}")
launch=(timeout -k 10 120 "${launch[@]}")
bake five "$work/five/2" 2 "${five[@]}" && same "a 5 x 5 grid on 2 ranks" "$work/five/alone" "$work/five/2"
launch=("${whole_launch[@]}")
grep -q "^outputs: rank 0 gathers the whole grid and writes every file: a rank's local grid is the whole grid" "$work/five/2/log" ||
  fail "a 5 x 5 grid on 2 ranks: rank 0 did not gather the grid"
# A tile set beside the whole files (outputs.tiles.resize): each rank its tiles of the layers
# resampled to 97², rank 0 the whole files at outputs.resize, one at a time; on 3 ranks.
tileset=("${tiles[@]}" --set 'outputs.tiles.resize=[97,97]' --set 'outputs.resize=[129,129]')
bake tileset "$work/tileset/alone" alone "${tileset[@]}" && bake tileset "$work/tileset/3" 3 "${tileset[@]}" &&
  same "a tile set beside the whole files on 3 ranks" "$work/tileset/alone" "$work/tileset/3"
grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/tileset/3/log" ||
  fail "a tile set beside the whole files on 3 ranks: the ranks did not write their own tiles"
[ -f "$work/tileset/3/out/depth.16.png" ] && [ -f "$work/tileset/3/out/depth_2_2.16.png" ] || fail "a tile set: no whole file or no tile"
# Avalanche maps and their motion frames under [outputs.tiles] with the default preset's avalanches
# and skiers (its displacement maps at 129 pixels, its VDB and meshes left out): each rank writes the maps' tiles
# that start in its subdomain from its replica's records, rank 0 the contact sheet, counted in
# the listing order on the others; the sun's and the wind's layers from each rank's window of
# the whole grid's precompute that the replica keeps; and the skiers' layers, the route map from
# the rank's window and the ski-track texture's tiles (2 texels a cell: 240 pixels, 8 x 8 tiles)
# from the replica's whole texture, each tile the rank's whose cells lie under its first pixel; on
# 3 ranks.
sed -e 's/^layers = \[/layers = ["temperature", "wind_shadow_mask", "ski_tracks", "ski_route_map", /' \
  "$root/presets/default.toml" > "$work/avmaps.toml"
grep -q '^layers = \["temperature", "wind_shadow_mask", "ski_tracks", "ski_route_map", ' "$work/avmaps.toml" ||
  fail "avalanche maps: the layers were not added"
avmaps=("$work/avmaps.toml" --set terrain.size=120 --set season.days=45 --set 'outputs.frames_days=[20,40]' --set outputs.vdb=false
        --set 'outputs.meshes=[]' --set outputs.avalanche_frame_interval_s=5 --set 'outputs.tiles.convention="unity"'
        --set outputs.tiles.size_px=33 --set outputs.ski_track_factor=2 --set 'outputs.displacement_size=[129,129]')
bake avmaps "$work/avmaps/alone" alone "${avmaps[@]}" && bake avmaps "$work/avmaps/3" 3 "${avmaps[@]}" &&
  same "avalanche maps in tiles on 3 ranks" "$work/avmaps/alone" "$work/avmaps/3"
grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/avmaps/3/log" ||
  fail "avalanche maps in tiles on 3 ranks: the ranks did not write their own tiles"
[ -f "$work/avmaps/alone/out/avalanches/001_deposit_0_0.exr" ] || fail "avalanche maps in tiles: no map of the first avalanche"
[ -f "$work/avmaps/alone/out/contact_sheet.png" ] || fail "avalanche maps in tiles: no contact sheet"
[ -f "$work/avmaps/3/out/temperature_0_0.exr" ] || fail "avalanche maps in tiles: no temperature tile"
[ -f "$work/avmaps/3/out/ski_tracks_7_7.exr" ] || fail "avalanche maps in tiles: no ski-track tile at the texture's far corner"
[ -f "$work/avmaps/3/out/ski_route_map_3_3.exr" ] || fail "avalanche maps in tiles: no route-map tile"
[ -f "$work/avmaps/3/out/displacement_surface_3_3.exr" ] || fail "avalanche maps in tiles: no displacement tile"
grep -qE "skiers: [0-9]+ .*, [1-9][0-9]* skied" "$work/avmaps/3/log" || fail "avalanche maps in tiles: nobody skied"
# The same resampled (outputs.resize): each rank's tiles of every map and motion frame from the
# cells their pixels read, out of its replica's records; on 2 ranks.
avresized=("${avmaps[@]}" --set 'outputs.resize=[129,129]')
bake avresized "$work/avresized/alone" alone "${avresized[@]}" && bake avresized "$work/avresized/2" 2 "${avresized[@]}" &&
  same "resampled avalanche maps in tiles on 2 ranks" "$work/avresized/alone" "$work/avresized/2"
grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/avresized/2/log" ||
  fail "resampled avalanche maps in tiles on 2 ranks: the ranks did not write their own tiles"
[ -f "$work/avresized/2/out/avalanches/001_deposit_3_3.exr" ] || fail "resampled avalanche maps in tiles: no map tile"
# The ski-track texture at one texel a cell is a layer of the grid's cells: resampled with the
# others and a channel of layers.exr on the ranks as in one process (each rank cuts its window of
# the replica's whole texture); in tiles on 2 ranks, and as whole files, with the avalanche maps,
# which rank 0 writes from its replica, on 3.
onetexel=("${avmaps[@]}" --set outputs.ski_track_factor=1 --set 'outputs.resize=[97,97]' --set outputs.multichannel_exr=true)
bake onetexel "$work/onetexel/alone" alone "${onetexel[@]}" && bake onetexel "$work/onetexel/2" 2 "${onetexel[@]}" &&
  same "a one-texel ski-track texture in tiles on 2 ranks" "$work/onetexel/alone" "$work/onetexel/2"
onetexelwhole=("$work/avmaps.toml" --set terrain.size=120 --set season.days=45 --set 'outputs.frames_days=[20,40]' --set outputs.vdb=false
               --set 'outputs.meshes=[]' --set outputs.avalanche_frame_interval_s=5 --set outputs.ski_track_factor=1
               --set 'outputs.resize=[97,97]' --set outputs.multichannel_exr=true --set 'outputs.displacement_size=[129,129]')
bake onetexel-whole "$work/onetexel-whole/alone" alone "${onetexelwhole[@]}" &&
  bake onetexel-whole "$work/onetexel-whole/3" 3 "${onetexelwhole[@]}" &&
  same "a one-texel ski-track texture and avalanche maps as whole files on 3 ranks" "$work/onetexel-whole/alone" "$work/onetexel-whole/3"
grep -q "^outputs: rank 0 writes every file, each gathered from the ranks one at a time" "$work/onetexel-whole/3/log" ||
  fail "a one-texel ski-track texture as whole files on 3 ranks: rank 0 did not write them one at a time"
[ -f "$work/onetexel-whole/3/out/avalanches/001_deposit.exr" ] || fail "avalanche maps as whole files: no map of the first avalanche"
# A constant wind, no events, the sun's and the wind's layers in tiles: each rank's day-0 wind and
# the layers from its parts of the precompute, which a constant wind fills once (a rank once ran
# its season without it and crashed in the wind transport); on 2 ranks.
calm=("$work/avmaps.toml" --set terrain.size=96 --set season.days=30 --set 'outputs.frames_days=[20]' --set outputs.avalanche_maps=false
      --set outputs.vdb=false --set 'outputs.meshes=[]' "${no_avalanches[@]}" --set 'outputs.layers=["depth", "wind_speed", "temperature"]'
      --set 'outputs.tiles.convention="unity"' --set outputs.tiles.size_px=33)
bake calm "$work/calm/alone" alone "${calm[@]}" && bake calm "$work/calm/2" 2 "${calm[@]}" &&
  same "a constant wind's layers in tiles on 2 ranks" "$work/calm/alone" "$work/calm/2"
grep -q "^outputs: each rank writes the tiles that start in its subdomain" "$work/calm/2/log" ||
  fail "a constant wind's layers in tiles on 2 ranks: the ranks did not write their own tiles"
grep -q "replica" "$work/calm/2/log" && fail "a constant wind's layers on 2 ranks: a replica without events"

# A no-snow mask on initial snow (rank 0 keeps the whole state until the season to take what it
# removes in the single process's order) and weight_rock, whose slopes read the next cells, on its
# own range (over each rank's own cells): on 4 ranks.
nosnow=("${tiles[@]}" --set initial_snow.stable=0.2 --set "multipliers.no_snow=\"$root/presets/art_direction/road.png\""
        --set 'outputs.ranges.weight_rock="own"')
bake nosnow "$work/nosnow/alone" alone "${nosnow[@]}" && bake nosnow "$work/nosnow/4" 4 "${nosnow[@]}" &&
  same "tiles with a no-snow mask on 4 ranks" "$work/nosnow/alone" "$work/nosnow/4"
grep -qE "no-snow mask: [1-9]" "$work/nosnow/alone/log" || fail "nosnow: the mask removed no snow"

# Art direction without events on ranks that each make their initial state on their local grid
# (rank 0 too: every rank writes its tiles and no no-snow mask needs the whole grid): initial snow
# from a constant and a mask, snowfall and melt multipliers from rasters, a masked timeline edit;
# the rasters placed and their volumes summed on the whole grid.
{ cat "$work/winds.toml"; cat <<TOML
[initial_snow]
stable = 0.2
powder = { mask = "$root/presets/art_direction/precipitation.png", depth_m = 0.3 }
[multipliers]
snowfall = { file = "$root/presets/art_direction/precipitation.png", range = [0.6, 1.4] }
melt = "$root/presets/art_direction/ski_area.png"
[[edits]]
day = 20
op = "add"
layer = "compacted"
depth_m = 0.4
mask = "$root/presets/art_direction/ski_area.png"
TOML
} > "$work/art_local.toml"
art_local=("$work/art_local.toml" "${tiles[@]:1}")
bake art-local "$work/art-local/alone" alone "${art_local[@]}"
for ranks in 3 4; do
  bake art-local "$work/art-local/$ranks" "$ranks" "${art_local[@]}" &&
    same "art direction on each rank's local grid, $ranks ranks" "$work/art-local/alone" "$work/art-local/$ranks"
done
grep -qE "edit 1: .*: [1-9]" "$work/art-local/alone/log" || fail "art-local: its edit added no snow"
grep -q "initial_snow.powder: [1-9].* m^3 placed" "$work/art-local/alone/log" || fail "art-local: no powder placed"

# GeoTIFF tiles of Unreal's 127 (2 x 2 on a grid of 253), frames beside the season (written in
# place where the ranks write their tiles): 4 ranks write their own, 3 cannot share 2 x 2 tiles
# (rank 0 gathers the grid and writes them all).
unreal=("${tiles[@]}" --set terrain.size=253 --set 'outputs.format="tiff"' --set 'outputs.tiles.convention="unreal"'
        --set outputs.tiles.size_px=127 --set 'run.frame_writing="beside"')
bake unreal "$work/unreal/alone" alone "${unreal[@]}"
for ranks in 3 4; do
  bake unreal "$work/unreal/$ranks" "$ranks" "${unreal[@]}" && same "unreal tiles on $ranks ranks" "$work/unreal/alone" "$work/unreal/$ranks"
done
grep -q "^outputs: each rank writes the tiles" "$work/unreal/4/log" || fail "unreal tiles on 4 ranks: not written by their ranks"
grep -q "^outputs: rank 0 gathers the whole grid and writes every file: the grid does not split" "$work/unreal/3/log" ||
  fail "unreal tiles on 3 ranks: not gathered on rank 0"

# The precompute's cache across ranks: each rank's part of the exposure and of each wind state is an
# entry of its own. A second bake with the same ranks reads them all; where one rank's part of a
# wind state is missing, every rank solves that state again (none waits in an exchange the others
# skip). The same files each time (one command line: the manifests agree too).
cached() {  # NAME: the tiles' scene on 3 ranks into $work/cache/NAME, the cache in $work/cache/entries
  mkdir -p "$work/cache/$1"
  (cd "$work/cache/$1" && timeout 300 "${launch[@]}" -n 3 "$bin" bake "${tiles[@]}" --out out --cache-dir "$work/cache/entries" --quiet \
    --threads 1 > log 2>&1) || { fail "cache $1: exit $?"; cat "$work/cache/$1/log" >&2; return 1; }
}
if cached first && cached again; then
  same "the second bake with the cache on 3 ranks" "$work/cache/first" "$work/cache/again"
  grep -q "sun exposure: from the cache (each rank its local grid's)" "$work/cache/again/log" || fail "cache: the exposure's parts were not read"
  grep -q "precompute: wind, 2 states (0 computed, 2 from the cache, each rank its local grid's" "$work/cache/again/log" ||
    fail "cache: the wind's parts were not read"
  parts=("$work"/cache/entries/wind-*-cells-0-0-*.bin)
  [ "${#parts[@]}" = 2 ] || fail "cache: rank 0 stored ${#parts[@]} wind parts, not one for each of 2 states"
  rm -f "${parts[0]}"
  cached missing && same "a bake missing rank 0's part of a wind state on 3 ranks" "$work/cache/first" "$work/cache/missing"
  grep -q "precompute: wind, 2 states (1 computed, 1 from the cache, each rank its local grid's" "$work/cache/missing/log" ||
    fail "cache: with rank 0's part of a state missing, the ranks did not solve that state alone"
fi

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
  # Its layers as whole files rank 0 writes one at a time (no VDB or meshes), NODATA in the masks
  # the ranks send; on 3 ranks.
  demwhole=("$work/dem.toml" --set outputs.vdb=false --set 'outputs.meshes=[]')
  bake dem-whole "$work/dem-whole/alone" alone "${demwhole[@]}" && bake dem-whole "$work/dem-whole/3" 3 "${demwhole[@]}" &&
    same "the dem as whole files on 3 ranks" "$work/dem-whole/alone" "$work/dem-whole/3"
  grep -q "^outputs: rank 0 writes every file, each gathered from the ranks one at a time" "$work/dem-whole/3/log" ||
    fail "the dem as whole files on 3 ranks: rank 0 did not write them one at a time"
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
refused cuda 'run.backend = "cuda": a bake across ranks' preset:default --set 'run.backend="cuda"'
refused missing-terrain /nonexistent/dem.asc preset:default --terrain /nonexistent/dem.asc "${no_avalanches[@]}"
# Found once the ranks have joined (the terrain loaded): they agree on the status.
# A 3 x 3 DEM: two ranks would each own a band one cell wide, narrower than the halo (2 cells).
printf 'ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n100 110 120\n105 115 125\n110 120 130\n' > "$work/tiny.asc"
refused tiny-grid "cannot be baked across ranks" preset:default --terrain "$work/tiny.asc" "${no_avalanches[@]}"
# This machine's ranks need more than the budget together, though one process alone fits it: refused
# up front on every rank, the message counting the ranks.
small_budget=(preset:default --set terrain.size=512 --set season.days=2 --set 'outputs.frames_days=[]' --set run.max_memory_gb=0.25
              "${no_avalanches[@]}")
refused ranks-memory "the 2 on this machine need about" "${small_budget[@]}"
(cd "$work/ranks-memory" && "$bin" bake "${small_budget[@]}" --out alone --no-cache > alone.log 2>&1) ||
  fail "ranks-memory: one process alone is refused too (the budget does not separate them)"

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

# Where each rank writes its tiles, one rank failing to write one (a folder in the way of rank
# 3's first tile, the south-east one of 3 x 3) ends every rank at once with its status and its one message, no manifest.
mkdir -p "$work/tile-fails/out/frames" "$work/tile-fails/out/depth_2_0.exr"
status=0
(cd "$work/tile-fails" && timeout 300 "${launch[@]}" -n 4 "$bin" bake "${tiles[@]}" --out out --no-cache --threads 1 > log 2>&1) ||
  status=$?
[ "$status" = 1 ] || fail "tile-fails: exit $status, not 1 (124: it hung)"
grep -q "^\[rank 3\] snowbake: failed: .*depth_2_0.exr: Is a directory" "$work/tile-fails/log" ||
  { fail "tile-fails: rank 3's message is not in the log"; cat "$work/tile-fails/log" >&2; }
[ ! -e "$work/tile-fails/out/manifest.json" ] || fail "tile-fails: a manifest was written"

if [ "$failures" -gt 0 ]; then
  echo "bake_across_ranks_test: $failures failures" >&2
  exit 1
fi
echo "bake_across_ranks_test: passed"
