# Imports a glTF/GLB into Blender (headless: blender -b --factory-startup --python
# tools/blender_bones.py -- FILE SECONDS BONE...) with Blender's own importer, plays its
# animation to SECONDS and prints one line "FACEANIM_BONES {json}": for each BONE of the
# armature that has it, how far the animation turned it from its rest pose, in the scene's
# world space as Blender holds it (Z up), as a quaternion [w, x, y, z], with the scene's frame
# rate. SECONDS may be several times, comma-separated: then "at" holds the bones at each, in
# order ("bones" those at the first). Nothing here is faceanim's code: Blender reads and plays
# the file.
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

args = script_args()
path, times, wanted = args[0], [float(t) for t in args[1].split(",")], args[2:]
open_gltf(path)
scene = bpy.context.scene
fps = scene.render.fps / scene.render.fps_base
# Each imported action on its own object: the importer leaves the last one active.
for obj in bpy.data.objects:
    if obj.animation_data and obj.animation_data.action is None and bpy.data.actions:
        obj.animation_data.action = bpy.data.actions[0]


def turns_at(seconds):
    frame = seconds * fps
    scene.frame_set(int(frame), subframe=frame - int(frame))
    bones = {}
    for obj in bpy.data.objects:
        if obj.type != "ARMATURE":
            continue
        world = obj.matrix_world.to_quaternion()
        for name in wanted:
            pose = obj.pose.bones.get(name)
            if pose is None:
                continue
            posed = pose.matrix.to_quaternion()
            rest = pose.bone.matrix_local.to_quaternion()
            turn = world @ posed @ rest.inverted() @ world.inverted()
            bones[name] = [turn.w, turn.x, turn.y, turn.z]
    return bones


at = [turns_at(t) for t in times]
actions = [a.name for a in bpy.data.actions]
report = {"fps": fps, "bones": at[0], "at": at, "actions": actions}
print("FACEANIM_BONES " + json.dumps(report))
