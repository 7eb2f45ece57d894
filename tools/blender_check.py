# Loads a bake's outputs in Blender (3.4, headless) as a user would, and writes what it found to
# DIR/blender_check.json for the test to judge (tests/blender_test.cpp):
#   blender -b --factory-startup --python tools/blender_check.py -- BAKE_DIR [TILED_BAKE_DIR]
# - snow_surface.glb imports as a mesh (vertex count, height range in Blender's z-up world);
# - snow.vdb imports as a volume object (its grid names);
# - displacement_depth.exr drives a Displace modifier on a grid mesh over the terrain's extent
#   (UV coordinates, strength 1, midlevel 0, nearest texel): the evaluated heights against the
#   EXR's texels;
# - snow_normal.png as the surface's tangent-space normal map (Normal Map node on its UVs), and
#   its decoded texels against the mesh's vertex normals;
# - one small Cycles image on the CPU (blender_check.png);
# - with TILED_BAKE_DIR: its snow_surface_x<c>_y<r>.glb tiles, and how far each border vertex of a
#   tile is from the nearest border vertex of its neighbour.
import json
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_tile_seams import tile_seams  # noqa: E402

out = sys.argv[sys.argv.index("--") + 1]
manifest = json.load(open(os.path.join(out, "manifest.json")))
grid = manifest["terrain"]
extent_x = grid["width"] * grid["cell_size_x_m"]
extent_y = grid["height"] * grid["cell_size_y_m"]
result = {"blender_version": bpy.app.version_string}

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

# 1. The glTF surface.
# Shading "SMOOTH": the default ("NORMALS") path of Blender 3.4's importer uses np.bool, which
# Debian 12's numpy 1.24 no longer has. Our normals are smooth anyway.
bpy.ops.import_scene.gltf(filepath=os.path.join(out, "snow_surface.glb"), import_shading="SMOOTH")
surface = [o for o in bpy.context.selected_objects if o.type == "MESH"][0]
zs = [(surface.matrix_world @ v.co).z for v in surface.data.vertices]
xs = [(surface.matrix_world @ v.co).x for v in surface.data.vertices]
ys = [(surface.matrix_world @ v.co).y for v in surface.data.vertices]
result["glb"] = {"vertices": len(surface.data.vertices), "polygons": len(surface.data.polygons),
                 "z_min": min(zs), "z_max": max(zs), "x_min": min(xs), "x_max": max(xs), "y_min": min(ys), "y_max": max(ys),
                 "uv_layers": len(surface.data.uv_layers)}

# 2. The OpenVDB volume.
bpy.ops.object.volume_import(filepath=os.path.join(out, "snow.vdb"))
volume = [o for o in bpy.context.selected_objects if o.type == "VOLUME"][0]
volume.data.grids.load()
result["vdb"] = {"object_type": volume.type, "grids": sorted(g.name for g in volume.data.grids)}

# 3. The displacement map on a grid mesh over the terrain's extent, through its UVs.
image = bpy.data.images.load(os.path.join(out, "displacement_depth.exr"))
image.colorspace_settings.name = "Non-Color"
n = 48
bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=1.0)
plane = bpy.context.active_object
plane.scale = (extent_x, extent_y, 1.0)
plane.location = (extent_x / 2, extent_y / 2, 0.0)
texture = bpy.data.textures.new("snow_depth", type="IMAGE")
texture.image = image
texture.extension = "EXTEND"
texture.use_interpolation = False  # nearest texel: the test compares texel values exactly
mod = plane.modifiers.new("displace", "DISPLACE")
mod.texture = texture
mod.texture_coords = "UV"
mod.strength = 1.0
mod.mid_level = 0.0
mod.direction = "Z"
depsgraph = bpy.context.evaluated_depsgraph_get()
evaluated = plane.evaluated_get(depsgraph).to_mesh()
pixels = list(image.pixels)  # RGBA floats, row 0 at the bottom (south)
w, h = image.size
worst = 0.0
count = 0
for v in evaluated.vertices:
    u = v.co.x + 0.5  # the grid primitive spans [-0.5, 0.5] in object space; its UVs [0, 1]
    t = v.co.y + 0.5
    fu, ft = u * w, t * h
    # Skip vertices on a texel border, where nearest sampling could go either way.
    if abs(fu - round(fu)) < 1e-3 or abs(ft - round(ft)) < 1e-3:
        continue
    i, j = min(w - 1, int(fu)), min(h - 1, int(ft))
    expected = pixels[4 * (j * w + i)]
    worst = max(worst, abs(v.co.z - expected))
    count += 1
max_displacement = max(v.co.z for v in evaluated.vertices)
plane.evaluated_get(depsgraph).to_mesh_clear()
result["displacement"] = {"image_size": [w, h], "checked_vertices": count, "max_abs_error_m": worst,
                          "max_displacement_m": max_displacement, "max_pixel_m": max(pixels[0::4])}

