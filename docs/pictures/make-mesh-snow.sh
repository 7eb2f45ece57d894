#!/usr/bin/env bash
# Remakes docs/mesh_snow_table.png: writes the scene's mesh, bakes docs/pictures/mesh_snow_table.toml
# in mode = "mesh" and draws mesh and snow body (Debian's python3 with numpy and OpenImageIO:
# apt-get install python3-numpy python3-openimageio). Run from the repository root after a build.
set -euo pipefail
cd "$(dirname "$0")/../.."
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 docs/pictures/mesh_snow_table.py obj "$work/table.obj"
cp docs/pictures/mesh_snow_table.toml "$work/scene.toml"
./build/snowbake bake "$work/scene.toml" --out "$work/bake"
/usr/bin/python3 docs/pictures/mesh_snow_table.py render "$work/table.obj" "$work/bake" docs/mesh_snow_table.png
