#!/usr/bin/env python3
"""Writes the committed seed inputs of the fuzz targets (fuzz/seeds/<target>/): a few tiny valid
files per parser and some near misses, made here so that their provenance is plain. Run from
anywhere: `python3 fuzz/seeds/generate.py`; the output is deterministic."""

import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write(target, name, data):
    os.makedirs(os.path.join(HERE, target), exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, target, name), "wb") as f:
        f.write(data)


# --- depth_png: 16-bit grey PNGs (what the reader accepts) and an 8-bit one (rejected). -------


def png(width, height, bit_depth, colour_type, rows, interlace=0):
    def chunk(kind, body):
        crc = zlib.crc32(kind + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, interlace)
    raw = b"".join(b"\x00" + r for r in rows)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def depth_png():
    values = [[0, 500, 1235], [0, 65000, 65535]]
    rows = [b"".join(struct.pack(">H", v) for v in r) for r in values]
    write("depth_png", "grey16_3x2.png", png(3, 2, 16, 0, rows))
    write("depth_png", "grey16_1x1.png", png(1, 1, 16, 0, [b"\x03\xe8"]))
    write("depth_png", "grey8_2x2.png", png(2, 2, 8, 0, [b"\x00\x80", b"\xff\x10"]))
    write("depth_png", "rgb16_1x1.png", png(1, 1, 16, 2, [b"\x00\x01\x00\x02\x00\x03"]))


# --- intrinsics_json and rigid_transform_json. -------------------------------------------------


def json_files():
    write("intrinsics_json", "vga.json",
          '{"width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5}\n')
    write("intrinsics_json", "pretty.json",
          '{\n  "width": 1920,\n  "height": 1080,\n  "fx": 1400.5,\n  "fy": 1401,\n'
          '  "cx": 960.25,\n  "cy": 539.5\n}\n')
    write("intrinsics_json", "negative_fx.json",
          '{"width": 640, "height": 480, "fx": -1, "fy": 1, "cx": 0, "cy": 0}')
    write("rigid_transform_json", "identity.json",
          '{"rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0, 0, 0.5]}\n')
    write("rigid_transform_json", "yaw.json",
          '{"rotation": [[0.955336489125606, 0.0, 0.29552020666133955], [0.0, 1.0, 0.0], '
          '[-0.29552020666133955, 0.0, 0.955336489125606]], "translation": [0.01, -0.02, 0.5]}\n')
    write("rigid_transform_json", "reflection.json",
          '{"rotation": [[1,0,0],[0,1,0],[0,0,-1]], "translation": [0, 0, 0.5]}')


# --- obj: the first byte is the fuzz target's option flags (0 = read everything). -------------


def keypoints_json():
    descriptor = ",".join(str((7 * i) % 256) for i in range(128))
    keypoint = '{"x":1.5,"y":2.0,"size":3.2,"angle":90.0,"response":0.02,"octave":16711681}'
    write("keypoints_json", "one.json",
          '{"width":10,"height":20,"keypoints":[%s],"descriptors":[[%s]]}' % (keypoint, descriptor))
    write("keypoints_json", "empty.json",
          '{"width":0,"height":0,"keypoints":[],"descriptors":[]}')
    write("keypoints_json", "short_descriptor.json",
          '{"width":1,"height":1,"keypoints":[%s],"descriptors":[[1,2,3]]}' % keypoint)


def obj():
    quad = ("o thing\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 2 0 1\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
            "usemtl skin\nf 1/1 2/2 3/3 4/4\nf -4/-4 5/5 -3/-3\nf 1/5 2/2 5/5\n")
    write("obj", "uv_seam.obj", "\x00# quad, triangle, a UV seam\n" + quad)
    write("obj", "colours_normals.obj",
          "\x00v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nvt 0 0\nvt 1 1\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
          "vn 0 0 1\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -4//1 -3//1 -1//1\n")
    write("obj", "positions_only.obj", "\x01v 0 0 0\nv 1 0 0 1\nv 0 1 0\nvt x\nf 1/9 2/9 3/9\n")
    write("obj", "no_faces.obj", "\x03v 0 0 0\r\nv 1e-9 -2.5 3\r\nf 1 2\r\n")


