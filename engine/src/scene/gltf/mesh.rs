//! A glTF mesh as pathwave's [`MeshData`]: its triangles primitives' positions, normals,
//! first texture coordinates and indices (of any of the three index types), in the mesh's own
//! space (a node's transform is the scene's business). Every value is checked: positions,
//! normals and uv finite, attribute counts equal, indices in range and whole triangles. What
//! is not read (tangents, colours, other uv sets, skin weights, morph targets) is warned about
//! by name; modes other than TRIANGLES are refused.
//!
//! glTF's uv has v running down an image (its origin is the image's top left), pathwave's v
//! runs up (an image's row 0 is v = 1): v is read as 1 - v.

use crate::accel::mesh::MeshData;
use crate::format::gltf::{GltfFile, name};
use glam::{Vec2, Vec3A};
use gltf::Semantic;
use gltf::accessor::Dimensions;
use gltf::mesh::Mode;
use serde::{Deserialize, Deserializer};
use std::path::Path;

/// Which mesh of a glTF file: `"name"` or its index, `3`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MeshRef {
    /// By its `name`.
    Name(String),
    /// By its index in the file's `meshes`.
    Index(u32),
}

impl<'de> Deserialize<'de> for MeshRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = MeshRef;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a mesh's name or its index in the file")
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<MeshRef, E> {
                Ok(MeshRef::Name(s.to_owned()))
            }
            fn visit_u64<E: serde::de::Error>(self, i: u64) -> Result<MeshRef, E> {
                u32::try_from(i)
                    .map(MeshRef::Index)
                    .map_err(|_| E::custom(format!("mesh index {i} is too large")))
            }
            fn visit_i64<E: serde::de::Error>(self, i: i64) -> Result<MeshRef, E> {
                match u64::try_from(i) {
                    Ok(i) => self.visit_u64(i),
                    Err(_) => Err(E::custom(format!("expected a mesh index >= 0, found {i}"))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl std::fmt::Display for MeshRef {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            MeshRef::Name(n) => write!(f, "{n:?}"),
            MeshRef::Index(i) => write!(f, "{i}"),
        }
    }
}

/// A mesh as a message names it: `mesh 2 "Cube"`.
pub fn mesh_name(m: &gltf::Mesh) -> String {
    format!("mesh {}{}", m.index(), name(m.name()))
}

impl GltfFile {
    /// The mesh `which` names; without a name, the file's one mesh. `path` names the file in
    /// errors.
    pub fn pick_mesh(&self, which: Option<&MeshRef>, path: &Path) -> Result<gltf::Mesh<'_>, String> {
        let list = || {
            let names: Vec<String> = self
                .doc
                .meshes()
                .map(|m| m.name().map_or(format!("{}", m.index()), |n| format!("{n:?}")))
                .collect();
            match names.is_empty() {
                true => "it has none".to_owned(),
                false => format!("it has {}", names.join(", ")),
            }
        };
        let found = match which {
            None if self.doc.meshes().len() == 1 => self.doc.meshes().next(),
            None => {
                return Err(format!(
                    "the glTF file {} holds {} meshes: say which with `mesh: \"name\"` ({})",
                    path.display(),
                    self.doc.meshes().len(),
                    list()
                ));
            }
            Some(MeshRef::Index(i)) => self.doc.meshes().nth(*i as usize),
            Some(MeshRef::Name(n)) => {
                let mut named = self.doc.meshes().filter(|m| m.name() == Some(n.as_str()));
                match (named.next(), named.next()) {
                    (Some(_), Some(_)) => {
                        return Err(format!(
                            "the glTF file {} has several meshes named {n:?}: give its index instead",
                            path.display()
                        ));
                    }
                    (m, _) => m,
                }
            }
        };
        found.ok_or_else(|| {
            format!("the glTF file {} has no mesh {} ({})", path.display(), which.unwrap(), list())
        })
    }

    /// Mesh `which` (see [`Self::pick_mesh`]) as pathwave's mesh: all its primitives, or only
    /// primitive `primitive`.
    pub fn mesh_data(
        &self,
        which: Option<&MeshRef>,
        primitive: Option<u32>,
        path: &Path,
    ) -> Result<MeshData, String> {
        let mesh = self.pick_mesh(which, path)?;
        let at = format!("the glTF file {}: {}", path.display(), mesh_name(&mesh));
        let count = mesh.primitives().len();
        let chosen: Vec<gltf::Primitive> = match primitive {
            None => mesh.primitives().collect(),
            Some(p) => match mesh.primitives().nth(p as usize) {
                Some(p) => vec![p],
                None => return Err(format!("{at} has no primitive {p} (it has {count})")),
            },
        };
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let (mut normals, mut uvs) = (Some(Vec::new()), Some(Vec::new()));
        for p in chosen {
            let at = format!("{at}, primitive {}", p.index());
            let part = self.primitive(&p, &at)?;
            let base = u32::try_from(positions.len())
                .ok()
                .filter(|b| b.checked_add(part.positions.len() as u32).is_some())
                .ok_or_else(|| format!("{at}: the mesh has more than 2^32 vertices"))?;
            positions.extend(part.positions);
            triangles.extend(part.triangles.into_iter().map(|t| t.map(|i| base + i)));
            match (&mut normals, part.normals) {
                (Some(n), Some(p)) => n.extend(p),
                _ => normals = None,
            }
            match (&mut uvs, part.uvs) {
                (Some(u), Some(p)) => u.extend(p),
                _ => uvs = None,
            }
        }
        super::super::assets::finish_mesh(positions, triangles, normals, uvs, Vec::new(), path)
    }

    /// One primitive, checked; `at` names it in errors and warnings.
    fn primitive(&self, p: &gltf::Primitive, at: &str) -> Result<Part, String> {
        if p.mode() != Mode::Triangles {
            return Err(format!(
                "{at}: its mode is {}: pathwave reads TRIANGLES only",
                match p.mode() {
                    Mode::Points => "POINTS",
                    Mode::Lines => "LINES",
                    Mode::LineLoop => "LINE_LOOP",
                    Mode::LineStrip => "LINE_STRIP",
                    Mode::TriangleStrip => "TRIANGLE_STRIP",
                    Mode::TriangleFan => "TRIANGLE_FAN",
                    Mode::Triangles => unreachable!(),
                }
            ));
        }
        let Some(pos) = p.get(&Semantic::Positions) else {
            return Err(format!("{at}: it has no POSITION"));
        };
        let positions: Vec<Vec3A> =
            vec3s(self.floats(&pos, Dimensions::Vec3, false, &format!("{at}: POSITION"))?);
        finite(&positions, |v| v.is_finite(), at, "POSITION", &pos)?;
        let n = positions.len();
        let same_count = |a: &gltf::Accessor, what: &str| match a.count() == n {
            true => Ok(()),
            false => {
                Err(format!("{at}: {what} (accessor {}) has {} elements, POSITION {n}", a.index(), a.count()))
            }
        };
        let normals = match p.get(&Semantic::Normals) {
            None => None,
            Some(a) => {
                same_count(&a, "NORMAL")?;
                let v = vec3s(self.floats(&a, Dimensions::Vec3, true, &format!("{at}: NORMAL"))?);
                finite(&v, |v| v.is_finite(), at, "NORMAL", &a)?;
                Some(v)
            }
        };
        let uvs = match p.get(&Semantic::TexCoords(0)) {
            None => None,
            Some(a) => {
                same_count(&a, "TEXCOORD_0")?;
                let f = self.floats(&a, Dimensions::Vec2, true, &format!("{at}: TEXCOORD_0"))?;
                let v: Vec<Vec2> = f.chunks_exact(2).map(|c| Vec2::new(c[0], 1.0 - c[1])).collect();
                finite(&v, |v| v.is_finite(), at, "TEXCOORD_0", &a)?;
                Some(v)
            }
        };
        let triangles = match p.indices() {
            Some(a) => {
                let idx = self.indices(&a, &format!("{at}: indices"))?;
                if let Some((k, i)) = idx.iter().enumerate().find(|(_, i)| **i as usize >= n) {
                    return Err(format!(
                        "{at}: index {k} of its indices (accessor {}) is {i}, beyond its {n} vertices",
                        a.index()
                    ));
                }
                if !idx.len().is_multiple_of(3) {
                    return Err(format!(
                        "{at}: it has {} indices (accessor {}), not a whole number of triangles",
                        idx.len(),
                        a.index()
                    ));
                }
                idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
            }
            None if n.is_multiple_of(3) => (0..n as u32).step_by(3).map(|i| [i, i + 1, i + 2]).collect(),
            None => {
                return Err(format!(
                    "{at}: it has no indices and {n} vertices, not a whole number of triangles"
                ));
            }
        };
        let unread: Vec<String> = p
            .attributes()
            .map(|(s, _)| s)
            .filter(|s| !matches!(s, Semantic::Positions | Semantic::Normals | Semantic::TexCoords(0)))
            .map(|s| match s {
                Semantic::Extras(name) => format!("_{name}"),
                s => s.to_string(),
            })
            .collect();
        if !unread.is_empty() {
            tracing::warn!("{at}: the attributes {} are not read", unread.join(", "));
        }
        if p.morph_targets().len() > 0 {
            tracing::warn!(
                "{at}: its {} morph targets are not read (the mesh keeps its base shape)",
                p.morph_targets().len()
            );
        }
        Ok(Part { positions, triangles, normals, uvs })
    }
}

/// A primitive's vertices and triangles.
struct Part {
    positions: Vec<Vec3A>,
    triangles: Vec<[u32; 3]>,
    normals: Option<Vec<Vec3A>>,
    uvs: Option<Vec<Vec2>>,
}

fn vec3s(f: Vec<f32>) -> Vec<Vec3A> {
    f.chunks_exact(3).map(|c| Vec3A::new(c[0], c[1], c[2])).collect()
}

/// Refuses the first element of `values` (accessor `a`'s, for `what`) that is not finite.
fn finite<T: std::fmt::Display>(
    values: &[T],
    ok: impl Fn(&T) -> bool,
    at: &str,
    what: &str,
    a: &gltf::Accessor,
) -> Result<(), String> {
    match values.iter().position(|v| !ok(v)) {
        None => Ok(()),
        Some(i) => {
            Err(format!("{at}: {what} element {i} (accessor {}) is {}, not finite", a.index(), values[i]))
        }
    }
}
