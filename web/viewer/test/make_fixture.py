#!/usr/bin/env python3
"""Write a tiny animated glb shaped like the exporter's output (test fixture).

Usage: python3 test/make_fixture.py OUT.glb [--grid 24x20] [--targets 3] [--keys 30] [--seconds 1]
(the defaults make the tiny fixture; e.g. --grid 80x62 --targets 90 --keys 300
--seconds 10 approximates a real face sequence for timing the viewer)

A face-like half-ellipsoid grid (POSITION, NORMAL, TEXCOORD_0, uint16
indices), 3 POSITION morph targets named in mesh.extras.targetNames, one
animation (morph weights + node translation/rotation, LINEAR, 30 keys over
1 s), a material with an embedded PNG baseColorTexture, and a camera node
that the viewer is expected to ignore. Standard library only; it must pass
test/validate_gltf.mjs with 0 errors and 0 warnings.
"""
import argparse
import json
import math
import struct
import zlib

F32 = struct.Struct('<f')


def f32(x):
    """Round to float32, so accessor min/max match the stored bytes exactly."""
    return F32.unpack(F32.pack(x))[0]


# ---------------------------------------------------------------- texture
def png(width, height, pixel):
    """Minimal RGB8 PNG; pixel(u, v) -> (r, g, b) with u, v in [0, 1)."""
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for x in range(width):
            rows.extend(pixel((x + 0.5) / width, (y + 0.5) / height))

    def chunk(kind, data):
        return (struct.pack('>I', len(data)) + kind + data
                + struct.pack('>I', zlib.crc32(kind + data) & 0xFFFFFFFF))

    ihdr = struct.pack('>IIBBBBB', width, height, 8, 2, 0, 0, 0)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', ihdr)
            + chunk(b'IDAT', zlib.compress(bytes(rows), 9)) + chunk(b'IEND', b''))


def face_texel(u, v):
    """Skin tone with dark eyes and a red mouth; v = 0 is the top of the image (glTF UVs)."""
    def near(cu, cv, ru, rv):
        return ((u - cu) / ru) ** 2 + ((v - cv) / rv) ** 2 < 1.0
    if near(0.36, 0.40, 0.07, 0.04) or near(0.64, 0.40, 0.07, 0.04):
        return (40, 30, 30)
    if near(0.50, 0.70, 0.14, 0.035):
        return (170, 40, 50)
    shade = 8 if (int(u * 8) + int(v * 8)) % 2 else 0  # faint checker: texture visibly sampled
    return (224 - shade, 178 - shade, 150 - shade)


# ---------------------------------------------------------------- geometry
RX, RY, RZ = 0.075, 0.10, 0.06  # half-ellipsoid radii in metres, face towards +z


def grid(nu, nv):
    pos, nrm, uv = [], [], []
    for j in range(nv + 1):
        v = j / nv
        pitch = math.radians(70) * (1 - 2 * v)  # +70 deg (top) .. -70 deg (bottom)
        for i in range(nu + 1):
            u = i / nu
            yaw = math.radians(85) * (2 * u - 1)
            d = (math.cos(pitch) * math.sin(yaw), math.sin(pitch), math.cos(pitch) * math.cos(yaw))
            p = (RX * d[0], RY * d[1], RZ * d[2])
            n = (p[0] / RX ** 2, p[1] / RY ** 2, p[2] / RZ ** 2)
            ln = math.sqrt(sum(c * c for c in n))
            pos.append(p)
            nrm.append(tuple(c / ln for c in n))
            uv.append((u, v))
    idx = []
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            b, c, d = a + 1, a + nu + 1, a + nu + 2
            idx += [a, c, b, b, c, d]  # counter-clockwise seen from +z
    return pos, nrm, uv, idx


def targets(pos, count):
    """jawOpen, smile, browRaise (+ bumps up to `count`): smooth relative POSITION offsets."""
    jaw, smile, brow = [], [], []
    for x, y, z in pos:
        low = max(0.0, -y / RY - 0.15)  # 0 above the mouth, growing downwards
        jaw.append((0.0, -0.035 * low, 0.01 * low))
        m = math.exp(-((y + 0.04) / 0.025) ** 2)  # mouth band
        smile.append((0.25 * x * m, 0.012 * m * abs(x) / RX, 0.0))
        up = max(0.0, y / RY - 0.2)
        brow.append((0.0, 0.03 * up, 0.005 * up))
    out = {'jawOpen': jaw, 'smile': smile, 'browRaise': brow}
    for k in range(3, count):  # filler targets: a small bump at a spot on the face
        cx, cy = RX * math.sin(k * 2.4) * 0.7, RY * math.cos(k * 1.7) * 0.7
        out[f'extra{k:02d}'] = [(0.0, 0.0, 0.006 * math.exp(-((x - cx) ** 2 + (y - cy) ** 2) / 0.0004))
                                for x, y, _ in pos]
    return dict(list(out.items())[:count])


# ---------------------------------------------------------------- glb writer
class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def view(self, data, target=None):
        while len(self.bin) % 4:  # keep every bufferView 4-byte aligned
            self.bin.append(0)
        bv = {'buffer': 0, 'byteOffset': len(self.bin), 'byteLength': len(data)}
        if target:
            bv['target'] = target
        self.bin.extend(data)
        self.views.append(bv)
        return len(self.views) - 1

    def floats(self, rows, kind, target=None, minmax=True):
        rows = [tuple(f32(c) for c in (r if isinstance(r, tuple) else (r,))) for r in rows]
        data = b''.join(struct.pack('<%df' % len(r), *r) for r in rows)
        acc = {'bufferView': self.view(data, target), 'componentType': 5126,
               'count': len(rows), 'type': kind}
        if minmax:
            acc['min'] = [min(r[k] for r in rows) for k in range(len(rows[0]))]
            acc['max'] = [max(r[k] for r in rows) for k in range(len(rows[0]))]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        data = struct.pack('<%dH' % len(idx), *idx)
        self.accessors.append({'bufferView': self.view(data, 34963), 'componentType': 5123,
                               'count': len(idx), 'type': 'SCALAR'})
        return len(self.accessors) - 1


