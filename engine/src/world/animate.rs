//! The animation systems: keyframed objects, camera and emission set for the frame's shutter.

use super::components::{
    Animated, CameraKeys, CameraParams, EmitKeys, FrameErrors, FrameTime, Materials, Motion, Transform,
};
use crate::scene::{CameraDesc, CameraView};
use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3, Vec3A};

/// Places keyframed objects for the frame's shutter: rotation and scale as at mid-shutter,
/// translation moving linearly from its position at shutter open to the one at shutter close
/// (as a [`Motion`], so rays see it at their own time). Components are written only when they
/// change, so a frame that moves nothing rebuilds nothing.
pub fn animate_objects(
    time: Res<FrameTime>,
    mut objects: Query<(Ref<Animated>, &mut Transform, &mut Motion)>,
) {
    for (anim, mut transform, mut motion) in &mut objects {
        if !(time.is_changed() || anim.is_changed()) {
            continue;
        }
        let at = |t: f32| anim.keys.at(t) * anim.base;
        let (t0, t1) = (time.open, time.close);
        let mid = at(0.5 * (t0 + t1));
        let (p0, p1) = (at(t0).translation, at(t1).translation);
        let v = if t1 > t0 { (p1 - p0) / (t1 - t0) } else { Vec3A::ZERO };
        // At time t the object is at p0 + v (t - t0) (plus its own motion, v_own t).
        let placed = Affine3A { matrix3: mid.matrix3, translation: p0 - v * t0 };
        let velocity = Vec3::from(v) + anim.velocity;
        transform.set_if_neq(Transform(placed));
        motion.set_if_neq(Motion { velocity });
    }
}

/// Sets the camera for the frame: keyframes at mid-shutter, shutter = the frame's.
pub fn animate_camera(
    time: Res<FrameTime>,
    keys: Res<CameraKeys>,
    mut camera: ResMut<CameraParams>,
    mut errors: ResMut<FrameErrors>,
) {
    if !(time.is_changed() || keys.is_changed()) {
        return;
    }
    let at = |t: f32| {
        let mut c = keys.base;
        let k = &keys.keys;
        // The loader refuses look_from, look_at and vfov keys for a `to_world` camera.
        let mut target = None;
        if let CameraView::LookAt { look_from, look_at, vfov, .. } = &mut c.view {
            if let Some(k) = &k.look_from {
                *look_from = k.at(t);
            }
            if let Some(k) = &k.look_at {
                *look_at = k.at(t);
            }
            if let Some(k) = &k.vfov {
                *vfov = k.at(t);
            }
            target = Some(*look_at - *look_from);
        }
        if let Some(k) = &k.focus_dist {
            c.focus_dist = k.at(t);
        } else if let Some(view) = target.filter(|_| k.look_from.is_some() || k.look_at.is_some()) {
            // The default focus distance follows the target.
            c.focus_dist = view.length();
        }
        c.shutter = (time.open, time.close);
        c
    };
    // A camera that moves while the shutter is open: its poses at open and close, between
    // which camera rays interpolate.
    let (open, close) = (at(time.open), at(time.close));
    // The keys may carry the camera where the loader would refuse it (look_from onto look_at,
    // vup along the view, a vfov or focus_dist through zero): the frame reports it.
    for (t, c) in [(time.open, &open), (time.close, &close)] {
        if let Err(e) = c.check() {
            errors.0.push(format!("animation: at time {t}, {e}"));
            return;
        }
    }
    let next = if same_camera(&open, &close) {
        (at(0.5 * (time.open + time.close)), None)
    } else {
        (open, Some(close))
    };
    let same = same_camera(&camera.0, &next.0)
        && match (&camera.1, &next.1) {
            (Some(a), Some(b)) => same_camera(a, b),
            (a, b) => a.is_none() && b.is_none(),
        };
    if !same {
        (camera.0, camera.1) = next;
    }
}

fn same_camera(a: &CameraDesc, b: &CameraDesc) -> bool {
    a == b
}

/// Sets keyframed emitted radiance for the frame (at mid-shutter).
pub fn animate_emission(time: Res<FrameTime>, keys: Res<EmitKeys>, mut materials: ResMut<Materials>) {
    if !time.is_changed() || keys.0.is_empty() {
        return;
    }
    let t = 0.5 * (time.open + time.close);
    let mut changed = false;
    for (id, track) in &keys.0 {
        // Curves that leave [0, MAX_EMISSION] are refused at load: this is rounding.
        let new = track.at(t).max(Vec3::ZERO);
        let m = &mut materials.bypass_change_detection().0[*id as usize];
        if m.emission().is_some_and(|e| e.emit != new) {
            m.set_emission(new);
            changed = true;
        }
    }
    if changed {
        materials.set_changed();
    }
}
