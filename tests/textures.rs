//! Textures through the whole renderer: a solid texture renders exactly like the colour it
//! holds (albedo) or agrees with it within the noise (emission, which takes another code path:
//! textured emitters are evaluated at the sampled light point).

mod common;
use common::*;
use pathwave::io::LinearImage;

fn cornell_with(textures: &str, white: &str, light: &str) -> pathwave::engine::scene::SceneDesc {
    let mut text = std::fs::read_to_string(root().join("scenes/cornell-diffuse.ron")).unwrap();
    text =
        text.replacen("    materials: {", &format!("    textures: {{ {textures} }},\n    materials: {{"), 1);
    text = text.replace(r#""white": Lambertian(albedo: (0.73, 0.73, 0.73))"#, white);
    text = text.replace(r#""light": DiffuseLight(emit: (15, 15, 15))"#, light);
    let mut desc = inline(&text);
    (desc.render.width, desc.render.height, desc.render.spp) =
        (48.try_into().unwrap(), 48.try_into().unwrap(), 64.try_into().unwrap());
    desc
}

#[test]
fn a_solid_albedo_texture_renders_like_its_colour() {
    let plain = cornell_with(
        "",
        r#""white": Lambertian(albedo: (0.73, 0.73, 0.73))"#,
        r#""light": DiffuseLight(emit: (15, 15, 15))"#,
    );
    let textured = cornell_with(
        r#""w": Solid((0.73, 0.73, 0.73))"#,
        r#""white": Lambertian(albedo: "w")"#,
        r#""light": DiffuseLight(emit: (15, 15, 15))"#,
    );
    assert!(render(&plain) == render(&textured));
}

#[test]
fn a_solid_emission_texture_agrees_with_its_colour() {
    let plain = cornell_with(
        "",
        r#""white": Lambertian(albedo: (0.73, 0.73, 0.73))"#,
        r#""light": DiffuseLight(emit: (15, 15, 15))"#,
    );
    let reference = render(&plain);
    let reference = LinearImage { width: 48, height: 48, pixels: reference.mean() };
    let mut textured = cornell_with(
        r#""l": Solid((15, 15, 15))"#,
        r#""white": Lambertian(albedo: (0.73, 0.73, 0.73))"#,
        r#""light": DiffuseLight(emit: "l")"#,
    );
    textured.render.seed = 99;
    let stats = block_z(&render(&textured), &reference, 8, 64);
    assert!(stats.agrees(), "{stats:?}");
    // And it would notice 5% less light.
    let mut dim = textured.clone();
    dim.textures.0[0].1 = pathwave::engine::scene::TextureDesc::Solid(
        pathwave::engine::texture::solid::Solid(pathwave::engine::scene::Rgb(glam::Vec3::splat(14.25))),
    );
    let stats = block_z(&render(&dim), &reference, 8, 64);
    assert!(!stats.agrees(), "5% less emission went unnoticed: {stats:?}");
}

/// A number from a texture: a grey solid texture standing for a rough conductor's alpha
/// renders exactly like the number, and a checker of 0.05 and 0.55, whose mean is that number,
/// does not (so the texture is read at each hit, not only its mean at load: making
/// `set_scalar` ignore the value made the second assert fail).
#[test]
fn a_solid_roughness_texture_renders_like_its_number() {
    let metal = |alpha: &str| format!(r#""white": RoughConductor(tint: (0.73, 0.73, 0.73), alpha: {alpha})"#);
    let light = r#""light": DiffuseLight(emit: (15, 15, 15))"#;
    let plain = render(&cornell_with("", &metal("0.3"), light));
    let textured = render(&cornell_with(r#""a": Solid((0.3, 0.3, 0.3))"#, &metal(r#""a""#), light));
    assert!(plain == textured);
    let checker = r#""a": UvChecker(u: 8, v: 8, even: (0.05, 0.05, 0.05), odd: (0.55, 0.55, 0.55))"#;
    let varying = render(&cornell_with(checker, &metal(r#""a""#), light));
    assert!(plain != varying);
}
