# Keys an animation by hand in Blender (headless: blender -b --factory-startup --python
# tools/blender_keyed.py -- IN.glb OUT.glb) as an animator would: imports IN with Blender's own
# importer, keys two shape keys of the face on the timeline at 24 fps (jawOpen 0 -> 1 -> 0 over
# frames 1-25, eyeBlink_L 0 -> 1 -> 0 over frames 1-13, Blender's default Bezier curves) and
# turns the head bone (rest, turned at frame 13, rest again at 25), exports OUT with Blender's
# own glTF exporter as one animation, and prints one line "FACEANIM_KEYED {json}": each key's
# value at every frame as Blender evaluates it, and the head bone's turn from rest at every
# frame in Blender's world (Z up) as a quaternion [w, x, y, z]. Nothing here is faceanim's code.
import json
import os
import sys

import bpy
from mathutils import Euler

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
armature = next(o for o in bpy.data.objects if o.type == "ARMATURE" and "Head" in o.pose.bones)
head = armature.pose.bones["Head"]
head.rotation_mode = "QUATERNION"
for frame, euler in [(1, (0.0, 0.0, 0.0)), (13, (0.35, -0.2, 0.25)), (25, (0.0, 0.0, 0.0))]:
    head.rotation_quaternion = Euler(euler).to_quaternion()
    head.keyframe_insert("rotation_quaternion", frame=frame)
curves = {"jawOpen": [], "eyeBlink_L": []}
turns = []
world = armature.matrix_world.to_quaternion()
rest = head.bone.matrix_local.to_quaternion()
for frame in range(1, 26):
    scene.frame_set(frame)
    for name, values in curves.items():
        values.append(keys[name].value)
    turn = world @ head.matrix.to_quaternion() @ rest.inverted() @ world.inverted()
    turns.append([turn.w, turn.x, turn.y, turn.z])
bpy.ops.export_scene.gltf(
    filepath=out, export_format="GLB", export_animations=True, export_nla_strips=False
)
print("FACEANIM_KEYED " + json.dumps({"fps": 24, "curves": curves, "head": turns}))
