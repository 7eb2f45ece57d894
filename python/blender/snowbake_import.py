# A Blender add-on (3.4 and later): File > Import > snowbake bake (manifest.json). It builds the
# scene a bake describes (docs/blender.md): the snow surface mesh (or, without one, the terrain
# grid raised to the snow surface by surface.exr), a snow material whose snow/rock mix is the
# bake's coverage mask, every 0-1 mask as a Non-Color image texture in that material, the normal
# map on the surface, the VDB as a volume with a density material, and frames as image sequences
# on the timeline (frame N = season day N).
# Install: copy this file into Blender's add-ons folder, or Edit > Preferences > Add-ons > Install.
bl_info = {
    "name": "snowbake bake import",
    "author": "snowbake",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > snowbake bake (manifest.json)",
    "description": "Import a snowbake bake: snow surface, snow material with its masks, VDB volume, frames",
    "category": "Import-Export",
}

import json
import os
import re

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ImportHelper

MESH_EXTENSIONS = (".glb", ".obj", ".ply")
SNOW_COLOUR = (0.92, 0.95, 1.0, 1.0)
ROCK_COLOUR = (0.08, 0.07, 0.06, 1.0)


def _files(manifest):
    return {f["path"]: f for f in manifest["files"]}


def _load_image(folder, path, non_color=True):
    image = bpy.data.images.load(os.path.join(folder, path), check_existing=True)
    if non_color:
        image.colorspace_settings.name = "Non-Color"
    return image


def _import_mesh(path):
    """One mesh file through Blender's own importers; the new mesh objects."""
    before = set(bpy.data.objects)
    if path.endswith(".glb"):
        # SMOOTH: the default normals path of Blender 3.4's glTF importer uses np.bool (gone in numpy 1.24).
        bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    elif path.endswith(".obj"):
        bpy.ops.wm.obj_import(filepath=path, up_axis="Z", forward_axis="Y")
    else:
        bpy.ops.import_mesh.ply(filepath=path)
    return [o for o in bpy.data.objects if o not in before and o.type == "MESH"]


def _surface_from_exr(folder, files, manifest):
    """Without a mesh: the terrain grid at the snow surface's height (surface.exr), UVs on the maps."""
    image = _load_image(folder, "surface.exr")
    w, h = image.size
    pixels = list(image.pixels)  # bottom row first, RGBA
    t = manifest["terrain"]
    dx, dy = t["width"] * t["cell_size_x_m"] / w, t["height"] * t["cell_size_y_m"] / h
    verts = [((x + 0.5) * dx, (y + 0.5) * dy, pixels[(y * w + x) * 4]) for y in range(h) for x in range(w)]
    faces = [(y * w + x, y * w + x + 1, (y + 1) * w + x + 1, (y + 1) * w + x) for y in range(h - 1) for x in range(w - 1)]
    mesh = bpy.data.meshes.new("snow_surface")
    mesh.from_pydata(verts, [], faces)
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        x, y = loop.vertex_index % w, loop.vertex_index // w
        uv.data[loop.index].uv = ((x + 0.5) / w, (y + 0.5) / h)
    obj = bpy.data.objects.new("snow_surface", mesh)
    bpy.context.collection.objects.link(obj)
    return [obj]


def _frame_sequence(folder, files, stem):
    """frames/STEM.DDDD.exr as one image sequence: (image, first day, last day), or None."""
    days = sorted(int(m.group(1)) for p in files if (m := re.fullmatch(r"frames/" + re.escape(stem) + r"\.(\d{4})\.exr", p)))
    if not days:
        return None
    image = _load_image(folder, "frames/%s.%04d.exr" % (stem, days[0]))
    image.source = "SEQUENCE"
    return image, days[0], days[-1]


