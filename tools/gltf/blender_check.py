# Independent check of `hmsm export --gltf` in Blender (docs/export.md): imports the GLB headless,
# plays the clip to key frame K and compares the evaluated (skinned) mesh with the vertices that
# `hmsm simulate --dump-vertices` wrote after the same number of steps, for each K given.
#
#   blender -b --factory-startup --python tools/gltf/blender_check.py -- FILE.glb HEIGHT K:VERTICES.bin ...
#
# (tools/gltf/blender_check.sh runs it end to end.) Blender shows key frame K at its frame K when
# the scene's frame rate is the clip's --fps (24 by default in Blender). HEIGHT is the tree's height (max minus min rest y); the check passes when the largest
# difference is within 1e-5 of it. Blender's importer turns glTF's y-up into z-up:
# (x, y, z) -> (x, -z, y). Prints the error and exits 1 on a mismatch.
import struct
import sys

import numpy

numpy.bool = bool  # Blender 3.4's glTF importer still uses numpy.bool, gone from Debian's numpy
import bpy  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
glb, height = args[0], float(args[1])
checks = [(int(a.split(":", 1)[0]), a.split(":", 1)[1]) for a in args[2:]]

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
scene = bpy.context.scene
meshes = [o for o in scene.objects if o.type == "MESH"]
if len(meshes) != 1:
    sys.exit(f"blender_check: expected one mesh object, found {len(meshes)}")
obj = meshes[0]
failed = False
for frame, vertices_file in checks:
    scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    world = obj.matrix_world
    got = [world @ v.co for v in mesh.vertices]
    data = open(vertices_file, "rb").read()
    expected = struct.unpack(f"<{len(data) // 4}f", data)
    if len(expected) != 3 * len(got):
        sys.exit(f"blender_check: {len(got)} vertices in Blender, {len(expected) // 3} in {vertices_file}")
    error = 0.0
    for i, p in enumerate(got):
        x, y, z = expected[3 * i:3 * i + 3]
        error = max(error, abs(p.x - x), abs(p.y + z), abs(p.z - y))  # hmsm (x, y, z) = Blender (x, -z, y)
    evaluated.to_mesh_clear()
    ok = error <= 1e-5 * height
    failed = failed or not ok
    print(f"blender_check: frame {frame} (fps {scene.render.fps}): {len(got)} vertices, "
          f"max error {error:.3g} m = {error / height:.3g} of tree height: {'ok' if ok else 'MISMATCH'}")
sys.exit(1 if failed else 0)
