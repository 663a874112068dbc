# Mitsuba 3's directional albedo of a white roughplastic (index 1.5): the mean weight of 2^22 of
# its BSDF samples and its standard error, per distribution, alpha and angle of incidence (the
# table of directional_albedo_is_mitsubas_and_sampling_agrees in engine/src/material/rough_plastic.rs).
#   /opt/mitsuba-anchor/bin/python scripts/mitsuba-plastic/albedo.py
import mitsuba as mi, drjit as dr, math, numpy as np
mi.set_variant('llvm_ad_rgb')
for dist in ['ggx','beckmann']:
  for alpha in [0.05,0.3,1.0]:
    b = mi.load_dict(dict(type='roughplastic', distribution=dist, alpha=alpha, int_ior=1.5, ext_ior=1.0, diffuse_reflectance={'type':'rgb','value':[1,1,1]}))
    for deg in [0,60,80]:
        N=1<<22
        si = dr.zeros(mi.SurfaceInteraction3f, N)
        t=math.radians(deg)
        si.wi = mi.Vector3f(math.sin(t),0,math.cos(t))
        si.sh_frame = mi.Frame3f(mi.Vector3f(0,0,1)); si.n=mi.Vector3f(0,0,1)
        s = mi.PCG32(N)
        bs, w = b.sample(mi.BSDFContext(), si, s.next_float32(), mi.Point2f(s.next_float32(), s.next_float32()))
        a=np.array(w[0]); print("(Distribution::%s, %g, %g, %.5f, %.5f)," % (dist.capitalize(), alpha, deg, a.mean(), a.std()/math.sqrt(N)))