def build(nu=24, nv=20, n_targets=3, keys=30, seconds=1.0):
    b = Builder()
    pos, nrm, uv, idx = grid(nu, nv)
    assert len(pos) <= 65535, 'uint16 indices: grid too fine'
    morphs = targets(pos, n_targets)
    ARRAY = 34962

    prim = {
        'attributes': {'POSITION': b.floats(pos, 'VEC3', ARRAY),
                       'NORMAL': b.floats(nrm, 'VEC3', ARRAY, minmax=False),
                       'TEXCOORD_0': b.floats(uv, 'VEC2', ARRAY, minmax=False)},
        'indices': b.indices(idx),
        'material': 0,
        'targets': [{'POSITION': b.floats(d, 'VEC3', ARRAY)} for d in morphs.values()],
    }

    times = [seconds * k / (keys - 1) for k in range(keys)]
    weights, trans, rots = [], [], []
    for t in times:
        s = 2 * math.pi * t / seconds
        w = [0.5 - 0.5 * math.cos(s),                    # jaw opens and closes
             max(0.0, math.sin(s)),                      # smile in the first half
             max(0.0, -math.sin(s))]                     # brows in the second half
        w += [0.5 + 0.5 * math.sin(s * (1 + k % 3) + k) for k in range(3, n_targets)]
        weights += w[:n_targets]
        trans.append((0.01 * math.sin(s), 0.005 * math.sin(2 * s), 0.0))
        yaw = math.radians(20) * math.sin(s)             # head turns left/right
        rots.append((0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2)))
    t_acc = b.floats(times, 'SCALAR')
    anim = {
        'name': 'performance',
        'samplers': [
            {'input': t_acc, 'output': b.floats(weights, 'SCALAR', minmax=False), 'interpolation': 'LINEAR'},
            {'input': t_acc, 'output': b.floats(trans, 'VEC3', minmax=False), 'interpolation': 'LINEAR'},
            {'input': t_acc, 'output': b.floats(rots, 'VEC4', minmax=False), 'interpolation': 'LINEAR'},
        ],
        'channels': [
            {'sampler': 0, 'target': {'node': 0, 'path': 'weights'}},
            {'sampler': 1, 'target': {'node': 0, 'path': 'translation'}},
            {'sampler': 2, 'target': {'node': 0, 'path': 'rotation'}},
        ],
    }

    image_view = b.view(png(64, 64, face_texel))
    gltf = {
        'asset': {'version': '2.0', 'generator': 'visage web/viewer test fixture'},
        'scene': 0,
        'scenes': [{'nodes': [0, 1]}],
        'nodes': [
            {'name': 'face', 'mesh': 0},
            {'name': 'camera', 'camera': 0, 'translation': [0.0, 0.0, 0.6]},
        ],
        'cameras': [{'type': 'perspective',
                     'perspective': {'yfov': 0.5, 'aspectRatio': 4 / 3, 'znear': 0.01, 'zfar': 10.0}}],
        'meshes': [{'name': 'face', 'primitives': [prim], 'weights': [0.0] * len(morphs),
                    'extras': {'targetNames': list(morphs)}}],
        'materials': [{'name': 'skin', 'pbrMetallicRoughness': {
            'baseColorTexture': {'index': 0}, 'metallicFactor': 0.0, 'roughnessFactor': 0.8}}],
        'textures': [{'sampler': 0, 'source': 0}],
        'samplers': [{'magFilter': 9729, 'minFilter': 9987, 'wrapS': 33071, 'wrapT': 33071}],
        'images': [{'bufferView': image_view, 'mimeType': 'image/png'}],
        'animations': [anim],
        'accessors': b.accessors,
        'bufferViews': b.views,
        'buffers': [{'byteLength': len(b.bin)}],
    }

    js = json.dumps(gltf, separators=(',', ':')).encode()
    js += b' ' * (-len(js) % 4)               # JSON chunk padded with spaces
    bin_ = bytes(b.bin) + b'\0' * (-len(b.bin) % 4)
    total = 12 + 8 + len(js) + 8 + len(bin_)
    return (struct.pack('<III', 0x46546C67, 2, total)
            + struct.pack('<II', len(js), 0x4E4F534A) + js
            + struct.pack('<II', len(bin_), 0x004E4942) + bin_)


def main():
    ap = argparse.ArgumentParser(description='Write an animated test glb.')
    ap.add_argument('out')
    ap.add_argument('--grid', default='24x20', help='cells across x down (default 24x20)')
    ap.add_argument('--targets', type=int, default=3, help='morph targets, >= 1 (default 3)')
    ap.add_argument('--keys', type=int, default=30, help='keyframes, >= 2 (default 30)')
    ap.add_argument('--seconds', type=float, default=1.0, help='clip length (default 1)')
    a = ap.parse_args()
    nu, nv = (int(x) for x in a.grid.lower().split('x'))
    if a.targets < 1 or a.keys < 2 or a.seconds <= 0:
        ap.error('need --targets >= 1, --keys >= 2, --seconds > 0')
    data = build(nu, nv, a.targets, a.keys, a.seconds)
    with open(a.out, 'wb') as f:
        f.write(data)
    print(f'{a.out}: {len(data)} bytes')


if __name__ == '__main__':
    main()
