# Mitsuba 3 references for tests/mitsuba-data/tests/scenes/participating_media_hg (written for
# pathwave: Henyey-Greenstein media under Mitsuba's museum environment map). Writes
# refs/*_ref_rgb.exr (the mean) and refs/*_ref_rgb_var.exr (the per-sample variance from the
# `moment` integrator, XYZ converted to RGB) as Mitsuba's test_renders.py writes them.
#   /opt/mitsuba-anchor/bin/python scripts/mitsuba-media/hg_refs.py 8192
import sys, glob, os, numpy as np
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
spp = int(sys.argv[1])
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..',
                    'tests', 'mitsuba-data', 'tests', 'scenes', 'participating_media_hg')
for s in sorted(glob.glob(os.path.join(here, '*.xml'))):
    stem = os.path.basename(s).rsplit('_', 1)[0]
    scene = mi.load_file(s, spp=spp)
    img = np.array(mi.render(scene, seed=1, spp=spp))
    # R, G, B, then the moment integrator's first and second moments in XYZ.
    m1, m2 = img[..., 3:6], img[..., 6:9]
    mi.Bitmap(img[..., :3]).write(os.path.join(here, 'refs', f'{stem}_ref_rgb.exr'))
    var = mi.Bitmap(np.ascontiguousarray(m2 - m1 * m1), mi.Bitmap.PixelFormat.XYZ)
    var.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(
        os.path.join(here, 'refs', f'{stem}_ref_rgb_var.exr'))
    print(stem, spp, 'spp')
