//! The binary a user runs knows only the kinds a user can write. The engine's test-only
//! material, shape, light and texture (its `test-material`, `test-shape`, `test-light` and
//! `test-texture` features), and the integrator's test-only stage (`test-stage`), are tested from
//! `tests/kinds/`, a package outside the workspace: were any package of the workspace to enable
//! them, cargo would build `target/release/pathwave` with them during `cargo test --workspace`,
//! and the user's next render would accept them.

use std::process::Command;

/// A scene whose material is `material` and whose one object is `shape`.
fn scene(material: &str, shape: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 1, 5), look_at: (0, 0, 0), vfov: 40),
            render: (width: 8, height: 8, spp: 1),
            materials: {{ "m": {material}(albedo: (0.5, 0.5, 0.5)) }},
            objects: [(shape: {shape}, material: "m")],
        )"#
    )
}

#[test]
fn the_binary_refuses_the_test_only_kinds() {
    let dir = std::env::temp_dir().join(format!("pathwave-user-binary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sphere = "Sphere(center: (0, 0, 0), radius: 1)";
    let disk = "TestDisk(center: (0, 0, 0), normal: (0, 1, 0), radius: 1)";
    let point = "TestPoint(position: (0, 3, 0), power: (100, 100, 100))";
    let stripes = "TestStripes(stripes: 4, even: (0, 0, 0), odd: (1, 1, 1))";
    for (name, text, kind, known) in [
        ("material", scene("TestDiffuse", sphere), "TestDiffuse", "Lambertian"),
        ("shape", scene("Lambertian", disk), "TestDisk", "Sphere"),
        (
            "light",
            scene("Lambertian", sphere).replace("objects:", &format!("lights: [{point}], objects:")),
            "TestPoint",
            "Point",
        ),
        (
            "texture",
            scene("Lambertian", sphere)
                .replace("materials:", &format!("textures: {{ \"t\": {stripes} }}, materials:")),
            "TestStripes",
            "Solid",
        ),
        // The same scene with kinds a user can write renders: the refusals are the kinds'.
        ("user", scene("Lambertian", sphere), "", ""),
    ] {
        let path = dir.join(format!("{name}.ron"));
        std::fs::write(&path, &text).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("render")
            .arg(&path)
            .arg("-o")
            .arg(dir.join(format!("{name}.exr")))
            .arg("--stats")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        match kind {
            // ...and runs no test-only stage (the integrator's `test-stage` feature), which
            // `--stats` would list.
            "" => assert!(o.status.success() && !err.contains("test_exposure"), "{err}"),
            _ => assert!(
                !o.status.success() && err.contains(kind) && err.contains(known),
                "{kind} is in the scene language of {}:\n{err}",
                env!("CARGO_BIN_EXE_pathwave")
            ),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
