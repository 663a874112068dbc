"""Writes the three glTF scenes that pathwave is compared on beside Blender Cycles
(scenes/cycles/{sampler,interior,shot}.glb; benches/cycles.py renders them with both):

  sampler   a material sampler: a row of metals and a row of dielectrics over roughness
            0.1 .. 0.9, a normal-mapped sphere (a generated bump pattern), a clear-coated one and
            a glass one (KHR_materials_transmission, KHR_materials_ior), on a floor before a
            wall, lit by a sun and an emissive panel (KHR_materials_emissive_strength)
  interior  a closed room lit by a lamp (a point light) and an emissive panel on a wall, with a
            table, a cabinet and a ball
  shot      an animated shot, frames 0..24 at 24 fps: the camera dollies and pans (translation
            and rotation channels), a box slides, turns and grows (translation, rotation and
            scale channels); lit by a sun and a spot light

Built with Blender's Python module and written by its glTF exporter, so the materials are
the exporter's reading of Principled BSDFs. No random numbers, but the exporter does not write
the same bytes twice (the sampler's buffer layout and the meshes' bytes vary from run to run):
the committed files are the ones benches/results/beside-cycles.md measured.
Run: /opt/vdbvenv/bin/python scenes/cycles/make.py   (bpy 5.0.1)
"""
import math
import os

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 24
    scene.frame_start, scene.frame_end, scene.frame_current = 0, 24, 0
    return scene


