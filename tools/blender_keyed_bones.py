# Keys a body's bones by hand in Blender (headless: blender -b --factory-startup --python
# tools/blender_keyed_bones.py -- IN.glb OUT.glb KIND) as an animator would, on a body with no
# shape keys: imports IN with Blender's own importer and keys, on the timeline at 24 fps with
# Blender's default Bezier curves,
#   KIND "jaw":  the Jaw bone opening (rest at frame 1, turned 12 degrees about its own X axis
#                at frame 13, rest again at 25): a face keyed on its bones;
#   KIND "walk": the Hips moving forward and back, the left upper leg swinging and the Head
#                turning, over the same frames: a body's own animation.
# Exports OUT with Blender's own glTF exporter (which also writes every other bone's rest as
# keys) and prints one line "FACEANIM_KEYED_BONES {json}": the frame rate and, per frame as
# Blender evaluates it, the Jaw bone's turn from rest in degrees. Nothing here is faceanim's code.
import json
import math
import os
import sys

import bpy
from mathutils import Euler

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

source, out, kind = script_args()[:3]
open_gltf(source)
scene = bpy.context.scene
scene.render.fps, scene.render.fps_base = 24, 1.0
scene.frame_start, scene.frame_end = 1, 25
armature = next(o for o in bpy.data.objects if o.type == "ARMATURE" and "Jaw" in o.pose.bones)
bones = armature.pose.bones


def key_turns(name, turns):
    bone = bones[name]
    bone.rotation_mode = "QUATERNION"
    for frame, euler in turns:
        bone.rotation_quaternion = Euler(euler).to_quaternion()
        bone.keyframe_insert("rotation_quaternion", frame=frame)


if kind == "jaw":
    key_turns("Jaw", [(1, (0, 0, 0)), (13, (math.radians(12), 0, 0)), (25, (0, 0, 0))])
elif kind == "walk":
    hips = bones["Hips"]
    for frame, y in [(1, 0.0), (13, 0.2), (25, 0.0)]:
        hips.location = (0.0, y, 0.0)
        hips.keyframe_insert("location", frame=frame)
    key_turns("LeftUpperLeg", [(1, (0, 0, 0)), (13, (0.5, 0, 0)), (25, (0, 0, 0))])
    key_turns("Head", [(1, (0, 0, 0)), (13, (0, 0.3, 0)), (25, (0, 0, 0))])
else:
    sys.exit(f"KIND must be jaw or walk, not {kind!r}")
jaw = []
for frame in range(1, 26):
    scene.frame_set(frame)
    turn = bones["Jaw"].matrix_basis.to_quaternion()
    jaw.append(math.degrees(turn.angle))
bpy.ops.export_scene.gltf(
    filepath=out, export_format="GLB", export_animations=True, export_nla_strips=False
)
print("FACEANIM_KEYED_BONES " + json.dumps({"fps": 24, "jaw": jaw}))
