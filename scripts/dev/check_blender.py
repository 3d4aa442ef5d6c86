# Dev-only: checks that Blender reads a `visage run --ply --glb` output folder as intended.
# Usage: blender -b --factory-startup --python scripts/dev/check_blender.py -- OUT_DIR
#    or, with Blender as a Python module (`pip install bpy==4.5.*` on Python 3.11):
#        python scripts/dev/check_blender.py -- OUT_DIR
# OBJ import + vertex order, Mesh Cache (PC2) playback and sequence.glb against OUT_DIR/meshes/*.ply.
import json
import math
import os
import struct
import sys

import bpy
from mathutils import Vector

OUT = sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else sys.exit("usage: ... -- OUT_DIR")
PLY_TYPES = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h", "ushort": "H",
             "int16": "h", "uint16": "H", "int": "i", "uint": "I", "int32": "i", "uint32": "I",
             "float": "f", "float32": "f", "double": "d", "float64": "d"}


def read_ply(path):
    """The x, y, z of a binary PLY's `vertex` element (which must come first)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode("ascii").splitlines()
    fmt = next(l.split()[1] for l in lines if l.startswith("format"))
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
    count, props, in_vertex = 0, [], False
    for l in lines:
        w = l.split()
        if w[0] == "element":
            if in_vertex:
                break
            in_vertex = w[1] == "vertex"
            assert in_vertex, f"{path}: vertex is not the first element"
            count = int(w[2])
        elif w[0] == "property" and in_vertex:
            props.append((w[-1], PLY_TYPES[w[1]]))
    row = struct.Struct(order + "".join(t for _, t in props))
    ix = [next(i for i, (n, _) in enumerate(props) if n == a) for a in "xyz"]
    return [tuple(r[i] for i in ix) for r in row.iter_unpack(data[end:end + row.size * count])]


def cam_to_blender(points):
    return [(x, z, -y) for x, y, z in points]


def max_err(a, b):
    assert len(a) == len(b), f"{len(a)} vs {len(b)} vertices"
    return max(math.dist(p, q) for p, q in zip(a, b))


def evaluated_world(obj):
    """World-space vertex positions after modifiers, shape keys and animation."""
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    me = ev.to_mesh()
    pts = [tuple(ev.matrix_world @ v.co) for v in me.vertices]
    ev.to_mesh_clear()
    return pts


def frames_of(n):
    return sorted({0, 1, 5, n // 2, 2 * n // 3, n - 1} & set(range(n)))


plys = {}


def ply(k):
    """meshes/{k:06d}.ply in Blender's axes."""
    if k not in plys:
        plys[k] = cam_to_blender(read_ply(os.path.join(OUT, "meshes", f"{k:06d}.ply")))
    return plys[k]


print(f"\n=== Blender {bpy.app.version_string}, output {OUT}")
n_ply = len([f for f in os.listdir(os.path.join(OUT, "meshes")) if f.endswith(".ply")])
with open(os.path.join(OUT, "metrics.json")) as f:  # video time of each frame (the glb's clock)
    times = [fr["time_s"] for fr in json.load(f)["frames"]]

# 1. OBJ import with default settings (forward -Z, up Y) and vertex order.
with open(os.path.join(OUT, "sequence.pc2"), "rb") as f:
    _magic, _version, pc2_points, pc2_start, pc2_rate, pc2_samples = struct.unpack("<12siiffi", f.read(32))
print(f"PC2: {pc2_points} points, {pc2_samples} samples, start {pc2_start}, sampling {pc2_rate}; {n_ply} PLYs")
obj_path = os.path.join(OUT, "mesh.obj")
if bpy.app.version >= (3, 3, 0):
    importer = "bpy.ops.wm.obj_import"
    bpy.ops.wm.obj_import(filepath=obj_path)
else:
    importer = "bpy.ops.import_scene.obj"
    bpy.ops.import_scene.obj(filepath=obj_path)
obj = bpy.context.selected_objects[0]
with open(obj_path) as f:
    obj_v = [tuple(map(float, l.split()[1:4])) for l in f if l.startswith("v ")]
imported = [tuple(obj.matrix_world @ v.co) for v in obj.data.vertices]
print(f"[obj] {importer}: {len(imported)} vertices (PC2 {pc2_points}) -> "
      f"{'OK' if len(imported) == pc2_points else 'MISMATCH'}")
print(f"[obj] max |imported - OBJ v (x,-z,y)| = {max_err(imported, [(x, -z, y) for x, y, z in obj_v]):.3e} m "
      f"(vertex order), vs PLY 0 = {max_err(imported, ply(0)):.3e} m")
mat = obj.active_material
images = [n.image for n in mat.node_tree.nodes if n.type == "TEX_IMAGE"] if mat and mat.use_nodes else []
print(f"[obj] material {mat.name if mat else None}: image nodes "
      f"{[(i.name, tuple(i.size)) for i in images if i]} -> {'OK' if any(i and i.size[0] for i in images) else 'NO TEXTURE'}")