def material(name, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=0.5, **extra):
    """A Principled BSDF material; `extra` sets other inputs by name ('Coat Weight', ...)."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    p = m.node_tree.nodes['Principled BSDF']
    p.inputs['Base Color'].default_value = (*base, 1.0)
    p.inputs['Metallic'].default_value = metallic
    p.inputs['Roughness'].default_value = roughness
    for k, v in extra.items():
        p.inputs[k].default_value = v
    return m


def emitter(name, rgb, strength):
    """A black Principled BSDF that emits rgb * strength (KHR_materials_emissive_strength)."""
    return material(name, base=(0.0, 0.0, 0.0), roughness=1.0,
                    **{'Emission Color': (*rgb, 1.0), 'Emission Strength': strength})


def link(ob, mat):
    ob.data.materials.append(mat)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def box(name, size, at, mat, rot_z=0.0):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=at, rotation=(0, 0, rot_z))
    ob = bpy.context.object
    ob.name = name
    ob.scale = size
    ob.data.materials.append(mat)
    return ob


def ball(name, r, at, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=r, location=at)
    ob = bpy.context.object
    ob.name = name
    bpy.ops.object.shade_smooth()
    ob.data.materials.append(mat)
    return ob


def plane(name, size, at, mat, rot=(0, 0, 0)):
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=at, rotation=rot)
    ob = bpy.context.object
    ob.name = name
    ob.scale = (*size, 1.0)
    ob.data.materials.append(mat)
    return ob


def camera(at, rot_deg, yfov_deg, aspect=4 / 3):
    cam = bpy.data.cameras.new('camera')
    cam.sensor_fit = 'VERTICAL'
    cam.angle_y = math.radians(yfov_deg)
    cam.clip_start, cam.clip_end = 0.05, 100.0
    ob = bpy.data.objects.new('camera', cam)
    ob.location = at
    ob.rotation_euler = [math.radians(a) for a in rot_deg]
    bpy.context.scene.collection.objects.link(ob)
    scene = bpy.context.scene
    scene.camera = ob
    scene.render.resolution_x, scene.render.resolution_y = round(240 * aspect), 240
    return ob


def light(kind, name, energy, at, rot_deg=(0, 0, 0), rgb=(1, 1, 1), **extra):
    li = bpy.data.lights.new(name, kind)
    li.energy = energy
    li.color = rgb
    for k, v in extra.items():
        setattr(li, k, v)
    ob = bpy.data.objects.new(name, li)
    ob.location = at
    ob.rotation_euler = [math.radians(a) for a in rot_deg]
    bpy.context.scene.collection.objects.link(ob)
    return ob


def normal_map(name, n=128, bumps=6, depth=0.6):
    """A tangent-space normal map (linear, 'Non-Color') of a grid of `bumps` x `bumps` round
    bumps: the normals of a height field, encoded as 0.5 + 0.5 n."""
    u = (np.arange(n) + 0.5) / n
    x, y = np.meshgrid(u, u)
    # The slopes of h = depth cos^2(pi b x) cos^2(pi b y) / (2 pi b) per unit of uv.
    dx = -depth * 2 * math.pi * bumps * np.cos(math.pi * bumps * x) * np.sin(math.pi * bumps * x) \
        * np.cos(math.pi * bumps * y) ** 2 / (2 * math.pi * bumps)
    dy = -depth * 2 * math.pi * bumps * np.cos(math.pi * bumps * y) * np.sin(math.pi * bumps * y) \
        * np.cos(math.pi * bumps * x) ** 2 / (2 * math.pi * bumps)
    nz = 1.0 / np.sqrt(1 + dx * dx + dy * dy)
    rgba = np.stack([0.5 + 0.5 * dx * nz, 0.5 + 0.5 * dy * nz, 0.5 + 0.5 * nz, np.ones_like(nz)], -1)
    img = bpy.data.images.new(name, n, n, alpha=False)
    img.colorspace_settings.name = 'Non-Color'
    img.pixels.foreach_set(rgba.astype(np.float32).ravel())
    img.file_format = 'PNG'
    img.pack()
    return img


def with_normal_map(mat, img):
    nt = mat.node_tree
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    nm = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(tex.outputs['Color'], nm.inputs['Color'])
    nt.links.new(nm.outputs['Normal'], nt.nodes['Principled BSDF'].inputs['Normal'])
    return mat


def sampler():
    reset()
    floor = material('floor', (0.5, 0.5, 0.5), roughness=0.8)
    plane('floor', (16, 18), (0, -4, 0), floor)
    plane('wall', (14, 6), (0, 5, 3), floor, rot=(math.radians(90), 0, 0))
    rough = [0.1, 0.3, 0.5, 0.7, 0.9]
    for i, r in enumerate(rough):
        x = 2.4 * (i - 2)
        ball('metal%d' % i, 0.9, (x, 3.6, 0.9), material('metal %.1f' % r, (0.95, 0.72, 0.35), 1.0, r))
        ball('plastic%d' % i, 0.9, (x, 1.0, 0.9), material('plastic %.1f' % r, (0.7, 0.08, 0.06), 0.0, r))
    ball('bumpy', 0.9, (-3.6, -1.6, 0.9),
         with_normal_map(material('bumpy', (0.15, 0.35, 0.7), roughness=0.35), normal_map('bumps')))
    ball('coated', 0.9, (0.0, -1.6, 0.9), material('coated', (0.1, 0.45, 0.12), roughness=0.6,
                                                   **{'Coat Weight': 1.0, 'Coat Roughness': 0.05}))
    ball('glass', 0.9, (3.6, -1.6, 0.9), material('glass', (1.0, 1.0, 1.0), roughness=0.0,
                                                  **{'Transmission Weight': 1.0, 'IOR': 1.5}))
    plane('panel', (6, 2), (0, -1.0, 6.5), emitter('panel', (1.0, 0.95, 0.85), 6.0),
          rot=(math.radians(180), 0, 0))
    light('SUN', 'sun', 2.5, (0, 0, 10), rot_deg=(40, 0, 30))
    camera((0, -10.5, 7.0), (58, 0, 0), 40)
    return 'sampler'


def interior():
    reset()
    wall = material('wall', (0.7, 0.68, 0.62), roughness=0.9)
    accent = material('accent', (0.2, 0.35, 0.55), roughness=0.9)
    floor = material('floor', (0.45, 0.3, 0.2), roughness=0.5)
    # The room, 6 x 5 x 3 m: six inward-facing quads (floor, ceiling, four walls).
    plane('floor', (6, 5), (0, 0, 0), floor)
    plane('ceiling', (6, 5), (0, 0, 3), wall, rot=(math.radians(180), 0, 0))
    plane('back', (6, 3), (0, 2.5, 1.5), accent, rot=(math.radians(90), 0, 0))
    plane('front', (6, 3), (0, -2.5, 1.5), wall, rot=(math.radians(-90), 0, 0))
    plane('left', (3, 5), (-3, 0, 1.5), wall, rot=(0, math.radians(90), 0))
    plane('right', (3, 5), (3, 0, 1.5), wall, rot=(0, math.radians(-90), 0))
    wood = material('wood', (0.55, 0.38, 0.22), roughness=0.4)
    box('table', (1.6, 0.9, 0.08), (0.4, 0.6, 0.74), wood)
    for i, (dx, dy) in enumerate(((-0.7, -0.38), (0.7, -0.38), (-0.7, 0.38), (0.7, 0.38))):
        box('leg%d' % i, (0.06, 0.06, 0.7), (0.4 + dx, 0.6 + dy, 0.35), wood)
    box('cabinet', (0.6, 1.2, 1.1), (2.65, 1.4, 0.55), material('cabinet', (0.8, 0.8, 0.78), roughness=0.3))
    ball('ball', 0.25, (0.6, 0.6, 1.03), material('ball', (0.9, 0.5, 0.1), roughness=0.2))
    plane('panel', (1.2, 0.8), (-2.98, 0.5, 1.6), emitter('panel', (0.75, 0.85, 1.0), 8.0),
          rot=(0, math.radians(90), 0))
    light('POINT', 'lamp', 120.0, (1.2, -0.6, 2.6), rgb=(1.0, 0.85, 0.65))
    camera((-1.8, -2.2, 1.5), (85, 0, -40), 55)
    return 'interior'


def shot():
    reset()
    scene = bpy.context.scene
    bpy.context.preferences.edit.keyframe_new_interpolation_type = 'LINEAR'
    ground = material('ground', (0.55, 0.55, 0.5), roughness=0.9)
    plane('ground', (20, 20), (0, 0, 0), ground)
    box('pillar', (0.6, 0.6, 2.0), (-1.8, 1.5, 1.0), material('pillar', (0.7, 0.7, 0.7), roughness=0.6))
    ball('ball', 0.6, (1.6, 1.8, 0.6), material('ball', (0.1, 0.3, 0.8), roughness=0.3))
    cube = box('mover', (0.8, 0.8, 0.8), (-1.0, -0.5, 0.4), material('mover', (0.85, 0.25, 0.1), roughness=0.5))
    for f, loc, rz, s in ((0, (-1.0, -0.5, 0.4), 0.0, 0.8), (12, (0.2, 0.0, 0.5), 50.0, 1.0),
                          (24, (1.0, 0.4, 0.6), 100.0, 1.2)):
        cube.location, cube.rotation_euler, cube.scale = loc, (0, 0, math.radians(rz)), (s, s, s)
        for path in ('location', 'rotation_euler', 'scale'):
            cube.keyframe_insert(path, frame=f)
    cam = camera((0.0, -7.0, 2.5), (75, 0, 0), 40)
    for f, loc, rz in ((0, (-2.0, -7.0, 2.5), -12.0), (24, (2.0, -6.0, 2.2), 14.0)):
        cam.location, cam.rotation_euler = loc, (math.radians(78), 0, math.radians(rz))
        for path in ('location', 'rotation_euler'):
            cam.keyframe_insert(path, frame=f)
    light('SUN', 'sun', 3.0, (0, 0, 10), rot_deg=(35, 0, -40), rgb=(1.0, 0.95, 0.9))
    light('SPOT', 'spot', 400.0, (2.5, -2.0, 4.0), rot_deg=(40, 0, 50), rgb=(0.8, 0.9, 1.0),
          spot_size=math.radians(50), spot_blend=0.3)
    scene.frame_set(0)
    return 'shot'


def export(name):
    for ob in bpy.context.scene.objects:       # punctual lights: no radius
        if ob.type == 'LIGHT':
            ob.data.shadow_soft_size = 0.0
    bpy.ops.export_scene.gltf(filepath=os.path.join(HERE, name + '.glb'), export_format='GLB',
                              export_cameras=True, export_lights=True, export_yup=True,
                              export_apply=True, export_animations=True,
                              export_frame_range=True, export_animation_mode='ACTIVE_ACTIONS')


if __name__ == '__main__':
    for build in (sampler, interior, shot):
        export(build())
