#!/usr/bin/env bash
# Remakes docs/ski_tracks_tyrol.png: bakes docs/pictures/ski_tracks_tyrol.toml (the real DEM in
# ../shared/data) and composes the picture (Debian's python3 with OpenImageIO and numpy:
# apt-get install python3-openimageio python3-numpy). Run from the repository root after a build.
set -euo pipefail
cd "$(dirname "$0")/../.."
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
./build/snowbake bake docs/pictures/ski_tracks_tyrol.toml --out "$out/bake"
/usr/bin/python3 docs/pictures/ski_tracks.py "$out/bake" docs/ski_tracks_tyrol.png
