"""Writes scenes/gltf-room.gltf and its buffer scenes/assets/gltf-room.bin: a glTF 2.0 scene
that `pathwave render scenes/gltf-room.gltf` reads whole (see the README's "glTF input").

A floor and a back wall (one mesh, two nodes: instances), a box with a smaller box on top
(one mesh; the top box a child node, placed by its parent's transform and its own), a gold
ball (metallic), a glass-grey pane of alpha 0.4 (alpha mode BLEND), an emissive panel
(KHR_materials_emissive_strength) under the ceiling, a point light and a spot light
(KHR_lights_punctual, in candela), and a perspective camera. Deterministic.
Run: python3 scenes/gltf-room.py
"""
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

buf = bytearray()
views, accessors = [], []


def add(data, component, kind, count, extra=None):
    """A buffer view and an accessor over `data`; the accessor's index."""
    while len(buf) % 4:
        buf.append(0)
    views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data)})
    buf.extend(data)
    a = {"bufferView": len(views) - 1, "componentType": component, "count": count, "type": kind}
    a.update(extra or {})
    accessors.append(a)
    return len(accessors) - 1


def mesh(name, pos, nrm, uv, idx, material):
    p = add(struct.pack("<%df" % (3 * len(pos)), *sum(pos, [])), 5126, "VEC3", len(pos),
            {"min": [min(v[k] for v in pos) for k in range(3)], "max": [max(v[k] for v in pos) for k in range(3)]})
    n = add(struct.pack("<%df" % (3 * len(nrm)), *sum(nrm, [])), 5126, "VEC3", len(nrm))
    t = add(struct.pack("<%df" % (2 * len(uv)), *sum(uv, [])), 5126, "VEC2", len(uv))
    i = add(struct.pack("<%dH" % len(idx), *idx), 5123, "SCALAR", len(idx))
    return {"name": name, "primitives": [{"attributes": {"POSITION": p, "NORMAL": n, "TEXCOORD_0": t},
                                          "indices": i, "material": material}]}


def quad(half):
    """A square in the xz plane facing +y."""
    pos = [[-half, 0, -half], [-half, 0, half], [half, 0, half], [half, 0, -half]]
    return pos, [[0, 1, 0]] * 4, [[0, 0], [0, 1], [1, 1], [1, 0]], [0, 1, 2, 0, 2, 3]


def cube():
    pos, nrm, uv, idx = [], [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            u, v = [0, 0, 0], [0, 0, 0]
            u[(axis + 1) % 3], v[(axis + 2) % 3] = 1, 1
            if sign < 0:
                u, v = v, u
            base = len(pos)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                pos.append([0.5 * (n[k] + a * u[k] + b * v[k]) for k in range(3)])
                nrm.append(n)
                uv.append([(a + 1) / 2, (1 - b) / 2])
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv, idx


def sphere(rings, segments):
    pos, nrm, uv, idx = [], [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segments + 1):
            ph = 2 * math.pi * j / segments
            n = [math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph)]
            pos.append(n)
            nrm.append(n)
            uv.append([j / segments, i / rings])
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            idx += [a, b, b + 1, a, b + 1, a + 1]
    return pos, nrm, uv, idx


def rot(axis, degrees):
    s, c = math.sin(math.radians(degrees) / 2), math.cos(math.radians(degrees) / 2)
    q = [0.0, 0.0, 0.0, c]
    q["xyz".index(axis)] = s
    return q


def look(frm, to):
    """The rotation taking -z to the direction from `frm` to `to`."""
    d = [b - a for a, b in zip(frm, to)]
    n = math.sqrt(sum(x * x for x in d))
    d = [x / n for x in d]
    q = [d[1], -d[0], 0.0, 1 - d[2]]  # (-z) x d, 1 + (-z) . d
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


materials = [
    {"name": "Floor", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.58, 1], "metallicFactor": 0,
                                               "roughnessFactor": 0.8}},
    {"name": "Red paint", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.08, 0.05, 1], "metallicFactor": 0,
                                                   "roughnessFactor": 0.35}},
    {"name": "Gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.766, 0.336, 1], "metallicFactor": 1,
                                              "roughnessFactor": 0.25}},
    {"name": "Pane", "alphaMode": "BLEND", "doubleSided": True,
     "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.5, 0.8, 0.4], "metallicFactor": 0, "roughnessFactor": 0.1}},
    {"name": "Panel", "emissiveFactor": [1.0, 0.85, 0.6],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6}},
     "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.1, 1], "metallicFactor": 0}},
]
meshes = [
    mesh("Floor", *quad(4), 0),
    mesh("Box", *cube(), 1),
    mesh("Ball", *sphere(32, 64), 2),
    mesh("Pane", *quad(0.6), 3),
    mesh("Panel", *quad(0.5), 4),
]
nodes = [
    {"name": "Floor", "mesh": 0},
    {"name": "Back wall", "mesh": 0, "translation": [0, 3, -3], "rotation": rot("x", 90)},
    {"name": "Box", "mesh": 1, "translation": [-1.3, 0.5, -0.4], "rotation": rot("y", 30), "children": [3]},
    {"name": "Box on top", "mesh": 1, "translation": [0, 0.8, 0], "rotation": rot("y", 20), "scale": [0.6, 0.6, 0.6]},
    {"name": "Ball", "mesh": 2, "matrix": [0.7, 0, 0, 0, 0, 0.7, 0, 0, 0, 0, 0.7, 0, 1.2, 0.7, 0.2, 1]},
    {"name": "Pane", "mesh": 3, "translation": [0.1, 0.6, 1.2], "rotation": rot("x", 90)},
    {"name": "Panel", "mesh": 4, "translation": [0, 2.9, -1.6], "rotation": rot("x", 180)},
    {"name": "Lamp", "translation": [2.5, 2.5, 2.5], "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"name": "Spot", "translation": [-2, 3.5, 2], "rotation": look([-2, 3.5, 2], [1.2, 0.7, 0.2]),
     "extensions": {"KHR_lights_punctual": {"light": 1}}},
    {"name": "Camera", "translation": [0, 1.8, 6], "rotation": rot("x", -10), "camera": 0},
]
doc = {
    "asset": {"version": "2.0", "generator": "scenes/gltf-room.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
    "scene": 0,
    "scenes": [{"name": "Room", "nodes": [0, 1, 2, 4, 5, 6, 7, 8, 9]}],
    "nodes": nodes,
    "meshes": meshes,
    "materials": materials,
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.75, "aspectRatio": 1.5, "znear": 0.05}}],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "Lamp", "type": "point", "color": [1.0, 0.95, 0.9], "intensity": 3000},
        {"name": "Spot", "type": "spot", "intensity": 6000, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.35}},
    ]}},
    "buffers": [{"uri": "assets/gltf-room.bin", "byteLength": len(buf)}],
    "bufferViews": views,
    "accessors": accessors,
}
with open(os.path.join(HERE, "assets", "gltf-room.bin"), "wb") as f:
    f.write(buf)
with open(os.path.join(HERE, "gltf-room.gltf"), "w") as f:
    json.dump(doc, f, indent=1)
    f.write("\n")