def _new_node_material(name):
    """A material with only an output node (what use_nodes starts with differs between versions and contexts)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    return mat, nodes.new("ShaderNodeOutputMaterial")


def snow_material(folder, files, manifest):
    """Principled BSDF mixing rock and snow by the coverage mask; every 0-1 mask as a Non-Color texture; the normal map."""
    mat, output = _new_node_material("snowbake_snow")
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    bsdf.inputs["Roughness"].default_value = 0.6
    uv = nodes.new("ShaderNodeUVMap")
    mix = nodes.new("ShaderNodeMixRGB")
    mix.name = "snow_mix"
    mix.inputs["Color1"].default_value = ROCK_COLOUR
    mix.inputs["Color2"].default_value = SNOW_COLOUR
    links.new(mix.outputs["Color"], bsdf.inputs["Base Color"])
    masks = [p for p, f in files.items() if "/" not in p and p.endswith(".exr") and f.get("unit") == "1"]
    wired = None
    for name in ("snow_coverage.exr", "weight_snow.exr"):
        if name in masks:
            wired = name
            break
    if wired is None and "depth.exr" in files:
        wired = "depth.exr"  # no mask: coverage from the depth (0 m bare, 1 m and more covered)
    for path in sorted(set(masks) | ({wired} if wired else set())):
        tex = nodes.new("ShaderNodeTexImage")
        tex.name = tex.label = os.path.splitext(path)[0]
        tex.image = _load_image(folder, path)
        tex.interpolation = "Linear"
        links.new(uv.outputs["UV"], tex.inputs["Vector"])
        if path == wired:
            sequence = _frame_sequence(folder, files, tex.name)
            if sequence:  # the frames drive the material on the timeline; the season's end after the last
                tex.image, first, last = sequence
                tex.image_user.frame_duration = last - first + 1
                tex.image_user.frame_start = first
                tex.image_user.frame_offset = first - 1
                tex.image_user.use_auto_refresh = True
            clamp = nodes.new("ShaderNodeClamp")
            links.new(tex.outputs["Color"], clamp.inputs["Value"])
            links.new(clamp.outputs["Result"], mix.inputs["Fac"])
    if "snow_normal.png" in files:
        tex = nodes.new("ShaderNodeTexImage")
        tex.name = tex.label = "snow_normal"
        tex.image = _load_image(folder, "snow_normal.png")
        links.new(uv.outputs["UV"], tex.inputs["Vector"])
        normal = nodes.new("ShaderNodeNormalMap")
        normal.space = "TANGENT"
        links.new(tex.outputs["Color"], normal.inputs["Color"])
        links.new(normal.outputs["Normal"], bsdf.inputs["Normal"])
    return mat


def volume_material():
    mat, output = _new_node_material("snowbake_snow_volume")
    vol = mat.node_tree.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density Attribute"].default_value = "density"
    vol.inputs["Color"].default_value = SNOW_COLOUR
    mat.node_tree.links.new(vol.outputs["Volume"], output.inputs["Volume"])
    return mat


def import_bake(manifest_path):
    """Builds the bake's objects in the current scene; returns them by role."""
    folder = os.path.dirname(os.path.abspath(manifest_path))
    manifest = json.load(open(manifest_path))
    files = _files(manifest)
    made = {"surface": [], "surface_files": {}, "volume": None, "frames": None}
    meshes = sorted(p for p in files if "/" not in p and p.startswith("snow_surface") and p.endswith(MESH_EXTENSIONS))
    # One format of the surface (a tile set is several files of it).
    for ext in MESH_EXTENSIONS:
        chosen = [p for p in meshes if p.endswith(ext)]
        if chosen:
            for p in chosen:
                made["surface_files"][p] = _import_mesh(os.path.join(folder, p))
                made["surface"] += made["surface_files"][p]
            break
    if not made["surface"] and "surface.exr" in files:
        made["surface"] = _surface_from_exr(folder, files, manifest)
    if made["surface"]:
        mat = snow_material(folder, files, manifest)
        for obj in made["surface"]:
            obj.data.materials.clear()
            obj.data.materials.append(mat)
        made["material"] = mat
    if "snow.vdb" in files:
        before = set(bpy.data.objects)
        bpy.ops.object.volume_import(filepath=os.path.join(folder, "snow.vdb"))
        made["volume"] = next(o for o in bpy.data.objects if o not in before)
        made["volume"].data.materials.append(volume_material())
    for stem in ("depth", "snow_coverage", "preview"):
        sequence = _frame_sequence(folder, files, stem)
        if sequence:
            made["frames"] = sequence
            bpy.context.scene.frame_start, bpy.context.scene.frame_end = sequence[1], sequence[2]
            break
    return made


class ImportSnowbake(bpy.types.Operator, ImportHelper):
    """Import a snowbake bake from its manifest.json"""
    bl_idname = "import_scene.snowbake"
    bl_label = "Import snowbake bake"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".json"
    filter_glob: StringProperty(default="manifest.json;*.json", options={"HIDDEN"})

    def execute(self, context):
        try:
            import_bake(self.filepath)
        except (OSError, KeyError, ValueError) as e:
            self.report({"ERROR"}, "snowbake: %s: %s" % (self.filepath, e))
            return {"CANCELLED"}
        return {"FINISHED"}


def _menu(self, context):
    self.layout.operator(ImportSnowbake.bl_idname, text="snowbake bake (manifest.json)")


def register():
    bpy.utils.register_class(ImportSnowbake)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    bpy.utils.unregister_class(ImportSnowbake)
