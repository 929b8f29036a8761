# Imports a glTF/GLB into Blender (run headless: blender -b --factory-startup --python tools/blender_shape_keys.py -- FILE)
# and prints one line "FACEANIM_REPORT {json}" describing every mesh object's shape keys:
# name and largest displacement from the basis (in glTF metres; Blender's axis swap does not
# change lengths), plus vertex count, the armatures (with their bone counts) and the animation
# actions found.
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

path = script_args()[0]
open_gltf(path)

report = {"blender": bpy.app.version_string, "objects": [], "armatures": [], "actions": []}
for obj in bpy.data.objects:
    if obj.type == "ARMATURE":
        report["armatures"].append({"name": obj.name, "bones": len(obj.data.bones)})
    if obj.type != "MESH":
        continue
    mesh = obj.data
    keys = []
    if mesh.shape_keys:
        basis = mesh.shape_keys.reference_key
        for key in mesh.shape_keys.key_blocks:
            if key == basis:
                continue
            largest = 0.0
            for a, b in zip(basis.data, key.data):
                d = (b.co - a.co).length
                if d > largest:
                    largest = d
            keys.append({"name": key.name, "max_displacement": largest})
    report["objects"].append({"name": obj.name, "vertices": len(mesh.vertices), "polygons": len(mesh.polygons), "shape_keys": keys})
for action in bpy.data.actions:
    report["actions"].append({"name": action.name, "fcurves": len(action.fcurves), "frame_range": list(action.frame_range)})
print("FACEANIM_REPORT " + json.dumps(report))
