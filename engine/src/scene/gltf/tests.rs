//! glTF files written by the tests: meshes read (every index type, `.gltf` with a data URI or a
//! `.bin`, `.glb`), meshes picked, and malformed files refused with what is wrong.

use super::{GltfFile, MeshRef};
use crate::scene::{MeshFormat, mesh_format};
use std::path::{Path, PathBuf};

/// A glTF document under construction: one buffer, a view and an accessor per array, and the
/// other top-level arrays as JSON text.
#[derive(Default)]
pub(super) struct Doc {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
    /// `"meshes": [..]` entries, and any other top-level member: `("nodes", "{..}")`.
    pub members: Vec<(&'static str, String)>,
}

impl Doc {
    /// An accessor over `bytes` (`count` elements of `ty` of component type `component`),
    /// with `more` JSON members; its index.
    pub fn accessor(&mut self, bytes: &[u8], component: u32, ty: &str, count: usize, more: &str) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        self.accessors.push(format!(
            r#"{{"bufferView":{},"componentType":{component},"count":{count},"type":"{ty}"{more}}}"#,
            self.views.len() - 1
        ));
        self.accessors.len() - 1
    }

    /// A buffer view over `bytes` (an image's); its index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A POSITION accessor (with its min and max, as glTF requires).
    pub fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let lo = (0..3).map(|k| p.iter().map(|v| v[k]).fold(f32::INFINITY, f32::min));
        let hi = (0..3).map(|k| p.iter().map(|v| v[k]).fold(f32::NEG_INFINITY, f32::max));
        let num = |x: f32| if x.is_finite() { format!("{x:?}") } else { "0".into() };
        let list = |v: Vec<f32>| v.into_iter().map(num).collect::<Vec<_>>().join(",");
        let more = format!(r#","min":[{}],"max":[{}]"#, list(lo.collect()), list(hi.collect()));
        self.accessor(&f32_bytes(p.as_flattened()), 5126, "VEC3", p.len(), &more)
    }

    /// A float accessor of `ty` over `v`.
    pub fn floats(&mut self, v: &[f32], ty: &str, per: usize) -> usize {
        self.accessor(&f32_bytes(v), 5126, ty, v.len() / per, "")
    }

    /// Indices as u8 (5121), u16 (5123) or u32 (5125).
    pub fn indices(&mut self, i: &[u32], component: u32) -> usize {
        let bytes: Vec<u8> = match component {
            5121 => i.iter().map(|&x| x as u8).collect(),
            5123 => i.iter().flat_map(|&x| (x as u16).to_le_bytes()).collect(),
            _ => i.iter().flat_map(|&x| x.to_le_bytes()).collect(),
        };
        self.accessor(&bytes, component, "SCALAR", i.len(), "")
    }

    /// The JSON, its buffer at `uri` (`None`: a data URI; `Some("")`: a `.glb`'s chunk).
    pub fn json(&self, uri: Option<&str>) -> String {
        use base64::Engine;
        let data;
        let uri = match uri {
            Some("") => String::new(),
            Some(u) => format!(r#","uri":"{u}""#),
            None => {
                data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
                format!(r#","uri":"data:application/octet-stream;base64,{data}""#)
            }
        };
        let mut out = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}{uri}}}],"bufferViews":[{}],"accessors":[{}]"#,
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        );
        let mut names: Vec<&str> = Vec::new();
        for (n, _) in &self.members {
            if !names.contains(n) {
                names.push(n);
            }
        }
        for n in names {
            let items: Vec<&str> =
                self.members.iter().filter(|(m, _)| *m == n).map(|(_, v)| v.as_str()).collect();
            match n {
                "scene" | "extensions" | "extensionsUsed" | "extensionsRequired" => {
                    out += &format!(r#","{n}":{}"#, items.join(","))
                }
                _ => out += &format!(r#","{n}":[{}]"#, items.join(",")),
            }
        }
        out + "}"
    }

    /// The document as a `.glb`.
    pub fn glb(&self) -> Vec<u8> {
        let mut json = self.json(Some("")).into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A folder of its own for test `tag`.
pub(super) fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-gltf-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const QUAD: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
const QUAD_TRIANGLES: [u32; 6] = [0, 1, 2, 0, 2, 3];

/// A document with one mesh "quad" (normals, uv, indices of `component` type).
fn quad(component: u32) -> Doc {
    let mut d = Doc::default();
    let p = d.positions(&QUAD);
    let n = d.floats(&[0.0, 0.0, 1.0].repeat(4), "VEC3", 3);
    let uv = d.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.25], "VEC2", 2);
    let i = d.indices(&QUAD_TRIANGLES, component);
    d.members.push((
        "meshes",
        format!(
            r#"{{"name":"quad","primitives":[{{"attributes":{{"POSITION":{p},"NORMAL":{n},"TEXCOORD_0":{uv}}},"indices":{i}}}]}}"#
        ),
    ));
    d
}

