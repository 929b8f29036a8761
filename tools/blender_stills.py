# Held-out stills of a character by a renderer faceanim's adapter never trains or tunes on:
# Blender's Cycles path tracer (CPU, headless), with an orthographic camera, one sun light and
# flat (faceted) shading — another lens, another light and another shading model than the
# adapter's training renders and than three.js. The adapter is measured on them with
# `faceanim adapt --eval-dir OUT`.
#
# Run: blender -b --factory-startup --python tools/blender_stills.py -- MODEL.glb POSES.json OUTDIR
# POSES.json: {"frames": [{"image": "0000.png", "weights": {"name": 0.5, ...}}, ...],
#              "neutral": "neutral.png" (optional),
#              "view": {"yaw": deg, "pitch": deg, "size": px, "samples": n, "sun": [az, el] deg,
#                       "background": [r, g, b]} (optional)}
# Writes OUTDIR/<image> for every frame (and the neutral), and OUTDIR/truth.json (the poses).
# Weights name the glTF's morph targets (Blender's shape keys); a name no mesh has is an error.
import json
import math
import os
import sys

import bpy
from mathutils import Euler, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402


def fail(message):
    print(f"blender_stills: {message}", file=sys.stderr)
    sys.exit(1)


args = script_args()
if len(args) != 3:
    fail("usage: blender -b --python blender_stills.py -- MODEL.glb POSES.json OUTDIR")
model, poses_path, out = args
with open(poses_path, encoding="utf-8") as f:
    poses = json.load(f)
view = {"yaw": -10.0, "pitch": 4.0, "size": 384, "samples": 12, "sun": [35.0, 30.0],
        "background": [0.32, 0.3, 0.27]}
view.update(poses.get("view", {}))
os.makedirs(out, exist_ok=True)

open_gltf(model)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
if not meshes:
    fail(f"{model}: no mesh")

# Flat shading: every face its own normal.
for obj in meshes:
    for polygon in obj.data.polygons:
        polygon.use_smooth = False

keys = {}
for obj in meshes:
    if obj.data.shape_keys:
        for block in obj.data.shape_keys.key_blocks[1:]:
            keys.setdefault(block.name, []).append(block)
for frame in poses["frames"]:
    for name in frame["weights"]:
        if name not in keys:
            fail(f"{poses_path}: {frame['image']}: no shape key named '{name}' in {model}")

# The head's box in Blender's world (Z up, -Y forward after the importer's axis change).
bpy.context.view_layer.update()
corners = [obj.matrix_world @ Vector(c) for obj in meshes for c in obj.bound_box]
low = Vector([min(c[i] for c in corners) for i in range(3)])
high = Vector([max(c[i] for c in corners) for i in range(3)])
centre = (low + high) / 2
extent = high - low

scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = int(view["samples"])
scene.cycles.use_denoising = False
scene.cycles.max_bounces = 2
scene.render.resolution_x = scene.render.resolution_y = int(view["size"])
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.render.image_settings.color_mode = "RGB"
scene.view_settings.view_transform = "Standard"

world = bpy.data.worlds.new("backdrop")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (*view["background"], 1.0)
world.node_tree.nodes["Background"].inputs[1].default_value = 0.35
scene.world = world

# One sun, from the front at the given azimuth (to the model's left of the camera) and elevation.
az, el = (math.radians(a) for a in view["sun"])
sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = 3.5
sun_data.angle = math.radians(2.0)
sun = bpy.data.objects.new("sun", sun_data)
# A sun shines along its local -Z: turn it to point from (direction) towards the face.
direction = Vector((math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)))
sun.rotation_euler = direction.to_track_quat("Z", "Y").to_euler()
scene.collection.objects.link(sun)

# The orthographic camera, in front of the face (-Y), turned by yaw and pitch about the head.
camera_data = bpy.data.cameras.new("camera")
camera_data.type = "ORTHO"
camera_data.ortho_scale = 1.25 * max(extent.x, extent.z)
camera_data.clip_end = 100 * extent.length
camera = bpy.data.objects.new("camera", camera_data)
yaw, pitch = math.radians(view["yaw"]), math.radians(view["pitch"])
distance = 3 * extent.length
offset = Vector((math.sin(yaw) * math.cos(pitch), -math.cos(yaw) * math.cos(pitch), math.sin(pitch)))
target = centre + Vector((0, 0, 0.08 * extent.z))
camera.location = target + distance * offset
camera.rotation_euler = (-offset).to_track_quat("-Z", "Y").to_euler()
scene.collection.objects.link(camera)
scene.camera = camera


def render(weights, image):
    for blocks in keys.values():
        for block in blocks:
            block.value = 0.0
    for name, w in weights.items():
        for block in keys[name]:
            block.value = float(w)
    scene.render.filepath = os.path.join(out, image)
    bpy.ops.render.render(write_still=True)


if poses.get("neutral"):
    render({}, poses["neutral"])
for frame in poses["frames"]:
    render(frame["weights"], frame["image"])

truth = {"frames": poses["frames"]}
if poses.get("neutral"):
    truth["neutral"] = poses["neutral"]
with open(os.path.join(out, "truth.json"), "w", encoding="utf-8") as f:
    json.dump(truth, f)
print(f"FACEANIM_STILLS {len(poses['frames'])} in {out}")
