# The Blender add-on (python/blender/snowbake_import.py) in Blender 3.4, headless, as a user runs
# it; writes what it found to RENDER_BAKE/blender_addon_check.json for tests/blender_addon_test.cpp:
#   blender -b --factory-startup --python tools/blender_addon_check.py -- ADDON RENDER_BAKE TILED_BAKE
# - the add-on registers and File > Import > snowbake bake is an operator;
# - RENDER_BAKE imported: surface, snow material (mask textures Non-Color, coverage wired to the
#   snow/rock mix, normal map wired to the BSDF), the VDB as a volume with a density material;
# - a 32 x 32 Cycles render from straight above (4 samples, CPU): the pixels' brightness where the
#   bake's snow_coverage is > 0.9 and < 0.1, and how much the render changes without the normal map;
# - TILED_BAKE imported: its mesh tiles (border vertices of neighbours against each other) and its
#   frames as an image sequence on the timeline.
import importlib
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_tile_seams import tile_seams  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
addon, render_bake, tiled_bake = args[0], args[1], args[2]
result = {"blender_version": bpy.app.version_string}

bpy.ops.wm.read_factory_settings(use_empty=True)
sys.path.insert(0, os.path.dirname(addon))
snowbake_import = importlib.import_module(os.path.splitext(os.path.basename(addon))[0])
snowbake_import.register()
result["registered"] = hasattr(bpy.types, "IMPORT_SCENE_OT_snowbake")
result["menu"] = snowbake_import._menu in getattr(bpy.types.TOPBAR_MT_file_import, "_dyn_ui_initialize")()

# 1. The render bake through the operator, as File > Import runs it.
status = bpy.ops.import_scene.snowbake(filepath=os.path.join(render_bake, "manifest.json"))
result["import_status"] = sorted(status)
scene = bpy.context.scene
surfaces = [o for o in scene.objects if o.type == "MESH"]
volumes = [o for o in scene.objects if o.type == "VOLUME"]
mat = surfaces[0].data.materials[0]
nodes = mat.node_tree.nodes
bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
masks = [n for n in nodes if n.type == "TEX_IMAGE" and n.name != "snow_normal"]
result["surface"] = {"objects": len(surfaces), "material": mat.name, "uv_layers": len(surfaces[0].data.uv_layers)}
result["material"] = {
    "mask_textures": sorted(n.name for n in masks),
    "mask_colorspaces": sorted({n.image.colorspace_settings.name for n in masks}),
    "coverage_wired": nodes["snow_mix"].inputs["Fac"].is_linked,
    "normal_map_wired": bsdf.inputs["Normal"].is_linked and "snow_normal" in nodes,
}
vmat = volumes[0].data.materials[0] if volumes and volumes[0].data.materials else None
result["volume"] = {"objects": len(volumes), "material_nodes": sorted(n.type for n in vmat.node_tree.nodes) if vmat else [],
                    "density_attribute": next((n.inputs["Density Attribute"].default_value for n in vmat.node_tree.nodes
                                               if n.type == "PRINCIPLED_VOLUME"), "") if vmat else ""}

# 2. From straight above, the sun overhead, no world light, the volume hidden (it would veil the surface).
manifest = json.load(open(os.path.join(render_bake, "manifest.json")))
ex = manifest["terrain"]["width"] * manifest["terrain"]["cell_size_x_m"]
ey = manifest["terrain"]["height"] * manifest["terrain"]["cell_size_y_m"]
for v in volumes:
    v.hide_render = True
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
camera.data.type = "ORTHO"
camera.data.ortho_scale = max(ex, ey)
camera.data.clip_end = 1e5
camera.location = (ex / 2, ey / 2, 10000.0)
scene.collection.objects.link(camera)
scene.camera = camera
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
sun.data.energy = 3.0
scene.collection.objects.link(sun)
scene.world = bpy.data.worlds.new("black")
scene.world.color = (0.0, 0.0, 0.0)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 32
scene.render.resolution_percentage = 100
scene.view_settings.view_transform = "Standard"


def render(name):
    scene.render.filepath = os.path.join(render_bake, name)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    px = list(image.pixels)  # RGBA, row 0 at the bottom
    return [sum(px[4 * i:4 * i + 3]) / 3 for i in range(32 * 32)]


lum = render("blender_addon_render.png")
coverage = bpy.data.images.load(os.path.join(render_bake, "snow_coverage.exr"))
cw, ch = coverage.size
cpx = list(coverage.pixels)
snowy, bare = [], []
for j in range(32):
    for i in range(32):
        c = cpx[4 * (int((j + 0.5) / 32 * ch) * cw + int((i + 0.5) / 32 * cw))]
        (snowy if c > 0.9 else bare if c < 0.1 else []).append(lum[j * 32 + i])
threshold = 0.5 * (sum(snowy) / len(snowy) + sum(bare) / len(bare)) if snowy and bare else 0
result["render"] = {"pixels_snow": len(snowy), "pixels_bare": len(bare),
                    "mean_snow": sum(snowy) / max(1, len(snowy)), "mean_bare": sum(bare) / max(1, len(bare)),
                    "snow_brighter_than_midpoint": sum(v > threshold for v in snowy) / max(1, len(snowy)),
                    "bare_darker_than_midpoint": sum(v < threshold for v in bare) / max(1, len(bare))}
# The normal map unlinked: the same render without it.
for link in list(mat.node_tree.links):
    if link.to_socket == bsdf.inputs["Normal"]:
        mat.node_tree.links.remove(link)
flat = render("blender_addon_render_no_normal_map.png")
result["normal_map_effect"] = {"mean_abs_difference": sum(abs(a - b) for a, b in zip(lum, flat)) / len(lum),
                               "mean_luminance": sum(lum) / len(lum)}

# 3. The tiled bake with frames, into an emptied scene.
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
made = snowbake_import.import_bake(os.path.join(tiled_bake, "manifest.json"))
tiles = {}
for path, objs in made["surface_files"].items():
    column, row = (int(p[1:]) for p in path[len("snow_surface_"):-4].split("_"))
    tiles[(column, row)] = [tuple(o.matrix_world @ v.co) for o in objs for v in o.data.vertices]
tm = json.load(open(os.path.join(tiled_bake, "manifest.json")))
size_m = 640.0  # the test's mesh_tile_size_m
top = tm["terrain"]["height"] * tm["terrain"]["cell_size_y_m"]
border, worst = tile_seams(tiles, size_m, top)
frames = made["frames"]
result["tiles"] = {"count": len(tiles), "border_vertices": border, "max_gap_m": worst}
result["frames"] = {"source": frames[0].source if frames else "", "first_day": frames[1] if frames else -1,
                    "last_day": frames[2] if frames else -1, "scene_frames": [bpy.context.scene.frame_start, bpy.context.scene.frame_end]}

with open(os.path.join(render_bake, "blender_addon_check.json"), "w") as f:
    json.dump(result, f, indent=2)
print("blender_addon_check:", json.dumps(result))