fn read(json: &str) -> Result<GltfFile, String> {
    GltfFile::new(json.as_bytes(), Path::new("t.gltf"))
}

fn mesh_of(
    json: &str,
    which: Option<MeshRef>,
    primitive: Option<u32>,
) -> Result<crate::accel::mesh::MeshData, String> {
    read(json)?.mesh_data(which.as_ref(), primitive, Path::new("t.gltf"))
}

#[test]
fn a_mesh_is_read_with_every_index_type() {
    for component in [5121, 5123, 5125] {
        let m = mesh_of(&quad(component).json(None), None, None).unwrap();
        assert_eq!(m.positions.iter().map(|p| p.to_array()).collect::<Vec<_>>(), QUAD.to_vec());
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]], "component type {component}");
        assert_eq!(m.normals.as_ref().unwrap()[3].to_array(), [0.0, 0.0, 1.0]);
        // glTF's v runs down the image, pathwave's up: v is read as 1 - v.
        let uvs: Vec<[f32; 2]> = m.uvs.unwrap().iter().map(|u| u.to_array()).collect();
        assert_eq!(uvs, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.75]]);
    }
}

#[test]
fn a_glb_and_a_gltf_with_a_bin_file_read_as_the_data_uri_does() {
    let d = quad(5123);
    let want = mesh_of(&d.json(None), None, None).unwrap();
    let glb = GltfFile::new(&d.glb(), Path::new("t.glb")).unwrap();
    assert_eq!(glb.mesh_data(None, None, Path::new("t.glb")).unwrap(), want);
    let dir = scratch("bin");
    std::fs::write(dir.join("quad data.bin"), &d.bin).unwrap();
    let path = dir.join("quad.gltf");
    let file = GltfFile::new(d.json(Some("quad%20data.bin")).as_bytes(), &path).unwrap();
    assert_eq!(file.mesh_data(None, None, &path).unwrap(), want);
    // Without its .bin: the buffer and the file are named.
    let err = GltfFile::new(d.json(Some("gone.bin")).as_bytes(), &path).unwrap_err();
    assert!(err.contains("buffer 0") && err.contains("there is no gone.bin in"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_mesh_is_picked_by_name_or_index_and_a_primitive_alone() {
    let mut d = quad(5123);
    let p = d.positions(&[[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]]);
    d.members.push(("meshes", format!(r#"{{"name":"tri","primitives":[{{"attributes":{{"POSITION":{p}}}}},{{"attributes":{{"POSITION":{p}}}}}]}}"#)));
    let json = d.json(None);
    let err = mesh_of(&json, None, None).unwrap_err();
    assert!(err.contains("holds 2 meshes") && err.contains(r#""quad", "tri""#), "{err}");
    let tri = mesh_of(&json, Some(MeshRef::Name("tri".into())), None).unwrap();
    // Both primitives, the second's vertices after the first's.
    assert_eq!(tri.triangles, vec![[0, 1, 2], [3, 4, 5]]);
    assert_eq!(tri.positions[4].z, 5.0);
    assert_eq!(mesh_of(&json, Some(MeshRef::Index(1)), Some(1)).unwrap().triangles, vec![[0, 1, 2]]);
    // A primitive without normals: the mesh has none.
    assert!(tri.normals.is_none());
    let err = mesh_of(&json, Some(MeshRef::Name("box".into())), None).unwrap_err();
    assert!(err.contains("no mesh \"box\""), "{err}");
    let err = mesh_of(&json, Some(MeshRef::Index(1)), Some(2)).unwrap_err();
    assert!(err.contains("mesh 1 \"tri\" has no primitive 2 (it has 2)"), "{err}");
}

/// `quad`'s JSON with `from` replaced by `to` (once, where it must be).
fn broken(from: &str, to: &str) -> String {
    let json = quad(5123).json(None);
    assert!(json.contains(from), "{from} in {json}");
    json.replacen(from, to, 1)
}

#[test]
fn malformed_files_are_refused_saying_what_is_wrong() {
    // Index 2 of the triangles (a u16 at byte 4 of its view) points past the 4 vertices.
    let mut d = quad(5123);
    let last = d.bin.len() - 12 + 4;
    d.bin[last] = 7;
    let err = mesh_of(&d.json(None), None, None).unwrap_err();
    assert!(
        err.contains("primitive 0: index 2 of its indices (accessor 3) is 7, beyond its 4 vertices"),
        "{err}"
    );
    // A NaN position.
    let mut d = quad(5123);
    d.bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = mesh_of(&d.json(None), None, None).unwrap_err();
    assert!(
        err.contains(
            "mesh 0 \"quad\", primitive 0: POSITION element 1 (accessor 0) is [NaN, 0, 0], not finite"
        ),
        "{err}"
    );
    let cases = [
        // More elements than the view holds.
        (r#""count":4,"type":"VEC3","min""#, r#""count":5,"type":"VEC3","min""#, "5 elements of 12 bytes"),
        // A view past its buffer.
        (r#""byteOffset":0,"byteLength":48"#, r#""byteOffset":0,"byteLength":4800"#, "overruns buffer 0"),
        // Lines.
        (r#""indices":3}"#, r#""indices":3,"mode":1}"#, "its mode is LINES: pathwave reads TRIANGLES only"),
        // Indices as floats.
        (r#""componentType":5123"#, r#""componentType":5126"#, "not scalar unsigned integers"),
        // Normals of the wrong count.
        (
            r#""count":4,"type":"VEC3"}"#,
            r#""count":3,"type":"VEC3"}"#,
            "NORMAL (accessor 1) has 3 elements, POSITION 4",
        ),
        // An accessor that is not there.
        (r#""NORMAL":1"#, r#""NORMAL":9"#, "not valid glTF 2.0"),
        // A POSITION accessor that is not there.
        (r#""POSITION":0"#, r#""POSITION":99"#, "POSITION is accessor 99, but there are 4"),
        // A buffer shorter than it says.
        (r#""buffers":[{"byteLength":"#, r#""buffers":[{"byteLength":9"#, "fewer than its byteLength"),
        // An extension pathwave does not read, required.
        (
            r#""asset""#,
            r#""extensionsRequired":["KHR_draco_mesh_compression"],"extensionsUsed":["KHR_draco_mesh_compression"],"asset""#,
            "requires the extension KHR_draco_mesh_compression",
        ),
    ];
    for (from, to, says) in cases {
        let err = mesh_of(&broken(from, to), None, None).unwrap_err();
        assert!(err.contains("t.gltf") && err.contains(says), "{says}: {err}");
    }
}

#[test]
fn the_format_is_told_by_content_then_extension() {
    let json = quad(5123).json(None);
    let format = |bytes: &[u8], name: &str| mesh_format(bytes, Path::new(name));
    assert_eq!(format(json.as_bytes(), "x.obj"), Ok(MeshFormat::Gltf));
    assert_eq!(format(&quad(5123).glb(), "x.mesh"), Ok(MeshFormat::Gltf));
    assert_eq!(format(b"ply\nformat ascii 1.0\n", "x.gltf"), Ok(MeshFormat::Ply));
    assert_eq!(format(b"v 0 0 0\n", "x.obj"), Ok(MeshFormat::Obj));
    let err = format(b"v 0 0 0\n", "x.stl").unwrap_err();
    assert!(err.contains("x.stl") && err.contains("OBJ (.obj), PLY (.ply), glTF 2.0 (.gltf, .glb)"), "{err}");
}

#[test]
fn a_ron_scene_places_a_gltf_mesh() {
    let dir = scratch("ron");
    let mut d = quad(5121);
    let p = d.positions(&[[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]]);
    d.members
        .push(("meshes", format!(r#"{{"name":"tri","primitives":[{{"attributes":{{"POSITION":{p}}}}}]}}"#)));
    std::fs::write(dir.join("m.glb"), d.glb()).unwrap();
    let scene = |mesh: &str| {
        format!(
            r#"Scene(camera: (look_from: (0, 0, 3), look_at: (0, 0, 0), vfov: 40),
               materials: {{"grey": Lambertian(albedo: (0.5, 0.5, 0.5))}},
               objects: [(shape: Mesh(file: "m.glb"{mesh}), material: "grey")])"#
        )
    };
    let path = dir.join("s.ron");
    let load = |mesh: &str| crate::scene::parse(&scene(mesh), &path);
    let desc = load(r#", mesh: "tri""#).unwrap();
    let crate::scene::ShapeDesc::Mesh(m) = &desc.objects[0].shape else { panic!() };
    assert_eq!(m.mesh.triangles.len(), 1);
    let err = load("").unwrap_err().to_string();
    assert!(err.contains("holds 2 meshes") && err.contains("s.ron:3:"), "{err}");
    let err = load(r#", mesh: "tri", shape_index: 1"#).unwrap_err().to_string();
    assert!(err.contains("shape_index 1 picks a mesh of a .serialized file"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A `.gltf` scene in a folder of its own: `quad`'s mesh, and `members` added.
fn scene_file(tag: &str, members: &[(&'static str, &str)]) -> (PathBuf, PathBuf) {
    let dir = scratch(tag);
    let mut d = quad(5123);
    d.members.extend(members.iter().map(|(n, v)| (*n, v.to_string())));
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    (dir, path)
}

fn close(a: glam::Affine3A, b: glam::Affine3A) -> bool {
    a.to_cols_array().iter().zip(b.to_cols_array()).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn the_hierarchy_places_shared_meshes_as_a_hand_written_ron_scene_does() {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // Node 0: T (1, 2, 3), a quarter turn about y, scale 2, holding node 1: a column-major
    // matrix translating by (0, 0, -1), with the mesh. Node 2: the same mesh, at (5, 0, 0).
    let nodes = [
        format!(r#"{{"translation":[1,2,3],"rotation":[0,{h},0,{h}],"scale":[2,2,2],"children":[1]}}"#),
        r#"{"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,-1,1],"mesh":0,"name":"child"}"#.to_owned(),
        r#"{"translation":[5,0,0],"mesh":0}"#.to_owned(),
        r#"{"translation":[0,0,10],"camera":0}"#.to_owned(),
    ];
    let nodes: Vec<(&str, &str)> = nodes.iter().map(|n| ("nodes", n.as_str())).collect();
    let mut members = nodes;
    members.push(("scenes", r#"{"nodes":[0,2,3]}"#));
    members.push((
        "cameras",
        r#"{"type":"perspective","perspective":{"yfov":0.5,"aspectRatio":1.5,"znear":0.1}}"#,
    ));
    let (dir, path) = scene_file("hierarchy", &members);
    let desc = crate::scene::load(&path).unwrap();
    let hand = r#"Scene(camera: (look_from: (0, 0, 1), look_at: (0, 0, 0), vfov: 40),
        materials: {"m": Lambertian(albedo: (0.5, 0.5, 0.5))},
        objects: [
            (shape: Sphere(center: (0, 0, 0), radius: 1), material: "m",
             transform: [Translate((0, 0, -1)), UniformScale(2), RotateY(90), Translate((1, 2, 3))]),
            (shape: Sphere(center: (0, 0, 0), radius: 1), material: "m", transform: [Translate((5, 0, 0))]),
        ])"#;
    let hand = crate::scene::parse(hand, Path::new("hand.ron")).unwrap();
    assert_eq!(desc.objects.len(), 2);
    for (o, h) in desc.objects.iter().zip(&hand.objects) {
        let (a, b) = (crate::scene::compose(&o.transform), crate::scene::compose(&h.transform));
        assert!(close(a, b), "{a:?} != {b:?}");
    }
    // One mesh, two instances.
    let mesh = |i: usize| match &desc.objects[i].shape {
        crate::scene::ShapeDesc::Mesh(m) => m.mesh.clone(),
        _ => panic!("not a mesh"),
    };
    assert!(std::sync::Arc::ptr_eq(&mesh(0), &mesh(1)));
    // The camera at (0, 0, 10) looks along -z, the image's left at -x; 0.5 radians of the
    // height; 1.5 times as wide as high.
    let crate::scene::CameraView::ToWorld { to_world, projection, near_clip, .. } = desc.camera.view else {
        panic!("not a to_world camera")
    };
    assert!(close(
        to_world,
        glam::Affine3A::from_cols(
            -glam::Vec3A::X,
            glam::Vec3A::Y,
            -glam::Vec3A::Z,
            glam::Vec3A::new(0.0, 0.0, 10.0)
        )
    ));
    let crate::scene::Projection::Perspective { fov, fov_axis } = projection else { panic!() };
    assert!((fov - 0.5f32.to_degrees()).abs() < 1e-4 && fov_axis == crate::format::FovAxis::Y);
    assert_eq!((desc.render.width.get(), desc.render.height.get()), (768, 512));
    assert_eq!(near_clip, Some(0.1));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn punctual_lights_are_converted_from_candela_and_lux() {
    use crate::lighting::punctual::LightDesc;
    let s = -std::f32::consts::FRAC_1_SQRT_2;
    let c = std::f32::consts::FRAC_1_SQRT_2;
    let nodes = [
        r#"{"translation":[0,3,0],"extensions":{"KHR_lights_punctual":{"light":0}}}"#.to_owned(),
        format!(r#"{{"rotation":[{s},0,0,{c}],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}}"#),
        r#"{"translation":[1,0,0],"extensions":{"KHR_lights_punctual":{"light":2}}}"#.to_owned(),
        r#"{"mesh":0}"#.to_owned(),
    ];
    let mut members: Vec<(&str, &str)> = nodes.iter().map(|n| ("nodes", n.as_str())).collect();
    members.push(("scenes", r#"{"nodes":[0,1,2,3]}"#));
    members.push(("extensionsUsed", r#"["KHR_lights_punctual"]"#));
    let lights = r#"{"KHR_lights_punctual":{"lights":[
        {"type":"point","color":[1,0.5,0.25],"intensity":1366},
        {"type":"directional","intensity":683},
        {"type":"spot","intensity":68.3,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.4}}]}}"#;
    members.push(("extensions", lights));
    let (dir, path) = scene_file("lights", &members);
    let desc = crate::scene::load(&path).unwrap();
    // A point of I cd: I / 683 W/sr (times its colour); a directional light of E lux:
    // E / 683 W/m^2, along the node's -z.
    let LightDesc::Point(p) = &desc.lights[0] else { panic!() };
    assert_eq!(
        (p.position.0, p.intensity.0),
        (glam::Vec3::new(0.0, 3.0, 0.0), glam::Vec3::new(2.0, 1.0, 0.5))
    );
    let LightDesc::Directional(d) = &desc.lights[1] else { panic!() };
    assert!((d.direction.0 - glam::Vec3::NEG_Y).length() < 1e-6, "{}", d.direction.0);
    assert_eq!(d.irradiance.0, glam::Vec3::ONE);
    let LightDesc::Spot(sp) = &desc.lights[2] else { panic!() };
    assert!((sp.intensity.0 - glam::Vec3::splat(0.1)).abs().max_element() < 1e-7);
    assert_eq!(sp.look_at.0, glam::Vec3::new(1.0, 0.0, -1.0));
    assert!((sp.cone_angle.0 - 0.4f32.to_degrees()).abs() < 1e-4);
    assert!((sp.falloff_start.0 - 0.2f32.to_degrees()).abs() < 1e-4);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn materials_become_the_gltf_brdf_masked_and_emitting() {
    let materials = [
        r#"{"name":"paint","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.2,0.1,1],"metallicFactor":0.3,"roughnessFactor":0.6}}"#,
        r#"{"name":"cut","alphaMode":"MASK","alphaCutoff":0.5,"pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.3]}}"#,
        r#"{"name":"veil","alphaMode":"BLEND","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.25]}}"#,
        r#"{"name":"lamp","emissiveFactor":[1,0.5,0],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}}}"#,
        r#"{"name":"varnish","pbrMetallicRoughness":{"metallicFactor":0,"roughnessFactor":0.5},"extensions":{"KHR_materials_ior":{"ior":1.4},"KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatRoughnessFactor":0.1}}}"#,
        r#"{"name":"glass","pbrMetallicRoughness":{"metallicFactor":0,"roughnessFactor":0},"extensions":{"KHR_materials_transmission":{"transmissionFactor":1}}}"#,
        r#"{"name":"frosted","pbrMetallicRoughness":{"metallicFactor":0,"roughnessFactor":0.2},"extensions":{"KHR_materials_transmission":{"transmissionFactor":1},"KHR_materials_ior":{"ior":1.33}}}"#,
    ];
    let mut members: Vec<(&str, &str)> = materials.iter().map(|m| ("materials", *m)).collect();
    let meshes: Vec<String> = (0..7)
        .map(|m| {
            format!(r#"{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":3,"material":{m}}}]}}"#)
        })
        .collect();
    members.extend(meshes.iter().map(|m| ("meshes", m.as_str())));
    let nodes: Vec<String> = (1..8).map(|m| format!(r#"{{"mesh":{m}}}"#)).collect();
    members.extend(nodes.iter().map(|n| ("nodes", n.as_str())));
    members.push(("scenes", r#"{"nodes":[0,1,2,3,4,5,6]}"#));
    members.push((
        "extensionsUsed",
        r#"["KHR_materials_emissive_strength","KHR_materials_ior","KHR_materials_clearcoat","KHR_materials_transmission"]"#,
    ));
    let (dir, path) = scene_file("materials", &members);
    let ron = super::to_ron(&path, &dir).unwrap().ron;
    for want in [
        r#""paint": MetallicRoughness(base_color: (0.8, 0.2, 0.1), metallic: 0.3, roughness: 0.6),"#,
        r#""varnish": MetallicRoughness(base_color: (1, 1, 1), metallic: 0, roughness: 0.5, ior: 1.4, clearcoat: 1, clearcoat_roughness: 0.1),"#,
        // Smooth clear glass: the smooth dielectric.
        r#""glass": Dielectric(ior: 1.5),"#,
        r#""frosted": Principled(base_color: (1, 1, 1), metallic: 0, roughness: 0.2, eta: 1.33, spec_trans: 1),"#,
        r#""cut": Mask(opacity: 0, material: "cut (opaque)"),"#,
        r#""veil": Mask(opacity: 0.25, material: "veil (opaque)"),"#,
        r#"material: "lamp", emit: (radiance: (4, 2, 0), two_sided: false)"#,
    ] {
        assert!(ron.contains(want), "{want} in\n{ron}");
    }
    let desc = crate::scene::load(&path).unwrap();
    assert_eq!(desc.objects.len(), 7);
    let emit = desc.objects[3].emit.as_ref().unwrap();
    assert_eq!(
        emit.radiance,
        crate::format::Color::Value(crate::format::Radiance(glam::Vec3::new(4.0, 2.0, 0.0)))
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn textures_map_with_their_transform_and_normal_maps_wrap() {
    let dir = scratch("texture");
    ::image::RgbImage::from_pixel(2, 2, ::image::Rgb([200, 100, 50])).save(dir.join("t.png")).unwrap();
    let mut d = quad(5123);
    d.members.push(("images", r#"{"uri":"t.png"}"#.into()));
    d.members.push(("textures", r#"{"source":0}"#.into()));
    d.members.push((
        "materials",
        r#"{"normalTexture":{"index":0},"pbrMetallicRoughness":{"baseColorTexture":{"index":0,"extensions":{"KHR_texture_transform":{"offset":[0.5,0],"scale":[2,2]}}}}}"#.into(),
    ));
    d.members[0].1 = d.members[0].1.replace(r#""indices":3}"#, r#""indices":3,"material":0}"#);
    d.members.push(("nodes", r#"{"mesh":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0]}"#.into()));
    d.members.push(("extensionsUsed", r#"["KHR_texture_transform"]"#.into()));
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    let ron = super::to_ron(&path, &dir).unwrap().ron;
    // glTF's (u, v) -> (2 u + 0.5, 2 v) with v = 1 - pathwave's v: pathwave's (u, v) ->
    // (2 u + 0.5, 2 v - 1).
    let want =
        r#"Image(file: "t.png", wrap: Repeat, filter: Bilinear, uv_transform: ((2, 0, 0.5), (0, 2, -1)))"#;
    assert!(ron.contains(want), "{want} in\n{ron}");
    // The normal map: the same image, raw, around the material.
    for want in [
        r#""texture 0 raw": Image(file: "t.png", wrap: Repeat, filter: Bilinear, raw: true),"#,
        r#""material 0": NormalMap(texture: "texture 0 raw", material: "material 0 (surface)"),"#,
    ] {
        assert!(ron.contains(want), "{want} in\n{ron}");
    }
    crate::scene::load(&path).unwrap();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_broken_hierarchy_is_refused() {
    let members = [
        ("nodes", r#"{"children":[1]}"#),
        ("nodes", r#"{"children":[0],"mesh":0}"#),
        ("scenes", r#"{"nodes":[0]}"#),
    ];
    let (dir, path) = scene_file("cycle", &members);
    let err = crate::scene::load(&path).unwrap_err().to_string();
    assert!(err.contains("s.gltf") && err.contains("nodes[0] is met twice"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn images_inside_a_glb_or_a_data_uri_are_read() {
    use base64::Engine;
    let png = |rgb: [u8; 3]| {
        let mut out = std::io::Cursor::new(Vec::new());
        let img =
            ::image::RgbImage::from_fn(2, 1, |x, _| ::image::Rgb(if x == 0 { rgb } else { [0, 0, 255] }));
        img.write_to(&mut out, ::image::ImageFormat::Png).unwrap();
        out.into_inner()
    };
    let (red, green) = (png([255, 0, 0]), png([0, 255, 0]));
    let mut d = quad(5123);
    let v = d.view(&red);
    d.members.push(("images", format!(r#"{{"bufferView":{v},"mimeType":"image/png"}}"#)));
    let uri = base64::engine::general_purpose::STANDARD.encode(&green);
    d.members.push(("images", format!(r#"{{"uri":"data:image/png;base64,{uri}"}}"#)));
    d.members.push(("textures", r#"{"source":0}"#.into()));
    d.members.push(("textures", r#"{"source":1}"#.into()));
    d.members.push((
        "materials",
        r#"{"normalTexture":{"index":1},"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}"#.into(),
    ));
    d.members[0].1 = d.members[0].1.replace(r#""indices":3}"#, r#""indices":3,"material":0}"#);
    d.members.push(("nodes", r#"{"mesh":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0]}"#.into()));
    let dir = scratch("embedded");
    let path = dir.join("s.glb");
    std::fs::write(&path, d.glb()).unwrap();
    let ron = super::to_ron(&path, &dir).unwrap().ron;
    for want in [
        r#""texture 0": GltfImage(file: "s.glb", image: 0, wrap: Repeat, filter: Bilinear),"#,
        r#""texture 1 raw": GltfImage(file: "s.glb", image: 1, wrap: Repeat, filter: Bilinear, raw: true),"#,
    ] {
        assert!(ron.contains(want), "{want} in\n{ron}");
    }
    let desc = crate::scene::load(&path).unwrap();
    let decoded = |bytes: Vec<u8>, raw: bool| {
        let t = crate::texture::TextureImage::from_image(
            ::image::load_from_memory(&bytes).unwrap(),
            Path::new("x"),
        )
        .unwrap();
        if raw { t.undecoded() } else { t }
    };
    let textures: Vec<_> = desc.textures.0.iter().map(|(_, t)| t.clone()).collect();
    let [crate::texture::TextureDesc::GltfImage(a), crate::texture::TextureDesc::GltfImage(b)] =
        &textures[..]
    else {
        panic!("{textures:?}")
    };
    assert_eq!(*a.texels, decoded(red, false));
    assert_eq!(*b.texels, decoded(green, true));
    // An image that is not there.
    let err = crate::scene::parse(
        r#"Scene(camera: (look_from: (0, 0, 1), look_at: (0, 0, 0), vfov: 40), textures: {"t": GltfImage(file: "s.glb", image: 5)}, materials: {}, objects: [])"#,
        &dir.join("x.ron"),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("image 5: there is no such image (it has 2)"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Found by the `gltf` fuzz target: the `gltf` crate's `Image::source` and `Camera::projection`
/// panicked on an image with a bufferView and no mimeType or with no source at all, and on a
/// camera whose type's object is missing.
#[test]
fn images_without_a_source_and_cameras_without_their_projection_do_not_panic() {
    let mut d = quad(5123);
    d.members.push(("images", r#"{"bufferView":0}"#.into()));
    d.members.push(("images", r#"{"name":"nothing"}"#.into()));
    let file = GltfFile::new(d.json(None).as_bytes(), Path::new("t.gltf")).unwrap();
    assert_eq!(file.image_bytes(0, Path::new("t.gltf")).unwrap().len(), 48);
    let err = file.image_bytes(1, Path::new("t.gltf")).unwrap_err();
    assert!(err.contains("image 1: it has neither a bufferView nor a uri"), "{err}");
    let members = [
        ("cameras", r#"{"type":"perspective","orthographic":{"xmag":1,"ymag":1,"znear":0,"zfar":1}}"#),
        ("nodes", r#"{"camera":0}"#),
        ("scenes", r#"{"nodes":[0]}"#),
    ];
    let (dir, path) = scene_file("camera", &members);
    let err = crate::scene::load(&path).unwrap_err().to_string();
    assert!(err.contains("cameras[0]: its `type` names a projection whose object it lacks"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn node_animations_become_keyframe_tracks() {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let mut d = quad(5123);
    // Node 0 (a root) moves from (0, 0, 0) to (2, 0, 0) over a second, linearly, and turns a
    // quarter about y at 1 s (a step); node 1, its child at (1, 0, 0), holds the mesh.
    let times = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let moves = d.floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0], "VEC3", 3);
    let turns = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, h, 0.0, h], "VEC4", 4);
    d.members.push((
        "animations",
        format!(
            r#"{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}},{{"sampler":1,"target":{{"node":0,"path":"rotation"}}}}],
               "samplers":[{{"input":{times},"output":{moves}}},{{"input":{times},"output":{turns},"interpolation":"STEP"}}]}}"#
        ),
    ));
    // Its rest translation, which the keys replace.
    d.members.push(("nodes", r#"{"translation":[5,5,5],"children":[1]}"#.into()));
    d.members.push(("nodes", r#"{"translation":[1,0,0],"mesh":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0]}"#.into()));
    let dir = scratch("animation");
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    let desc = crate::scene::load(&path).unwrap();
    assert_eq!(desc.animation.frames.get(), 25);
    let o = &desc.objects[0];
    let at = |t: f32| o.animate.as_ref().unwrap().at(t) * crate::scene::compose(&o.transform);
    let origin = |t: f32| at(t).transform_point3(glam::Vec3::ZERO);
    // Half way: moved by (1, 0, 0), not turned; just before 1 s, still not turned; at 1 s the
    // child's (1, 0, 0) turned to (0, 0, -1).
    for (t, want) in [(0.5, (2.0, 0.0, 0.0)), (0.999, (2.998, 0.0, 0.0)), (1.0, (2.0, 0.0, -1.0))] {
        let got = origin(t);
        assert!((got - glam::Vec3::from(want)).length() < 1e-5, "at {t}: {got}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A camera node that a translation and a rotation channel move: its eye and its view at each
/// frame are the node's as glTF interpolates it (linear and slerp; a cubic-spline channel
/// through its tangents). Checked against the path in closed form. (Keyed at the two key times
/// alone, the target's linear keys miss the slerp at 0.25 s by 0.22; reading the cubic
/// spline's values without its tangents misses by 1 at 0.5 s: both fail.)
#[test]
fn a_moving_camera_follows_its_node() {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let mut d = quad(5123);
    // Node 0 holds the camera: from (0, 0, 5) to (2, 0, 5) in a second, turning a quarter
    // about y (from looking along -z to looking along -x); then its position a cubic spline
    // from 0 (out-tangent (0, 4, 0)) to 0 (in-tangent (0, -4, 0)): y(s) = 4 s (1 - s).
    let times = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let moves = d.floats(&[0.0, 0.0, 5.0, 2.0, 0.0, 5.0], "VEC3", 3);
    let turns = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, h, 0.0, h], "VEC4", 4);
    d.members.push((
        "animations",
        format!(
            r#"{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"translation"}}}},{{"sampler":1,"target":{{"node":1,"path":"rotation"}}}}],
               "samplers":[{{"input":{times},"output":{moves}}},{{"input":{times},"output":{turns}}}]}}"#
        ),
    ));
    d.members.push(("nodes", r#"{"mesh":0}"#.into()));
    d.members.push(("nodes", r#"{"translation":[9,9,9],"camera":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0,1]}"#.into()));
    d.members.push(("cameras", r#"{"type":"perspective","perspective":{"yfov":0.5,"znear":0.1}}"#.into()));
    let dir = scratch("moving-camera");
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    let desc = crate::scene::load(&path).unwrap();
    let crate::scene::CameraView::LookAt { look_from, look_at, vup, vfov } = desc.camera.view else {
        panic!("not a look_at camera")
    };
    assert_eq!(
        (look_from, look_at, vup),
        (glam::Vec3::new(0.0, 0.0, 5.0), glam::Vec3::new(0.0, 0.0, 4.0), glam::Vec3::Y)
    );
    assert!((vfov - 0.5f32.to_degrees()).abs() < 1e-4);
    let keys = &desc.animation.camera;
    let (from, to) = (keys.look_from.as_ref().unwrap(), keys.look_at.as_ref().unwrap());
    for frame in [0, 6, 12, 18, 24] {
        let t = frame as f32 / 24.0;
        let angle = std::f32::consts::FRAC_PI_2 * t;
        let eye = glam::Vec3::new(2.0 * t, 0.0, 5.0);
        let ahead = glam::Vec3::new(-angle.sin(), 0.0, -angle.cos());
        assert!((from.at(t) - eye).length() < 1e-5, "frame {frame}: eye {}", from.at(t));
        assert!((to.at(t) - (eye + ahead)).length() < 1e-5, "frame {frame}: target {}", to.at(t));
    }
    // The height as a cubic spline (in-tangent, value, out-tangent per key).
    let spline = d.floats(
        &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, -4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "VEC3",
        3,
    );
    let json = d.json(None).replace(
        &format!(r#"{{"input":{times},"output":{moves}}}"#),
        &format!(r#"{{"input":{times},"output":{spline},"interpolation":"CUBICSPLINE"}}"#),
    );
    std::fs::write(&path, json).unwrap();
    let desc = crate::scene::load(&path).unwrap();
    let from = desc.animation.camera.look_from.unwrap();
    for s in [0.25f32, 0.5, 0.75] {
        let y = 4.0 * s * (1.0 - s);
        assert!((from.at(s) - glam::Vec3::new(0.0, y, 0.0)).length() < 1e-5, "at {s}: {}", from.at(s));
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Found by the `gltf` fuzz target: the `gltf` crate unwraps a channel's path, which its
/// validation lets through when it does not know the name, and its node, which it lets through
/// past the last.
#[test]
fn a_channel_of_an_unknown_path_is_passed_over_and_one_of_no_node_refused() {
    let mut d = quad(5123);
    let times = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let moves = d.floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0], "VEC3", 3);
    d.members.push((
        "animations",
        format!(
            r#"{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"rtanslation"}}}}],"samplers":[{{"input":{times},"output":{moves}}}]}}"#
        ),
    ));
    d.members.push(("nodes", r#"{"mesh":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0]}"#.into()));
    let dir = scratch("bad-channel");
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    let desc = crate::scene::load(&path).unwrap();
    assert!(desc.objects[0].animate.is_none());
    let json = d.json(None).replace(r#""node":0,"path":"rtanslation""#, r#""node":7,"path":"translation""#);
    std::fs::write(&path, json).unwrap();
    let err = crate::scene::load(&path).unwrap_err().to_string();
    assert!(err.contains("animations[0] channel 0: its target is node 7, but there are 1"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Found by the `gltf` fuzz target: a key at 3e38 s overflowed the frame count.
#[test]
fn a_key_at_the_end_of_time_gives_as_many_frames_as_there_can_be() {
    let mut d = quad(5123);
    let times = d.floats(&[0.0, 3e38], "SCALAR", 1);
    let moves = d.floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0], "VEC3", 3);
    d.members.push((
        "animations",
        format!(
            r#"{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}}],"samplers":[{{"input":{times},"output":{moves}}}]}}"#
        ),
    ));
    d.members.push(("nodes", r#"{"mesh":0}"#.into()));
    d.members.push(("scenes", r#"{"nodes":[0]}"#.into()));
    let dir = scratch("end-of-time");
    let path = dir.join("s.gltf");
    std::fs::write(&path, d.json(None)).unwrap();
    assert_eq!(crate::scene::load(&path).unwrap().animation.frames.get(), u32::MAX);
    std::fs::remove_dir_all(dir).unwrap();
}
