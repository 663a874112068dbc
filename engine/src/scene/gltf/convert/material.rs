//! glTF materials as RON: metallic-roughness materials as `MetallicRoughness` (the
//! specification's BRDF; `Principled` where they transmit, `Dielectric` for smooth clear
//! glass), with `Mask` for the alpha modes
//! MASK and BLEND, `NormalMap` for normal textures and `emit` for emissive ones; textures as
//! `Image` (an image file beside the glTF) or `GltfImage` (one inside it), with
//! `KHR_texture_transform` as a `uv_transform`.
//!
//! Emission: `emissiveFactor` times `KHR_materials_emissive_strength` is the emitted radiance,
//! as Blender's importer sets its emission colour and strength, on the front side (both for
//! `doubleSided` materials).

use super::{Converter, file_name, num, rgb};
use crate::format::gltf::{ImageAt, name, uri_path};
use crate::material::microfacet::SMOOTH_ALPHA;
use glam::Vec3;
use gltf::material::AlphaMode;
use std::fmt::Write;
use std::path::Path;

impl Converter<'_> {
    /// The RON material of glTF material `m` (made on its first use) and the `emit` of the
    /// objects that have it.
    pub(super) fn material(&mut self, m: gltf::Material, path: &Path) -> (String, Option<String>) {
        if let Some(done) = self.material_names.get(&m.index()) {
            return done.clone();
        }
        let at = match m.index() {
            Some(i) => format!("materials[{i}]{}", name(m.name())),
            None => "the default material".to_owned(),
        };
        let warn = |what: String| tracing::warn!("{}: {at}: {what}", path.display());
        let base_name = match (m.index(), m.name()) {
            (None, _) => "glTF default".to_owned(),
            (Some(_), Some(n)) if self.file.doc.materials().filter(|o| o.name() == Some(n)).count() == 1 => {
                n.to_owned()
            }
            (Some(i), n) => format!("{} {i}", n.unwrap_or("material")),
        };
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let mut fields = String::new();
        let base_texture =
            pbr.base_color_texture().and_then(|t| self.texture(&t, "baseColorTexture", &at, path));
        match &base_texture {
            Some(t) => {
                if [r, g, b] != [1.0; 3] {
                    warn(format!(
                        "its baseColorFactor ({r}, {g}, {b}) times its texture: pathwave takes the texture alone"
                    ));
                }
                write!(fields, "base_color: {t:?}").unwrap();
            }
            None => write!(fields, "base_color: {}", rgb([r, g, b])).unwrap(),
        }
        write!(
            fields,
            ", metallic: {}, roughness: {}",
            num(pbr.metallic_factor()),
            num(pbr.roughness_factor())
        )
        .unwrap();
        if pbr.metallic_roughness_texture().is_some() {
            warn("its metallicRoughnessTexture is not read (pathwave's textured numbers take no channel): its factors are".into());
        }
        // Opaque: the glTF BRDF itself; transmitting: the principled BSDF's refraction.
        let transmission = m.transmission().filter(|t| t.transmission_factor() > 0.0);
        let ior = m.ior().filter(|i| *i != 1.5);
        let coat = m.extension_value("KHR_materials_clearcoat");
        let kind = if let Some(t) = &transmission {
            if let Some(ior) = ior {
                write!(fields, ", eta: {}", num(ior)).unwrap();
            }
            write!(fields, ", spec_trans: {}", num(t.transmission_factor())).unwrap();
            if t.transmission_texture().is_some() {
                warn("its transmissionTexture is not read: its transmissionFactor is".into());
            }
            if coat.is_some() {
                warn("it transmits: its KHR_materials_clearcoat is not read".into());
            }
            "Principled"
        } else {
            if let Some(ior) = ior {
                write!(fields, ", ior: {}", num(ior)).unwrap();
            }
            if let Some(coat) = coat {
                for (key, field) in
                    [("clearcoatFactor", "clearcoat"), ("clearcoatRoughnessFactor", "clearcoat_roughness")]
                {
                    let Some(v) = coat.get(key).and_then(|v| v.as_f64()) else { continue };
                    let clamped = v.clamp(0.0, 1.0);
                    if clamped != v {
                        warn(format!("its {key} {v} is not in [0, 1]: {clamped} is used"));
                    }
                    write!(fields, ", {field}: {}", num(clamped as f32)).unwrap();
                }
                if ["clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"]
                    .iter()
                    .any(|k| coat.get(*k).is_some())
                {
                    warn("its clear coat's textures are not read: its factors are".into());
                }
            }
            "MetallicRoughness"
        };
        if m.occlusion_texture().is_some() {
            warn("its occlusionTexture is not read (the path tracer finds occlusion)".into());
        }
        let normal_map = m.normal_texture().and_then(|n| {
            if n.scale() != 1.0 {
                warn(format!(
                    "its normalTexture's scale {} is not read: the map's normals are used",
                    n.scale()
                ));
            }
            if n.extension_value("KHR_texture_transform").is_some() {
                warn(
                    "its normalTexture's KHR_texture_transform is not read: the map is read untransformed"
                        .into(),
                );
            }
            self.image_texture(n.texture(), n.tex_coord(), String::new(), true, "normalTexture", &at, path)
        });
        // Clear glass as smooth as a mirror (GGX width `roughness^2` below `SMOOTH_ALPHA`,
        // where every rough material of pathwave is smooth): the smooth dielectric that the
        // principled BSDF's transmission tends to. Cycles renders such glass by a delta lobe
        // too; the principled BSDF's narrowest lobe (width `SMOOTH_ALPHA`) would reach a delta
        // sun through it as glints and caustics that neither the specification's smooth
        // surface nor Cycles shows.
        let smooth_glass = transmission.as_ref().is_some_and(|t| t.transmission_factor() == 1.0)
            && pbr.metallic_factor() == 0.0
            && pbr.roughness_factor().powi(2) < SMOOTH_ALPHA
            && pbr.metallic_roughness_texture().is_none()
            && base_texture.is_none()
            && [r, g, b] == [1.0; 3];
        let plain = match smooth_glass {
            true => format!("Dielectric(ior: {})", num(ior.unwrap_or(1.5))),
            false => format!("{kind}({fields})"),
        };
        let opacity = match m.alpha_mode() {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                if base_texture.is_some() {
                    warn("alpha mode MASK: its texture's alpha is not read (pathwave's textures are RGB): the factor's is".into());
                }
                if alpha >= cutoff { 1.0 } else { 0.0 }
            }
            AlphaMode::Blend => {
                if base_texture.is_some() {
                    warn("alpha mode BLEND: its texture's alpha is not read (pathwave's textures are RGB): the factor's is".into());
                }
                alpha
            }
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let factor = Vec3::from(m.emissive_factor()) * strength;
        let emissive_texture =
            m.emissive_texture().and_then(|t| self.texture(&t, "emissiveTexture", &at, path));
        let radiance = match emissive_texture {
            Some(t) if factor == Vec3::ONE => Some(format!("{t:?}")),
            Some(_) if factor == Vec3::ZERO => None,
            Some(_) => {
                warn(format!(
                    "its emissive factor times strength {factor} times its texture: pathwave takes the factor alone"
                ));
                Some(rgb(factor.to_array()))
            }
            None if factor == Vec3::ZERO => None,
            None => Some(rgb(factor.to_array())),
        };
        let emit = radiance.map(|r| format!("(radiance: {r}, two_sided: {})", m.double_sided()));
        // A normal map wraps the material, as Mask does: a wrapper does not emit.
        let plain = match normal_map {
            Some(_) if emit.is_some() => {
                warn(
                    "it emits: its normalTexture is not read (pathwave's `emit` is for plain materials)"
                        .into(),
                );
                plain
            }
            Some(t) => {
                let surface = format!("{base_name} (surface)");
                self.materials.push((surface.clone(), (plain, at.clone())));
                format!("NormalMap(texture: {t:?}, material: {surface:?})")
            }
            None => plain,
        };
        let (ron_name, emit) = if opacity < 1.0 {
            let inner = format!("{base_name} (opaque)");
            self.materials.push((inner.clone(), (plain, at.clone())));
            let mask = format!("Mask(opacity: {}, material: {inner:?})", num(opacity));
            self.materials.push((base_name.clone(), (mask, at.clone())));
            if emit.is_some() {
                warn("it emits and is not opaque: pathwave's `emit` is for opaque materials, so it does not emit".into());
            }
            (base_name, None)
        } else {
            self.materials.push((base_name.clone(), (plain, at.clone())));
            (base_name, emit)
        };
        self.material_names.insert(m.index(), (ron_name.clone(), emit.clone()));
        (ron_name, emit)
    }

    /// The name of the RON texture for texture `info` (`what` of material `at`; sRGB), made
    /// on its first use; `None` (warned about) for one pathwave cannot read.
    fn texture(&mut self, info: &gltf::texture::Info, what: &str, at: &str, path: &Path) -> Option<String> {
        let transform = info.texture_transform();
        let set = transform.as_ref().and_then(|x| x.tex_coord()).unwrap_or(info.tex_coord());
        let uv = transform.map(|x| uv_transform(x.offset(), x.rotation(), x.scale())).unwrap_or_default();
        self.image_texture(info.texture(), set, uv, false, what, at, path)
    }

    /// [`Self::texture`] of texture `t` read through uv set `set` and the `uv_transform` `uv`
    /// (empty for none), its 8-bit values raw (a normal map) or sRGB.
    #[expect(clippy::too_many_arguments, reason = "what it reads, and where it is for messages")]
    fn image_texture(
        &mut self,
        t: gltf::Texture,
        set: u32,
        uv: String,
        raw: bool,
        what: &str,
        at: &str,
        path: &Path,
    ) -> Option<String> {
        let warn =
            |m: String| tracing::warn!("{}: {at}: {what} (textures[{}]): {m}", path.display(), t.index());
        if set != 0 {
            warn(format!("it reads TEXCOORD_{set}, which pathwave does not read: TEXCOORD_0 is used"));
        }
        let key = (t.index(), uv.clone(), raw);
        if let Some(done) = self.texture_names.get(&key) {
            return done.clone();
        }
        // The texture's source (validated as an index of the document's images).
        let image = t.source().index();
        // An image file beside the glTF is an `Image`; one inside it a `GltfImage`.
        let source = match self.file.image_at(image) {
            Ok(ImageAt::Uri(uri)) if !uri.starts_with("data:") => uri_path(uri)
                .map(|p| format!("Image(file: {}", file_name(&self.file.dir.join(p), self.base)))
                .map_err(|m| warn(format!("{m}: it is not read"))),
            Ok(_) => Ok(format!("GltfImage(file: {}, image: {image}", self.file_name)),
            Err(m) => {
                warn(format!("image {image}: {m}: it is not read"));
                Err(())
            }
        };
        let named = source.ok().map(|source| {
            let sampler = t.sampler();
            use gltf::texture::{MagFilter, WrappingMode};
            let wrap = |w: WrappingMode| match w {
                WrappingMode::Repeat => "Repeat",
                WrappingMode::ClampToEdge => "Clamp",
                WrappingMode::MirroredRepeat => "Mirror",
            };
            if sampler.wrap_s() != sampler.wrap_t() {
                warn(format!(
                    "it wraps s ({}) and t ({}) differently: pathwave wraps both as s",
                    wrap(sampler.wrap_s()),
                    wrap(sampler.wrap_t())
                ));
            }
            let filter = match sampler.mag_filter() {
                Some(MagFilter::Nearest) => "Nearest",
                _ => "Bilinear",
            };
            let mut ron = format!("{source}, wrap: {}, filter: {filter}", wrap(sampler.wrap_s()));
            if raw {
                ron.push_str(", raw: true");
            }
            if !uv.is_empty() {
                write!(ron, ", uv_transform: {uv}").unwrap();
            }
            ron.push(')');
            let name = format!(
                "texture {}{}{}",
                t.index(),
                if raw { " raw" } else { "" },
                if uv.is_empty() { String::new() } else { format!(" {}", self.textures.len()) }
            );
            self.textures.push((name.clone(), (ron, format!("{at}, textures[{}]", t.index()))));
            name
        });
        self.texture_names.insert(key, named.clone());
        named
    }
}

/// `KHR_texture_transform` as pathwave's `uv_transform` (empty for none): glTF's uv' = T R S uv
/// (the spec's matrices) in glTF's uv, whose v is pathwave's 1 - v, so pathwave's map is
/// F (T R S) F with F: (u, v) -> (u, 1 - v).
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> String {
    if offset == [0.0; 2] && rotation == 0.0 && scale == [1.0; 2] {
        return String::new();
    }
    let (s, c) = (rotation.sin(), rotation.cos());
    let t = glam::Mat3::from_cols_array_2d(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [offset[0], offset[1], 1.0]]);
    let r = glam::Mat3::from_cols_array_2d(&[[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]);
    let sc = glam::Mat3::from_diagonal(Vec3::new(scale[0], scale[1], 1.0));
    let f = glam::Mat3::from_cols_array_2d(&[[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 1.0]]);
    let m = (f * t * r * sc * f).transpose().to_cols_array_2d();
    format!(
        "(({}, {}, {}), ({}, {}, {}))",
        num(m[0][0]),
        num(m[0][1]),
        num(m[0][2]),
        num(m[1][0]),
        num(m[1][1]),
        num(m[1][2])
    )
}
