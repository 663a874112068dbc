//! A medium bounded by a closed mesh renders like the same medium in the analytic box, and an
//! open mesh is refused as a boundary; a grid medium read from an OpenVDB file renders like the
//! same values read from a `.vol` placed where the OpenVDB grid's transform puts them.

mod common;
use common::*;
use pathwave::engine::scene::Body;
use pathwave::metrics::rel_mse;

const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";

fn scene(shape: &str, density: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0.5, 1.2, 3.5), look_at: (0.5, 0.4, 0.5), vfov: 40),
            render: (width: 48, height: 48, spp: 64, max_depth: 16),
            background: Sky(bottom: (0.2, 0.2, 0.2), top: (1.2, 1.2, 1.2)),
            materials: {{ "floor": Lambertian(albedo: (0.6, 0.6, 0.6)) }},
            objects: [
                (shape: Quad(q: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "floor"),
                (shape: {shape}, medium: (density: {density}, albedo: (0.8, 0.8, 0.8)),
                 transform: [RotateY(25), Scale((1, 1.3, 1))]),
            ],
        )"#
    )
}

#[test]
fn a_closed_mesh_bounds_a_medium_like_the_box() {
    let dir = std::env::temp_dir().join(format!("pathwave-mesh-media-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("cube.obj"), CUBE).unwrap();
    let load = |text: String| {
        let p = dir.join("s.ron");
        std::fs::write(&p, text).unwrap();
        pathwave::engine::scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
    };
    let boxed = render(&load(scene("Box(a: (0, 0, 0), b: (1, 1, 1))", 2.0))).mean();
    let meshed = render(&load(scene(r#"Mesh(file: "cube.obj")"#, 2.0))).mean();
    let denser = render(&load(scene("Box(a: (0, 0, 0), b: (1, 1, 1))", 2.1))).mean();
    let (same, control) = (rel_mse(&meshed, &boxed), rel_mse(&denser, &boxed));
    eprintln!("mesh vs box relMSE {same:.2e}; density +5% {control:.2e}");
    // Same seed, same paths: only the boundary arithmetic differs.
    assert!(same < 0.01 * control, "mesh {same} vs control {control}");

    // One face missing: refused, naming the file and an open edge.
    let open: String = CUBE.lines().filter(|l| *l != "f 2 8 6").map(|l| format!("{l}\n")).collect();
    std::fs::write(dir.join("open.obj"), open).unwrap();
    let p = dir.join("o.ron");
    std::fs::write(&p, scene(r#"Mesh(file: "open.obj")"#, 2.0)).unwrap();
    let e = pathwave::engine::scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("a medium needs a closed mesh") && e.contains("open.obj") && e.contains("borders 1"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A grid medium in a box around `scenes/assets/smoke-*.vdb`'s active voxels (world x -0.425 to
/// 0.525, y -0.025 to 1.175, z -0.175 to 0.775), its grid `grid`.
fn grid_scene(grid: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0.2, 1.0, -2.6), look_at: (0.05, 0.55, 0.3), vfov: 40),
            render: (width: 40, height: 40, spp: 8, max_depth: 8),
            background: Sky(bottom: (0.2, 0.2, 0.2), top: (1.2, 1.1, 1.0)),
            materials: {{}},
            objects: [
                (shape: Box(a: (-0.45, -0.05, -0.2), b: (0.55, 1.2, 0.8)),
                 medium: (density: 20, albedo: (0.8, 0.8, 0.8), grid: {grid}),
                 transform: [RotateY(20), Translate((0, 0.1, 0))]),
            ],
        )"#
    )
}

/// Media naming the same grid of an OpenVDB file share one dense box (made once: a box may
/// hold 1 GiB); another grid name would make its own. Checked to fail with a box made at
/// every pick.
#[test]
fn media_naming_one_openvdb_grid_share_its_box() {
    let dir = std::env::temp_dir().join(format!("pathwave-vdb-shared-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vdb = root().join("scenes/assets/smoke-zip.vdb");
    let medium =
        format!(r#"medium: (density: 2, albedo: (0.8, 0.8, 0.8), grid: (file: "{}"))"#, vdb.display());
    let scene = format!(
        r#"Scene(
            camera: (look_from: (0, 1, -3), look_at: (0, 0.5, 0), vfov: 40),
            materials: {{}},
            objects: [
                (shape: Box(a: (-1, 0, -1), b: (1, 2, 1)), {medium}),
                (shape: Box(a: (2, 0, -1), b: (4, 2, 1)), {medium}, transform: [Translate((2.5, 0, 0))]),
            ],
        )"#
    );
    let p = dir.join("s.ron");
    std::fs::write(&p, scene).unwrap();
    let desc = pathwave::engine::scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let grids: Vec<_> = desc
        .objects
        .iter()
        .map(|o| match &o.body {
            Body::Volume(m) => m.grid.as_ref().and_then(|g| g.placed()).expect("a grid read at load").grid,
            Body::Surface(_) => panic!("a surface"),
        })
        .collect();
    assert!(std::sync::Arc::ptr_eq(&grids[0], &grids[1]), "two boxes of one grid");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_openvdb_grid_renders_like_its_values_from_a_vol() {
    let assets = root().join("scenes/assets");
    let dir = std::env::temp_dir().join(format!("pathwave-vdb-media-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let load = |grid: String| {
        let p = dir.join("s.ron");
        std::fs::write(&p, grid_scene(&grid)).unwrap();
        pathwave::engine::scene::load(&p)
    };
    // Where the grid's transform puts the unit cube of its dense box: the .vol's placement.
    let path = assets.join("smoke-blosc.vdb");
    let file = pathwave::engine::format::vdb::VdbFile::parse(std::fs::read(&path).unwrap(), &path).unwrap();
    let m = file.grid("density").unwrap().world_from_unit().as_affine3a();
    let (c, t) = (m.matrix3, m.translation);
    let rows: Vec<String> = (0..3)
        .map(|i| format!("[{:?}, {:?}, {:?}, {:?}]", c.x_axis[i], c.y_axis[i], c.z_axis[i], t[i]))
        .collect();
    let vol = format!(
        r#"(file: "{}", transform: [Matrix([{}, [0, 0, 0, 1]])])"#,
        assets.join("smoke-vdb.vol").display(),
        rows.join(", ")
    );
    let want = render(&load(vol.clone()).unwrap_or_else(|e| panic!("{e}"))).mean();
    for name in ["smoke-blosc.vdb", "smoke-half.vdb", "smoke-zip.vdb"] {
        let vdb = format!(r#"(file: "{}", name: "density")"#, assets.join(name).display());
        let got = render(&load(vdb).unwrap_or_else(|e| panic!("{e}"))).mean();
        assert!(got == want, "{name}: the pixels differ from the .vol's");
    }
    // A transform of its own places the grid after the OpenVDB transform, as after the .vol's
    // matrix.
    let moved = "UniformScale(0.8), Translate((0.1, 0.05, 0))";
    let vdb = format!(r#"(file: "{}", transform: [{moved}])"#, assets.join("smoke-blosc.vdb").display());
    let got = render(&load(vdb).unwrap_or_else(|e| panic!("{e}"))).mean();
    let vol_moved = vol.replace("[0, 0, 0, 1]])]", &format!("[0, 0, 0, 1]]), {moved}]"));
    let want_moved = render(&load(vol_moved).unwrap_or_else(|e| panic!("{e}"))).mean();
    let (same, control) = (rel_mse(&got, &want_moved), rel_mse(&want, &want_moved));
    eprintln!("moved: vdb vs vol relMSE {same:.2e}; moved vs not {control:.2e}");
    assert!(got == want_moved && control > 1e-3, "moved grid: relMSE {same} vs control {control}");
    // The default name is "density"; a name the file lacks lists those it has, and a .vol
    // takes none.
    let vdb = |name: &str| format!(r#"(file: "{}"{name})"#, assets.join("smoke-blosc.vdb").display());
    assert!(render(&load(vdb("")).unwrap_or_else(|e| panic!("{e}"))).mean() == want);
    let e = load(vdb(r#", name: "smoke""#)).unwrap_err().to_string();
    assert!(
        e.contains("smoke-blosc.vdb") && e.contains(r#"no grid named "smoke"; its grids: "density""#),
        "{e}"
    );
    let e = load(vdb(r#", name: "velocity""#)).unwrap_err().to_string();
    assert!(e.contains("Tree_vec3s_5_4_3: pathwave reads scalar float grids"), "{e}");
    let e = load(format!(r#"(file: "{}", name: "density")"#, assets.join("smoke-vdb.vol").display()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("the .vol file") && e.contains("holds one grid"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
