# Writes a glTF's meshes again with Blender's own exporters and without shape keys: a head as a
# scanner or sculpting tool hands it over. OUT ending in .obj: one OBJ, no materials; else a GLB
# with its skins (and its animations, as Blender keys them). With `subdivide`, every mesh is
# subdivided once (Catmull-Clark, applied): a denser head, about four times the vertices, for
# timing `faceanim generate-shapes`.
#
#   blender -b --factory-startup --python tools/blender_bare.py -- IN.glb OUT.{obj,glb} [subdivide]
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

args = script_args()
source, out = args[0], args[1]
subdivide = args[2:] == ["subdivide"]
open_gltf(source)
for obj in bpy.data.objects:
    if obj.type != "MESH":
        continue
    if obj.data.shape_keys:
        obj.shape_key_clear()
    if subdivide:
        bpy.context.view_layer.objects.active = obj
        modifier = obj.modifiers.new("subdivide", "SUBSURF")
        modifier.levels = 1
        bpy.ops.object.modifier_apply(modifier=modifier.name)
if out.lower().endswith(".obj"):
    bpy.ops.export_scene.obj(filepath=out, use_materials=False)
else:
    bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_skins=True)
print("FACEANIM_BARE", json.dumps({"out": out}))
