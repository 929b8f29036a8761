# Builds a full-body avatar the way VRoid Studio, Character Creator, MakeHuman/MPFB, Mixamo and
# Blender users' files are built, and writes it with Blender's own glTF exporter:
#
#   blender -b --factory-startup --python tools/blender_avatar.py -- HEAD.glb OUT.glb
#
# - the head is HEAD.glb (an ICT-FaceKit head) imported by Blender's glTF importer, split into
#   one material per part (its vertex colours tell skin, lips, brows, eyes, teeth, gums apart),
#   so that the exporter writes one primitive per material, each with its own POSITION, NORMAL,
#   TEXCOORD_0, JOINTS_0 and WEIGHTS_0 accessors and every morph target;
# - its 53 shape keys plus VRoid-style ones made from mixes of them (Fcl_BRW_*, Fcl_EYE_*,
#   Fcl_MTH_* with the vowels A I U E O, Fcl_ALL_* emotions, Fcl_HA_* teeth-only keys, and a few
#   keys that move nothing), over 100 in all;
# - a body of several materials and a hair mesh without shape keys;
# - the brows' material cut out by alpha (alphaMode MASK, cutoff 0.4);
# - two armatures (so the file has several skins): the body's, with spine, neck and head bones
#   and, below the head, eye bones at the eyes' centres (the eyeballs weighted to them) and a
#   jaw bone at the jaw's hinge (as Ready Player Me's and Character Creator's skeletons have
#   them), in centimetres under an object scaled by 0.01 as Mixamo's and Character Creator's
#   are, and the hair's own;
# - materials using clearcoat, specular and emission strength, so that KHR_materials_* extensions
#   are written, and one image texture.
#
# Nothing here is faceanim's code: Blender writes every byte of the file.
import os
import sys

import bmesh
import bpy
import numpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_gltf import open_gltf, script_args  # noqa: E402

args = script_args()
head_path, out_path = args[0], args[1]
# "bare": the same avatar exported without any shape keys, as a scan, a sculpt or an avatar
# whose face was never rigged comes.
bare = args[2:] == ["bare"]
# "remeshed": the face rebuilt by Blender's Decimate modifier (another topology, about a third
# of the vertices), its VRoid-style keys carried over by a Surface Deform modifier bound to the
# original head, and ARKit's own keys left out: a rig made by other software whose shapes are
# not ARKit's and whose vertices are nobody's template.
remeshed = args[2:] == ["remeshed"]
# "jaw-skinned": the chin skinned to the jaw bone, whose turn opens the mouth, and the head's
# jawOpen key made a corrective that only shapes the lips around that turn (a tenth of its
# motion), as Character Creator's jaw opens by its bone with a morph beside it.
jaw_skinned = args[2:] == ["jaw-skinned"]
# "jaw-and-vowels": the chin skinned to the jaw bone while the VRoid-style vowels open it on
# their own, and ARKit's own keys left out (an avatar whose mouth opens by its vowel keys, its
# jaw bone weighted as well).
jaw_and_vowels = args[2:] == ["jaw-and-vowels"]
# "eyes-on-head": the eyeballs skinned to the head, the eye bones left carrying nothing (a rig
# whose eyes move by their shape keys alone, its eye bones kept for other tools).
eyes_on_head = args[2:] == ["eyes-on-head"]

open_gltf(head_path)
face = next(o for o in bpy.data.objects if o.type == "MESH")
face.name = "Face"
face.data.name = "Face"

CM = 100.0  # the body armature works in centimetres, as Mixamo's and CC's do


def material(name, color, **principled):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    for key, value in principled.items():
        bsdf.inputs[key].default_value = value
    return m


