//! Every scene in `scenes/` (RON and glTF) loads and renders (small and fast) without NaN and
//! not black.

mod common;
use common::*;

#[test]
fn every_scene_renders() {
    let mut names: Vec<String> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".ron") || n.ends_with(".gltf"))
        .collect();
    names.sort();
    assert!(names.len() >= 3, "{names:?}");
    for name in names {
        let mut desc = scene(&name);
        let aspect = desc.render.width.get() as f32 / desc.render.height.get() as f32;
        desc.render.width = 48.try_into().unwrap();
        desc.render.height = ((48.0 / aspect) as u32).max(1).try_into().unwrap();
        desc.render.spp = 4.try_into().unwrap();
        let film = render(&desc);
        assert_eq!(film.non_finite(), 0, "{name}: NaN or Inf samples");
        let mean = film.mean();
        let avg = mean.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / mean.len() as f32;
        assert!(avg > 0.01, "{name} renders black");
    }
}