# 4. A small Cycles render on the CPU.
camera_data = bpy.data.cameras.new("camera")
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
camera.location = (extent_x / 2, -0.6 * extent_y, result["glb"]["z_max"] + 0.8 * extent_x)
camera.rotation_euler = (math.radians(50), 0.0, 0.0)
scene.camera = camera
sun_data = bpy.data.lights.new("sun", type="SUN")
sun = bpy.data.objects.new("sun", sun_data)
sun.rotation_euler = (math.radians(40), 0.0, math.radians(30))
scene.collection.objects.link(sun)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.render.resolution_x = 96
scene.render.resolution_y = 64
scene.render.filepath = os.path.join(out, "blender_check.png")
bpy.ops.render.render(write_still=True)
result["render"] = {"path": scene.render.filepath, "exists": os.path.exists(scene.render.filepath)}

# 5. The normal map on the surface: Image (Non-Color) -> Normal Map (tangent space, the UVs) ->
# Principled BSDF; and at each vertex the texel under its UV, decoded (n = 2 p - 1 in the frame
# u east, v north, up), against the mesh's own normal there.
material = bpy.data.materials.new("snow")
material.use_nodes = True
nodes, links = material.node_tree.nodes, material.node_tree.links
bsdf = nodes["Principled BSDF"]
normal_image = bpy.data.images.load(os.path.join(out, "snow_normal.png"))
normal_image.colorspace_settings.name = "Non-Color"
tex = nodes.new("ShaderNodeTexImage")
tex.image = normal_image
normal_map = nodes.new("ShaderNodeNormalMap")
normal_map.space = "TANGENT"
normal_map.uv_map = surface.data.uv_layers[0].name
links.new(tex.outputs["Color"], normal_map.inputs["Color"])
links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
surface.data.materials.clear()
surface.data.materials.append(material)
npx = list(normal_image.pixels)  # RGBA, row 0 at the bottom (south)
nw, nh = normal_image.size
uv_of = {}
for loop in surface.data.loops:
    uv_of.setdefault(loop.vertex_index, surface.data.uv_layers[0].data[loop.index].uv)
angles, flipped = [], []  # flipped: had the map DirectX's green, the angle it would give
def angle_deg(n, m):
    cos = sum(a * b for a, b in zip(n, m)) / (math.sqrt(sum(c * c for c in n)) * m.length)
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))
for v in surface.data.vertices:
    u, t = uv_of[v.index]
    i, j = min(nw - 1, max(0, int(u * nw))), min(nh - 1, max(0, int(t * nh)))
    n = [2.0 * npx[4 * (j * nw + i) + k] - 1.0 for k in range(3)]
    m = surface.matrix_world.to_3x3() @ v.normal
    angles.append(angle_deg(n, m))
    flipped.append(angle_deg([n[0], -n[1], n[2]], m))
angles.sort()
flipped.sort()
result["normal_map"] = {"image_size": list(normal_image.size), "linked": bsdf.inputs["Normal"].is_linked,
                        "vertices": len(angles), "median_angle_deg": angles[len(angles) // 2],
                        "p95_angle_deg": angles[int(0.95 * (len(angles) - 1))],
                        "median_angle_deg_green_flipped": flipped[len(flipped) // 2]}

# 6. Mesh tiles: every border vertex of a tile against its neighbour's border vertices.
if len(sys.argv) > sys.argv.index("--") + 2:
    tiled = sys.argv[sys.argv.index("--") + 2]
    tiles = {}
    for name in sorted(os.listdir(tiled)):
        if name.startswith("snow_surface_x") and name.endswith(".glb"):
            column, row = (int(p[1:]) for p in name[len("snow_surface_"):-4].split("_"))
            bpy.ops.import_scene.gltf(filepath=os.path.join(tiled, name), import_shading="SMOOTH")
            obj = [o for o in bpy.context.selected_objects if o.type == "MESH"][0]
            tiles[(column, row)] = [tuple(obj.matrix_world @ v.co) for v in obj.data.vertices]
    manifest_tiled = json.load(open(os.path.join(tiled, "manifest.json")))
    size_m = 640.0  # the test's mesh_tile_size_m
    top = manifest_tiled["terrain"]["height"] * manifest_tiled["terrain"]["cell_size_y_m"]
    border_vertices, worst = tile_seams(tiles, size_m, top)
    result["tiles"] = {"count": len(tiles), "border_vertices": border_vertices, "max_gap_m": worst}

with open(os.path.join(out, "blender_check.json"), "w") as f:
    json.dump(result, f, indent=2)
print("blender_check:", json.dumps(result))