# --- the face: one material per part, from the vertex colours --------------------------------
mesh = face.data
attribute = mesh.color_attributes[0] if len(mesh.color_attributes) else None
palette = {}
loop_colors = None
if attribute is not None:
    values = numpy.zeros(len(attribute.data) * 4, dtype=numpy.float32)
    attribute.data.foreach_get("color", values)
    values = values.reshape(-1, 4)
    per_loop = attribute.domain == "CORNER"
    loop_colors = values
part_of_face = []
for poly in mesh.polygons:
    if loop_colors is None:
        key = (0, 0, 0)
    elif attribute.domain == "CORNER":
        key = tuple(numpy.round(loop_colors[poly.loop_start][:3], 2))
    else:
        key = tuple(numpy.round(loop_colors[mesh.loops[poly.loop_start].vertex_index][:3], 2))
    part_of_face.append(palette.setdefault(key, len(palette)))
mesh.materials.clear()
part_names = ["Skin", "Lips", "Brows", "Eyes", "Teeth", "Gums", "Inner", "Other"]
for key, index in sorted(palette.items(), key=lambda kv: kv[1]):
    name = "Face_" + (part_names[index] if index < len(part_names) else f"Part{index}")
    extra = {}
    if index == 1:
        extra = {"Clearcoat": 0.6, "Clearcoat Roughness": 0.2}
    if index == 3:
        extra = {"Specular": 0.9, "Specular Tint": 0.3}
    m = material(name, key, **extra)
    if index == 2:
        # Brows cut out by their alpha, as VRoid's and most anime avatars' are (glTF MASK).
        m.blend_method = "CLIP"
        m.alpha_threshold = 0.4
    mesh.materials.append(m)
mesh.polygons.foreach_set("material_index", part_of_face)

# --- VRoid-style shape keys, mixed from the head's own ------------------------------------------
keys = mesh.shape_keys.key_blocks
own = [k.name for k in keys if k != mesh.shape_keys.reference_key]


def mix(name, weights):
    for k in keys:
        k.value = 0.0
    for key_name, w in weights.items():
        if key_name in keys:
            keys[key_name].value = w
    face.shape_key_add(name=name, from_mix=True)
    for k in keys:
        k.value = 0.0


