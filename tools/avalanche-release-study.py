#!/usr/bin/env python3
"""Spontaneous avalanches in a 90-day winter with four 3-day storms (issue #25, docs/models/avalanches.md).

Bakes the winter on each Tyrol DEM with the default parameters and counts, from the manifest,
the spontaneous releases per storm (from a storm's start to the next one's) per km^2 of release
terrain (bedrock slopes 30-50 degrees), the slopes they started on, and the rate per km^2 of
terrain per week against the paper's once a week.

    python3 tools/avalanche-release-study.py build/snowbake ../shared/data [work-dir]
"""
import json
import math
import os
import subprocess
import sys

STORMS = [(5, 8), (27, 30), (49, 52), (71, 74)]
DAYS = 90


def read_asc(path):
    with open(path) as f:
        header = {}
        for _ in range(6):
            k, v = f.readline().split()
            header[k.lower()] = float(v)
        rows = [list(map(float, line.split())) for line in f if line.strip()]
    return header, rows


def terrain_areas_km2(path):
    """(valid area, area of slopes 30-50 degrees), from central differences of the bedrock."""
    h, z = read_asc(path)
    nodata, cell = h.get("nodata_value", -9999.0), h["cellsize"]
    ny, nx = len(z), len(z[0])
    valid = release = 0
    for y in range(1, ny - 1):
        for x in range(1, nx - 1):
            c = z[y][x]
            if c == nodata:
                continue
            valid += 1
            n = (z[y][x - 1], z[y][x + 1], z[y - 1][x], z[y + 1][x])
            if nodata in n:
                continue
            gx, gy = (n[1] - n[0]) / (2 * cell), (n[3] - n[2]) / (2 * cell)
            if 30.0 <= math.degrees(math.atan(math.hypot(gx, gy))) <= 50.0:
                release += 1
    return valid * cell * cell * 1e-6, release * cell * cell * 1e-6


def scene(dem):
    storms = "".join(f"[[weather.snowfall]]\nstart_day = {a}\nend_day = {b}\n" for a, b in STORMS)
    return (f'[terrain]\nfile = "{dem}"\n[season]\nstart_date = 2026-01-01\ndays = {DAYS}\n'
            "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 6.0\n" + storms +
            "[parameters]\nrain_snow_limit_m = 1000\nskiers_per_hour = 0\n"
            '[outputs]\nlayers = ["depth", "avalanche_peak_thickness"]\n')


def study(binary, dem, work):
    name = os.path.splitext(os.path.basename(dem))[0]
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, name + ".toml")
    with open(path, "w") as f:
        f.write(scene(os.path.abspath(dem)))
    out = os.path.join(work, name)
    subprocess.run([binary, "bake", path, "--out", out, "--quiet"], check=True, stdout=subprocess.DEVNULL)
    manifest_path = next(os.path.join(r, f) for r, _, fs in os.walk(out) for f in fs if f == "manifest.json")
    with open(manifest_path) as f:
        manifest = json.load(f)
    avalanches = manifest["run"]["avalanches"] if "run" in manifest else manifest["avalanches"]
    spont = [a for a in avalanches if not a["user"] and a["released"]]
    valid_km2, release_km2 = terrain_areas_km2(dem)
    per_storm = []
    for k, (start, _) in enumerate(STORMS):
        end = STORMS[k + 1][0] if k + 1 < len(STORMS) else DAYS + 1
        per_storm.append([a for a in spont if start <= a["day"] < end])
    before_first = [a for a in spont if a["day"] < STORMS[0][0]]
    slopes = [a["rupture_slope_deg"] for a in spont]
    rate = len(spont) / valid_km2 / (DAYS / 7.0)
    print(f"| {name} | {valid_km2:.2f} | {release_km2:.2f} | " +
          ", ".join(f"{len(s)} ({len(s) / release_km2:.1f}/km²)" for s in per_storm) +
          f" | {len(before_first)} | " + (f"{min(slopes):.1f}–{max(slopes):.1f}" if slopes else "none") +
          f" | {rate:.2f} |")
    return per_storm, slopes, rate, release_km2


def main():
    binary, data = sys.argv[1], sys.argv[2]
    work = sys.argv[3] if len(sys.argv) > 3 else "/tmp/snowbake-release-study"
    print(f"90 days from 1 January, storms on days {STORMS}, sea-level temperature 6 °C, default parameters")
    print("\n| DEM | terrain (km²) | release terrain 30–50° (km²) | spontaneous releases per storm (per km² of release terrain) "
          "| before the first storm | rupture slopes (°) | rate per km² of terrain per week |\n|---|---|---|---|---|---|---|")
    for dem in ("tyrol_avaWog_5m.asc", "tyrol_avaKot_5m.asc"):
        study(binary, os.path.join(data, "dem", dem), work)


if __name__ == "__main__":
    main()
