# Writes a glTF's meshes as one OBJ file with Blender's own OBJ exporter, shape keys dropped: a
# head as a scanner or sculpting tool hands it over (no blendshapes, no materials).
#
#   blender -b --factory-startup --python tools/blender_to_obj.py -- IN.glb OUT.obj
import sys

import bpy
import numpy

# Blender 3.4's glTF importer still uses `numpy.bool` (see blender_avatar.py).
if not hasattr(numpy, "bool"):
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1 :]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=args[0])
for obj in bpy.data.objects:
    if obj.type == "MESH" and obj.data.shape_keys:
        obj.shape_key_clear()
bpy.ops.export_scene.obj(filepath=args[1], use_materials=False)
print("FACEANIM_OBJ", args[1])
