"""Writes a copy of a GLB whose morph targets are named shape_1, shape_2, … in the order they
come (mesh.extras.targetNames), so that their names say nothing: the material the retarget
benchmark makes its map on. Usage: python3 rename_targets.py IN.glb OUT.glb"""
import json
import struct
import sys

data = open(sys.argv[1], "rb").read()
magic, version, _ = struct.unpack_from("<4sII", data, 0)
assert magic == b"glTF" and version == 2, "not a GLB 2.0 file"
length, kind = struct.unpack_from("<I4s", data, 12)
assert kind == b"JSON"
gltf = json.loads(data[20 : 20 + length])
rest = data[20 + length :]
count = 0
for mesh in gltf.get("meshes", []):
    names = (mesh.get("extras") or {}).get("targetNames")
    if names:
        mesh["extras"]["targetNames"] = [f"shape_{count + k + 1}" for k in range(len(names))]
        count += len(names)
text = json.dumps(gltf, separators=(",", ":")).encode()
text += b" " * (-len(text) % 4)
out = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + len(rest))
out += struct.pack("<I4s", len(text), b"JSON") + text + rest
open(sys.argv[2], "wb").write(out)
print(f"{count} targets renamed", file=sys.stderr)
