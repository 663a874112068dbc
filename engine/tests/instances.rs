//! Mesh instances: the ECS builds one BLAS per mesh, rebuilds the TLAS only when instances
//! come, go or change mesh or material, refits it when they move, and does nothing when
//! nothing changed; an instanced mesh is hit where the same mesh baked into world-space
//! triangles is hit.

use bevy_ecs::prelude::*;
use glam::{Affine3A, Quat, Vec3, Vec3A};
use pathwave_engine::accel::mesh::MeshData;
use pathwave_engine::material::Material;
use pathwave_engine::math::Ray;
use pathwave_engine::placement::Form;
use pathwave_engine::scene::{ShapeDesc, parse};
use pathwave_engine::world::{
    Instanced, MaterialId, MeshLibrary, SceneInstances, SceneWorld, Shape, Transform,
};
use std::path::Path;
use std::sync::Arc;

fn empty_world() -> SceneWorld {
    let desc = parse(
        r#"Scene(
            camera: (look_from: (0, 0, 30), look_at: (0, 0, 0), vfov: 40),
            materials: { "a": Lambertian(albedo: (0.5, 0.5, 0.5)), "b": Metal(albedo: (0.9, 0.9, 0.9)) },
            objects: [],
        )"#,
        Path::new("<test>"),
    )
    .unwrap();
    SceneWorld::new(&desc)
}

fn mesh(rings: u32) -> Form {
    Form::Mesh(Arc::new(MeshData::knot(rings, 12)))
}

/// A rotation, a non-uniform scale, a translation and, for odd `i`, a mirror.
fn placement(i: usize) -> Affine3A {
    let f = i as f32;
    let mirror = if i % 2 == 1 { Vec3::new(-1.0, 1.0, 1.0) } else { Vec3::ONE };
    Affine3A::from_scale_rotation_translation(
        mirror * Vec3::new(1.0 + 0.1 * f, 0.7, 1.3),
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7 * f),
        Vec3::new(5.0 * (f % 5.0) - 10.0, 5.0 * (f / 5.0).floor() - 5.0, 0.3 * f),
    )
}

/// (BLAS builds, TLAS builds, TLAS refits).
fn counts(w: &SceneWorld) -> (u64, u64, u64) {
    let i = w.world.resource::<SceneInstances>();
    (w.world.resource::<MeshLibrary>().builds, i.builds, i.refits)
}

#[test]
fn blas_and_tlas_are_rebuilt_only_when_their_inputs_change() {
    let mut w = empty_world();
    let shape = mesh(40);
    let entities: Vec<Entity> = (0..20)
        .map(|i| {
            w.world.spawn((Transform(placement(i)), Shape(shape.clone()), MaterialId(0), Instanced)).id()
        })
        .collect();
    let first = w.update();
    assert_eq!(counts(&w), (1, 1, 0), "one BLAS for twenty instances of one mesh");
    first.instances.validate().unwrap();
    first.instances.blas[0].validate().unwrap();
    assert_eq!(first.instances.list.len(), 20);
    assert_eq!(first.instances.blas.len(), 1);
    assert!(first.features.instances);

    // Nothing changed: nothing is rebuilt and the scene is the same.
    let again = w.update();
    assert_eq!(counts(&w), (1, 1, 0));
    assert!(Arc::ptr_eq(&first, &again));

    // Moving one instance refits the TLAS; no BLAS is built.
    w.world.entity_mut(entities[3]).insert(Transform(placement(3) * Affine3A::from_translation(Vec3::Z)));
    let moved = w.update();
    assert_eq!(counts(&w), (1, 1, 1));
    moved.instances.validate().unwrap();
    assert!(!Arc::ptr_eq(&moved.instances, &first.instances), "the old frame keeps its TLAS");
    let k = w.world.resource::<SceneInstances>().entities.iter().position(|e| *e == entities[3]).unwrap();
    assert_eq!(first.instances.list[k].world_from_object, placement(3));
    let now = placement(3) * Affine3A::from_translation(Vec3::Z);
    assert_eq!(moved.instances.list[k].world_from_object, now);

    // A material edit rebuilds the TLAS, still no BLAS.
    w.world.entity_mut(entities[5]).insert(MaterialId(1));
    w.update();
    assert_eq!(counts(&w), (1, 2, 1));

    // Another instance of the same mesh: TLAS rebuild, no BLAS.
    let extra =
        w.world.spawn((Transform(placement(20)), Shape(shape.clone()), MaterialId(0), Instanced)).id();
    w.update();
    assert_eq!(counts(&w), (1, 3, 1));

    // A new mesh: one more BLAS.
    w.world.entity_mut(extra).insert(Shape(mesh(30)));
    let two = w.update();
    assert_eq!(counts(&w), (2, 4, 1));
    assert_eq!(two.instances.blas.len(), 2);

    // Despawning is seen (trackers are cleared per update) and the unused mesh is dropped.
    w.world.despawn(extra);
    let back = w.update();
    assert_eq!(counts(&w), (2, 5, 1));
    assert_eq!(back.instances.list.len(), 20);
    assert_eq!(back.instances.blas.len(), 1);
    assert_eq!(w.world.resource::<MeshLibrary>().len(), 1);
}

