# Mitsuba 3 references for the scenes of one folder of tests/mitsuba-data/tests/scenes that are
# not in mitsuba-data (bsdf_spheres_unmasked, participating_media_hg). Writes refs/*_ref_rgb.exr
# (the mean) and refs/*_ref_rgb_var.exr (the per-sample variance from the `moment` integrator,
# XYZ converted to RGB) as Mitsuba's test_renders.py writes them. INTEGRATOR sets a scene's
# `integrator` default (bsdf_spheres_unmasked was rendered with `path`).
#   /opt/mitsuba-anchor/bin/python scripts/mitsuba_refs.py bsdf_spheres_unmasked 16384 path
#   /opt/mitsuba-anchor/bin/python scripts/mitsuba_refs.py participating_media_hg 8192
import sys, glob, os, numpy as np
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
folder, spp = sys.argv[1], int(sys.argv[2])
params = {'integrator': sys.argv[3]} if len(sys.argv) > 3 else {}
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..',
                    'tests', 'mitsuba-data', 'tests', 'scenes', folder)
for s in sorted(glob.glob(os.path.join(here, '*.xml'))):
    stem = os.path.basename(s).rsplit('_', 1)[0]
    scene = mi.load_file(s, spp=spp, **params)
    img = np.array(mi.render(scene, seed=1, spp=spp))
    # R, G, B, then the moment integrator's first and second moments in XYZ.
    m1, m2 = img[..., 3:6], img[..., 6:9]
    mi.Bitmap(img[..., :3]).write(os.path.join(here, 'refs', f'{stem}_ref_rgb.exr'))
    var = mi.Bitmap(np.ascontiguousarray(m2 - m1 * m1), mi.Bitmap.PixelFormat.XYZ)
    var.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(
        os.path.join(here, 'refs', f'{stem}_ref_rgb_var.exr'))
    print(stem, spp, 'spp')