# --- ply: ASCII, binary little- and big-endian. ------------------------------------------------

PLY_ALL = ("element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "property float nx\nproperty float ny\nproperty float nz\nproperty float s\n"
           "property float t\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n")


def ply():
    write("ply", "ascii.ply",
          "ply\nformat ascii 1.0\ncomment seed\n" + PLY_ALL
          + "0 0 1 0 0 -1 0 0 255 0 0\n1 0 1.5 0 0 -1 1 0 0 255 0\n"
          "0 1 2 0 0 -1 0 1 0 0 255\n3 0 1 2\n")
    body = b""
    for i, p in enumerate([(0, 0, 1), (1, 0, 1.5), (0, 1, 2)]):
        body += struct.pack("<8f", *p, 0, 0, -1, p[0], p[1]) + bytes([200, 100, i])
    body += b"\x03" + struct.pack("<3i", 0, 1, 2)
    write("ply", "binary_le.ply",
          ("ply\nformat binary_little_endian 1.0\n" + PLY_ALL).encode() + body)
    head = ("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n"
            "property double y\nproperty double z\nproperty uchar flags\nelement face 1\n"
            "property list uchar uint vertex_indices\nproperty float quality\n"
            "element extra 1\nproperty short a\nend_header\n")
    body = b""
    for i, p in enumerate([(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]):
        body += struct.pack(">3d", *p) + bytes([i])
    body += b"\x04" + struct.pack(">4I", 0, 1, 2, 3) + struct.pack(">f", 0.5)
    body += struct.pack(">h", -7)
    write("ply", "binary_be_quad.ply", head.encode() + body)
    # An element whose items take no bytes, with a huge count (used to hang the reader).
    # A second vertex element (its vertices came without the first one's normals).
    write("ply", "two_vertex_elements.ply",
          "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
          "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
          "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
          "0 0 1 0 0 -1\n1 0 1\n")
    write("ply", "binary_empty_element.ply",
          b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
          b"property float y\nproperty float z\nelement padding 99999999999999999\nend_header\n"
          + struct.pack("<3f", 1, 2, 3))


# --- pc2 ---------------------------------------------------------------------------------------


def pc2():
    def cache(points, samples, frames):
        head = b"POINTCACHE2\0" + struct.pack("<iiffi", 1, points, 5.0, 1.0, samples)
        return head + b"".join(struct.pack("<3f", *p) for f in frames for p in f)

    write("pc2", "two_frames.pc2",
          cache(2, 2, [[(1, 2, 3), (4, 5, 6)], [(0.5, 0.25, -1), (0, 0, 0)]]))
    write("pc2", "empty.pc2", cache(3, 0, []))
    write("pc2", "truncated.pc2", cache(2, 2, [[(1, 2, 3), (4, 5, 6)]]))
    # Counts whose byte size overflows a u64 (used to panic on the multiplication).
    write("pc2", "overflowing_counts.pc2",
          b"POINTCACHE2\0" + struct.pack("<5I", 0xBFF01, 0x7F000000, 0xFDC0, 0x80000000, 0x3F00002A))


# --- exif: IFD0 -> Exif IFD -> FocalLengthIn35mmFilm, either byte order. ----------------------


def exif():
    def tiff(mm, little):
        e = "<" if little else ">"
        b = (b"II" if little else b"MM") + struct.pack(e + "HI", 42, 8)
        b += struct.pack(e + "H", 1) + struct.pack(e + "HHII", 0x8769, 4, 1, 26) + struct.pack(e + "I", 0)
        b += struct.pack(e + "H", 1) + struct.pack(e + "HHIHH", 0xA405, 3, 1, mm, 0)
        return b + struct.pack(e + "I", 0)

    write("exif", "little_28mm.tiff", tiff(28, True))
    write("exif", "big_50mm.tiff", tiff(50, False))
    write("exif", "app1_35mm.exif", b"Exif\0\0" + tiff(35, False))


# --- canonical_mesh: GeometryPipelineMetadata protobuf (fields as canonical_mesh.rs reads). ----


def varint(v):
    out = b""
    while True:
        b = v & 0x7F
        v >>= 7
        if v:
            out += bytes([b | 0x80])
        else:
            return out + bytes([b])


def field(number, wire, payload):
    key = varint(number << 3 | wire)
    if wire == 2:
        return key + varint(len(payload)) + payload
    return key + payload


def canonical_mesh():
    floats = struct.pack("<10f", 0.1, 0.2, 0.3, 0.4, 0.5, -1, -2, -3, 0.25, 0.75)
    packed_idx = b"".join(varint(i) for i in (0, 1, 467, 300, 2, 1))
    mesh = field(3, 2, floats) + field(4, 2, packed_idx) + field(1, 0, varint(7))
    basis = field(1, 0, varint(4)) + field(2, 5, struct.pack("<f", 0.5))
    write("canonical_mesh", "packed.binarypb",
          field(1, 2, mesh) + field(2, 2, basis) + field(2, 2, field(1, 0, varint(6))))
    unpacked = b"".join(field(3, 5, struct.pack("<f", x)) for x in (1, 2, 3, 0.5, 0.5))
    unpacked += b"".join(field(4, 0, varint(i)) for i in (5, 6, 7))
    write("canonical_mesh", "unpacked.binarypb",
          field(1, 2, unpacked) + field(2, 2, field(1, 0, varint(467)) + field(2, 5, b"\0\0\x80?"))
          + field(9, 1, b"\0" * 8))


# --- tflite: small graphs of the operators the engine runs, as TFLite flatbuffers. ------------
# Values: ("i8", v) / ("i32", v) inline; ("table", [field or None]), ("tables", [...]),
# ("vec", count, raw bytes), ("str", s) by forward reference (children after their parent).


def fb_put(buf, v):
    def slot():
        buf.extend(b"\0\0\0\0")
        return len(buf) - 4

    def patch(at, target):
        buf[at:at + 4] = struct.pack("<I", target - at)

    start = len(buf)
    kind = v[0]
    if kind == "table":
        fields = v[1]
        n = len(fields)
        buf.extend(struct.pack("<HH", 4 + 2 * n, 4 + 4 * n))
        for i, f in enumerate(fields):
            buf.extend(struct.pack("<H", 4 + 4 * i if f is not None else 0))
        table = len(buf)
        buf.extend(struct.pack("<i", table - start))
        children = []
        for f in fields:
            if f is None:
                buf.extend(b"\0\0\0\0")
            elif f[0] == "i8":
                buf.extend(struct.pack("<bxxx", f[1]))
            elif f[0] == "i32":
                buf.extend(struct.pack("<i", f[1]))
            else:
                children.append((slot(), f))
        for at, child in children:
            patch(at, fb_put(buf, child))
        return table
    if kind == "tables":
        buf.extend(struct.pack("<I", len(v[1])))
        slots = [slot() for _ in v[1]]
        for at, child in zip(slots, v[1]):
            patch(at, fb_put(buf, child))
        return start
    if kind == "vec":
        buf.extend(struct.pack("<I", v[1]) + v[2])
        return start
    if kind == "str":
        buf.extend(struct.pack("<I", len(v[1])) + v[1].encode() + b"\0")
        return start
    raise ValueError(kind)


def ints(values):
    return ("vec", len(values), struct.pack("<%di" % len(values), *values))


def f32s(values):
    return struct.pack("<%df" % len(values), *values)


def f16s(halves):
    return struct.pack("<%dH" % len(halves), *halves)


OPS = {"ADD": 0, "CONCATENATION": 2, "CONV_2D": 3, "DEPTHWISE_CONV_2D": 4, "DEPTH_TO_SPACE": 5,
       "DEQUANTIZE": 6, "MAX_POOL_2D": 17, "RELU": 19, "RESHAPE": 22, "RESIZE_BILINEAR": 23,
       "PAD": 34, "PRELU": 54, "DENSIFY": 124}
FLOAT32, FLOAT16, INT32 = 0, 1, 2


def model(tensors, ops, inputs, outputs, buffers):
    """tensors: (name, shape, type, buffer[, sparsity]); ops: (code, inputs, outputs[, options]);
    buffers: raw bytes, buffer 0 empty."""
    codes = sorted({op[0] for op in ops}, key=lambda c: OPS[c])
    t_tables = []
    for t in tensors:
        fields = [ints(t[1]), ("i8", t[2]), ("i32", t[3]), ("str", t[0])]
        if len(t) > 4:
            fields += [None, None, t[4]]
        t_tables.append(("table", fields))
    o_tables = []
    for op in ops:
        fields = [("i32", codes.index(op[0])), ints(op[1]), ints(op[2])]
        if len(op) > 3:
            fields += [("i8", 1), ("table", op[3])]
        o_tables.append(("table", fields))
    subgraph = ("table", [("tables", t_tables), ints(inputs), ints(outputs), ("tables", o_tables),
                          ("str", "main")])
    root = ("table", [
        ("i32", 3),
        ("tables", [("table", [("i8", min(OPS[c], 127)), None, ("i32", 1), ("i32", OPS[c])])
                    for c in codes]),
        ("tables", [subgraph]),
        ("str", "visage fuzz seed"),
        ("tables", [("table", [("vec", len(b), b)] if b else []) for b in buffers]),
    ])
    buf = bytearray(b"\0\0\0\0TFL3")
    at = fb_put(buf, root)
    buf[0:4] = struct.pack("<I", at)
    return bytes(buf)


def small_model(alpha_shape=(1, 1, 2), inputs=(0,), outputs=(8,), extra=()):
    """x -> conv 1x1 (float16 kernel behind DEQUANTIZE) -> PReLU -> + x -> reshape."""
    return model(
        [("x", [1, 2, 2, 2], FLOAT32, 0), ("k16", [2, 1, 1, 2], FLOAT16, 1),
         ("k", [2, 1, 1, 2], FLOAT32, 0), ("bias", [2], FLOAT32, 2),
         ("conv", [1, 2, 2, 2], FLOAT32, 0), ("alpha", list(alpha_shape), FLOAT32, 3),
         ("prelu", [1, 2, 2, 2], FLOAT32, 0), ("sum", [1, 2, 2, 2], FLOAT32, 0),
         ("flat", [1, 8], FLOAT32, 0)] + list(extra),
        [("DEQUANTIZE", [1], [2]), ("CONV_2D", [0, 2, 3], [4], [("i8", 0), ("i32", 1), ("i32", 1)]),
         ("PRELU", [4, 5], [6]), ("ADD", [0, 6], [7], [("i8", 0)]), ("RESHAPE", [7, -1], [8])],
        list(inputs), list(outputs),
        [b"", f16s([0x3C00, 0, 0, 0xBC00]), f32s([0.5, 0.0]), f32s([0.25, 0.5])])


def tflite():
    write("tflite", "conv_prelu_add.tflite", small_model())
    # Findings: dimensions whose product overflows; a second input read as an output.
    write("tflite", "huge_shape.tflite", small_model(alpha_shape=(0x7FFFFFFF, 0x7FFFFFFF, 8)))
    write("tflite", "two_inputs.tflite",
          small_model(inputs=(0, 9), outputs=(8, 9), extra=[("second", [1, 64], FLOAT32, 0)]))
    # x -> depthwise 3x3 SAME -> ReLU -> max pool 2x2/2 -> pad -> concat with x.
    write("tflite", "depthwise_pool_pad_concat.tflite", model(
        [("x", [1, 4, 4, 2], FLOAT32, 0), ("dk", [1, 3, 3, 2], FLOAT32, 1),
         ("db", [2], FLOAT32, 2), ("dw", [1, 4, 4, 2], FLOAT32, 0),
         ("relu", [1, 4, 4, 2], FLOAT32, 0), ("pool", [1, 2, 2, 2], FLOAT32, 0),
         ("pads", [4, 2], INT32, 3), ("padded", [1, 4, 4, 2], FLOAT32, 0),
         ("cat", [1, 4, 4, 4], FLOAT32, 0)],
        [("DEPTHWISE_CONV_2D", [0, 1, 2], [3], [("i8", 0), ("i32", 1), ("i32", 1), ("i32", 1)]),
         ("RELU", [3], [4]),
         ("MAX_POOL_2D", [4], [5], [("i8", 1), ("i32", 2), ("i32", 2), ("i32", 2), ("i32", 2)]),
         ("PAD", [5, 6], [7]),
         ("CONCATENATION", [7, 0], [8], [("i32", 3), ("i8", 0)])],
        [0], [8],
        [b"", f32s([0.1 * i for i in range(18)]), f32s([0.0, 1.0]),
         struct.pack("<8i", 0, 0, 1, 1, 1, 1, 0, 0)]))
    # The full-range detector's operators: sparse float16 kernel -> DENSIFY -> DEQUANTIZE,
    # conv + fused ReLU, DEPTH_TO_SPACE, RESIZE_BILINEAR (half-pixel), conv, ADD + ReLU.
    csr = ("table", [("i8", 1), None, ("i8", 3), ("table", [("vec", 5, bytes([0, 1, 1, 2, 3]))]),
                     ("i8", 3), ("table", [("vec", 3, bytes([0, 0, 0]))])])
    dense = [("table", [("i8", 0), ("i32", n)]) for n in (4, 1, 1)]
    sparsity = ("table", [ints([0, 1, 2, 3]), None, ("tables", dense + [csr])])
    write("tflite", "sparse_depth_to_space_resize.tflite", model(
        [("x", [1, 1, 2, 1], FLOAT32, 0), ("k16s", [4, 1, 1, 1], FLOAT16, 1, sparsity),
         ("k16", [4, 1, 1, 1], FLOAT16, 0), ("k", [4, 1, 1, 1], FLOAT32, 0),
         ("bias4", [4], FLOAT32, 2), ("conv", [1, 1, 2, 4], FLOAT32, 0),
         ("d2s", [1, 2, 4, 1], FLOAT32, 0), ("size", [2], INT32, 3),
         ("resized", [1, 4, 4, 1], FLOAT32, 0), ("k2", [1, 1, 1, 1], FLOAT32, 4),
         ("bias1", [1], FLOAT32, 5), ("conv2", [1, 4, 4, 1], FLOAT32, 0),
         ("sum", [1, 4, 4, 1], FLOAT32, 0)],
        [("DENSIFY", [1], [2]), ("DEQUANTIZE", [2], [3]),
         ("CONV_2D", [0, 3, 4], [5], [("i8", 0), ("i32", 1), ("i32", 1), ("i8", 1)]),
         ("DEPTH_TO_SPACE", [5], [6], [("i32", 2)]),
         ("RESIZE_BILINEAR", [6, 7], [8], [None, None, ("i8", 0), ("i8", 1)]),
         ("CONV_2D", [8, 9, 10], [11]), ("ADD", [8, 11], [12], [("i8", 1)])],
        [0], [12],
        [b"", f16s([0x3C00, 0xBC00, 0x4000]), f32s([0.0] * 4), struct.pack("<2i", 4, 4),
         f32s([-2.0]), f32s([1.0])]))


# --- tum_list: TUM RGB-D lists (rgb.txt / depth.txt) and near misses. ---------------------

write("tum_list", "rgb.txt", "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n"
      "# timestamp filename\n1305031102.175304 rgb/1305031102.175304.png\n"
      "1305031102.211214 rgb/1305031102.211214.png\n")
write("tum_list", "unsorted_extra_columns.txt", "2.0 b.png extra\n1.0 a.png\n\n")
write("tum_list", "bad_time.txt", "nan rgb/x.png\n1e999 rgb/y.png\n")

# --- network_config: depth network descriptions and near misses. ---------------------------

write("network_config", "full.json",
      '{"input": {"width": 256, "height": 256, "layout": "nchw", "color": "rgb", '
      '"scale": 0.00392156862745098, "mean": [0.485, 0.456, 0.406], '
      '"std": [0.229, 0.224, 0.225], "resize": "stretch"}, '
      '"output": {"kind": "inverse", "scale": 1.0, "measures": "z"}, '
      '"region": "face", "face_margin": 0.5, "align": "auto"}')
write("network_config", "metric.json", '{"output": {"kind": "metric", "scale": 0.001}, "align": "scale"}')
write("network_config", "bad.json", '{"input": {"std": [0, 1, 1]}, "align": "none"}')


# --- batch_manifest: the first byte picks JSON Lines (1) or plain lines (0). ----------------

write("batch_manifest", "plain.txt", "\x00clips/a.mp4\n# a comment\n\nclips/b.mp4\tcam.json\n")
write("batch_manifest", "json_lines.jsonl",
      '\x01{"input": "a.mp4", "id": "take-1", "options": ["--fov-deg", "60"]}\n'
      '{"input": "b.mp4", "intrinsics": "cam.json"}\n')
write("batch_manifest", "same_id_twice.txt", "\x00a.mp4\nsub/../a.mkv\n")
write("batch_manifest", "bom_and_bad_entry.jsonl", '\x01\ufeff{"input": 3, "extra": true}\n')

# --- streamed_records: landmarks.json / blendshapes.json as a killed run leaves them. -------

write("streamed_records", "cut_in_a_record.json",
      '{"frames": [{"index": 0, "faces": []},{"index": 1, "faces": [{"landmarks": [[1.5, 2')
write("streamed_records", "complete.json",
      '{"fps": 30.0, "frames": [{"index": 0, "source": "a\\"}{b]", "w": [0.1]}]}\n')
write("streamed_records", "no_frames.json", '{"landmarks": [{"index": 0}]}')

# --- image: the image inputs (PNG, JPEG). ----------------------------------------------------

write("image", "rgb_2x2.png", png(2, 2, 8, 2, [b"\xff\x00\x00\x00\xff\x00", b"\x00\x00\xff\xff\xff\xff"]))
write("image", "grey_1x1.png", png(1, 1, 8, 0, [b"\x80"]))
JPEG_8X8 = bytes.fromhex("ffd8ffe000104a46494600010200000100010000fffe00104c61766335392e33372e31303000ffdb004300080a0a0b0a0b0d0d0d0d0d0d100f101010101010101010101012121215151512121210101212141415151717171515151517171919191e1e1c1c2323242b2b33ffc4004c0001010000000000000000000000000000000601010100000000000000000000000000000607100100000000000000000000000000000000110100000000000000000000000000000000ffc00011080008000803012200021100031100ffda000c03010002110311003f008b00517f7fffd9")
write("image", "red_8x8.jpg", JPEG_8X8)
write("image", "truncated.jpg", JPEG_8X8[:100])


if __name__ == "__main__":
    depth_png()
    json_files()
    keypoints_json()
    obj()
    ply()
    pc2()
    exif()
    canonical_mesh()
    tflite()
