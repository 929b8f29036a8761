# What the Blender scripts here share: their arguments after `--`, and a glTF opened in an
# empty scene by Blender's own importer. Imported by blender_avatar.py, blender_bare.py,
# blender_shape_keys.py and blender_stills.py (beside them on sys.path).
import sys

import bpy
import numpy

# Debian bookworm pairs Blender 3.4 with NumPy 1.24, which removed the `numpy.bool` alias that
# Blender 3.4's glTF importer still uses; restore it so the stock importer runs unchanged.
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def script_args():
    """The arguments after Blender's own, which end at `--`."""
    return sys.argv[sys.argv.index("--") + 1 :]


def open_gltf(path):
    """An empty scene with `path` imported by Blender's glTF importer."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
