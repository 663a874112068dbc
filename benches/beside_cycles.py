#!/usr/bin/env python3
"""pathwave beside Blender Cycles on the glTF scenes of scenes/cycles/ (written by
scenes/cycles/make.py): both render the same .glb file, Cycles through Blender's glTF importer.

  beside_cycles.py render SCENE -o OUT.exr --spp N [--seed S] [--frame F] [--depth D] [--ggx]
      (run with the bpy venv, /opt/vdbvenv/bin/python): one Cycles render; prints a JSON line
      with render_s, the time of bpy.ops.render.render alone
  beside_cycles.py bench [--scenes sampler,interior,shot] [--spp 16,64] [--ref-spp 1024] [--reps 16]
      [--json OUT] [--png DIR] [--pathwave-args '--light-tracing on']
      (run with a python that has numpy and mitsuba, /opt/mitsuba-anchor/bin/python): for each
      scene a converged render by each renderer (cached in $CYCLES_REFS, /tmp/cycles-refs by
      default), then pathwave and Cycles alternately at each spp; prints the per-channel
      means of the converged renders (pathwave's against Cycles'), each renderer's relMSE
      against its own converged render (its noise: the two differ by their models too, which
      would otherwise dominate) and the equal-error time ratio (pathwave's relMSE x time over
      Cycles'; both errors fall as 1/spp, so below 1 pathwave reaches Cycles' error sooner),
      from the mean relMSE over the reps (seeds 100, 101, ..) and from their median: a sun's
      caustics through sharp glossy lobes make the error heavy-tailed, one firefly of ~2000
      lifting a 16-spp image's relMSE from 0.1 to 2, so a few reps' mean is mostly luck.
      --png DIR writes the converged renders side by side as DIR/cycles-SCENE.png (Cycles left;
      the README's images: --png docs)

Settings, the same for both: 320 x 240 pixels, a one-pixel box filter, 2 threads, no denoiser,
no clamping, linear EXR. Cycles: CPU path tracing, Standard view transform, light tree,
caustics on, filter glossy 0, adaptive sampling off, max bounces D - 1 of every kind (Cycles
counts bounces after the first hit: 0 is direct light only, pathwave's max_depth 1; Mitsuba's
max_depth is pathwave's plus one). The importer's defaults that the file does not say are
undone: a point or spot light gets radius 0 and a sun angle 0 (KHR_lights_punctual lights are
points and parallel beams), the world is black and not sampled. `--ggx` swaps the Principled
BSDFs' multiple-scattering GGX (the importer's default) for single-scattering GGX, the
glTF BRDF's (a model variant, not the bench's).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import shlex
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENES = os.path.join(ROOT, 'scenes', 'cycles')
BPY = os.environ.get('BPY_PY', '/opt/vdbvenv/bin/python')
PATHWAVE = os.environ.get('PATHWAVE', os.path.join(ROOT, 'target', 'release', 'pathwave'))
REFS = os.environ.get('CYCLES_REFS', '/tmp/cycles-refs')
WIDTH, HEIGHT, THREADS, DEPTH = 320, 240, 2, 12
FRAME = {'shot': 12}        # the frame compared of an animated scene


def cycles_render(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument('scene')
    ap.add_argument('-o', '--output', required=True)
    ap.add_argument('--spp', type=int, default=16)
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--frame', type=int, default=0)
    ap.add_argument('--depth', type=int, default=DEPTH)
    ap.add_argument('--ggx', action='store_true')
    ap.add_argument('--lambert', action='store_true')
    a = ap.parse_args(argv)
    import bpy
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    for ob in list(bpy.data.objects):          # the startup scene's cube, light and camera
        bpy.data.objects.remove(ob, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.lights, bpy.data.cameras, bpy.data.materials):
        for d in list(coll):
            coll.remove(d)
    bpy.ops.import_scene.gltf(filepath=os.path.join(SCENES, a.scene + '.glb'))
    cams = [o for o in scene.objects if o.type == 'CAMERA']
    scene.camera = cams[0]
    for o in scene.objects:
        if o.type == 'LIGHT':
            o.data.shadow_soft_size = 0.0
            if o.data.type == 'SUN':
                o.data.angle = 0.0
    for m in bpy.data.materials:
        for n in (m.node_tree.nodes if m.node_tree else ()):
            if n.type == 'BSDF_PRINCIPLED' and a.ggx:
                n.distribution = 'GGX'
            if n.type == 'BSDF_PRINCIPLED' and a.lambert:
                n.inputs['Specular IOR Level'].default_value = 0.0
    world = bpy.data.worlds.new('black')
    world.use_nodes = True
    world.node_tree.nodes['Background'].inputs['Strength'].default_value = 0.0
    world.cycles.sampling_method = 'NONE'
    scene.world = world
    r = scene.render
    c = scene.cycles
    c.device = 'CPU'
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.time_limit = 0.0
    c.seed = a.seed
    c.use_animated_seed = False
    c.pixel_filter_type = 'BOX'
    c.filter_width = 1.0
    for k in ('max_bounces', 'diffuse_bounces', 'glossy_bounces', 'transmission_bounces',
              'volume_bounces', 'transparent_max_bounces'):
        setattr(c, k, a.depth - 1)
    c.caustics_reflective = c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.use_light_tree = True
    c.film_exposure = 1.0
    r.resolution_x, r.resolution_y, r.resolution_percentage = WIDTH, HEIGHT, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_motion_blur = False
    r.threads_mode = 'FIXED'
    r.threads = THREADS
    r.use_compositing = r.use_sequencer = False
    r.dither_intensity = 0.0
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = 'Standard', 'None', 0.0, 1.0
    im = r.image_settings
    im.file_format, im.color_mode, im.color_depth, im.exr_codec = 'OPEN_EXR', 'RGB', '32', 'ZIP'
    scene.frame_set(a.frame)
    r.filepath = os.path.abspath(a.output)
    r.use_file_extension = False
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(json.dumps(dict(render_s=time.perf_counter() - t, spp=a.spp, seed=a.seed,
                          bpy=bpy.app.version_string)))


def run_cycles(scene, out, spp, seed, extra=()):
    cmd = [BPY, os.path.abspath(__file__), 'render', scene, '-o', out, '--spp', str(spp),
           '--seed', str(seed), '--frame', str(FRAME.get(scene, 0))] + list(extra)
    p = subprocess.run(cmd, capture_output=True, text=True)
    lines = [l for l in p.stdout.splitlines() if l.startswith('{"render_s"')]
    if p.returncode or not lines:
        sys.exit('Cycles failed on %s: %s' % (scene, (p.stdout + p.stderr)[-2000:]))
    return json.loads(lines[-1])['render_s']


def run_pathwave(scene, out, spp, seed, extra=()):
    glb = os.path.join(SCENES, scene + '.glb')
    common = ['--width', str(WIDTH), '--height', str(HEIGHT), '--spp', str(spp), '--seed', str(seed),
              '-t', str(THREADS), '--max-depth', str(DEPTH)] + list(extra)
    if scene in FRAME:
        f = FRAME[scene]
        pattern = out.replace('.exr', '_{frame:04}.exr')
        cmd = [PATHWAVE, 'animate', glb, '-o', pattern, '--frames', '%d..%d' % (f, f + 1), '--shutter', '0',
               '--overwrite'] + common
        p = subprocess.run(cmd, capture_output=True, text=True)
        m = re.search(r'in ([0-9.]+) s; ETA', p.stdout + p.stderr)
        if not p.returncode:
            os.replace(pattern.replace('{frame:04}', '%04d' % f), out)
    else:
        p = subprocess.run([PATHWAVE, 'render', glb, '-o', out, '-q'] + common, capture_output=True, text=True)
        m = re.search(r' in ([0-9.]+) s', p.stdout + p.stderr)
    if p.returncode or not m:
        sys.exit('pathwave failed on %s: %s' % (scene, (p.stdout + p.stderr)[-2000:]))
    return float(m.group(1))


def bench(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument('--scenes', default='sampler,interior,shot')
    ap.add_argument('--spp', default='16,64')
    ap.add_argument('--ref-spp', type=int, default=1024)
    ap.add_argument('--reps', type=int, default=16)
    ap.add_argument('--json', default=None)
    ap.add_argument('--png', default=None, help='write cycles-SCENE.png (Cycles | pathwave) here')
    ap.add_argument('--pathwave-args', default='',
                    help="more options for pathwave, such as '--light-tracing on' (its converged render "
                         'is then made and cached with them too)')
    a = ap.parse_args(argv)
    extra = shlex.split(a.pathwave_args)
    tag = ''.join('-' + re.sub('[^A-Za-z0-9.]+', '', x) for x in extra)
    sys.path.insert(0, '/work/shared/anchors/mitsuba')
    import numpy as np
    import metrics
    os.makedirs(REFS, exist_ok=True)
    tmp = tempfile.mkdtemp()
    rows = []
    for scene in a.scenes.split(','):
        ref_path = os.path.join(REFS, '%s-%d.exr' % (scene, a.ref_spp))
        if not os.path.exists(ref_path):
            s = run_cycles(scene, ref_path, a.ref_spp, 1)
            print('%s: Cycles reference, %d spp in %.1f s' % (scene, a.ref_spp, s), file=sys.stderr, flush=True)
        pw_ref_path = os.path.join(REFS, '%s-pathwave%s-%d.exr' % (scene, tag, a.ref_spp))
        if not os.path.exists(pw_ref_path):
            s = run_pathwave(scene, pw_ref_path, a.ref_spp, 1, extra)
            print('%s: pathwave reference, %d spp in %.1f s' % (scene, a.ref_spp, s), file=sys.stderr, flush=True)
        ref, pw_ref = metrics.load(ref_path), metrics.load(pw_ref_path)
        between = metrics.metrics(pw_ref, ref)
        for spp in [int(x) for x in a.spp.split(',')]:
            pw, cy = [], []
            for r in range(a.reps):
                out = os.path.join(tmp, 'pw.exr')
                t = run_pathwave(scene, out, spp, 100 + r, extra)
                pw.append((t, metrics.metrics(metrics.load(out), pw_ref)))
                out = os.path.join(tmp, 'cy.exr')
                t = run_cycles(scene, out, spp, 100 + r)
                cy.append((t, metrics.metrics(metrics.load(out), ref)))
            tp, tc = min(x[0] for x in pw), min(x[0] for x in cy)
            ep = sum(x[1]['relmse'] for x in pw) / a.reps
            ec = sum(x[1]['relmse'] for x in cy) / a.reps
            mep = float(np.median([x[1]['relmse'] for x in pw]))
            mec = float(np.median([x[1]['relmse'] for x in cy]))
            mp, mr = between['mean_test'], between['mean_ref']
            row = dict(scene=scene, spp=spp, pathwave_s=round(tp, 3), cycles_s=round(tc, 3),
                       pathwave_relmse=round(ep, 6), cycles_relmse=round(ec, 6),
                       equal_error_time_ratio=round(ep * tp / (ec * tc), 3),
                       pathwave_relmse_median=round(mep, 6), cycles_relmse_median=round(mec, 6),
                       equal_error_time_ratio_median=round(mep * tp / (mec * tc), 3), reps=a.reps,
                       mean_cycles=[round(v, 5) for v in mr], mean_pathwave=[round(v, 5) for v in mp],
                       mean_diff_pct=[round(100 * (p / q - 1), 2) for p, q in zip(mp, mr)],
                       relmse_between=round(between['relmse'], 5), ref_spp=a.ref_spp)
            rows.append(row)
            print(json.dumps(row), flush=True)
        if a.png:
            os.makedirs(a.png, exist_ok=True)
            gap = np.ones((ref.shape[0], 4, 3))
            write_png(np.concatenate([ref, gap, pw_ref], 1), os.path.join(a.png, 'cycles-%s.png' % scene))
    if a.json:
        with open(a.json, 'w') as f:
            for r in rows:
                f.write(json.dumps(r) + '\n')
    print('\n| scene | spp | mean R G B Cycles | pathwave vs Cycles % | pathwave s | Cycles s '
          '| relMSE pathwave | relMSE Cycles | equal-error time pathwave/Cycles '
          '| median relMSE pathwave | median relMSE Cycles | equal-error time, medians |')
    print('|---|---|---|---|---|---|---|---|---|---|---|---|')
    for r in rows:
        print('| %s | %d | %s | %s | %.2f | %.2f | %.4g | %.4g | %.2f | %.4g | %.4g | %.2f |' % (
            r['scene'], r['spp'], ' '.join('%.4f' % v for v in r['mean_cycles']),
            ' '.join('%+.1f' % v for v in r['mean_diff_pct']), r['pathwave_s'], r['cycles_s'],
            r['pathwave_relmse'], r['cycles_relmse'], r['equal_error_time_ratio'],
            r['pathwave_relmse_median'], r['cycles_relmse_median'], r['equal_error_time_ratio_median']))


def write_png(img, path):
    """Standard view transform: sRGB of the clipped linear values, 8 bits."""
    import mitsuba as mi
    import numpy as np
    x = np.clip(np.nan_to_num(img), 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    b = mi.Bitmap(np.round(255 * x).astype(np.uint8), mi.Bitmap.PixelFormat.RGB)
    b.write(path)


if __name__ == '__main__':
    if len(sys.argv) > 1 and sys.argv[1] == 'render':
        cycles_render(sys.argv[2:])
    elif len(sys.argv) > 1 and sys.argv[1] == 'bench':
        bench(sys.argv[2:])
    else:
        sys.exit(__doc__)