#[test]
fn an_instance_is_hit_where_its_baked_triangles_are() {
    let shape = mesh(48);
    let mut inst = empty_world();
    let mut baked = empty_world();
    for i in 0..10 {
        inst.world.spawn((Transform(placement(i)), Shape(shape.clone()), MaterialId(0), Instanced));
        baked.world.spawn((Transform(placement(i)), Shape(shape.clone()), MaterialId(0)));
    }
    let (a, b) = (inst.update(), baked.update());
    assert!(a.features.instances && !b.features.instances);
    assert!(a.geometry.prims.is_empty() && b.instances.is_empty());
    let (mut hits, mut s) = (0, 9u32);
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let mut disagree = 0;
    for _ in 0..20000 {
        let o = Vec3A::new(rnd(), rnd(), rnd()) * 25.0;
        let d = Vec3A::new(rnd() * 10.0, rnd() * 5.0, rnd() * 3.0) - o;
        let ray = Ray::new(o, d);
        let (x, y) = (a.intersect(&ray, f32::INFINITY), b.intersect(&ray, f32::INFINITY));
        assert_eq!(a.occluded(&ray, f32::INFINITY), x.is_some());
        match (x, y) {
            (Some(x), Some(y)) => {
                hits += 1;
                assert!((x.t - y.t).abs() <= 1e-4 * y.t, "t {} vs {}", x.t, y.t);
                assert!((x.surface.p - y.surface.p).length() <= 1e-4 * (1.0 + y.surface.p.length()));
                assert!(x.surface.n.dot(y.surface.n) > 0.9999, "normals {} {}", x.surface.n, y.surface.n);
                assert_eq!(x.material, 0);
            }
            (None, None) => {}
            // Rays through a shared edge may differ when rounded in two spaces.
            _ => disagree += 1,
        }
    }
    assert!(hits > 3000, "{hits}");
    assert!(disagree <= 2, "{disagree} rays hit in one form only");
}

#[test]
fn scenes_instance_meshes_unless_they_emit() {
    let dir = std::env::temp_dir().join(format!("pathwave-instances-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = dir.join("s.ron");
    std::fs::write(
        &scene,
        r#"Scene(
            camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
            materials: { "a": Lambertian(albedo: (0.5, 0.5, 0.5)), "l": DiffuseLight(emit: (1, 1, 1)) },
            objects: [
                (shape: Mesh(file: "tri.obj"), material: "a"),
                (shape: Mesh(file: "tri.obj"), material: "a", transform: [Translate((2, 0, 0))]),
                (shape: Mesh(file: "tri.obj"), material: "l", transform: [Translate((0, 2, 0))]),
            ],
        )"#,
    )
    .unwrap();
    let desc = pathwave_engine::scene::load(&scene).unwrap();
    let [ShapeDesc::Mesh(m0), ShapeDesc::Mesh(m1), _] = [0, 1, 2].map(|i| desc.objects[i].shape.clone())
    else {
        panic!("meshes")
    };
    assert!(Arc::ptr_eq(&m0.mesh, &m1.mesh), "one file, one mesh");
    let mut w = SceneWorld::new(&desc);
    let s = w.update();
    assert_eq!((s.instances.list.len(), s.instances.blas.len()), (2, 1));
    assert_eq!((s.geometry.prims.len(), s.lights.prims.len()), (1, 1), "the emitter stays a primitive");
    assert!(matches!(s.materials[s.geometry.material[0] as usize], Material::DiffuseLight(_)));
    let n = w.world.query_filtered::<(), With<Instanced>>().iter(&w.world).count();
    assert_eq!(n, 2);
    std::fs::remove_dir_all(&dir).unwrap();
}