both = lambda stem, w=1.0: {f"{stem}_L": w, f"{stem}_R": w}  # noqa: E731
vroid = {
    "Fcl_ALL_Angry": {**both("browDown"), **both("mouthFrown", 0.6), **both("eyeSquint", 0.5)},
    "Fcl_ALL_Fun": {**both("mouthSmile", 0.7), **both("cheekSquint", 0.5)},
    "Fcl_ALL_Joy": {**both("mouthSmile"), **both("eyeBlink", 0.7)},
    "Fcl_ALL_Sorrow": {**both("browInnerUp"), **both("mouthFrown")},
    "Fcl_ALL_Surprised": {**both("browInnerUp"), **both("browOuterUp"), "jawOpen": 0.5},
    "Fcl_BRW_Angry": both("browDown"),
    "Fcl_BRW_Fun": both("browOuterUp", 0.5),
    "Fcl_BRW_Joy": both("browOuterUp", 0.7),
    "Fcl_BRW_Sorrow": both("browInnerUp"),
    "Fcl_BRW_Surprised": {**both("browInnerUp"), **both("browOuterUp")},
    "Fcl_EYE_Natural": {},
    "Fcl_EYE_Angry": both("eyeSquint"),
    "Fcl_EYE_Close": both("eyeBlink"),
    "Fcl_EYE_Close_R": {"eyeBlink_R": 1.0},
    "Fcl_EYE_Close_L": {"eyeBlink_L": 1.0},
    "Fcl_EYE_Fun": {**both("eyeSquint", 0.6), **both("cheekSquint", 0.6)},
    "Fcl_EYE_Joy": both("eyeBlink", 0.8),
    "Fcl_EYE_Joy_R": {"eyeBlink_R": 0.8},
    "Fcl_EYE_Joy_L": {"eyeBlink_L": 0.8},
    "Fcl_EYE_Sorrow": both("eyeSquint", 0.4),
    "Fcl_EYE_Surprised": both("eyeWide"),
    "Fcl_EYE_Spread": both("eyeWide", 0.5),
    "Fcl_EYE_Iris_Hide": {},
    "Fcl_EYE_Highlight_Hide": {},
    "Fcl_MTH_Close": {"mouthClose": 1.0, "jawOpen": 0.3},
    "Fcl_MTH_Up": both("mouthUpperUp"),
    "Fcl_MTH_Down": both("mouthLowerDown"),
    "Fcl_MTH_Angry": both("mouthFrown"),
    "Fcl_MTH_Small": {"mouthPucker": 0.6},
    "Fcl_MTH_Large": {**both("mouthStretch"), "jawOpen": 0.4},
    "Fcl_MTH_Neutral": {},
    "Fcl_MTH_Fun": both("mouthSmile", 0.6),
    "Fcl_MTH_Joy": both("mouthSmile"),
    "Fcl_MTH_Sorrow": both("mouthFrown", 0.8),
    "Fcl_MTH_Surprised": {"jawOpen": 0.6, "mouthFunnel": 0.5},
    "Fcl_MTH_SkinFung": {"mouthRollUpper": 0.3},
    "Fcl_MTH_SkinFung_R": {"mouthPress_R": 0.5},
    "Fcl_MTH_SkinFung_L": {"mouthPress_L": 0.5},
    "Fcl_MTH_A": {"jawOpen": 0.8},
    "Fcl_MTH_I": {**both("mouthStretch"), "jawOpen": 0.1},
    "Fcl_MTH_U": {"mouthPucker": 1.0, "jawOpen": 0.1},
    "Fcl_MTH_E": {**both("mouthStretch", 0.6), "jawOpen": 0.35},
    "Fcl_MTH_O": {"mouthFunnel": 1.0, "jawOpen": 0.4},
}
# --- the chin on the jaw bone, jawOpen its corrective ------------------------------------------
# (Before the mixes below, so that every key made from jawOpen is a corrective too.)
chin_vertices = set()
if jaw_skinned or jaw_and_vowels:
    basis = mesh.shape_keys.reference_key
    jaw_key = keys["jawOpen"]
    moved = [(jaw_key.data[v].co - basis.data[v].co).length for v in range(len(mesh.vertices))]
    largest = max(moved)
    chin_vertices = {v for v, d in enumerate(moved) if d > 0.5 * largest}
if jaw_skinned:
    for v in range(len(mesh.vertices)):
        jaw_key.data[v].co = basis.data[v].co + 0.1 * (jaw_key.data[v].co - basis.data[v].co)

for name, weights in vroid.items():
    mix(name, weights)

# Teeth-only keys (zero on every other primitive), as VRoid's Fcl_HA_* are.
teeth_part = 4 if len(palette) > 4 else len(palette) - 1
teeth_vertices = set()
for poly, part in zip(mesh.polygons, part_of_face):
    if part == teeth_part:
        teeth_vertices.update(poly.vertices)
basis = mesh.shape_keys.reference_key
for name, offset in [("Fcl_HA_Hide", (0, 0.0, -0.01)), ("Fcl_HA_Fung1", (0, -0.002, 0)),
                     ("Fcl_HA_Fung2", (0, 0.002, 0)), ("Fcl_HA_Short", (0, 0, 0.002))]:
    key = face.shape_key_add(name=name, from_mix=False)
    for v in teeth_vertices:
        key.data[v].co = basis.data[v].co + Vector(offset)

# Custom keys up to a realistic count: left/right corrective pairs as artists add them.
for i in range(4):
    mix(f"Custom_Smile_{i}_L", {"mouthSmile_L": 0.25 * (i + 1), "cheekSquint_L": 0.1 * i})
    mix(f"Custom_Smile_{i}_R", {"mouthSmile_R": 0.25 * (i + 1), "cheekSquint_R": 0.1 * i})

