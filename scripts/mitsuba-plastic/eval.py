# Mitsuba 3's eval_pdf of plastic and roughplastic (scalar_rgb) for pairs of directions given as
# (theta, phi) in degrees about the normal z: the tables of the eval_and_pdf_match_mitsuba tests in
# engine/src/material/plastic.rs and rough_plastic.rs. Mitsuba's si.wi is pathwave's wo.
#   /opt/mitsuba-anchor/bin/python scripts/mitsuba-plastic/eval.py
import mitsuba as mi, drjit as dr, math
mi.set_variant('scalar_rgb')
def si_for(wi):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(wi)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0,0,1))
    si.n = mi.Vector3f(0,0,1)
    return si
def d(theta, phi):
    t, p = math.radians(theta), math.radians(phi)
    return [math.sin(t)*math.cos(p), math.sin(t)*math.sin(p), math.cos(t)]
pairs = [(0,0,30,0),(30,0,30,180),(30,0,45,90),(60,0,20,200),(80,0,70,180),(10,0,85,45),(45,0,45,180),(70,0,10,30)]
cfgs = [
 dict(type='plastic', diffuse_reflectance={'type':'rgb','value':[0.1,0.27,0.36]}, int_ior=1.9),
 dict(type='plastic', diffuse_reflectance={'type':'rgb','value':[0.8,0.5,0.2]}, int_ior='bk7', ext_ior='air', nonlinear=True),
 dict(type='roughplastic', distribution='ggx', alpha=0.1, int_ior='bk7', ext_ior='air', diffuse_reflectance={'type':'rgb','value':[0.02,0.2,0.1]}),
 dict(type='roughplastic', distribution='ggx', alpha=0.4, int_ior='bk7', ext_ior='air', nonlinear=True, diffuse_reflectance={'type':'rgb','value':[0.02,0.2,0.1]}),
 dict(type='roughplastic', distribution='ggx', alpha=1.0, int_ior='bk7', ext_ior='air', diffuse_reflectance={'type':'rgb','value':[0.5,0.5,0.5]}),
 dict(type='roughplastic', distribution='beckmann', alpha=0.05, diffuse_reflectance={'type':'rgb','value':[0.5,0.5,0.5]}),
 dict(type='roughplastic', distribution='beckmann', alpha=0.3, int_ior=1.9, diffuse_reflectance={'type':'rgb','value':[0.7,0.2,0.4]}, specular_reflectance={'type':'rgb','value':[0.5,0.8,1.0]}),
]
ctx = mi.BSDFContext()
for c in cfgs:
    b = mi.load_dict(c)
    print('#', {k:v for k,v in c.items()})
    for (ti,pi,to,po) in pairs:
        wi, wo = d(ti,pi), d(to,po)
        v, pdf = b.eval_pdf(ctx, si_for(wi), mi.Vector3f(wo))
        print("((%g, %g), (%g, %g), [%.7g, %.7g, %.7g], %.7g)," % (ti,pi,to,po, v[0], v[1], v[2], pdf))