# 2. Mesh Cache modifier: defaults except format and file.
mod = obj.modifiers.new("cache", "MESH_CACHE")
mod.cache_format, mod.filepath = "PC2", os.path.join(OUT, "sequence.pc2")
print(f"[pc2] modifier: time_mode {mod.time_mode}, play_mode {mod.play_mode}, frame_start {mod.frame_start}, "
      f"frame_scale {mod.frame_scale}, axes {mod.forward_axis}/{mod.up_axis}, interpolation {mod.interpolation}")
scene = bpy.context.scene
print(f"[pc2] scene: fps {scene.render.fps}/{scene.render.fps_base}, frames {scene.frame_start}..{scene.frame_end}")
print(f"[pc2] object rotation from the OBJ importer (mesh data keeps the OBJ's own axes): "
      f"{tuple(round(math.degrees(a), 1) for a in obj.rotation_euler)} deg")
for f in frames_of(min(n_ply, pc2_samples)):
    scene.frame_set(f)
    print(f"[pc2] scene frame {f:3d} (sample {f - mod.frame_start:g}): world max err vs PLY {f:06d} = "
          f"{max_err(evaluated_world(obj), ply(f)):.3e} m")

# 3. glTF import (default options) into an empty scene.
try:  # Debian's Blender 3.4 glTF add-on still uses np.bool, which NumPy 1.24 removed.
    import warnings
    import numpy
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        numpy.bool = getattr(numpy, "bool", bool)
except ImportError:
    print("[glb] no numpy: Blender's glTF importer needs it (apt-get install python3-numpy)")
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
bpy.ops.import_scene.gltf(filepath=os.path.join(OUT, "sequence.glb"))
face = next(o for o in scene.objects if o.type == "MESH")
keys = face.data.shape_keys.key_blocks if face.data.shape_keys else []
names = [k.name for k in keys]
print(f"[glb] objects {[(o.name, o.type) for o in scene.objects]}; {len(face.data.vertices)} vertices")
cam = next((o for o in scene.objects if o.type == "CAMERA"), None)
if cam:
    rot = cam.matrix_world.to_3x3()
    rnd = lambda v: tuple(round(c, 3) for c in v)
    print(f"[glb] camera at {rnd(cam.matrix_world.translation)} looks along {rnd(rot @ Vector((0, 0, -1)))}, "
          f"up {rnd(rot @ Vector((0, 1, 0)))} (camera z, -y in Blender: (0, 1, 0), (0, 0, 1))")
print(f"[glb] {len(keys)} shape keys (incl. basis): {names[:6]}{' ...' if len(names) > 6 else ''}")


def animation(owner):
    """The action animating `owner` and its F-curves: since Blender 4.4 one action holds a slot
    per animated owner (the glTF importer puts the object and its shape keys in one), each
    with its own curves."""
    ad = owner.animation_data if owner else None
    act = ad.action if ad else None
    if act is None:
        return None, []
    if getattr(ad, "action_slot", None) is not None:
        from bpy_extras import anim_utils
        bag = anim_utils.action_get_channelbag_for_slot(act, ad.action_slot)
        return act, list(bag.fcurves) if bag else []
    return act, list(act.fcurves)


obj_act, obj_curves = animation(face)
key_act, key_curves = animation(face.data.shape_keys)
for label, act, curves in (("object", obj_act, obj_curves), ("shape keys", key_act, key_curves)):
    paths = sorted({fc.data_path for fc in curves})
    k = [kp.co[0] for kp in curves[0].keyframe_points] if curves else []
    print(f"[glb] {label} action: {act.name if act else None}, {len(curves)} curves, paths {paths[:4]}, "
          f"keys at frames {[round(x, 3) for x in k[:3]]} .. {round(k[-1], 3) if k else None}")
print(f"[glb] scene after import: fps {scene.render.fps}/{scene.render.fps_base}, "
      f"frames {scene.frame_start}..{scene.frame_end} (importer places time t at frame t * render.fps)")
weights = {fc.data_path.split('"')[1]: [kp.co[1] for kp in fc.keyframe_points] for fc in key_curves}
for kb in list(keys)[1:4]:
    w = weights.get(kb.name, [0])
    print(f"[glb] {kb.name}: slider {kb.slider_min:.3f}..{kb.slider_max:.3f}, animated {min(w):.3f}..{max(w):.3f}")


def compare_glb(label):
    for k in frames_of(n_ply):
        t = times[k] if k < len(times) else k / 30.0
        fr = t * scene.render.fps
        scene.frame_set(int(math.floor(fr)), subframe=fr - math.floor(fr))
        print(f"[glb] {label}: video frame {k:3d} (t={t:.4f} s) -> scene frame {fr:6.3f}: "
              f"max err vs PLY = {max_err(evaluated_world(face), ply(k)):.3e} m")


compare_glb("as imported")
for kb in list(keys)[1:]:  # shape-key values are clamped to the slider range
    kb.slider_min, kb.slider_max = -10.0, 10.0
compare_glb("sliders -10..10")
print("=== done\n")