# The jaw-and-vowels variant keeps only the keys mixed above, as a VRoid avatar has.
if jaw_and_vowels:
    for name in own:
        face.shape_key_remove(keys[name])

# --- another topology: the face decimated, its VRoid keys carried over ------------------------
if remeshed:
    kept_keys = [k.name for k in keys if k != mesh.shape_keys.reference_key and k.name not in own]
    bpy.ops.object.select_all(action="DESELECT")
    face.select_set(True)
    bpy.context.view_layer.objects.active = face
    bpy.ops.object.duplicate()
    new = bpy.context.active_object
    new.shape_key_clear()
    decimate = new.modifiers.new("Decimate", "DECIMATE")
    decimate.ratio = 0.35
    bpy.ops.object.modifier_apply(modifier=decimate.name)
    deform = new.modifiers.new("Carry", "SURFACE_DEFORM")
    deform.target = face
    bpy.ops.object.surfacedeform_bind(modifier=deform.name)
    for k in keys:
        k.value = 0.0
    new.shape_key_add(name="Basis", from_mix=False)
    for name in kept_keys:
        keys[name].value = 1.0
        bpy.context.view_layer.update()
        bpy.ops.object.modifier_apply_as_shapekey(keep_modifier=True, modifier=deform.name)
        new.data.shape_keys.key_blocks[-1].name = name
        keys[name].value = 0.0
    new.modifiers.remove(deform)
    bpy.data.objects.remove(face)
    face = new
    face.name = "Face"
    mesh = face.data
    mesh.name = "Face"

# --- place the head in centimetres at head height -----------------------------------------------
bpy.ops.object.select_all(action="DESELECT")
face.select_set(True)
bpy.context.view_layer.objects.active = face
face.scale = (CM, CM, CM)
bpy.ops.object.transform_apply(location=False, rotation=True, scale=True)
zs = [v.co.z for v in mesh.vertices]
head_bottom = min(zs)
head_top = max(zs)
neck_height = 145.0
face.location.z = neck_height - head_bottom
bpy.ops.object.transform_apply(location=True, rotation=False, scale=False)
head_top = neck_height + (head_top - head_bottom)

# --- the body: rings from the feet to the neck, one material per band ---------------------------
bm = bmesh.new()
rings, segments = 40, 24
profile = []
for r in range(rings + 1):
    z = neck_height * r / rings
    if z < 85:
        radius = 9 + 3 * z / 85  # legs (one column, as a long skirt)
    elif z < 100:
        radius = 16
    elif z < 130:
        radius = 16 - 2 * (z - 100) / 30
    else:
        radius = 14 - 9 * (z - 130) / 15
    profile.append((z, radius))
verts = []
for z, radius in profile:
    ring = []
    for s in range(segments):
        a = 2 * numpy.pi * s / segments
        ring.append(bm.verts.new((radius * numpy.cos(a), radius * 0.7 * numpy.sin(a), z)))
    verts.append(ring)
band_materials = ["Body_Shoes", "Body_Pants", "Body_Belt", "Body_Shirt", "Body_Skin"]
bands = [0, 4, 34, 36, 37, 40]
for r in range(rings):
    band = next(i for i in range(len(bands) - 1) if bands[i] <= r < bands[i + 1])
    for s in range(segments):
        f = bm.faces.new((verts[r][s], verts[r][(s + 1) % segments], verts[r + 1][(s + 1) % segments], verts[r + 1][s]))
        f.material_index = band
