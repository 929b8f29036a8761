# Keys an animation by hand in Blender (headless: blender -b --factory-startup --python
# tools/blender_keyed.py -- IN.glb OUT.glb) as an animator would: imports IN with Blender's own
# importer, keys two shape keys of the face on the timeline at 24 fps (jawOpen 0 -> 1 -> 0 over
# frames 1-25, eyeBlink_L 0 -> 1 -> 0 over frames 1-13, Blender's default Bezier curves),
# exports OUT with Blender's own glTF exporter, and prints one line "FACEANIM_KEYED {json}":
# each key's value at every frame as Blender evaluates it. Nothing here is faceanim's code.
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

source, out = script_args()[:2]
open_gltf(source)
scene = bpy.context.scene
scene.render.fps, scene.render.fps_base = 24, 1.0
scene.frame_start, scene.frame_end = 1, 25
face = next(
    o
    for o in bpy.data.objects
    if o.type == "MESH" and o.data.shape_keys and "jawOpen" in o.data.shape_keys.key_blocks
)
keys = face.data.shape_keys.key_blocks
for name, frames in [("jawOpen", [(1, 0.0), (13, 1.0), (25, 0.0)]), ("eyeBlink_L", [(1, 0.0), (7, 1.0), (13, 0.0)])]:
    for frame, value in frames:
        keys[name].value = value
        keys[name].keyframe_insert("value", frame=frame)
curves = {"jawOpen": [], "eyeBlink_L": []}
for frame in range(1, 26):
    scene.frame_set(frame)
    for name, values in curves.items():
        values.append(keys[name].value)
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_animations=True)
print("FACEANIM_KEYED " + json.dumps({"fps": 24, "curves": curves}))
