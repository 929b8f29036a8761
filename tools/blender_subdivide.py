# Subdivides every mesh of a glTF once (Catmull-Clark, applied) and writes it with Blender's own
# exporter: a denser head for timing `faceanim generate-shapes` (about 4× the vertices).
#
#   blender -b --factory-startup --python tools/blender_subdivide.py -- IN.glb OUT.glb
import sys

import bpy
import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1 :]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=args[0])
for obj in bpy.data.objects:
    if obj.type == "MESH" and not obj.data.shape_keys:
        bpy.context.view_layer.objects.active = obj
        modifier = obj.modifiers.new("subdivide", "SUBSURF")
        modifier.levels = 1
        bpy.ops.object.modifier_apply(modifier=modifier.name)
bpy.ops.export_scene.gltf(filepath=args[1], export_format="GLB", export_skins=True)