body_mesh = bpy.data.meshes.new("Body")
bm.to_mesh(body_mesh)
bm.free()
body_mesh.uv_layers.new(name="UVMap")
body = bpy.data.objects.new("Body", body_mesh)
bpy.context.scene.collection.objects.link(body)
image = bpy.data.images.new("BodyPattern", 16, 16)
pixels = []
for y in range(16):
    for x in range(16):
        on = (x // 4 + y // 4) % 2
        pixels += [0.2 + 0.6 * on, 0.3, 0.8 - 0.5 * on, 1.0]
image.pixels = pixels
image.pack()
for i, name in enumerate(band_materials):
    colour = [(0.1, 0.1, 0.1), (0.2, 0.2, 0.5), (0.4, 0.25, 0.1), (0.8, 0.8, 0.9), (0.9, 0.7, 0.6)][i]
    extra = {"Emission Strength": 2.0, "Emission": (0.1, 0.1, 0.0, 1.0)} if name == "Body_Belt" else {}
    m = material(name, colour, **extra)
    if name == "Body_Shirt":
        tex = m.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = image
        m.node_tree.links.new(tex.outputs["Color"], m.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    body_mesh.materials.append(m)

# --- hair: a cap over the top and back of the head, two materials, no shape keys ---------------
xs = [v.co.x for v in mesh.vertices if v.co.z > head_top - 12]
ys = [v.co.y for v in mesh.vertices if v.co.z > head_top - 12]
centre = Vector(((max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2, head_top - 9))
radius = 0.55 * (max(xs) - min(xs))
bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12, radius=1.0)
hair = bpy.context.active_object
hair.name = "Hair"
hair.data.name = "Hair"
hair.scale = (radius, radius * 1.1, radius * 0.9)
hair.location = centre + Vector((0, 2.5, 1.5))  # Blender's +Y is the back of the head
bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
# Open at the face and the neck: keep what lies above the brows or behind the ears.
bm = bmesh.new()
bm.from_mesh(hair.data)
brow = centre.z + 1.0
gone = [v for v in bm.verts if v.co.z < brow and v.co.y < centre.y + 4.0 or v.co.z < centre.z - 10]
bmesh.ops.delete(bm, geom=gone, context="VERTS")
bm.to_mesh(hair.data)
bm.free()
hair.data.materials.append(material("Hair_Base", (0.25, 0.12, 0.05)))
hair.data.materials.append(material("Hair_Highlight", (0.5, 0.3, 0.1), **{"Sheen": 0.5}))
middle = sum(v.co.z for v in hair.data.vertices) / len(hair.data.vertices)
for poly in hair.data.polygons:
    poly.material_index = 0 if poly.center.z < middle + 3 else 1


# --- armatures ----------------------------------------------------------------------------------
def armature(name, bones):
    data = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    made = {}
    for bone_name, head, tail, parent in bones:
        b = data.edit_bones.new(bone_name)
        b.head, b.tail = head, tail
        if parent:
            b.parent = made[parent]
        made[bone_name] = b
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


# The eyes' centres (the eye material's vertices, each side) and the jaw's hinge (behind the
# eyes, below them: where the ear meets the cheek).
eye_material = [i for i, m in enumerate(mesh.materials) if m.name == "Face_Eyes"]
eye_points = [
    mesh.vertices[v].co.copy()
    for poly in mesh.polygons
    if poly.material_index in eye_material
    for v in poly.vertices
]


def centre(points):
    return sum(points, Vector()) / len(points)


left_points = [p for p in eye_points if p.x > 0]
right_points = [p for p in eye_points if p.x < 0]
if left_points and right_points:
    left_eye, right_eye = centre(left_points), centre(right_points)
else:
    left_eye = Vector((3.2, -8.0, head_top - 11.0))
    right_eye = Vector((-3.2, -8.0, head_top - 11.0))
middle_eye = (left_eye + right_eye) / 2
hinge = Vector((0.0, middle_eye.y + 8.0, middle_eye.z - 6.0))
chin = Vector((0.0, middle_eye.y - 2.0, middle_eye.z - 13.0))
look = Vector((0.0, -2.0, 0.0))

body_rig = armature(
    "Armature",
    [
        ("Hips", (0, 0, 90), (0, 0, 100), None),
        ("Spine", (0, 0, 100), (0, 0, 115), "Hips"),
        ("Chest", (0, 0, 115), (0, 0, 130), "Spine"),
        ("Neck", (0, 0, 130), (0, 0, neck_height + 5), "Chest"),
        ("Head", (0, 0, neck_height + 5), (0, 0, head_top), "Neck"),
        ("LeftEye", tuple(left_eye), tuple(left_eye + look), "Head"),
        ("RightEye", tuple(right_eye), tuple(right_eye + look), "Head"),
        ("Jaw", tuple(hinge), tuple(chin), "Head"),
        ("LeftUpperLeg", (8, 0, 90), (8, 0, 45), "Hips"),
        ("RightUpperLeg", (-8, 0, 90), (-8, 0, 45), "Hips"),
    ],
)
hair_rig = armature(
    "HairRig",
    [
        ("HairRoot", (0, 0, head_top - 10), (0, 0, head_top), None),
        ("HairFront", (0, -8, head_top - 5), (0, -12, head_top - 15), "HairRoot"),
        ("HairBack", (0, 8, head_top - 5), (0, 12, head_top - 20), "HairRoot"),
    ],
)


def skin(obj, rig, weights_of):
    for name in {n for v in obj.data.vertices for n, _ in weights_of(v)}:
        obj.vertex_groups.new(name=name)
    for v in obj.data.vertices:
        for name, w in weights_of(v):
            obj.vertex_groups[name].add([v.index], w, "REPLACE")
    modifier = obj.modifiers.new("Armature", "ARMATURE")
    modifier.object = rig
    obj.parent = rig


def body_weights(v):
    co = v.co
    z = co.z
    if z < 90:
        return [("LeftUpperLeg" if co.x >= 0 else "RightUpperLeg", 1.0)]
    for lo, hi, a, b in [(90, 110, "Hips", "Spine"), (110, 125, "Spine", "Chest"), (125, 140, "Chest", "Neck")]:
        if z < hi:
            t = (z - lo) / (hi - lo)
            return [(a, 1 - t), (b, t)]
    return [("Neck", 1.0)]


# The eyeballs turn with their bones (as VRoid's and Character Creator's do).
eye_vertices = {v for poly in mesh.polygons if poly.material_index in eye_material for v in poly.vertices}


def face_weights(v):
    co = v.co
    if v.index in eye_vertices and not eyes_on_head:
        return [("LeftEye" if co.x > 0 else "RightEye", 1.0)]
    if v.index in chin_vertices:
        return [("Jaw", 1.0)]
    if co.z < neck_height + 3:
        t = max(0.0, (co.z - neck_height + 5) / 8)
        return [("Neck", 1 - t), ("Head", t)] if t > 0 else [("Neck", 1.0)]
    return [("Head", 1.0)]


def hair_weights(v):
    co = v.co
    if co.y < -2:
        return [("HairFront", 0.7), ("HairRoot", 0.3)]
    if co.y > 2:
        return [("HairBack", 0.7), ("HairRoot", 0.3)]
    return [("HairRoot", 1.0)]


skin(body, body_rig, body_weights)
skin(face, body_rig, face_weights)
skin(hair, hair_rig, hair_weights)

# The body rig in centimetres under an object scaled to metres (Mixamo, Character Creator).
for rig in (body_rig, hair_rig):
    rig.scale = (1 / CM, 1 / CM, 1 / CM)

if bare:
    for obj in bpy.data.objects:
        if obj.type == "MESH" and obj.data.shape_keys:
            obj.shape_key_clear()

bpy.ops.export_scene.gltf(
    filepath=out_path,
    export_format="GLB",
    export_skins=True,
    export_morph=True,
    export_morph_normal=False,
    export_colors=False,
    export_animations=False,
    export_materials="EXPORT",
)
print("FACEANIM_AVATAR", out_path)
